/* A grid of G^D cells over [0, 1)^D for neighbour searches (clsamp/geometry/cells.py:
 * sorted_by_cell sorts the points by (set, cell) on the host; neighbour_cells is the
 * NumPy twin of neighbour below, and its cells are those of cell_of). The flat cell of
 * coordinates c is sum_k c[k] G^(D - 1 - k), the first axis most significant. With G >= 3
 * the 3^D cells around a cell are distinct; G == 1 is one cell holding every point.
 *
 * Build option: D (dimensions). */
#ifndef CLSAMP_CELLS_H
#define CLSAMP_CELLS_H

#ifndef D
#error "cells.h needs D, the dimensions"
#endif

/* the flat index of neighbour o (0 .. 3^D - 1, digits -1, 0, +1, the last axis least
 * significant) of cell coordinates c, wrapped on the torus; with G == 1 the one cell */
inline uint neighbour(const int *c, uint o, const int G)
{
    if (G == 1)
        return 0;
    uint flat = 0;
    int digits[D];
    for (int k = D - 1; k >= 0; --k) {
        digits[k] = (int)(o % 3) - 1;
        o /= 3;
    }
    for (int k = 0; k < D; ++k) {
        int v = c[k] + digits[k];
        v = v < 0 ? v + G : v >= G ? v - G : v;
        flat = flat * (uint)G + (uint)v;
    }
    return flat;
}

/* the cells of one set: G^D */
inline uint cells_count(const int G)
{
    uint cells = 1;
    for (int k = 0; k < D; ++k)
        cells *= (uint)G;
    return cells;
}

#if CLSAMP_FP64
/* the cell coordinates of x, (int)(x G) clamped to G - 1, as sorted_by_cell finds them */
inline void cell_of(const double *x, const int G, int *c)
{
    for (int k = 0; k < D; ++k) {
        const int v = (int)(x[k] * (double)G);
        c[k] = v < G - 1 ? v : G - 1;
    }
}
#endif

#if CLSAMP_FP64
/* the gap along one axis from coordinate xk to the box of the cell digit (-1, 0, +1) steps
 * from cell ck (cells 1 / G wide), less a margin far above the rounding of x G and of a
 * squared distance, and at least 0 */
inline double cells_gap(const double xk, const int ck, const int digit, const double inv_G)
{
    const double gap = (digit > 0 ? (double)(ck + 1) * inv_G - xk
                        : digit < 0 ? xk - (double)ck * inv_G : 0.0) - 1e-12;
    return gap > 0.0 ? gap : 0.0;
}

/* whether a lower bound lb of a squared distance passes the squared reach reach2, with a
 * margin far above the rounding */
inline bool cells_past(const double lb, const double reach2)
{
    return lb > reach2 * 1.000001;
}

/* whether neighbour o of cell c (as neighbour() numbers them) lies wholly beyond the reach
 * from x, its squared reach reach2 no more than the cells' width squared (G >= 3): a lower
 * bound of the squared distance from x to the cell's box, the sum of each axis's
 * cells_gap squared, passes reach2 (cells_past). Such a cell holds no point within the
 * reach (on the torus too: with G >= 3 the cell's nearest image is the one next to c), so
 * a search that skips it finds what the full stencil finds, in the same order. Worth its
 * cost from 3-D on, where most of the 3^D cells' corners lie beyond the reach. */
inline bool cell_beyond(const double *x, const int *c, uint o, const int G, const double reach2)
{
    const double inv_G = 1.0 / (double)G;
    double lb = 0.0;
    for (int k = D - 1; k >= 0; --k) {
        const double gap = cells_gap(x[k], c[k], (int)(o % 3) - 1, inv_G);
        o /= 3;
        lb = lb + gap * gap;
    }
    return cells_past(lb, reach2);
}
#endif

#if CLSAMP_FP64
/* The stencil of a cell as rows along the last axis: cells_rows(G, noff) of them for a
 * stencil of noff cells (3^D, or 1 with G == 1). */
inline uint cells_rows(const int G, const uint noff)
{
    return G > 1 ? noff / 3 : 1;
}

/* The sorted ranges of the cells of stencil row o (neighbours 3 o .. 3 o + 2 as
 * neighbour() numbers them: the cells c[D - 1] - 1 .. c[D - 1] + 1 along the last axis, the
 * other axes fixed) of the set whose cell starts are st (G >= 3): consecutive cells lie
 * together in sorted order, so the row is one range, or two where it wraps around the
 * torus; from 3-D on a cell wholly beyond the reach from x (cell_beyond's bound, reach2)
 * is left out, and a row whose cells all are, at once. With G == 1 the one row is the one
 * cell. Writes the non-empty ranges lo[k] .. hi[k] - 1 in stencil order and returns how
 * many (0, 1 or 2): walking them finds the points that the cells one at a time hold, in
 * the same order. */
inline uint cells_row_ranges(__global const uint *st, const int *c, const double *x,
                             const int G, const uint o, const double reach2, uint *lo,
                             uint *hi)
{
    if (G == 1) {
        lo[0] = st[0];
        hi[0] = st[1];
        return hi[0] > lo[0] ? 1u : 0u;
    }
#if D == 2
    /* in 2-D, a row that does not wrap is one range, found without neighbour() */
    if (c[1] >= 1 && c[1] <= G - 2) {
        int ry = c[0] + (int)o - 1;
        ry = ry < 0 ? ry + G : ry >= G ? ry - G : ry;
        const uint at = (uint)ry * (uint)G + (uint)c[1];
        lo[0] = st[at - 1];
        hi[0] = st[at + 2];
        return hi[0] > lo[0] ? 1u : 0u;
    }
#endif
#if D >= 3
    /* cell_beyond's bound in two parts: the row's first D - 1 axes once (a row wholly
     * beyond the reach has no cell to walk), then each cell's last axis */
    const double inv_G = 1.0 / (double)G;
    double row = 0.0;
    uint digits = o;
    for (int k = D - 2; k >= 0; --k) {
        const double gap = cells_gap(x[k], c[k], (int)(digits % 3) - 1, inv_G);
        digits /= 3;
        row = row + gap * gap;
    }
    if (cells_past(row, reach2))
        return 0;
#endif
    const uint base = neighbour(c, 3 * o + 1, G) - (uint)c[D - 1];
    uint ranges = 0, a = 0, b = 0;
    int last = -2;
    for (int dl = -1; dl <= 1; ++dl) {
#if D >= 3
        const double gap = cells_gap(x[D - 1], c[D - 1], dl, inv_G);
        if (cells_past(row + gap * gap, reach2))
            continue;
#endif
        int cell = c[D - 1] + dl;
        cell = cell < 0 ? cell + G : cell >= G ? cell - G : cell;
        if (cell == last + 1) {
            b = st[base + (uint)cell + 1];
        } else {
            if (b > a) {
                lo[ranges] = a;
                hi[ranges] = b;
                ranges += 1;
            }
            a = st[base + (uint)cell];
            b = st[base + (uint)cell + 1];
        }
        last = cell;
    }
    if (b > a) {
        lo[ranges] = a;
        hi[ranges] = b;
        ranges += 1;
    }
    return ranges;
}

/* coordinate k of the 4 sorted points from j into y[k] (double4 lanes): in 2-D the even
 * and odd lanes of two loads, in 4-D the four loads transposed; else, and for the last
 * points of pts (total of them), gathered one by one, the points past the end clamped to
 * the last, so that no lane reads past the buffer */
inline void cells_load4(__global const double *pts, const uint total, const uint j, double4 *y)
{
#if D == 2
    if (j + 4 <= total) {
        const double4 a = vload4(0, pts + 2 * (size_t)j), b = vload4(1, pts + 2 * (size_t)j);
        y[0] = (double4)(a.even, b.even);
        y[1] = (double4)(a.odd, b.odd);
        return;
    }
#elif D == 4
    if (j + 4 <= total) {
        __global const double *p = pts + 4 * (size_t)j;
        const double4 a = vload4(0, p), b = vload4(1, p), c = vload4(2, p), d = vload4(3, p);
        y[0] = (double4)(a.x, b.x, c.x, d.x);
        y[1] = (double4)(a.y, b.y, c.y, d.y);
        y[2] = (double4)(a.z, b.z, c.z, d.z);
        y[3] = (double4)(a.w, b.w, c.w, d.w);
        return;
    }
#endif
    _Pragma("unroll")
    for (int k = 0; k < D; ++k) {
        double c[4];
        for (uint l = 0; l < 4; ++l) {
            const size_t at = j + l < total ? j + l : total - 1;
            c[l] = pts[at * D + k];
        }
        y[k] = vload4(0, c);
    }
}
#endif

inline void cell_coordinates(uint flat, const int G, int *c)
{
    for (int k = D - 1; k >= 0; --k) {
        c[k] = (int)(flat % (uint)G);
        flat /= (uint)G;
    }
}

#endif
