/* Nearest-site assignment of a regular density grid on the integer torus of voronoi.h.
 * NumPy reference: clsamp/geometry/voronoi.py (assign_reference).
 *
 * The density is the regular g x g grid of cell centres, X_m = ((2 m_x + 1) 2^B) div (2 g),
 * computed from its index, never stored. voronoi_build_grid sorts the sites into their
 * grid, then voronoi_assign finds the nearest site of every density point through it and
 * sums each site's offsets: one Lloyd pass (lloyd.cl moves the sites), or the CVT energy.
 * Ties between equally near sites go to the smaller site index, as numpy.argmin does.
 *
 * Build options from the host (clsamp.geometry.voronoi.DEFINES): VOR_BITS, VOR_SEGMENT. */
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

/* Nearest site of (X, Y) by rings of cells around its own: exact, since every site outside
 * ring k is at least k * width + 1 away along some axis. */
inline long vor_nearest_rings(const uint X, const uint Y, __global const uint *s, const uint n,
                                const uint G, __global const uint *start,
                                __global const uint *list, uint *site_out)
{
    const long width = (long)(VOR_SIZE / G);   /* G is a power of two */
    const int cx = (int)vor_cell(X, G), cy = (int)vor_cell(Y, G);
    long best = LONG_MAX;
    uint site = n;
    for (int k = 0;; ++k) {
        for (int dy = -k; dy <= k; ++dy) {
            const int step = (dy == -k || dy == k) ? 1 : 2 * k;
            for (int dx = -k; dx <= k; dx += (k == 0 ? 1 : step)) {
                const uint c = (uint)(((cy + dy) % (int)G + (int)G) % (int)G) * G
                             + (uint)(((cx + dx) % (int)G + (int)G) % (int)G);
                for (uint q = start[c]; q < start[c + 1]; ++q) {
                    const uint i = list[q];
                    const long d2 = vor_d2(X, Y, s[2 * i], s[2 * i + 1]);
                    if (d2 < best || (d2 == best && i < site)) {
                        best = d2;
                        site = i;
                    }
                }
            }
        }
        if (2 * k + 1 >= (int)G || best <= (long)k * width * (long)k * width)
            break;
    }
    *site_out = site;
    return best;
}

/* Grid (segments, realizations); a segment is up to VOR_SEGMENT consecutive density points
 * of one row. The sites of the cells around the segment (one ring beyond the cells it
 * spans) are gathered once; a point whose nearest gathered site is within one cell width
 * has its answer (anything not gathered is farther), the others search rings.
 * acc holds (sum dx, sum dy, count) per site relative to the site, flushed with integer
 * atomics (order-free, so deterministic) each time the nearest site changes along the
 * segment; energy gets each segment's sum of squared distances as (low 32 bits, high bits)
 * so the realization's total cannot overflow; far_* keep each segment's farthest density
 * point for re-seeding empty sites. */
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
    const uint cells = G * G;
    const uint per_row = (g + VOR_SEGMENT - 1) / VOR_SEGMENT;
    const uint row = seg / per_row;
    const uint x0 = (seg % per_row) * VOR_SEGMENT;
    const uint x1 = min(g, x0 + VOR_SEGMENT);
    __global const uint *s = sites + (size_t)r * n * 2;
    __global const uint *start = cell_start + (size_t)r * (cells + 1);
    __global const uint *list = cell_sites + (size_t)r * n;
    __global long *a = acc + (size_t)r * n * 3;
    const long width = (long)(VOR_SIZE / G);
    const uint Y = vor_density_coordinate(row, g);
    const int cy = (int)vor_cell(Y, G);
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
    long e = 0, far = -1;
    uint far_m = row * g + x0;
    uint current = n;
    long sx = 0, sy = 0, count = 0;
    for (uint xi = x0; xi < x1; ++xi) {
        const uint X = vor_density_coordinate(xi, g);
        long best = LONG_MAX;
        uint site = n;
        if (gathered) {
            for (uint k = 0; k < nc; ++k) {
                const long d2 = vor_d2(X, Y, cxs[k], cys[k]);
                if (d2 < best || (d2 == best && cid[k] < site)) {
                    best = d2;
                    site = cid[k];
                }
            }
        }
        if (!gathered || best > width * width)
            best = vor_nearest_rings(X, Y, s, n, G, start, list, &site);
        e += best;
        if (best > far) {
            far = best;
            far_m = row * g + xi;
        }
        if (site != current) {
            if (count) {
                atom_add(a + 3 * current, sx);
                atom_add(a + 3 * current + 1, sy);
                atom_add(a + 3 * current + 2, count);
            }
            current = site;
            sx = sy = count = 0;
        }
        sx += vor_delta(X, s[2 * site]);
        sy += vor_delta(Y, s[2 * site + 1]);
        count += 1;
    }
    if (count) {
        atom_add(a + 3 * current, sx);
        atom_add(a + 3 * current + 1, sy);
        atom_add(a + 3 * current + 2, count);
    }
    __global long *en = energy + (size_t)r * energy_stride + energy_offset;
    atom_add(en, e & 0xFFFFFFFFL);
    atom_add(en + 1, e >> 32);
    far_d2[(size_t)r * segments + seg] = far;
    far_index[(size_t)r * segments + seg] = far_m;
}
