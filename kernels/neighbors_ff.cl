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
 * Build options: D, PERIODIC. FP_CONTRACT OFF: the error-free transformations need every
 * operation rounded as written. Grid (total points): best[i] = the sorted index of the
 * nearest other point of its realization in the 3^D neighbouring cells, or 0xFFFFFFFF. */
#include "float_float.h"
#include "cells.h"

#pragma OPENCL FP_CONTRACT OFF

#ifndef PERIODIC
#define PERIODIC 1
#endif

inline float2 ff_sum(const float2 a, const float2 b)
{
    float h, l;
    FF_ADD(float, a.x, a.y, b.x, b.y, h, l);
    return (float2)(h, l);
}

inline float2 ff_square(const float2 a)
{
    float h, l;
    FF_MUL(float, a.x, a.y, a.x, a.y, h, l);
    return (float2)(h, l);
}

/* comparisons of normalized pairs: by hi, then lo */
inline int ff_below(const float2 a, const float2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }

/* min(|a - b|, 1 - |a - b|) on the torus, |a - b| in the cube */
inline float2 ff_delta(const float2 a, const float2 b)
{
    float2 t = ff_sum(a, -b);
    t = t.x < 0.0f ? -t : t;
#if PERIODIC
    const float2 u = ff_sum((float2)(1.0f, 0.0f), -t);
    t = ff_below(u, t) ? u : t;
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
    uint total_cells = 1;
    for (int k = 0; k < D; ++k)
        total_cells *= (uint)G;
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
            float2 d2 = ff_square(ff_delta(x[0], y[0]));
            for (int k = 1; k < D; ++k)
                d2 = ff_sum(d2, ff_square(ff_delta(x[k], y[k])));
            if (ff_below(d2, nearest)) {
                nearest = d2;
                found = j;
            }
        }
    }
    best[gi] = found;
}
