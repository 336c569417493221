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
/* whether neighbour o of cell c (as neighbour() numbers them) lies wholly beyond the reach
 * from x, its squared reach reach2 no more than the cells' width squared (G >= 3): a lower
 * bound of the squared distance from x to the cell's box, each axis's gap less a margin
 * far above the rounding of x G and of a squared distance, passes reach2. Such a cell
 * holds no point within the reach (on the torus too: with G >= 3 the cell's nearest image
 * is the one next to c), so a search that skips it finds what the full stencil finds, in
 * the same order. Worth its cost from 3-D on, where most of the 3^D cells' corners lie
 * beyond the reach. */
inline bool cell_beyond(const double *x, const int *c, uint o, const int G, const double reach2)
{
    const double inv_G = 1.0 / (double)G;
    double lb = 0.0;
    for (int k = D - 1; k >= 0; --k) {
        const int digit = (int)(o % 3) - 1;
        o /= 3;
        double gap = digit > 0 ? (double)(c[k] + 1) * inv_G - x[k]
                   : digit < 0 ? x[k] - (double)c[k] * inv_G : 0.0;
        gap = gap - 1e-12;
        gap = gap > 0.0 ? gap : 0.0;
        lb = lb + gap * gap;
    }
    return lb > reach2 * 1.000001;
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
