/* Nearest-site assignment of a regular density grid on the integer torus of voronoi.h.
 * NumPy reference: clsamp/geometry/voronoi.py (assign_reference).
 *
 * The density is the regular g^VOR_DIM grid of cell centres, X_m = ((2 m_x + 1) 2^B) div (2 g)
 * along each axis, computed from its index m = sum_a m_a g^a, never stored.
 * voronoi_build_grid sorts the sites into their grid, then voronoi_assign finds the nearest site of every density point through it and
 * sums each site's offsets: one Lloyd pass (lloyd.cl moves the sites), or the CVT energy.
 * Ties between equally near sites go to the smaller site index, as numpy.argmin does.
 *
 * Build options from the host (clsamp.geometry.voronoi.defines): VOR_BITS, VOR_SEGMENT, and
 * VOR_DIM where it is not 2 (1 .. 4). In 2-D each segment first gathers the sites around it;
 * in 1, 3 and 4-D every point searches rings of cells. */
#pragma OPENCL EXTENSION cl_khr_int64_base_atomics : enable
#include "voronoi.h"

#ifndef VOR_SEGMENT
#error "VOR_SEGMENT must be given by the host: clsamp.geometry.voronoi.DEFINES"
#endif
#define VOR_CANDIDATES 64     /* sites gathered per segment before falling back to rings */

inline uint vor_density_coordinate(const uint k, const uint g)
{
    return (uint)((((ulong)(2 * k + 1)) << VOR_BITS) / (2 * (ulong)g));
}

/* The exact squared distance from the point X to site s (VOR_DIM coordinates each). */
inline long vor_d2_point(const uint *X, __global const uint *s)
{
    long d2 = 0;
    for (int a = 0; a < VOR_DIM; ++a) {
        const long d = vor_delta(X[a], s[a]);
        d2 += d * d;
    }
    return d2;
}

/* Nearest site of the point X by rings of cells around its own (ring k: the cells whose
 * largest offset along an axis is k, wrapped). Exact: while the rings do not wrap onto
 * themselves, every site outside rings 0..k is at least k * width + wall away, wall the
 * distance from X to the nearest face of its own cell, so a best below that square is
 * final (strictly below: an unvisited site at that distance with a smaller index would
 * win the tie). Ties to the smaller site index.
 * A cell at offset o is skipped where the squared distance from X to its box along o
 * (per axis (|o| - 1) width plus X's distance to its own cell's face on that side)
 * exceeds the best so far: no site in it can be nearer or tie. Where the rings wrap, a
 * cell is visited at every offset that reaches it, the shortest way round among them, so
 * a site is skipped only where it is farther than that bound the shortest way. */
inline long vor_nearest_rings(const uint *X, __global const uint *s, const uint n,
                              const uint G, __global const uint *start,
                              __global const uint *list, uint *site_out)
{
    const long width = (long)(VOR_SIZE / G);   /* G is a power of two */
    int own[VOR_DIM];
    long low[VOR_DIM];
    long wall = width;
    for (int a = 0; a < VOR_DIM; ++a) {
        own[a] = (int)vor_cell(X[a], G);
        low[a] = (long)X[a] - (long)own[a] * width;
        wall = min(wall, min(low[a], width - low[a]));
    }
    long best = LONG_MAX;
    uint site = n;
    for (int k = 0;; ++k) {
        const int side = 2 * k + 1;
        int cube = 1;
        for (int a = 0; a < VOR_DIM; ++a)
            cube *= side;
        for (int t = 0; t < cube; ++t) {
            int rest = t, on_ring = 0;
            uint c = 0, stride = 1;
            long box = 0;
            for (int a = 0; a < VOR_DIM; ++a) {
                const int o = rest % side - k;
                rest /= side;
                on_ring |= o == k || o == -k;
                c += (uint)(((own[a] + o) % (int)G + (int)G) % (int)G) * stride;
                stride *= G;
                const long gap = o > 0 ? (long)(o - 1) * width + width - low[a]
                               : o < 0 ? (long)(-o - 1) * width + low[a] : 0;
                box += gap * gap;
            }
            if (!on_ring || box > best)
                continue;
            for (uint q = start[c]; q < start[c + 1]; ++q) {
                const uint i = list[q];
                const long d2 = vor_d2_point(X, s + (size_t)VOR_DIM * i);
                if (d2 < best || (d2 == best && i < site)) {
                    best = d2;
                    site = i;
                }
            }
        }
        const long reach = (long)k * width + wall;
        if (2 * k + 1 >= (int)G || best < reach * reach)
            break;
    }
    *site_out = site;
    return best;
}

/* Add a site's sums (offsets per axis, count) to acc with integer atomics. */
inline void vor_flush(__global long *a, const uint site, const long *sums)
{
    if (sums[VOR_DIM])
        for (int ax = 0; ax <= VOR_DIM; ++ax)
            atom_add(a + (size_t)(VOR_DIM + 1) * site + ax, sums[ax]);
}

/* Grid (segments, realizations); a segment is up to VOR_SEGMENT consecutive density points
 * of one line along x (line l holds the points l g .. l g + g - 1; in 2-D a row).
 * In 2-D the sites of the cells around the segment (one ring beyond the cells it spans) are
 * gathered once; a point whose nearest gathered site is within one cell width has its answer
 * (anything not gathered is farther); the others, and every point in 1, 3 and 4-D, search
 * rings. acc holds (sum of offsets per axis, count) per site relative to the site, flushed
 * with integer atomics (order-free, so deterministic) each time the nearest site changes
 * along the segment; energy gets each segment's sum of squared distances as (low 32 bits,
 * high bits) so the realization's total cannot overflow; far_* keep each segment's
 * farthest density point for re-seeding empty sites. */
__kernel void voronoi_assign(__global const uint *sites, const uint n, const uint G,
                             __global const uint *cell_start, __global const uint *cell_sites,
                             const uint g, const uint segments,
                             __global long *acc, __global long *energy, const uint energy_stride,
                             const uint energy_offset,
                             __global long *far_d2, __global uint *far_index)
{
    const uint seg = get_global_id(0);
    const uint r = get_global_id(1);
    if (seg >= segments)
        return;
    const uint per_row = (g + VOR_SEGMENT - 1) / VOR_SEGMENT;
    const uint line = seg / per_row;
    const uint x0 = (seg % per_row) * VOR_SEGMENT;
    const uint x1 = min(g, x0 + VOR_SEGMENT);
    __global const uint *s = sites + (size_t)r * n * VOR_DIM;
    __global const uint *start = cell_start + (size_t)r * (vor_cells(G) + 1);
    __global const uint *list = cell_sites + (size_t)r * n;
    __global long *a = acc + (size_t)r * n * (VOR_DIM + 1);
    uint X[VOR_DIM];
    uint rest = line;
    for (int ax = 1; ax < VOR_DIM; ++ax) {
        X[ax] = vor_density_coordinate(rest % g, g);
        rest /= g;
    }
#if VOR_DIM == 2
    const long width = (long)(VOR_SIZE / G);
    const int cy = (int)vor_cell(X[1], G);
    const int cxa = (int)vor_cell(vor_density_coordinate(x0, g), G);
    const int cxb = (int)vor_cell(vor_density_coordinate(x1 - 1, g), G);
    uint cid[VOR_CANDIDATES], cxs[VOR_CANDIDATES], cys[VOR_CANDIDATES];
    uint nc = 0;
    int gathered = (int)G >= cxb - cxa + 3;     /* the ring of cells does not wrap onto itself */
    for (int dy = -1; gathered && dy <= 1; ++dy) {
        const uint crow = (uint)(((cy + dy) % (int)G + (int)G) % (int)G) * G;
        for (int cx = cxa - 1; gathered && cx <= cxb + 1; ++cx) {
            const uint c = crow + (uint)((cx % (int)G + (int)G) % (int)G);
            for (uint q = start[c]; q < start[c + 1]; ++q) {
                if (nc == VOR_CANDIDATES) {
                    gathered = 0;
                    break;
                }
                const uint i = list[q];
                cid[nc] = i;
                cxs[nc] = s[2 * i];
                cys[nc] = s[2 * i + 1];
                ++nc;
            }
        }
    }
#endif
    long e = 0, far = -1;
    uint far_m = line * g + x0;
    uint current = n;
    long sums[VOR_DIM + 1];
    for (int ax = 0; ax <= VOR_DIM; ++ax)
        sums[ax] = 0;
    for (uint xi = x0; xi < x1; ++xi) {
        X[0] = vor_density_coordinate(xi, g);
        long best = LONG_MAX;
        uint site = n;
#if VOR_DIM == 2
        if (gathered) {
            for (uint k = 0; k < nc; ++k) {
                const long d2 = vor_d2(X[0], X[1], cxs[k], cys[k]);
                if (d2 < best || (d2 == best && cid[k] < site)) {
                    best = d2;
                    site = cid[k];
                }
            }
        }
        if (!gathered || best > width * width)
#endif
            best = vor_nearest_rings(X, s, n, G, start, list, &site);
        e += best;
        if (best > far) {
            far = best;
            far_m = line * g + xi;
        }
        if (site != current) {
            vor_flush(a, current, sums);
            current = site;
            for (int ax = 0; ax <= VOR_DIM; ++ax)
                sums[ax] = 0;
        }
        for (int ax = 0; ax < VOR_DIM; ++ax)
            sums[ax] += vor_delta(X[ax], s[(size_t)VOR_DIM * site + ax]);
        sums[VOR_DIM] += 1;
    }
    vor_flush(a, current, sums);
    __global long *en = energy + (size_t)r * energy_stride + energy_offset;
    atom_add(en, e & 0xFFFFFFFFL);
    atom_add(en + 1, e >> 32);
    far_d2[(size_t)r * segments + seg] = far;
    far_index[(size_t)r * segments + seg] = far_m;
}
