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
#include "inline_builtins.h"
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
/* In double: the same operations as the integer form below, which PoCL runs faster than
 * that form through f64bits.h's hardware branch (docs/performance.md, "Stratified and
 * permutations"). */
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

/* stratum_point of four points, one a lane (same count): with fp64 the four divisions and
 * checks in vector lanes, a lane that needs the nudge (rare) redone by stratum_point. */
inline ulong4 stratum_point4(const uint4 k, const ulong4 ub, const uint count)
{
#if CLSAMP_FP64
    const double c = (double)count;
    const double4 kd = convert_double4(k);
    const double4 x = (kd + as_double4(ub)) / c;
    const double4 y = x * c;
    if (!clsamp_any4l((y >= kd + 1.0) | (y < kd)))
        return as_ulong4(x);
#endif
    return (ulong4)(stratum_point(k.s0, ub.s0, count), stratum_point(k.s1, ub.s1, count),
                    stratum_point(k.s2, ub.s2, count), stratum_point(k.s3, ub.s3, count));
}

/* Four 2-D points, lane l = point l, at p (2 words a point): the first `lanes` of them. */
inline void store_points2(__global ulong *p, const ulong4 x, const ulong4 y, const uint lanes)
{
    p[0] = x.s0;
    p[1] = y.s0;
    if (lanes > 1u) {
        p[2] = x.s1;
        p[3] = y.s1;
    }
    if (lanes > 2u) {
        p[4] = x.s2;
        p[5] = y.s2;
    }
    if (lanes > 3u) {
        p[6] = x.s3;
        p[7] = y.s3;
    }
}

/* Grid (ceil(n / 4) padded, realizations); out has shape (realizations, n, d). Work-item q
 * makes points 4q .. 4q + 3, one a vector lane (their Philox blocks and divisions side by
 * side). Dimension j is split into radix[j] strata and belongs to group group[j] (groups
 * are contiguous runs of dimensions). Point i of a group takes cell c = perms[r, g, i]
 * (PERMUTED) or c = i, whose mixed-radix digits (first dimension fastest) are its strata
 * in the group's dimensions. perms has shape (realizations, groups, n). */
__kernel void stratified_points(__global ulong *out, const uint n, const uint d,
                                const uint start, const uint realization0,
                                const uint key_lo, const uint key_hi, const uint stream,
                                __global const uint *radix, __global const uint *group,
                                __global const uint *perms, const uint groups)
{
    const uint i0 = 4u * get_global_id(0);
    const uint r = get_global_id(1);
    if (i0 >= n)
        return;
    const uint2 key = (uint2)(key_lo, key_hi);
    const uint lanes = n - i0;                        /* points to store: min(lanes, 4) */
    /* lanes past n repeat point n - 1 (made, not stored) */
    const uint4 lane = (uint4)(i0) + (uint4)(0u, 1u, 2u, 3u);
    const uint4 i = lane < n ? lane : (uint4)(n - 1u);
    __global ulong *p = out + ((size_t)r * n + i0) * d;
    uint current = 0xFFFFFFFFu;
    uint4 cell = 0;
    ulong4 ux = (ulong4)(0x3FE0000000000000UL), uy = ux;     /* 0.5 */
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
            __global const uint *row = perms + ((size_t)r * groups + current) * n;
            cell = (uint4)(row[i.s0], row[i.s1], row[i.s2], row[i.s3]);
#else
            cell = i;
#endif
        }
        const uint strata = radix[j];
        const uint4 digit = cell % strata;
        cell /= strata;
#ifdef DIMS_PER_ITEM
        if (j < j0)
            continue;
#endif
#if !CENTERED
        /* pair j >> 1's Philox blocks: at its first dimension, or a chunk's first */
#ifdef DIMS_PER_ITEM
        const bool pair = (j & 1u) == 0u || j == j0;
#else
        const bool pair = (j & 1u) == 0u;
#endif
        if (pair) {
            uint4 w0, w1, w2, w3;
            philox4x32_10_x4((uint4)(start) + i, (uint4)(realization0 + r), (uint4)(j >> 1),
                             (uint4)(stream), key, &w0, &w1, &w2, &w3);
            ux = clsamp_unit4_bits(w0, w1);
            uy = clsamp_unit4_bits(w2, w3);
        }
#endif
        const ulong4 x = stratum_point4(digit, (j & 1u) ? uy : ux, strata);
        p[j] = x.s0;
        if (lanes > 1u)
            p[d + j] = x.s1;
        if (lanes > 2u)
            p[2 * d + j] = x.s2;
        if (lanes > 3u)
            p[3 * d + j] = x.s3;
    }
}

/* Chiu, Shirley, Wang (1994): grid (ceil(n / 4) padded, realizations), n = mx * my points,
 * point p = row * mx + col, work-item q making points 4q .. 4q + 3 in vector lanes. Its x lies
 * in column col and in substratum col * my + colperm[col][row] of the n x-slabs; its y in
 * row row and substratum row * mx + rowperm[row][col].
 * colperm: (realizations, mx, my), rowperm: (realizations, my, mx). */
__kernel void multijittered_points(__global ulong *out, const uint mx, const uint my,
                                   const uint start, const uint realization0,
                                   const uint key_lo, const uint key_hi, const uint stream,
                                   __global const uint *colperm, __global const uint *rowperm)
{
    const uint i0 = 4u * get_global_id(0);
    const uint r = get_global_id(1);
    const uint n = mx * my;
    if (i0 >= n)
        return;
    const uint4 lane = (uint4)(i0) + (uint4)(0u, 1u, 2u, 3u);
    const uint4 i = lane < n ? lane : (uint4)(n - 1u);       /* past n: made, not stored */
    const uint4 col = i % mx;
    const uint4 row = i / mx;
    uint4 w0, w1, w2, w3;
    philox4x32_10_x4((uint4)(start) + i, (uint4)(realization0 + r), (uint4)(0u), (uint4)(stream),
                     (uint2)(key_lo, key_hi), &w0, &w1, &w2, &w3);
    __global const uint *cp = colperm + (size_t)r * n, *rp = rowperm + (size_t)r * n;
    const uint4 sx = (uint4)(cp[col.s0 * my + row.s0], cp[col.s1 * my + row.s1],
                             cp[col.s2 * my + row.s2], cp[col.s3 * my + row.s3]);
    const uint4 sy = (uint4)(rp[row.s0 * mx + col.s0], rp[row.s1 * mx + col.s1],
                             rp[row.s2 * mx + col.s2], rp[row.s3 * mx + col.s3]);
    const ulong4 x = stratum_point4(col * my + sx, clsamp_unit4_bits(w0, w1), n);
    const ulong4 y = stratum_point4(row * mx + sy, clsamp_unit4_bits(w2, w3), n);
    store_points2(out + ((size_t)r * n + i0) * 2, x, y, n - i0);
}

/* Kensler (2013), final "cmj" listing with aspect 1: grid (ceil(n / 4) padded,
 * realizations), work-item q making points 4q .. 4q + 3 in vector lanes; m = floor(sqrt(n))
 * columns, rows = ceil(n / m). The pattern p of a realization is Philox word 0 of
 * (perm_stream, realization, index 0); jitter comes from Philox (point_stream, index
 * start + i) instead of Kensler's 32-bit hash. */
__kernel void correlated_multijittered_points(__global ulong *out, const uint n, const uint m,
                                              const uint rows, const uint start,
                                              const uint realization0, const uint key_lo,
                                              const uint key_hi, const uint point_stream,
                                              const uint perm_stream)
{
    const uint i0 = 4u * get_global_id(0);
    const uint r = get_global_id(1);
    if (i0 >= n)
        return;
    const uint2 key = (uint2)(key_lo, key_hi);
    const uint p = clsamp_bits(key, perm_stream, realization0 + r, 0u, 0u);
    /* lanes past n take point n - 1 (made, not stored) */
    const uint4 lane = (uint4)(i0) + (uint4)(0u, 1u, 2u, 3u);
    const uint4 i = lane < n ? lane : (uint4)(n - 1u);
    const uint4 s = clsamp_permute4(i, n, p * 0x51633e2du);
    const uint4 sx = clsamp_permute4(s % m, m, p * 0x68bc21ebu);
    const uint4 sy = clsamp_permute4(s / m, rows, p * 0x02e5be93u);
    uint4 w0, w1, w2, w3;
    philox4x32_10_x4((uint4)(start) + i, (uint4)(realization0 + r), (uint4)(0u),
                     (uint4)(point_stream), key, &w0, &w1, &w2, &w3);
    const ulong4 x = stratum_point4(sx * rows + sy, clsamp_unit4_bits(w0, w1), m * rows);
    const ulong4 y = stratum_point4(s, clsamp_unit4_bits(w2, w3), n);
    store_points2(out + ((size_t)r * n + i0) * 2, x, y, n - i0);
}
