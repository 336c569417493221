/* COUNTING_SORT(name, T, cell) defines
 *     name(p, n, cells, grid, base, start, list):
 * the stable counting sort of items 0 .. n - 1 of p by cell(p, i, grid), a cell in
 * [0, cells), in one work-item (sequential: no atomics). It writes start[c] = base + the
 * first sorted place of cell c for c < cells (the caller writes start[cells] = base + n
 * where that entry is its own: sets that share one start array share it), and list[k] =
 * the k-th item in sorted order, ties in index order: the order of a stable argsort of the
 * cells (clsamp.geometry.cells.sorted_by_cell, integer_torus.build_grid). Voronoi's grids of
 * sites (voronoi.h) and gbn's resident sort by cell (gbn.cl) are both this. */
#ifndef CLSAMP_COUNTING_SORT_H
#define CLSAMP_COUNTING_SORT_H

#define COUNTING_SORT(name, T, cell)                                                       \
    inline void name(__global const T *p, const uint n, const uint cells, const uint grid, \
                     const uint base, __global uint *start, __global uint *list)            \
    {                                                                                       \
        for (uint c = 0; c < cells; ++c)                                                    \
            start[c] = 0;                                                                   \
        for (uint i = 0; i < n; ++i)                                                        \
            start[cell(p, i, grid)] += 1;                                                   \
        uint run = base;                                                                    \
        for (uint c = 0; c < cells; ++c) {                                                  \
            const uint count = start[c];                                                    \
            start[c] = run;                                                                 \
            run += count;                                                                   \
        }                                                                                   \
        /* start[c] is cell c's cursor, which leaves it at cell c + 1's start */             \
        for (uint i = 0; i < n; ++i)                                                        \
            list[start[cell(p, i, grid)]++ - base] = i;                                     \
        for (uint c = cells - 1; c > 0; --c)                                                \
            start[c] = start[c - 1];                                                        \
        start[0] = base;                                                                    \
    }

#endif
