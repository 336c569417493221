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

BITS = 22
SIZE = 1 << BITS
MASK = SIZE - 1
HALF = 1 << (BITS - 1)
UNIT = 1.0 / SIZE
MAX_CELL_POINTS = 1 << 20     # squared distances (< 2^43) of this many points sum in int64

DEFINES = {"VOR_BITS": BITS}  # the build options every kernel on the integer torus needs


def to_torus(points):
    """Points in [0, 1) as integer torus coordinates (uint32, ``floor(x 2^BITS)``); a
    device array stays on the device (``kernels/integer_torus.cl``, the same integers)."""
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
    """Integer torus coordinates back to float64 points in [0, 1) (exact)."""
    return np.asarray(coords, dtype=np.float64) * UNIT


def delta(a, b):
    """a - b on the integer torus, in [-2^(BITS-1), 2^(BITS-1)), as int64 (``vor_delta``):
    ((a - b + HALF) mod SIZE) - HALF."""
    d = np.asarray(a, dtype=np.int64) - np.asarray(b, dtype=np.int64)
    d += HALF
    d &= MASK
    d -= HALF
    return d


def distance2(ax, ay, bx, by):
    """Exact squared toroidal distances (int64, units of 2^-2BITS), broadcasting."""
    dx, dy = delta(ax, bx), delta(ay, by)
    return dx * dx + dy * dy


def round_mean(s, c):
    """The integer nearest s / c, halves up (``vor_round_mean``); c > 0.

    Moving a site by it never raises its cell's energy: with mean m and step q,
    sum (d - q)^2 - sum d^2 = c q (q - 2 m) <= 0 whenever |q - m| <= 1/2.
    """
    s = np.asarray(s, dtype=np.int64)
    c = np.asarray(c, dtype=np.int64)
    return np.floor_divide(2 * s + c, 2 * c)


def cell_of(x, G):
    """Grid cell (per axis) of integer coordinates in a G x G grid (``vor_cell``)."""
    return ((np.asarray(x, dtype=np.uint64) * np.uint64(G)) >> np.uint64(BITS)).astype(np.int64)


def build_grid(sites, G):
    """Counting sort of one realization's sites into G x G cells (``voronoi_build_grid``).

    Returns ``(cell_start, cell_sites)``: the sites of cell ``c = cy * G + cx`` are
    ``cell_sites[cell_start[c]:cell_start[c + 1]]``, in index order.
    """
    cell = cell_of(sites[:, 1], G) * G + cell_of(sites[:, 0], G)
    order = np.argsort(cell, kind="stable")
    start = np.zeros(G * G + 1, dtype=np.int64)
    np.cumsum(np.bincount(cell, minlength=G * G), out=start[1:])
    return start, order


def exact_total(lo, hi):
    """Exact totals of int64 sums kept as (low 32 bits, high bits) parts, as Python ints."""
    lo = np.asarray(lo, dtype=np.int64)
    hi = np.asarray(hi, dtype=np.int64)
    return [int(a) + (int(b) << 32) for a, b in zip(lo.ravel(), hi.ravel(), strict=True)]


def split_total(values):
    """Exact sum of int64 values (each < 2^63) as a Python int, whatever their count."""
    v = np.asarray(values, dtype=np.int64).ravel()
    return int(np.sum(v & 0xFFFFFFFF)) + (int(np.sum(v >> 32)) << 32)
