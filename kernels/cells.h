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

inline void cell_coordinates(uint flat, const int G, int *c)
{
    for (int k = D - 1; k >= 0; --k) {
        c[k] = (int)(flat % (uint)G);
        flat /= (uint)G;
    }
}

#endif
