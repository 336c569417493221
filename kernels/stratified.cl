/* The stratified family: regular, jittered, uncorrelated jitter, Latin hypercube,
 * multi-jittered (Chiu-Shirley-Wang 1994) and correlated multi-jittered (Kensler 2013).
 * NumPy references: clsamp/samplers/stratified.py (same function names).
 *
 * Integer arithmetic and exactly rounded double operations only, so every device
 * gives the same bits; the doubles are written as their bit patterns (f64bits.h), by
 * integer arithmetic where the device has no fp64. Build options: PERMUTED (cells come from a permutation
 * buffer) and CENTERED (cell centres instead of jitter) for stratified_points. */
#pragma OPENCL FP_CONTRACT OFF
#include "permutation.h"
#include "dims.h"

#ifndef PERMUTED
#define PERMUTED 0
#endif
#ifndef CENTERED
#define CENTERED 0
#endif

/* (k + u) / count, nudged by ulps so that floor(x * count) == k in double arithmetic:
 * the rounding of k + u and of the division may otherwise carry a point across the
 * stratum's edge (and the last stratum's point to 1.0). The rounded quotient is less
 * than two ulps from the nearest admissible double (four if the ulp halves on the
 * way), so four steps each way suffice. floor(y) > k is written y >= k + 1 and
 * floor(y) < k as y < k (exact for integer k < 2^32): PoCL's double floor() is a slow
 * library call; fixed steps with selects and integer ulp moves (x > 0 here) behind
 * one rarely taken test keep the kernel vectorizable. */
#define CLSAMP_STRATUM_STEPS 4

#if CLSAMP_FP64
/* In double: the same operations as the integer form below (measured 10% faster on PoCL
 * than that form through f64bits.h's hardware branch). */
inline ulong stratum_point(const uint k, const ulong ub, const uint count)
{
    const double u = as_double(ub), c = (double)count, kd = (double)k;
    double x = (kd + u) / c;
    if (x * c >= kd + 1.0 || x * c < kd) {
        for (int step = 0; step < CLSAMP_STRATUM_STEPS; ++step)
            x = x * c >= kd + 1.0 ? as_double(as_long(x) - 1) : x;
        for (int step = 0; step < CLSAMP_STRATUM_STEPS; ++step)
            x = x * c < kd ? as_double(as_long(x) + 1) : x;
    }
    return as_ulong(x);
}
#else
inline ulong stratum_point(const uint k, const ulong u, const uint count)
{
    const ulong kd = f64_from_int(k), next = f64_add(kd, F64_ONE);     /* k + 1, exact */
    ulong x = f64_div_int(f64_add(kd, u), count);
    const ulong y = f64_mul_int(x, count);
    if (y >= next || y < kd) {      /* non-negative doubles order as their bits */
        for (int step = 0; step < CLSAMP_STRATUM_STEPS; ++step)
            x = f64_mul_int(x, count) >= next ? f64_next_down(x) : x;
        for (int step = 0; step < CLSAMP_STRATUM_STEPS; ++step)
            x = f64_mul_int(x, count) < kd ? f64_next_up(x) : x;
    }
    return x;
}
#endif

/* Grid (n padded, realizations); out has shape (realizations, n, d).
 * Dimension j is split into radix[j] strata and belongs to group group[j] (groups are
 * contiguous runs of dimensions). Point i of a group takes cell c = perms[r, g, i]
 * (PERMUTED) or c = i, whose mixed-radix digits (first dimension fastest) are its
 * strata in the group's dimensions. perms has shape (realizations, groups, n). */
__kernel void stratified_points(__global ulong *out, const uint n, const uint d,
                                const uint start, const uint realization0,
                                const uint key_lo, const uint key_hi, const uint stream,
                                __global const uint *radix, __global const uint *group,
                                __global const uint *perms, const uint groups)
{
    const uint i = get_global_id(0);
    const uint r = get_global_id(1);
    if (i >= n)
        return;
    const uint2 key = (uint2)(key_lo, key_hi);
    __global ulong *p = out + ((size_t)r * n + i) * d;
    uint current = 0xFFFFFFFFu;
    uint cell = 0;
    ulong2 u = (ulong2)(0x3FE0000000000000UL);   /* 0.5 */
    /* a chunk of dimensions (dims.h) that starts inside a group walks from the group's
     * first dimension, to take the digits before it off the cell */
#ifdef DIMS_PER_ITEM
    const uint j0 = CLSAMP_DIM0;
    uint first = j0 < d ? j0 : d;
    while (first > 0 && first < d && group[first - 1] == group[first])
        --first;
#else
    const uint first = 0;
#endif
    for (uint j = first; j < CLSAMP_DIM_END(d); ++j) {
        if (group[j] != current) {
            current = group[j];
#if PERMUTED
            cell = perms[((size_t)r * groups + current) * n + i];
#else
            cell = i;
#endif
        }
        const uint strata = radix[j];
        const uint digit = cell % strata;
        cell /= strata;
#ifdef DIMS_PER_ITEM
        if (j < j0)
            continue;
#if !CENTERED
        if ((j & 1u) == 0u || j == j0)
            u = clsamp_uniform2_bits(key, stream, realization0 + r, start + i, j >> 1);
#endif
#elif !CENTERED
        if ((j & 1u) == 0u)
            u = clsamp_uniform2_bits(key, stream, realization0 + r, start + i, j >> 1);
#endif
        p[j] = stratum_point(digit, (j & 1u) ? u.y : u.x, strata);
    }
}

/* Chiu, Shirley, Wang (1994): grid (n padded, realizations), n = mx * my points, point
 * p = row * mx + col. Its x lies in column col and in substratum col * my + colperm[col][row]
 * of the n x-slabs; its y in row row and substratum row * mx + rowperm[row][col].
 * colperm: (realizations, mx, my), rowperm: (realizations, my, mx). */
__kernel void multijittered_points(__global ulong *out, const uint mx, const uint my,
                                   const uint start, const uint realization0,
                                   const uint key_lo, const uint key_hi, const uint stream,
                                   __global const uint *colperm, __global const uint *rowperm)
{
    const uint i = get_global_id(0);
    const uint r = get_global_id(1);
    const uint n = mx * my;
    if (i >= n)
        return;
    const uint col = i % mx;
    const uint row = i / mx;
    const ulong2 u = clsamp_uniform2_bits((uint2)(key_lo, key_hi), stream, realization0 + r, start + i, 0);
    const uint sx = colperm[((size_t)r * mx + col) * my + row];
    const uint sy = rowperm[((size_t)r * my + row) * mx + col];
    __global ulong *p = out + ((size_t)r * n + i) * 2;
    p[0] = stratum_point(col * my + sx, u.x, n);
    p[1] = stratum_point(row * mx + sy, u.y, n);
}

/* Kensler (2013), final "cmj" listing with aspect 1: grid (n padded, realizations);
 * m = floor(sqrt(n)) columns, rows = ceil(n / m). The pattern p of a realization is
 * Philox word 0 of (perm_stream, realization, index 0); jitter comes from Philox
 * (point_stream, index start + i) instead of Kensler's 32-bit hash. */
__kernel void correlated_multijittered_points(__global ulong *out, const uint n, const uint m,
                                              const uint rows, const uint start,
                                              const uint realization0, const uint key_lo,
                                              const uint key_hi, const uint point_stream,
                                              const uint perm_stream)
{
    const uint i = get_global_id(0);
    const uint r = get_global_id(1);
    if (i >= n)
        return;
    const uint2 key = (uint2)(key_lo, key_hi);
    const uint p = clsamp_bits(key, perm_stream, realization0 + r, 0u, 0u);
    const uint s = clsamp_permute(i, n, p * 0x51633e2du);
    const uint sx = clsamp_permute(s % m, m, p * 0x68bc21ebu);
    const uint sy = clsamp_permute(s / m, rows, p * 0x02e5be93u);
    const ulong2 u = clsamp_uniform2_bits(key, point_stream, realization0 + r, start + i, 0);
    __global ulong *q = out + ((size_t)r * n + i) * 2;
    q[0] = stratum_point(sx * rows + sy, u.x, m * rows);
    q[1] = stratum_point(s, u.y, n);
}
