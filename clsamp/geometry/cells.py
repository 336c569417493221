"""A grid of cells over [0, 1)^d for neighbour searches: the points of many sets sorted
by (set, cell), and the 3^d stencil of neighbouring cells, in the order
``kernels/cells.h`` walks them.

Users: the pair statistics of :mod:`clsamp.metrics.neighbors` and the minimum distance
(analysis), and the ``gbn`` sampler's n-body pass and ``sample_elimination``'s neighbour search
(samplers); the kernels include
``cells.h``.
"""

import numpy as np


def stable_order(key, bound):
    """``np.argsort(key, kind="stable")`` for integer keys in [0, bound), by NumPy's radix
    sort: keys below 2^16 as uint16 in one pass, keys below 2^32 in two (the low 16 bits,
    then the high ones, each pass stable); NumPy sorts other integer types by comparison.

    Parameters
    ----------
    key : ndarray of int
        Non-negative, below ``bound``.
    bound : int

    Returns
    -------
    ndarray of int64
        The permutation that sorts ``key``, ties in index order.

    Examples
    --------
    >>> import numpy as np
    >>> from clsamp.geometry.cells import stable_order
    >>> stable_order(np.array([70000, 3, 70000, 2]), 2**20).tolist()
    [3, 1, 0, 2]
    """
    key = np.asarray(key)
    if bound <= 1 << 16:
        return np.argsort(key.astype(np.uint16), kind="stable").astype(np.int64, copy=False)
    if bound <= 1 << 32:
        order = np.argsort((key & 0xFFFF).astype(np.uint16), kind="stable")
        return order[np.argsort((key[order] >> 16).astype(np.uint16), kind="stable")].astype(
            np.int64, copy=False)
    return np.argsort(key, kind="stable")


def sorted_by_cell(batch, cells):
    """The points of all realizations sorted by (realization, cell) of a grid of cells, the
    order the neighbour kernels walk them in.

    Parameters
    ----------
    batch : ndarray (r, n, d)
        Checked sets.
    cells : int
        Cells per axis: a grid of ``cells ** d`` cells.

    Returns
    -------
    points : ndarray (r n, d)
        Sorted.
    cell : ndarray of uint32, shape (r n,)
        The flat cell of each sorted point (the first axis most significant).
    start : ndarray of uint32, shape (r cells^d + 1,)
        The first sorted index of each (realization, cell).
    order : ndarray of int64, shape (r n,)
        Sorted index -> original (flat) index.

    Examples
    --------
    >>> import numpy as np
    >>> from clsamp.geometry.cells import sorted_by_cell
    >>> pts, cell, start, order = sorted_by_cell(np.array([[[0.9, 0.1], [0.1, 0.1]]]), 2)
    >>> cell.tolist(), start.tolist(), order.tolist()
    ([0, 2], [0, 1, 1, 2, 2], [1, 0])
    """
    r, n, d = batch.shape
    index = np.minimum((batch * cells).astype(np.int64), cells - 1)
    flat = np.zeros((r, n), dtype=np.int64)
    for k in range(d):
        flat = flat * cells + index[..., k]
    total = cells ** d
    key = (np.arange(r, dtype=np.int64)[:, None] * total + flat).ravel()
    order = stable_order(key, r * total)
    counts = np.bincount(key, minlength=r * total)
    start = np.concatenate(([0], np.cumsum(counts))).astype(np.uint32)
    pts = np.ascontiguousarray(batch.reshape(r * n, d)[order])
    return pts, flat.ravel()[order].astype(np.uint32), start, order


def cells_for(reach, points=None, d=None, cells_a_point=1.0):
    """Cells per axis for neighbours within ``reach``: as many cells at least ``reach``
    wide as fit, or 1 (every pair) when fewer than 3 fit, so that the 3^d neighbouring
    cells are always distinct.

    Parameters
    ----------
    reach : float
        The longest distance a neighbour may have.
    points, d : int, optional
        With both, the grid has at most about ``cells_a_point`` cells a point of a set of
        ``points`` in d dimensions: narrower cells only add empty ones to the stencil (and
        short reaches in many dimensions would ask for more cells than memory holds);
        wider cells find the same pairs.
    cells_a_point : float

    Returns
    -------
    int

    Examples
    --------
    >>> cells_for(0.01), cells_for(0.01, points=1000, d=2), cells_for(0.01, 50, 8, 4.0)
    (100, 31, 1)
    """
    # (a subnormal reach makes 1 / reach infinite)
    cells = int(min(1.0 / reach, 2.0 ** 62)) if reach > 0 else 1
    if points is not None:
        cells = min(cells, int((cells_a_point * points) ** (1.0 / d)))
    return cells if cells >= 3 else 1


def neighbour_cells(cell, offset, cells, d):
    """NumPy twin of ``neighbour`` in ``kernels/cells.h``: the flat index of neighbour
    ``offset`` (0 .. 3^d - 1; its base-3 digits, the last axis least significant, are
    the steps -1, 0, +1) of each flat cell, wrapped on the torus; 0 for a 1-cell grid.

    Parameters
    ----------
    cell : ndarray of int
        Flat cells (as :func:`sorted_by_cell` gives them).
    offset : int
        The stencil entry.
    cells : int
        Cells per axis.
    d : int
        Dimensions.

    Returns
    -------
    ndarray of int64
    """
    cell = np.asarray(cell, dtype=np.int64)
    if cells == 1:
        return np.zeros_like(cell)
    digits = [(offset // 3 ** (d - 1 - k)) % 3 - 1 for k in range(d)]
    flat = np.zeros_like(cell)
    for k in range(d):
        coordinate = (cell // cells ** (d - 1 - k)) % cells
        flat = flat * cells + (coordinate + digits[k]) % cells
    return flat
