/* Periodic Lloyd relaxation (Lloyd 1982): the move of every site to the periodic centroid
 * of its cell, after the assignment pass of voronoi.cl has summed each cell's offsets.
 * NumPy reference: clsamp/samplers/lloyd.py (lloyd_reference).
 *
 * Build options from the host (clsamp.geometry.integer_torus.DEFINES): VOR_BITS. */
#include "voronoi.h"

/* Grid (n, realizations): each site to the rounded mean of its cell (unwrapped relative to
 * the site); empty sites stay and are counted in empty[r] for the host to re-seed. */
__kernel void lloyd_move(__global uint *sites, const uint n, __global long *acc,
                         __global uint *counts, __global uint *empty)
{
    const uint i = get_global_id(0);
    const uint r = get_global_id(1);
    if (i >= n)
        return;
    __global long *a = acc + ((size_t)r * n + i) * 3;
    __global uint *s = sites + ((size_t)r * n + i) * 2;
    const long c = a[2];
    counts[(size_t)r * n + i] = (uint)c;
    if (c > 0) {
        s[0] = (uint)((long)s[0] + vor_round_mean(a[0], c)) & VOR_MASK;
        s[1] = (uint)((long)s[1] + vor_round_mean(a[1], c)) & VOR_MASK;
    } else {
        atomic_inc(empty + r);
    }
    a[0] = a[1] = a[2] = 0;
}
