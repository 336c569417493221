"""The exact integer torus of the Voronoi optimizers (``lloyd``, ``ccvt``).

Positions are integers in [0, 2^BITS) per axis: a point x in [0, 1) is
``floor(x * 2^BITS)`` and goes back as ``X / 2^BITS``. Toroidal differences, squared
distances, centroid sums and energies are exact int64 arithmetic, so the OpenCL kernels
(``kernels/voronoi.h``) and the NumPy functions here give the same bits, integer atomics
are order-free (deterministic), and an energy that may not rise provably does not --
exactly, with no rounding to argue about. With 22 bits the positions resolve 2.4e-7, far
below the spacing of any set these optimizers make, and a squared distance is below 2^43,
so 2^20 of them sum in int64.

The kernels take ``BITS`` as the build option ``VOR_BITS`` (:data:`DEFINES`); this module
is its one source.
"""

import numpy as np

from .cells import stable_order

BITS = 22
SIZE = 1 << BITS
MASK = SIZE - 1
HALF = 1 << (BITS - 1)
UNIT = 1.0 / SIZE
MAX_CELL_POINTS = 1 << 20     # squared distances (< 2^43) of this many points sum in int64

DEFINES = {"VOR_BITS": BITS}  # the build options every kernel on the integer torus needs


def to_torus(points):
    """Points in [0, 1) as integer torus coordinates (uint32, ``floor(x 2^BITS)``); a
    device array stays on the device (``kernels/integer_torus.cl``, the same integers).

    Parameters
    ----------
    points : array_like or pyopencl.array.Array
        Coordinates in [0, 1), any shape.

    Returns
    -------
    ndarray or pyopencl.array.Array of uint32
        The same shape, where the points are.

    Examples
    --------
    >>> to_torus([0.0, 0.5, 0.9999999999]).tolist()
    [0, 2097152, 4194303]
    """
    from .. import runtime
    if runtime.is_device_array(points):
        import pyopencl.array as cla
        flat = runtime.device_block(points.reshape((1, -1, 1)), 0, 1)
        out = cla.empty(runtime.queue(), points.shape, np.uint32)
        if points.size:
            runtime.kernel("integer_torus.cl", "points_to_torus", DEFINES)(
                runtime.queue(), (points.size,), None, flat.data, np.uint64(points.size), out.data)
        return out
    return np.minimum(np.floor(np.asarray(points, dtype=np.float64) * SIZE), MASK).astype(np.uint32)


def to_unit(coords):
    """Integer torus coordinates back to float64 points in [0, 1) (exact).

    Parameters
    ----------
    coords : array_like of int

    Returns
    -------
    ndarray of float64
        ``coords * 2^-BITS``.
    """
    return np.asarray(coords, dtype=np.float64) * UNIT


def delta(a, b):
    """a - b on the integer torus, in [-2^(BITS-1), 2^(BITS-1)), as int64 (``vor_delta``):
    ((a - b + HALF) mod SIZE) - HALF.

    Parameters
    ----------
    a, b : array_like of int
        Integer coordinates, broadcast.

    Returns
    -------
    ndarray of int64

    Examples
    --------
    >>> delta(1, SIZE - 1).tolist()          # across the seam
    2
    """
    d = np.asarray(a, dtype=np.int64) - np.asarray(b, dtype=np.int64)
    d += HALF
    d &= MASK
    d -= HALF
    return d


def distance2(ax, ay, bx, by):
    """Exact squared toroidal distances (int64, units of 2^-2BITS), broadcasting.

    Parameters
    ----------
    ax, ay, bx, by : array_like of int
        The two points' integer coordinates.

    Returns
    -------
    ndarray of int64
    """
    dx, dy = delta(ax, bx), delta(ay, by)
    return dx * dx + dy * dy


def round_mean(s, c):
    """The integer nearest s / c, halves up (``vor_round_mean``); c > 0.

    Moving a site by it never raises its cell's energy: with mean m and step q,
    sum (d - q)^2 - sum d^2 = c q (q - 2 m) <= 0 whenever |q - m| <= 1/2.

    Parameters
    ----------
    s : array_like of int
        Sums (of a cell's offsets from its site).
    c : array_like of int
        Counts, positive.

    Returns
    -------
    ndarray of int64

    Examples
    --------
    >>> round_mean([5, -5, 7], [2, 2, 2]).tolist()       # 2.5, -2.5, 3.5: halves up
    [3, -2, 4]
    """
    s = np.asarray(s, dtype=np.int64)
    c = np.asarray(c, dtype=np.int64)
    return np.floor_divide(2 * s + c, 2 * c)


def cell_of(x, G):
    """Grid cell (per axis) of integer coordinates in a G x G grid (``vor_cell``).

    Parameters
    ----------
    x : array_like of int
        Integer coordinates along one axis.
    G : int
        Cells per axis.

    Returns
    -------
    ndarray of int64
        ``floor(x G / 2^BITS)``, in [0, G).
    """
    return ((np.asarray(x, dtype=np.uint64) * np.uint64(G)) >> np.uint64(BITS)).astype(np.int64)


def build_grid(sites, G):
    """Counting sort of one realization's sites into G x G cells (``voronoi_build_grid``).

    Parameters
    ----------
    sites : ndarray of int
        (n, 2) integer coordinates.
    G : int
        Cells per axis.

    Returns
    -------
    cell_start : ndarray of int64
        (G * G + 1,): the sites of cell ``c = cy * G + cx`` are
        ``cell_sites[cell_start[c]:cell_start[c + 1]]``.
    cell_sites : ndarray of int
        Site indices, grouped by cell, in index order within a cell.
    """
    cell = cell_of(sites[:, 1], G) * G + cell_of(sites[:, 0], G)
    order = stable_order(cell, G * G)
    start = np.zeros(G * G + 1, dtype=np.int64)
    np.cumsum(np.bincount(cell, minlength=G * G), out=start[1:])
    return start, order


def exact_total(lo, hi):
    """Exact totals of int64 sums kept as (low 32 bits, high bits) parts, as Python ints.

    Parameters
    ----------
    lo, hi : array_like of int
        The parts, one pair per total (the kernels' two atomic accumulators).

    Returns
    -------
    list of int
        ``lo + hi * 2^32`` for each pair.
    """
    lo = np.asarray(lo, dtype=np.int64)
    hi = np.asarray(hi, dtype=np.int64)
    return [int(a) + (int(b) << 32) for a, b in zip(lo.ravel(), hi.ravel(), strict=True)]


def split_total(values):
    """Exact sum of int64 values (each < 2^63) as a Python int, whatever their count.

    Parameters
    ----------
    values : array_like of int

    Returns
    -------
    int

    Examples
    --------
    >>> split_total([2**62, 2**62, 2**62]) == 3 * 2**62
    True
    """
    v = np.asarray(values, dtype=np.int64).ravel()
    return int(np.sum(v & 0xFFFFFFFF)) + (int(np.sum(v >> 32)) << 32)
