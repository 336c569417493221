/* zsobol: Owen-scrambled Sobol' indexed by the pixel's Morton code (Ahmed and Wonka 2020,
 * pbrt-v4's ZSobolSampler). NumPy reference: clsamp/samplers/zsobol.py.
 *
 * out is (pixels, n, d).
 * words: (pairs, 4) uint: Owen seeds of x and y and the low/high words of the pair's
 * 64-bit digit-permutation seed. perms: the 24 permutations of 4 digits (24 x 4).
 * bytes: Sobol' dimension 1's direction numbers as xor tables by index byte.
 * Integer arithmetic and exact scaling by 2^-32 only: every device gives the same bits,
 * written as bit patterns (f64bits.h).
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

/* The permuted digits of sample index bits at shifts >= m (those of the Morton code alone,
 * the same for every sample of the pixel) and below (per sample): pbrt's GetSampleIndex split
 * in two. With odd = m & 1 every digit's shift 2i - odd has the parity of m, so a digit lies
 * wholly above or wholly below bit m. */
inline ulong zsobol_high(const ulong code, const uint m, const uint digits, const ulong seed,
                         __global const uint *perms)
{
    const uint odd = m & 1u;
    const ulong index = code << m;
    ulong out = 0;
    for (int i = (int)digits - 1; i >= (int)odd; --i) {
        const uint shift = 2u * (uint)i - odd;
        if (shift < m)
            break;
        const uint digit = (uint)(index >> shift) & 3u;
        const uint p = (uint)((mix64((index >> (shift + 2u)) ^ seed) >> 24) % 24UL);
        out |= (ulong)perms[4u * p + digit] << shift;
    }
    return out;
}

inline uint zsobol_low(const ulong code, const uint s, const uint m, const ulong seed,
                       __global const uint *perms)
{
    const uint odd = m & 1u;
    const ulong index = (code << m) | (ulong)s;
    uint out = 0;
    for (int shift = (int)m - 2; shift >= (int)odd; shift -= 2) {
        const uint digit = (uint)(index >> shift) & 3u;
        const uint p = (uint)((mix64((index >> (shift + 2)) ^ seed) >> 24) % 24UL);
        out |= perms[4u * p + digit] << shift;
    }
    if (odd)
        out |= (uint)((index & 1UL) ^ (mix64((index >> 1) ^ seed) & 1UL));
    return out;
}

/* Sobol' dimension 1 of index a (natural order): the xor of the direction numbers of its set
 * bits, by bytes (table: 4 x 256 xors of 8 direction numbers each). */
inline uint sobol1(const uint a, __global const uint *bytes)
{
    return bytes[a & 255u] ^ bytes[256u + ((a >> 8) & 255u)] ^ bytes[512u + ((a >> 16) & 255u)]
           ^ bytes[768u + (a >> 24)];
}

#ifndef ZS_BLOCK
#define ZS_BLOCK 16
#endif

/* Grid: (ceil(n / ZS_BLOCK) padded to the local size, pixels); work-item (b, r) makes samples
 * b ZS_BLOCK .. of pixel pixel0 + r. bytes: sobol1's table. */
__kernel void zsobol_points(__global ulong *out, __global const uint *words,
                            __global const uint *perms, __global const uint *bytes, const uint n,
                            const uint m, const uint d, const uint pixel0, const uint width,
                            const uint log2_side)
{
    const uint s0 = get_global_id(0) * ZS_BLOCK;
    const uint r = get_global_id(1);
    if (s0 >= n)
        return;
    const uint pixel = pixel0 + r;
    const ulong code = spread_bits(pixel % width) | (spread_bits(pixel / width) << 1);
    const uint digits = log2_side + (m + 1u) / 2u;
    const uint end = min(n, s0 + ZS_BLOCK);
    for (uint p = 0; 2u * p < d; ++p) {
        const uint4 w = vload4(p, words);
        const ulong seed = (ulong)w.z | ((ulong)w.w << 32);
        const uint high = (uint)zsobol_high(code, m, digits, seed, perms);
        for (uint s = s0; s < end; ++s) {
            const uint index = high | zsobol_low(code, s, m, seed, perms);
            __global ulong *row = out + ((size_t)r * n + s) * d;
            row[2u * p] = f64_scaled(owen_scramble_base2(reverse_bits32(index), w.x), -32);
            if (2u * p + 1u < d)
                row[2u * p + 1u] = f64_scaled(owen_scramble_base2(sobol1(index, bytes), w.y), -32);
        }
    }
}
