/* The starting partition of CCVT (clsamp/samplers/ccvt/start.py, start_partition): the
 * power diagram pass. NumPy twin: clsamp/samplers/ccvt/power.py, power_pass_reference (the
 * same integers).
 *
 * Every density point finds, among the sites in the 3 x 3 cells of a G x G grid around it
 * (all n sites when G == 1; the host lists them per cell), the two smallest power
 * distances |x - s_i|^2 - w_i on the integer torus of voronoi.h, in the order (power
 * distance, site index): the owner, the runner-up and their difference (the margin,
 * >= 0). Exact int64: the result does not depend on the order in which the candidates are
 * visited, hence not on the device. */
#include "voronoi.h"

/* From the host (clsamp.samplers.ccvt.pairs): CCVT_NO_OWNER, the owner of a point with no
 * candidate, and CCVT_NO_SECOND, the margin of a point with one. */
#if !defined(CCVT_NO_OWNER) || !defined(CCVT_NO_SECOND)
#error "CCVT_NO_OWNER and CCVT_NO_SECOND come from clsamp.samplers.ccvt.pairs"
#endif

/* Global size (M, r). points: realization r's M points start at r * stride (stride 0:
 * one set for all). The candidates of a point in cell c of realization r (G == 1: one
 * cell, every site) are W entries from (r * G * G + c) * W: the sites' indices (cand_id,
 * ascending, padded with n), coordinates (cand_xy) and weights (cand_w), side by side so
 * that a point streams through its row instead of following the indices; owner, second
 * (r, M): site indices; margin (r, M). */
__kernel void ccvt_power(__global const uint2 *points, const uint M, const uint stride,
                         __global const uint *cand_id, __global const uint2 *cand_xy,
                         __global const long *cand_w, const uint n, const uint G,
                         const uint W, __global uint *owner, __global uint *second,
                         __global long *margin)
{
    const uint j = get_global_id(0), r = get_global_id(1);
    if (j >= M)
        return;
    const size_t at = (size_t)r * M + j;
    const uint2 x = points[(size_t)r * stride + j];
    const uint cell = G == 1 ? 0 : vor_cell(x.y, G) * G + vor_cell(x.x, G);
    const size_t row = ((size_t)r * G * G + cell) * W;
    long c1 = CCVT_NO_SECOND, c2 = CCVT_NO_SECOND;
    uint i1 = CCVT_NO_OWNER, i2 = CCVT_NO_OWNER;
    for (uint t = 0; t < W; ++t) {
        const uint i = cand_id[row + t];
        if (i >= n)
            break;   /* the padding: the rest of the row is padding too */
        const uint2 s = cand_xy[row + t];
        const long c = vor_d2(x.x, x.y, s.x, s.y) - cand_w[row + t];
        /* the row is in ascending index order, so "before" in (power distance, index) is a
         * strictly smaller distance; selects, not branches (which way a point's comparisons
         * go is a coin toss the branch predictor loses) */
        const int nearer1 = c < c1, nearer2 = c < c2;
        c2 = nearer1 ? c1 : (nearer2 ? c : c2);
        i2 = nearer1 ? i1 : (nearer2 ? i : i2);
        c1 = nearer1 ? c : c1;
        i1 = nearer1 ? i : i1;
    }
    owner[at] = i1;
    second[at] = i2 == CCVT_NO_OWNER ? i1 : i2;
    margin[at] = i2 == CCVT_NO_OWNER ? CCVT_NO_SECOND : c2 - c1;
}
