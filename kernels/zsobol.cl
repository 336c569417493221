/* zsobol: Owen-scrambled Sobol' indexed by the pixel's Morton code (Ahmed and Wonka 2020,
 * pbrt-v4's ZSobolSampler). NumPy reference: clsamp/samplers/zsobol.py.
 *
 * Grid: (n padded to the local size, pixels). Work-item (s, r) makes sample s of pixel
 * pixel0 + r in every dimension: out is (pixels, n, d).
 * words: (pairs, 4) uint: Owen seeds of x and y and the low/high words of the pair's
 * 64-bit digit-permutation seed. perms: the 24 permutations of 4 digits (24 x 4).
 * v1: the 32 direction numbers of Sobol' dimension 1.
 * Integer arithmetic and exact scaling by 2^-32 only: every device gives the same bits.
 */
#pragma OPENCL FP_CONTRACT OFF
#include "lowdiscrepancy.h"

inline ulong spread_bits(ulong v)
{
    v &= 0xFFFFUL;
    v = (v | (v << 8)) & 0x00FF00FFUL;
    v = (v | (v << 4)) & 0x0F0F0F0FUL;
    v = (v | (v << 2)) & 0x33333333UL;
    return (v | (v << 1)) & 0x55555555UL;
}

/* The permuted Sobol' index of sample s of the pixel with Morton code `code`. */
inline uint zsobol_index(const ulong code, const uint s, const uint m, const uint digits,
                         const ulong seed, __global const uint *perms)
{
    const uint odd = m & 1u;
    const ulong index = (code << m) | (ulong)s;
    ulong out = 0;
    for (int i = (int)digits - 1; i >= (int)odd; --i) {
        const uint shift = 2u * (uint)i - odd;
        const uint digit = (uint)(index >> shift) & 3u;
        const ulong higher = index >> (shift + 2u);
        const uint p = (uint)((mix64(higher ^ seed) >> 24) % 24UL);
        out |= (ulong)perms[4u * p + digit] << shift;
    }
    if (odd)
        out |= (index & 1UL) ^ (mix64((index >> 1) ^ seed) & 1UL);
    return (uint)out;
}

__kernel void zsobol_points(__global double *out, __global const uint *words,
                            __global const uint *perms, __global const uint *v1, const uint n,
                            const uint m, const uint d, const uint pixel0, const uint width,
                            const uint log2_side)
{
    const uint s = get_global_id(0);
    const uint r = get_global_id(1);
    if (s >= n)
        return;
    const uint pixel = pixel0 + r;
    const ulong code = spread_bits(pixel % width) | (spread_bits(pixel / width) << 1);
    const uint digits = log2_side + (m + 1u) / 2u;
    __global double *row = out + ((size_t)r * n + s) * d;
    for (uint p = 0; 2u * p < d; ++p) {
        const uint4 w = vload4(p, words);
        const ulong seed = (ulong)w.z | ((ulong)w.w << 32);
        const uint index = zsobol_index(code, s, m, digits, seed, perms);
        row[2u * p] = (double)owen_scramble_base2(reverse_bits32(index), w.x) * 0x1p-32;
        if (2u * p + 1u < d) {
            uint y = 0;
            for (uint c = 0, a = index; a != 0u; ++c, a >>= 1)
                if (a & 1u)
                    y ^= v1[c];
            row[2u * p + 1u] = (double)owen_scramble_base2(y, w.y) * 0x1p-32;
        }
    }
}
