"""Dart throwing for a fixed n in d = 5..8 (and a sparse one below): darts into the whole
torus, neighbours through cells at least r wide, the round loop both backends share.

The background grid of side r / sqrt(d) that tracks the voids (:mod:`.grid`) has
(sqrt(d) / r)^d cells, about 100 a point in 5-D and 5600 in 8-D at rho = 0.75, and its
neighbour windows (2 sqrt(d) + 3)^d: 6095 cells a dart in 5-D, hundreds of thousands in
8-D. Beyond d = 4 the sampler therefore throws its darts into the whole torus, as plain
dart throwing does (Cook 1986; in parallel rounds as Wei 2008), and finds the points near a
dart through a grid of cells of side 1/G >= r (:mod:`clsamp.geometry.cells`, at most about
one cell a point, so memory stays linear in n), whose 3^d cells around a dart hold every
point closer than r. Without voids no set is known to be maximal: a realization still
short of n after ``COARSE_ROUNDS`` rounds counts as stuck and is drawn again, as a
maximal one is in :func:`.sampler._draw`. Maximal sets are made for d <= 4 only. In d <= 4
a fixed n is thrown this way too where the fine grid would hold more than ``COARSE_SPARSE``
cells a point: a radius far below the spacing, whose darts nearly all land.
"""

import numpy as np

from ...errors import InvalidArgumentError
from ...geometry.cells import cells_for, sorted_by_cell, stable_order
from .grid import IN

COARSE_MIN_D = 5        # the first dimension thrown this way
COARSE_SPARSE = 256     # d <= 4: a fixed n with more fine-grid cells a point is thrown so
COARSE_STEPS = 4        # greedy steps per round (the fine grid's level-0 count)
COARSE_ROUNDS = 64      # rounds before a realization short of n counts as stuck
COARSE_RHO = 0.65       # the default relative radius in d >= 5 (0.75 below): reached in
                        # 4-6 rounds, where 0.7 takes 11-36 and 0.75 is out of reach in 64
                        # (docs/performance.md, "Poisson disk in 4 to 8 dimensions")
DART_BITS = 26          # the Philox index word holds the dart in 26 bits, the attempt above


class CoarseGeometry:
    """The parameters of a coarse run: dimension, radius, threshold, cells and darts.

    Parameters
    ----------
    d : int
        5 to 8, or 1 to 4 for a sparse n (``COARSE_SPARSE``).
    radius : float
    r2 : float
        The acceptance threshold of squared distances (:func:`.grid.acceptance_threshold`).
    n : int
        Points a set: the darts a round throws into each unfinished set.

    Attributes
    ----------
    G : int
        Cells per axis: the most cells at least r wide, at most n^(1/d), and 1 (every pair)
        where fewer than 3 fit (:func:`clsamp.geometry.cells.cells_for`) or where the 3^d
        cells around a dart would cost more to visit than the n points, 3^d (4 + n / G^d)
        >= n (8-D below about 32 000 points).
    cells : int
        G^d.
    stencil : int
        The cells around a cell that can hold a neighbour: 3^d, or 1 when G == 1.
    darts : int
        Darts a round throws into each unfinished set (n).
    footprint : int
        What one realization holds, in grid-cell slots, for the batch size.
    """

    def __init__(self, d, radius, r2, n):
        if n >= 1 << DART_BITS:
            raise InvalidArgumentError(
                f"'n' must be below 2^{DART_BITS} for d >= {COARSE_MIN_D} (coarse dart "
                f"throwing numbers its darts in {DART_BITS} bits), got {n}")
        self.d, self.radius, self.r2 = d, radius, r2
        G = cells_for(radius, n, d)
        # the cells pay only where the 3^d around a dart hold far fewer than the n points:
        # a cell visited costs about four distances (docs/performance.md)
        self.G = G if G >= 3 and 3 ** d * (4 + n / G ** d) < n else 1
        self.cells = self.G ** d
        self.stencil = 3 ** d if self.G > 1 else 1
        self.darts = int(n)
        self.footprint = self.cells + 2 * self.darts
        self.nblocks = d // 2 + 1


def ragged_by_cell(points, sets, count, G):
    """Points of several sets sorted by (set, cell), as the kernels walk them.

    Parameters
    ----------
    points : ndarray (m, d)
    sets : ndarray (m,) of int
        Each point's set, 0 .. count - 1, ascending.
    count : int
        The number of sets.
    G : int
        Cells per axis.

    Returns
    -------
    sorted_points : ndarray (m, d)
    start : ndarray of uint32, shape (count G^d + 1,)
        The first sorted index of each (set, cell).
    order : ndarray of int64
        Sorted index -> index in ``points``.
    """
    cells = G ** points.shape[1]
    _, cell, _, by_cell = sorted_by_cell(points[None], G)
    flat = np.empty(len(points), dtype=np.int64)
    flat[by_cell] = cell
    key = np.asarray(sets, dtype=np.int64) * cells + flat
    order = stable_order(key, count * cells)
    start = np.concatenate(([0], np.cumsum(np.bincount(key, minlength=count * cells))))
    return np.ascontiguousarray(points[order]), start.astype(np.uint32), order


def throw_coarse(backend, n):
    """Run rounds until every realization of the batch holds n points or is stuck.

    Each round: ``geo.darts`` darts into every unfinished set, valid when no accepted point
    is closer than r (``throw``); the valid darts sorted by (set, cell) and settled by
    ``COARSE_STEPS`` greedy steps (``resolve``); a set whose count passes n keeps the
    round's highest-priority winners (then the lower sorted index), as the fine grid does.

    Parameters
    ----------
    backend : NumpyCoarse or DeviceCoarse
    n : int

    Returns
    -------
    counts : ndarray of int
        Points per realization.
    short : ndarray of bool
        Realizations still short of n after ``COARSE_ROUNDS`` rounds.
    stats : dict
        Rounds and darts thrown.
    """
    geo, B = backend.geo, backend.B
    D = geo.darts
    pts = np.zeros((B, n, geo.d), dtype=np.float64)
    counts = np.zeros(B, dtype=np.int64)
    darts = rounds = 0
    for round_ in range(COARSE_ROUNDS):
        active = np.flatnonzero(counts < n)
        if not active.size:
            break
        rounds += 1
        A = active.size
        held = np.repeat(np.arange(A), counts[active])
        accepted = np.concatenate([pts[b, :counts[b]] for b in active]) if held.size else \
            np.zeros((0, geo.d))
        spts, pstart, _ = ragged_by_cell(accepted, held, A, geo.G)
        cand, prio, valid = backend.throw(active, spts, pstart, round_)
        darts += A * D
        scand, _, dstart, order = sorted_by_cell(cand.reshape(A, D, geo.d), geo.G)
        state = backend.resolve(scand, prio[order], valid[order], dstart)
        won = np.flatnonzero(state == IN)
        rel = won // D
        need = n - counts[active]
        # each set's winners best first: higher priority, then lower sorted index
        best = np.lexsort((won, -prio[order][won].astype(np.int64), rel))
        first = np.searchsorted(rel[best], np.arange(A))
        rank = np.arange(best.size) - first[rel[best]]
        keep = np.sort(best[rank < need[rel[best]]])        # back to (set, cell) order
        kept_rel = rel[keep]
        slot = counts[active][kept_rel] + np.arange(keep.size) \
            - np.searchsorted(kept_rel, kept_rel)
        pts[active[kept_rel], slot] = scand[won[keep]]
        counts[active] += np.bincount(kept_rel, minlength=A)
    short = counts < n
    backend.points = pts
    return counts, short, {"rounds": rounds, "darts": darts}


def gather_coarse(pts, dst, out, skip):
    """Copy each realization's points, in the order they were accepted (each round's in
    cell order), into ``out``.

    Parameters
    ----------
    pts : ndarray (B, n, d)
        The sets of a batch.
    dst : ndarray of int
        Per realization, the row of ``out`` its first point goes to; ``skip`` leaves it out.
    out : ndarray or pyopencl.array.Array
        (total, d) float64.
    skip : int
        The ``dst`` of a realization that is redrawn.
    """
    n = pts.shape[1]
    for b, lo in enumerate(np.asarray(dst, dtype=np.int64)):
        if lo != skip:
            if isinstance(out, np.ndarray):
                out[lo:lo + n] = pts[b]
            else:
                out[lo:lo + n].set(np.ascontiguousarray(pts[b]))
