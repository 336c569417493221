/* Pair statistics of point sets on the unit torus, through a grid of cells
 * (clsamp/metrics/neighbors.py; NumPy twins there): the Gaussian-smoothed pair-distance
 * sums of the pair correlation function and the nearest-neighbour distances.
 *
 * The points of all realizations come sorted by (realization, cell) in pts (total, D);
 * cell[i] is the flat cell of sorted point i in a G^D grid and start (r G^D + 1) the first
 * sorted index of each (realization, cell). With G >= 3 a point meets the points of its
 * 3^D neighbouring cells (distinct cells); the host passes G = 1 (one cell, every pair)
 * when the reach is too long for three cells.
 *
 * Distances: exactly rounded double operations, no contraction, in the order of
 * clsamp.geometry.torus.distance2 (kernels/torus.h, as the Poisson-disk kernels): the nearest-neighbour
 * distances agree with the NumPy twin bit for bit. The smoothing sums use exp: their
 * bits depend on the device's exp (within a few ulps). Build options: D, PERIODIC; NR
 * (radii) for pcf_sums, UNIFORM (radii r0 + k step) and PPI (points a work-item takes).
 * In the unit cube (PERIODIC 0) the stencil still wraps: a wrapped neighbour cell holds
 * points at least a cell width away in the cube, which the reach test drops.
 */
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#pragma OPENCL FP_CONTRACT OFF
#include "torus.h"
#include "cells.h"

/* PERIODIC 1: distances on the torus; 0: in the unit cube, each pair of the PCF weighted
 * by the translation edge correction 1 / prod_k (1 - |x_k - y_k|) (Ohser 1983) */
#ifndef PERIODIC
#define PERIODIC 1
#endif
#if PERIODIC
#define pair_distance2 torus_distance2
#else
#define pair_distance2 cube_distance2
#endif

#ifdef NR
#if UNIFORM
/* Add one pair's Gaussian to the radii k0 .. k1: e = exp(-t^2 / 2 sigma^2) at radius k0
 * (t = radius_k0 - s), then e_{k+1} = e_k a_k, a_{k+1} = a_k b along the uniform radii. */
inline void add_gaussian(double *hist, double e, double a, const double b, const int k0, const int k1)
{
    for (int k = k0; k <= k1; ++k) {
        hist[k] += e;
        e *= a;
        a *= b;
    }
}

/* The pairs waiting in (tb, kb0, kb1): their two exp as one double4 exp each (PoCL's
 * vector exp costs about what one scalar exp does), then the recurrence per pair. A lane
 * with kb0 > kb1 adds nothing. */
inline void flush_pairs(double *hist, const double *tb, const double *wb, const int *kb0,
                        const int *kb1, const double step, const double inv2s2, const double b)
{
    const double4 t = (double4)(tb[0], tb[1], tb[2], tb[3]);
#if PERIODIC
    const double4 e = exp(-(t * t) * inv2s2);
#else
    const double4 e = exp(-(t * t) * inv2s2) * (double4)(wb[0], wb[1], wb[2], wb[3]);
#endif
    const double4 a = exp(-(2.0 * t * step + step * step) * inv2s2);
    add_gaussian(hist, e.s0, a.s0, b, kb0[0], kb1[0]);
    add_gaussian(hist, e.s1, a.s1, b, kb0[1], kb1[1]);
    add_gaussian(hist, e.s2, a.s2, b, kb0[2], kb1[2]);
    add_gaussian(hist, e.s3, a.s3, b, kb0[3], kb1[3]);
}
#endif

/* Grid (items, realizations). For the points [w PPI, (w + 1) PPI) of a realization, every
 * unordered pair within reach once: the partners after the point in its own cell and
 * every point of the forward half of the neighbouring cells (offsets after the centre in
 * the 3^D stencil; with G >= 3 cell c + o and c - o are distinct, so each pair of cells
 * is met from one side):
 * out[r][w][k] += exp(-(radius_k - s)^2 / (2 sigma^2)) for the radii with
 * |radius_k - s| <= cut (s the pair's distance). UNIFORM radii take the Gaussian along
 * k by a recurrence (two exp a pair, four pairs to a vector exp; b = exp(-2 step^2 /
 * 2 sigma^2) from the host). */
__kernel void pcf_sums(__global const double *pts, __global const uint *cell,
                       __global const uint *start, const uint n, const int G, const uint noff,
                       const double reach2, __global const double *radii, const double r0,
                       const double step, const double inv_step, const double inv2s2, const double cut,
                       const double b,
                       const uint items, __global double *out)
{
    const uint w = get_global_id(0), r = get_global_id(1);
    if (w >= items)
        return;
    double hist[NR];
    for (int k = 0; k < NR; ++k)
        hist[k] = 0.0;
#if UNIFORM
    double tb[4] = {0.0, 0.0, 0.0, 0.0}, wb[4] = {1.0, 1.0, 1.0, 1.0};
    int kb0[4] = {0, 0, 0, 0}, kb1[4] = {-1, -1, -1, -1};
    int waiting = 0;
#endif
    const uint cells = (uint)G;
    uint total_cells = 1;
    for (int k = 0; k < D; ++k)
        total_cells *= cells;
    const uint centre = (noff - 1) / 2;
    const size_t base = (size_t)r * n;
    const uint stop = (w + 1) * PPI < n ? (w + 1) * PPI : n;
    for (uint i = w * PPI; i < stop; ++i) {
        const size_t gi = base + i;
        double x[D];
        for (int k = 0; k < D; ++k)
            x[k] = pts[gi * D + k];
        int c[D];
        cell_coordinates(cell[gi], G, c);
        for (uint o = centre; o < noff; ++o) {
            const size_t slot = (size_t)r * total_cells + neighbour(c, o, G);
            const uint s1 = start[slot + 1];
            for (uint j = o == centre ? (uint)gi + 1 : start[slot]; j < s1; ++j) {
                const double d2 = pair_distance2(x, pts + (size_t)j * D, D);
                if (d2 >= reach2)
                    continue;
                const double s = sqrt(d2);
#if PERIODIC
                const double weight = 1.0;
#else
                double cover = 1.0;     /* the volume of the cube and its translate's overlap */
                for (int k = 0; k < D; ++k)
                    cover *= 1.0 - cube_delta(x[k], pts[(size_t)j * D + k]);
                const double weight = 1.0 / cover;
#endif
#if UNIFORM
                /* k0 = max(0, ceil(lo)), k1 = min(NR - 1, floor(hi)) by conversions:
                 * PoCL calls ceil and floor out of line */
                const double lo = (s - cut - r0) * inv_step, hi = (s + cut - r0) * inv_step;
                if (hi < 0.0)
                    continue;
                int k0 = 0;
                if (lo > 0.0) {
                    k0 = (int)lo;
                    k0 += (double)k0 < lo;
                }
                const int k1 = hi > (double)(NR - 1) ? NR - 1 : (int)hi;
                if (k0 > k1)
                    continue;
                tb[waiting] = (r0 + (double)k0 * step) - s;
                wb[waiting] = weight;
                kb0[waiting] = k0;
                kb1[waiting] = k1;
                if (++waiting == 4) {
                    flush_pairs(hist, tb, wb, kb0, kb1, step, inv2s2, b);
                    waiting = 0;
                }
#else
                for (int k = 0; k < NR; ++k) {
                    const double t = radii[k] - s;
                    if (t <= cut && t >= -cut)
                        hist[k] += weight * exp(-(t * t) * inv2s2);
                }
#endif
            }
        }
    }
#if UNIFORM
    for (int l = waiting; l < 4; ++l) {
        kb0[l] = 0;
        kb1[l] = -1;
    }
    flush_pairs(hist, tb, wb, kb0, kb1, step, inv2s2, b);
#endif
    __global double *row = out + ((size_t)r * items + w) * NR;
    for (int k = 0; k < NR; ++k)
        row[k] = hist[k];
}
#endif

/* Grid (total points): d2[i] = the smallest squared distance from sorted point i to
 * another point of its realization in the 3^D neighbouring cells (every point when
 * G == 1), or INFINITY if there is none. Exact whenever it is at most (1 / G)^2: every
 * point farther than two cells is farther than one cell width. */
__kernel void nearest_neighbor(__global const double *pts, __global const uint *cell,
                               __global const uint *start, const uint n, const uint total,
                               const int G, const uint noff, __global double *d2)
{
    const uint gi = get_global_id(0);
    if (gi >= total)
        return;
    const uint r = gi / n;
    const uint total_cells = cells_count(G);
    double x[D];
    for (int k = 0; k < D; ++k)
        x[k] = pts[(size_t)gi * D + k];
    int c[D];
    cell_coordinates(cell[gi], G, c);
    double best = INFINITY;
    for (uint o = 0; o < noff; ++o) {
        const size_t slot = (size_t)r * total_cells + neighbour(c, o, G);
        const uint s1 = start[slot + 1];
        for (uint j = start[slot]; j < s1; ++j) {
            if (j == gi)
                continue;
            const double v = pair_distance2(x, pts + (size_t)j * D, D);
            best = v < best ? v : best;
        }
    }
    d2[gi] = best;
}
