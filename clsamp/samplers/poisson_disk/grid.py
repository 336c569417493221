"""The background grid of dart throwing and the constants both backends share: cells of
side 1/G < r / sqrt(d) (at most one point each), the windows of neighbouring cells a dart
or a box must look at, and the acceptance threshold."""

import math

import numpy as np

from ...errors import SamplingError
from ...geometry import torus

HEXAGONAL_DENSITY = math.pi / math.sqrt(12.0)   # 0.906899...: the largest 'rho' accepted
MAX_RADIUS = 0.5            # beyond, a disk overlaps its own periodic image
MAX_CELLS = 2**24           # grid cells per realization (memory: ~ 9 + 8 d bytes each,
                            # and about as much again for the active cells)
BATCH_CELLS = 2**21         # grid cells of the realizations handled in one launch
LEVEL0_ROUNDS = 2           # rounds of darts at grid-cell level before refining every round
MAX_LEVEL = 30              # subcell coordinates are 32-bit
MAX_ROUNDS = 2048           # the dart tag holds the round in 11 bits
MAX_RANK = 2**20            # and the rank within a grid cell's entries in 20 bits
RESOLVE_STEPS = (4, 2)      # greedy steps per round at level 0 and deeper (dart_resolve);
                            # darts still open stay out (deep darts rarely conflict)
MAX_ATTEMPTS = 8            # redraws of a realization that became maximal below n
NO_ROUND = np.uint32(0xFFFFFFFF)
OUT, OPEN, IN = 0, 1, 2     # dart states of dart_resolve
SKIP = 0xFFFFFFFF           # gather: a realization that is redrawn


def grid_size(radius, d):
    """Grid cells per axis, G = floor(sqrt(d) / r) + 1: cells of side 1/G < r / sqrt(d),
    so a cell's diagonal is shorter than r and a cell holds at most one point.

    Parameters
    ----------
    radius : float
        The disks' radius r.
    d : int

    Returns
    -------
    int

    Examples
    --------
    >>> from clsamp.samplers.poisson_disk.grid import grid_size
    >>> grid_size(0.1, 2)          # sqrt(2) / 0.1 = 14.1
    15
    """
    return int(math.floor(math.sqrt(d) / radius)) + 1


def grid_cells(radius, d):
    """The background grid's cells, :func:`grid_size` ^ d, as a float: infinity where that
    passes 2^1000 (a radius too small for any grid: its callers refuse a maximal set, or
    throw a fixed n into the whole torus).

    Parameters
    ----------
    radius : float
    d : int

    Returns
    -------
    float

    Examples
    --------
    >>> from clsamp.samplers.poisson_disk.grid import grid_cells
    >>> grid_cells(0.1, 2), grid_cells(1e-310, 3)
    (225.0, inf)
    """
    if not math.sqrt(d) / radius < 2.0 ** (1000 / d):
        return math.inf
    return float(grid_size(radius, d) ** d)


def cells_text(cells):
    """:func:`grid_cells`'s count for a message: three digits, or "over 1e301" for infinity.

    Parameters
    ----------
    cells : float

    Returns
    -------
    str
    """
    return "over 1e301" if math.isinf(cells) else f"{cells:.3g}"


def reach(radius, G):
    """K: grid cells at offset above K on some axis are r or more apart (side 1/G).

    Parameters
    ----------
    radius : float
    G : int
        Grid cells per axis.

    Returns
    -------
    int
        floor(r G) + 1.
    """
    return int(math.floor(radius * G)) + 1


def acceptance_threshold(radius, scale=1.0, target=None):
    """The smallest double r2 >= radius^2 with sqrt(r2) / scale >= target in double
    arithmetic (target defaults to radius / scale).

    Darts are accepted when their squared distance is >= r2, so the minimum distance that
    :func:`clsamp.metrics.min_distance` measures (a square root of the same bits),
    divided by ``scale`` (d_max for a relative radius, whose target is rho), is never
    below the promise, not even by an ulp.

    Parameters
    ----------
    radius : float
    scale : float
        What the measured distance is divided by (1 for an absolute radius).
    target : float, optional
        The promised minimum of distance / scale; default radius / scale.

    Returns
    -------
    float
        r2.
    """
    if target is None:
        target = radius / scale
    r2 = radius * radius
    while math.sqrt(r2) < radius or math.sqrt(r2) / scale < target:
        r2 = math.nextafter(r2, math.inf)
    return r2


def level_of(round_):
    """Refinement level of round ``round_``: level 0 for LEVEL0_ROUNDS rounds, then one
    level deeper each round (the same for all realizations, so none depends on another).

    Parameters
    ----------
    round_ : int

    Returns
    -------
    int
    """
    return max(0, round_ - (LEVEL0_ROUNDS - 1))


def resolve_steps(round_):
    """Greedy steps of round ``round_`` (a function of the round alone, as the level).

    Parameters
    ----------
    round_ : int

    Returns
    -------
    int
        RESOLVE_STEPS[0] at level 0, RESOLVE_STEPS[1] deeper.
    """
    return RESOLVE_STEPS[0] if level_of(round_) == 0 else RESOLVE_STEPS[1]


def window_offsets(radius, G, d):
    """The grid offsets whose cells can hold a point closer than r to a point of the
    centre cell, nearest first (ties in np.ndindex order): the kernels' window table.

    Cells at offset o are at least sqrt(sum_k max(|o_k| - 1, 0)^2) / G apart; offsets
    beyond K = floor(r G) + 1 on an axis are at least r apart, and so are those the bound
    puts at r or more (kept, with a margin of 1e-9, when the bound is within rounding of r).
    Order does not change any result (the kernels ask "is there any"), only how soon the
    loops stop.

    Parameters
    ----------
    radius : float
    G : int
        Grid cells per axis.
    d : int

    Returns
    -------
    ndarray
        int64 of shape (count, d).
    """
    K = reach(radius, G)
    offsets = np.array(list(np.ndindex(*(2 * K + 1,) * d)), dtype=np.int64) - K
    gap = np.maximum(np.abs(offsets) - 1, 0).astype(np.float64) / G
    bound2 = np.sum(gap * gap, axis=1)
    keep = bound2 < radius * radius * (1.0 + 1e-9)
    order = np.argsort(bound2[keep], kind="stable")
    return offsets[keep][order]


def cover_window(radius, G, d, level):
    """The grid offsets whose points can cover a whole level-``level`` box (side
    w = 1 / (G 2^level)) of the centre cell, nearest first: dart_refine's table.

    A point in the cell at offset o is, along axis k, at least w / 2 from the farther end
    of the box when o_k = 0 and (|o_k| - 1) / G + w when o_k != 0; offsets whose bound
    reaches r (with a margin of 1e-9) can cover nothing. At level 0 this leaves the 3^d
    nearest cells of the 5^d that dart_throw must search, where most entries are refined.

    Parameters
    ----------
    radius : float
    G : int
        Grid cells per axis.
    d : int
    level : int

    Returns
    -------
    ndarray
        int64 of shape (count, d), a subset of :func:`window_offsets` in its order.
    """
    offsets = window_offsets(radius, G, d)
    w = 1.0 / (G * 2.0 ** level)
    a = np.abs(offsets)
    gap = np.where(a == 0, w / 2.0, (np.maximum(a, 1) - 1) / G + w)
    keep = np.sum(gap * gap, axis=1) < radius * radius * (1.0 + 1e-9)
    return offsets[keep]


def cell_coords(flat, G, d):
    """The integer coordinates of grid cells from their flat (row-major) indices, as
    ``cell_coords`` in the kernel.

    Parameters
    ----------
    flat : ndarray of int
    G : int
        Grid cells per axis.
    d : int

    Returns
    -------
    ndarray
        int64 of shape flat.shape + (d,); the last axis varies fastest in ``flat``.

    Examples
    --------
    >>> import numpy as np
    >>> from clsamp.samplers.poisson_disk.grid import cell_coords, flat_index
    >>> c = cell_coords(np.array([7]), 4, 2)
    >>> c.tolist(), flat_index(c, 4).tolist()
    ([[1, 3]], [7])
    """
    coords = np.empty(flat.shape + (d,), dtype=np.int64)
    rest = flat.astype(np.int64)
    for k in range(d - 1, -1, -1):
        coords[..., k] = rest % G
        rest = rest // G
    return coords


def flat_index(coords, G):
    """The flat (row-major) indices of grid cells, each coordinate wrapped on the torus
    first: the inverse of :func:`cell_coords`.

    Parameters
    ----------
    coords : ndarray of int
        (..., d) coordinates, any integers.
    G : int
        Grid cells per axis.

    Returns
    -------
    ndarray
        int64 of shape coords.shape[:-1].
    """
    flat = np.zeros(coords.shape[:-1], dtype=np.int64)
    for k in range(coords.shape[-1]):
        flat = flat * G + coords[..., k] % G
    return flat


def far_corner2(c, M, p):
    """Squared distance from p to the farthest corner of the boxes with integer coordinates
    c (side 1/M), on the torus, as far_corner2 in the kernel.

    Parameters
    ----------
    c : ndarray of int
        (..., d) box coordinates.
    M : float
        Boxes per axis.
    p : ndarray
        (..., d) points, broadcast against the boxes.

    Returns
    -------
    ndarray
        float64 of the broadcast shape without the last axis.
    """
    lo = c.astype(np.float64) / M
    hi = (c + 1).astype(np.float64) / M
    f = np.maximum(torus.wrapped_delta(lo, p), torus.wrapped_delta(hi, p))
    f = np.where(f > 0.5 - (hi - lo), 0.5, f)
    total = f[..., 0] * f[..., 0]
    for k in range(1, f.shape[-1]):
        total = total + f[..., k] * f[..., k]
    return total


def child_bits(children, d):
    """Bit k of child t is its half on axis k (axis 0 the most significant), as in the kernel.

    Parameters
    ----------
    children : int
        2^d to split a box into its halves, 1 to keep it.
    d : int

    Returns
    -------
    ndarray
        (children, d): row t holds child t's half (0 or 1) on each axis.
    """
    t = np.arange(children)
    return np.stack([(t >> (d - 1 - k)) & 1 for k in range(d)], axis=-1)


class Geometry:
    """The parameters of one run: dimension, radius, grid and threshold.

    Parameters
    ----------
    d : int
    radius : float
    r2 : float
        The acceptance threshold of squared distances (:func:`acceptance_threshold`).

    Attributes
    ----------
    G : int
        Grid cells per axis (:func:`grid_size`).
    cells : int
        G^d.
    window : ndarray
        :func:`window_offsets`.
    nblocks : int
        Philox blocks a dart draws: d coordinates and a priority word.
    footprint : int
        What one realization holds, in grid-cell slots, for the batch size (``cells``).
    """

    def __init__(self, d, radius, r2):
        self.d = d
        self.radius = radius
        self.r2 = r2
        self.G = grid_size(radius, d)
        self.cells = self.G ** d
        self.window = window_offsets(radius, self.G, d)
        # the kernels wrap a neighbour's coordinate with one correction
        assert np.abs(self.window).max() <= self.G
        self.nblocks = d // 2 + 1
        self.footprint = self.cells
        self._cover = {}

    def cover(self, level):
        """The cover window for boxes at ``level`` (:func:`cover_window`, cached).

        Parameters
        ----------
        level : int

        Returns
        -------
        ndarray
        """
        if level not in self._cover:
            self._cover[level] = cover_window(self.radius, self.G, self.d, level)
        return self._cover[level]


def rank_overflow():
    """The error for a grid cell with more active entries than a dart's tag can number.

    Returns
    -------
    SamplingError
    """
    return SamplingError(
        f"poisson_disk: more than {MAX_RANK} active subcells in one grid cell "
        "(a bug: please report it with the seed and radius)")
