/* Nearest neighbours in float-float (clsamp/metrics/neighbors.py with
 * precision="float-float"; the double kernel is nearest_neighbor in neighbors.cl, whose
 * grid of cells and launch this keeps): for devices without fp64. The host splits the
 * sorted points into float-float pairs (float2: hi, lo); here each candidate's squared
 * distance is float-float (float_float.h: the wrapped difference, its square, the sum from
 * the first coordinate to the last) and the kernel returns the index of the nearest, whose
 * distance the host then computes in float64 (clsamp.geometry.torus.distance2): the bits
 * of the double path unless two candidates' distances lie within the float-float error of
 * each other (clsamp.metrics.neighbors.float_float_bound).
 *
 * pcf_sums_ff (below) is the pair correlation's pair sums in float-float, as pcf_sums.
 *
 * Build options: D, PERIODIC; NR, PPI and UNIFORM for pcf_sums_ff. FP_CONTRACT OFF: the error-free
 * transformations need every operation rounded as written. nearest_neighbor_ff's grid
 * (total points): best[i] = the sorted index of the nearest other point of its
 * realization in the 3^D neighbouring cells, or 0xFFFFFFFF. */
#include "float_float.h"
#include "cells.h"

#pragma OPENCL FP_CONTRACT OFF

#ifndef PERIODIC
#define PERIODIC 1
#endif




/* min(|a - b|, 1 - |a - b|) on the torus, |a - b| in the cube */
inline float2 ff_delta(const float2 a, const float2 b)
{
    float2 t = ff2_add(a, -b);
    t = t.x < 0.0f ? -t : t;
#if PERIODIC
    const float2 u = ff2_add((float2)(1.0f, 0.0f), -t);
    t = ff2_less(u, t) ? u : t;
#endif
    return t;
}

__kernel void nearest_neighbor_ff(__global const float2 *pts, __global const uint *cell,
                                  __global const uint *start, const uint n, const uint total,
                                  const int G, const uint noff, __global uint *best)
{
    const uint gi = get_global_id(0);
    if (gi >= total)
        return;
    const uint r = gi / n;
    const uint total_cells = cells_count(G);
    float2 x[D];
    for (int k = 0; k < D; ++k)
        x[k] = pts[(size_t)gi * D + k];
    int c[D];
    cell_coordinates(cell[gi], G, c);
    float2 nearest = (float2)(INFINITY, 0.0f);
    uint found = 0xFFFFFFFFu;
    for (uint o = 0; o < noff; ++o) {
        const size_t slot = (size_t)r * total_cells + neighbour(c, o, G);
        const uint s1 = start[slot + 1];
        for (uint j = start[slot]; j < s1; ++j) {
            if (j == gi)
                continue;
            __global const float2 *y = pts + (size_t)j * D;
            float2 t = ff_delta(x[0], y[0]);
            float2 d2 = ff2_mul(t, t);
            for (int k = 1; k < D; ++k) {
                t = ff_delta(x[k], y[k]);
                d2 = ff2_add(d2, ff2_mul(t, t));
            }
            if (ff2_less(d2, nearest)) {
                nearest = d2;
                found = j;
            }
        }
    }
    best[gi] = found;
}

#ifdef NR

/* Grid (items, realizations): as pcf_sums in neighbors.cl (every unordered pair within
 * reach once, through the forward half of the 3^D stencil), in float-float:
 * out[r][w][k] += weight exp(-(radius_k - s)^2 / (2 sigma^2)) for |radius_k - s| <= cut
 * (radii, inv2s2, cut, step, step^2 and b = exp(-2 step^2 / 2 sigma^2) as float-float
 * pairs from the host; weight 1 on the torus, the translation edge correction in the
 * cube). UNIFORM radii (r0 + k step) take the Gaussian along k by the double kernel's
 * recurrence, two exp a pair; others evaluate each radius' Gaussian. */
inline int within_cut(const float2 radius, const float2 s, const float2 cut)
{
    const float2 dt = ff2_add(radius, -s);
    return !ff2_less(cut, dt.x < 0.0f ? -dt : dt);
}

__kernel void pcf_sums_ff(__global const float2 *pts, __global const uint *cell,
                          __global const uint *start, const uint n, const int G, const uint noff,
                          const float2 reach2, __global const float2 *radii, const float2 inv2s2,
                          const float2 cut, __global const float2 *coef, const float2 step,
                          const float2 step2, const float2 b, const float inv_step,
                          const uint items, __global float2 *out)
{
    const uint w = get_global_id(0), r = get_global_id(1);
    if (w >= items)
        return;
    float2 hist[NR];
    for (int k = 0; k < NR; ++k)
        hist[k] = (float2)(0.0f);
    const uint total_cells = cells_count(G);
    const uint centre = (noff - 1) / 2;
    const size_t base = (size_t)r * n;
    const uint stop = (w + 1) * PPI < n ? (w + 1) * PPI : n;
    for (uint i = w * PPI; i < stop; ++i) {
        const size_t gi = base + i;
        float2 x[D];
        for (int k = 0; k < D; ++k)
            x[k] = pts[gi * D + k];
        int c[D];
        cell_coordinates(cell[gi], G, c);
        for (uint o = centre; o < noff; ++o) {
            const size_t slot = (size_t)r * total_cells + neighbour(c, o, G);
            const uint s1 = start[slot + 1];
            for (uint j = o == centre ? (uint)gi + 1 : start[slot]; j < s1; ++j) {
                __global const float2 *y = pts + (size_t)j * D;
                float2 t = ff_delta(x[0], y[0]);
                float2 d2 = ff2_mul(t, t);
#if !PERIODIC
                float2 cover = ff2_add((float2)(1.0f, 0.0f), -t);
#endif
                for (int k = 1; k < D; ++k) {
                    t = ff_delta(x[k], y[k]);
                    d2 = ff2_add(d2, ff2_mul(t, t));
#if !PERIODIC
                    float h, l;
                    const float2 side = ff2_add((float2)(1.0f, 0.0f), -t);
                    FF_MUL(float, cover.x, cover.y, side.x, side.y, h, l);
                    cover = (float2)(h, l);
#endif
                }
                if (!ff2_less(d2, reach2))
                    continue;
                const float2 s = ff2_sqrt(d2);
#if UNIFORM
                /* the radii within the cut, a contiguous run k0 .. k1: from a float guess,
                 * moved by the float-float test |radius_k - s| <= cut */
                int k0 = clamp((int)((s.x - cut.x - radii[0].x) * inv_step), 0, NR - 1);
                while (k0 > 0 && within_cut(radii[k0 - 1], s, cut))
                    --k0;
                while (k0 < NR && !within_cut(radii[k0], s, cut) && ff2_less(radii[k0], s))
                    ++k0;
                if (k0 == NR || !within_cut(radii[k0], s, cut))
                    continue;
                int k1 = k0;
                while (k1 + 1 < NR && within_cut(radii[k1 + 1], s, cut))
                    ++k1;
                /* e_k = exp(-t_k^2 / 2 sigma^2) along t_k = t_k0 + (k - k0) step:
                 * e_{k+1} = e_k a_k, a_k = exp(-(2 t_k step + step^2) / 2 sigma^2), a_{k+1} = a_k b */
                const float2 t0 = ff2_add(radii[k0], -s);
                float h, l;
                FF_MUL(float, t0.x, t0.y, t0.x, t0.y, h, l);
                FF_MUL(float, h, l, inv2s2.x, inv2s2.y, h, l);
                float2 e = ff2_exp((float2)(-h, -l), coef);
                FF_MUL(float, t0.x, t0.y, step.x, step.y, h, l);
                const float2 twice = ff2_add((float2)(2.0f * h, 2.0f * l), step2);
                FF_MUL(float, twice.x, twice.y, inv2s2.x, inv2s2.y, h, l);
                float2 a = ff2_exp((float2)(-h, -l), coef);
#if !PERIODIC
                FF_DIV(float, e.x, e.y, cover.x, cover.y, h, l);
                e = (float2)(h, l);
#endif
                for (int k = k0; k <= k1; ++k) {
                    hist[k] = ff2_add(hist[k], e);
                    FF_MUL(float, e.x, e.y, a.x, a.y, h, l);
                    e = (float2)(h, l);
                    FF_MUL(float, a.x, a.y, b.x, b.y, h, l);
                    a = (float2)(h, l);
                }
#else
                for (int k = 0; k < NR; ++k) {
                    const float2 dt = ff2_add(radii[k], -s);
                    if (ff2_less(cut, dt.x < 0.0f ? -dt : dt))
                        continue;
                    float h, l;
                    FF_MUL(float, dt.x, dt.y, dt.x, dt.y, h, l);
                    FF_MUL(float, h, l, inv2s2.x, inv2s2.y, h, l);
                    float2 e = ff2_exp((float2)(-h, -l), coef);
#if !PERIODIC
                    FF_DIV(float, e.x, e.y, cover.x, cover.y, h, l);
                    e = (float2)(h, l);
#endif
                    hist[k] = ff2_add(hist[k], e);
                }
#endif
            }
        }
    }
    __global float2 *row = out + ((size_t)r * items + w) * NR;
    for (int k = 0; k < NR; ++k)
        row[k] = hist[k];
}
#endif
