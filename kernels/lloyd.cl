/* Periodic Lloyd relaxation (Lloyd 1982): the move of every site to the periodic centroid
 * of its cell, after the assignment pass of voronoi.cl has summed each cell's offsets.
 * NumPy reference: clsamp/samplers/lloyd.py (lloyd_reference).
 *
 * Build options from the host (clsamp.geometry.voronoi.defines): VOR_BITS, VOR_DIM where it is
 * not 2. */
#include "voronoi.h"

/* Grid (n, realizations): each site to the rounded mean of its cell (unwrapped relative to
 * the site), coordinate by coordinate; empty sites stay and are counted in empty[r] for the
 * host to re-seed. acc holds (sums of offsets per axis, count) per site. */
__kernel void lloyd_move(__global uint *sites, const uint n, __global long *acc,
                         __global uint *counts, __global uint *empty)
{
    const uint i = get_global_id(0);
    const uint r = get_global_id(1);
    if (i >= n)
        return;
    __global long *a = acc + ((size_t)r * n + i) * (VOR_DIM + 1);
    __global uint *s = sites + ((size_t)r * n + i) * VOR_DIM;
    const long c = a[VOR_DIM];
    counts[(size_t)r * n + i] = (uint)c;
    if (c > 0) {
        for (int ax = 0; ax < VOR_DIM; ++ax)
            s[ax] = (uint)((long)s[ax] + vor_round_mean(a[ax], c)) & VOR_MASK;
    } else {
        atomic_inc(empty + r);
    }
    for (int ax = 0; ax <= VOR_DIM; ++ax)
        a[ax] = 0;
}
