/* The integer torus and the site grid, shared by the nearest-site assignment
 * (voronoi.cl), Lloyd (lloyd.cl) and CCVT (ccvt*.cl).
 * NumPy twins: clsamp/geometry/integer_torus.py (the torus, the grid).
 *
 * VOR_DIM (default 2, CCVT's) is the dimension of the sites and of their grid; a site is
 * VOR_DIM consecutive coordinates, a cell index sum_a cell_a G^a (x fastest).
 *
 * Positions live on an integer torus: a coordinate is an integer in [0, 2^VOR_BITS)
 * (point x in [0, 1) is floor(x * 2^VOR_BITS)). Toroidal differences, squared
 * distances, centroid sums and energies are then exact 64-bit integers: every device
 * gets the same bits, sums do not depend on their order (so integer atomics are
 * deterministic), and "the energy never rises" holds exactly, not up to rounding.
 * With 22 bits a squared distance is below 2^43, so 2^20 of them sum without overflow. */
#ifndef CLSAMP_VORONOI_H
#define CLSAMP_VORONOI_H

#include "counting_sort.h"

/* VOR_BITS comes from the host (clsamp.geometry.integer_torus.BITS, its one source). */
#ifndef VOR_BITS
#error "VOR_BITS must be given by the host: clsamp.geometry.integer_torus.DEFINES"
#endif
#define VOR_SIZE (1u << VOR_BITS)
#define VOR_MASK (VOR_SIZE - 1u)
#define VOR_HALF (1 << (VOR_BITS - 1))
#ifndef VOR_DIM
#define VOR_DIM 2
#endif

/* a - b on the torus, in [-2^(B-1), 2^(B-1)). */
inline long vor_delta(const uint a, const uint b)
{
    int d = (int)((a - b) & VOR_MASK);
    if (d >= VOR_HALF)
        d -= (int)VOR_SIZE;
    return (long)d;
}

inline long vor_d2(const uint ax, const uint ay, const uint bx, const uint by)
{
    const long dx = vor_delta(ax, bx);
    const long dy = vor_delta(ay, by);
    return dx * dx + dy * dy;
}

/* Cell of a coordinate in a grid of G cells per axis. */
inline uint vor_cell(const uint x, const uint G)
{
    return (uint)(((ulong)x * G) >> VOR_BITS);
}

/* floor((2 s + c) / (2 c)) for c > 0: the integer nearest to the mean s / c (halves up).
 * Moving a site by it never raises its cell's energy: with mean m and step q,
 * sum (d - q)^2 - sum d^2 = c q (q - 2 m) <= 0 whenever |q - m| <= 1/2. */
inline long vor_round_mean(const long s, const long c)
{
    const long a = 2 * s + c, b = 2 * c;
    long q = a / b;
    if (a % b != 0 && a < 0)
        --q;
    return q;
}

/* G^VOR_DIM: the cells of the site grid. */
inline uint vor_cells(const uint G)
{
    uint cells = 1;
    for (int a = 0; a < VOR_DIM; ++a)
        cells *= G;
    return cells;
}

/* The cell of site i of s: sum_a cell(s_a) G^a (in 2-D cy G + cx). */
inline uint vor_site_cell(__global const uint *s, const uint i, const uint G)
{
    uint c = 0;
    for (int a = VOR_DIM - 1; a >= 0; --a)
        c = c * G + vor_cell(s[VOR_DIM * i + a], G);
    return c;
}

COUNTING_SORT(vor_sort_sites, uint, vor_site_cell)

/* Background grid of the sites of one realization: a counting sort into G^VOR_DIM cells,
 * sites in index order inside each cell (deterministic). Sequential: n is small next to
 * the density points, and a sequential sort needs no atomics. */
inline void vor_build_grid_one(__global const uint *s, const uint n, const uint G,
                               __global uint *start, __global uint *list)
{
    const uint cells = vor_cells(G);
    vor_sort_sites(s, n, cells, G, 0, start, list);
    start[cells] = n;
}

/* One work-item per realization. */
__kernel void voronoi_build_grid(__global const uint *sites, const uint n, const uint G,
                                 __global uint *cell_start, __global uint *cell_sites,
                                 const uint realizations)
{
    const uint r = get_global_id(0);
    if (r >= realizations)
        return;
    vor_build_grid_one(sites + (size_t)r * n * VOR_DIM, n, G,
                       cell_start + (size_t)r * (vor_cells(G) + 1), cell_sites + (size_t)r * n);
}

#endif
