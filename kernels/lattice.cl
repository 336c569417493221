/* Rank-1 lattices and Kronecker sequences. NumPy reference: clsamp/samplers/lattice.py.
 *
 * Grid: (n padded to the local size, realizations); out is (realizations, n, d).
 * shifts: (realizations, d) Cranley-Patterson shifts, applied when SHIFT is 1.
 * Integer arithmetic and exact scalings (one correctly rounded division for the Fibonacci
 * lattice): every device gives the same bits, written as bit patterns (f64bits.h).
 */
#pragma OPENCL FP_CONTRACT OFF
#include "lowdiscrepancy.h"

#ifndef SHIFT
#define SHIFT 0
#endif

inline ulong shifted(ulong x, __global const ulong *shifts, uint r, uint d, uint j)
{
#if SHIFT
    return f64_shift_mod1(x, shifts[(size_t)r * d + j]);
#else
    return x;
#endif
}

#ifndef GRAY
#define GRAY 0
#endif

/* Extensible lattice in base 2: ((reverse32(i) z_j) mod 2^32) 2^-32; GRAY: index i's Gray
 * code i ^ (i >> 1) in place of i. */
__kernel void lattice_points(__global ulong *out, __global const uint *z,
                             __global const ulong *shifts, const uint n, const uint d,
                             const uint start)
{
    const uint i = get_global_id(0), r = get_global_id(1);
    if (i >= n)
        return;
    const uint k = start + i;
    const uint radical = reverse_bits32(GRAY ? k ^ (k >> 1) : k);
    __global ulong *row = out + ((size_t)r * n + i) * d;
    for (uint j = 0; j < d; ++j)
        row[j] = shifted(f64_scaled(radical * z[j], -32), shifts, r, d, j);
}

/* The rank-1 lattice rule of n points in natural order: (i z_j mod n) / n, one correctly
 * rounded division (the Fibonacci lattice: z = (1, F_(m-1)), n = F_m). */
__kernel void natural_points(__global ulong *out, __global const uint *z,
                             __global const ulong *shifts, const uint n, const uint d,
                             const uint start)
{
    const uint i = get_global_id(0), r = get_global_id(1);
    if (i >= n)
        return;
    const ulong k = (ulong)(start + i);
    __global ulong *row = out + ((size_t)r * n + i) * d;
    for (uint j = 0; j < d; ++j)
        row[j] = shifted(f64_div((k * z[j]) % n, n, 0), shifts, r, d, j);
}

/* Kronecker: the top 53 bits of (i A_j) mod 2^64, times 2^-53. */
__kernel void kronecker_points(__global ulong *out, __global const uint *alphas,
                               __global const ulong *shifts, const uint n, const uint d,
                               const uint start)
{
    const uint i = get_global_id(0), r = get_global_id(1);
    if (i >= n)
        return;
    const ulong k = (ulong)(start + i);
    __global ulong *row = out + ((size_t)r * n + i) * d;
    for (uint j = 0; j < d; ++j) {
        const ulong a = (ulong)alphas[2u * j] | ((ulong)alphas[2u * j + 1u] << 32);
        row[j] = shifted(f64_scaled((k * a) >> 11, -53), shifts, r, d, j);
    }
}
