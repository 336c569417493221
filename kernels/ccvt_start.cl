/* The starting partition of CCVT (clsamp/samplers/ccvt.py, start_partition): the power
 * diagram pass. NumPy twin: ccvt.power_pass_reference (the same integers).
 *
 * Every density point finds, among the sites in the 3 x 3 cells of a G x G grid around it
 * (all n sites when G == 1), the two smallest power distances |x - s_i|^2 - w_i on the
 * integer torus of voronoi.h, in the order (power distance, site index): the owner, the
 * runner-up and their difference (the margin, >= 0). Exact int64: the result does not
 * depend on the order in which the candidates are visited, hence not on the device. */
#include "voronoi.h"

#define START_NO_SECOND 0x7FFFFFFFFFFFFFFFL   /* margin when a point has one candidate */

inline int start_before(const long c, const uint i, const long c2, const uint i2)
{
    return c < c2 || (c == c2 && i < i2);
}

inline void start_visit(const uint i, const uint px, const uint py,
                        __global const uint *sites, __global const long *weight,
                        long *c1, uint *i1, long *c2, uint *i2)
{
    const long c = vor_d2(px, py, sites[2 * i], sites[2 * i + 1]) - weight[i];
    if (start_before(c, i, *c1, *i1)) {
        *c2 = *c1;
        *i2 = *i1;
        *c1 = c;
        *i1 = i;
    } else if (start_before(c, i, *c2, *i2)) {
        *c2 = c;
        *i2 = i;
    }
}

/* Global size (M, r). points: realization r's M points start at r * stride (stride 0:
 * one set for all); sites (r, n, 2), weight (r, n), the grid of each realization as
 * voronoi_build_grid makes it; owner, second (r, M): site indices; margin (r, M). */
__kernel void ccvt_power(__global const uint2 *points, const uint M, const uint stride,
                         __global const uint *sites, __global const long *weight, const uint n,
                         __global const uint *cell_start, __global const uint *cell_sites,
                         const uint G, __global uint *owner, __global uint *second,
                         __global long *margin)
{
    const uint j = get_global_id(0), r = get_global_id(1);
    if (j >= M)
        return;
    const size_t at = (size_t)r * M + j;
    const uint2 x = points[(size_t)r * stride + j];
    __global const uint *s = sites + (size_t)r * n * 2;
    __global const long *w = weight + (size_t)r * n;
    long c1 = START_NO_SECOND, c2 = START_NO_SECOND;
    uint i1 = 0xFFFFFFFFu, i2 = 0xFFFFFFFFu;
    if (G == 1) {
        for (uint i = 0; i < n; ++i)
            start_visit(i, x.x, x.y, s, w, &c1, &i1, &c2, &i2);
    } else {
        __global const uint *start = cell_start + (size_t)r * (G * G + 1);
        __global const uint *list = cell_sites + (size_t)r * n;
        const uint cx = vor_cell(x.x, G), cy = vor_cell(x.y, G);
        /* the neighbouring cells, wrapped without a division (G >= 4) */
        const uint xs[3] = {cx == 0 ? G - 1 : cx - 1, cx, cx == G - 1 ? 0 : cx + 1};
        const uint ys[3] = {cy == 0 ? G - 1 : cy - 1, cy, cy == G - 1 ? 0 : cy + 1};
        for (int oy = 0; oy < 3; ++oy) {
            const uint row = ys[oy] * G;
            for (int ox = 0; ox < 3; ++ox) {
                const uint c = row + xs[ox];
                for (uint t = start[c]; t < start[c + 1]; ++t)
                    start_visit(list[t], x.x, x.y, s, w, &c1, &i1, &c2, &i2);
            }
        }
    }
    owner[at] = i1;
    second[at] = i2 == 0xFFFFFFFFu ? i1 : i2;
    margin[at] = i2 == 0xFFFFFFFFu ? START_NO_SECOND : c2 - c1;
}
