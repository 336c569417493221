"""What the Voronoi optimizers (``lloyd``, ``ccvt``) share: the integer torus, the site
grid and the sampler base that records the optimization.

Positions are integers in [0, 2^BITS) per axis (``kernels/voronoi.h``): a point x in
[0, 1) is ``floor(x * 2^BITS)`` and goes back as ``X / 2^BITS``. Toroidal differences,
squared distances, centroid sums and energies are exact int64 arithmetic, so the OpenCL
kernels and the NumPy references here give the same bits, integer atomics are
order-free (deterministic), and the energy provably never rises -- exactly, with no
rounding to argue about. With 22 bits the positions resolve 2.4e-7, far below the
spacing of any set these optimizers are used for.
"""

import numpy as np

from .. import philox, point_metrics
from ..validation import check_points
from .base import Sampler

BITS = 22                     # VOR_BITS in kernels/voronoi.h
SIZE = 1 << BITS
MASK = SIZE - 1
HALF = 1 << (BITS - 1)
UNIT = 1.0 / SIZE
MAX_CELL_POINTS = 1 << 20     # squared distances (< 2^43) of this many points sum in int64

HEXAGONAL_NE = 5.0 / (18.0 * np.sqrt(3.0))   # N*E of the hexagonal lattice, 0.160375
WHITE_NOISE_NE = 1.0 / np.pi                 # expected N*E of independent uniform sites


def to_torus(points):
    """Points in [0, 1) as integer torus coordinates (uint32, ``floor(x 2^BITS)``)."""
    return np.minimum(np.floor(np.asarray(points, dtype=np.float64) * SIZE), MASK).astype(np.uint32)


def to_unit(coords):
    """Integer torus coordinates back to float64 points in [0, 1) (exact)."""
    return np.asarray(coords, dtype=np.float64) * UNIT


def delta(a, b):
    """a - b on the integer torus, in [-2^(BITS-1), 2^(BITS-1)), as int64 (``vor_delta``):
    ((a - b + HALF) mod SIZE) - HALF, in three passes over the arrays."""
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
    """The integer nearest s / c, halves up (``vor_round_mean``); c > 0."""
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


def initial_sites(seed, realizations, n, start=0):
    """Initial sites, uint32 (r, n, 2): words 0 and 1 of Philox (seed, Stream.INIT, r, start + i),
    top BITS bits each. The optimizers' density points use other words of the stream."""
    r = np.asarray(realizations, dtype=np.uint32)[:, None, None]
    i = (np.uint64(start) + np.arange(n, dtype=np.uint64)).astype(np.uint32)[None, :, None]
    w = np.arange(2, dtype=np.uint32)[None, None, :]
    return philox.random_words(seed, philox.Stream.INIT, r, i, w) >> np.uint32(32 - BITS)


def exact_total(lo, hi):
    """Exact totals of int64 sums kept as (low 32 bits, high bits) parts, as Python ints."""
    lo = np.asarray(lo, dtype=np.int64)
    hi = np.asarray(hi, dtype=np.int64)
    return [int(a) + (int(b) << 32) for a, b in zip(lo.ravel(), hi.ravel(), strict=True)]


def split_total(values):
    """Exact sum of int64 values (each < 2^63) as a Python int, whatever their count."""
    v = np.asarray(values, dtype=np.int64).ravel()
    return int(np.sum(v & 0xFFFFFFFF)) + (int(np.sum(v >> 32)) << 32)


class VoronoiSampler(Sampler):
    """Base of the optimizers: ``sample`` runs the optimization and keeps its record.

    After ``sample`` the sampler holds ``energy_history`` (one value per iteration,
    never rising; (iterations,) for one set, (r, iterations) for a batch),
    ``normalized_energy`` (N*E of the returned sets: float or (r,)) and, computed on
    demand, ``relative_radius`` (rho, :func:`clsamp.point_metrics.relative_radius`).
    """

    dimensions = (2,)
    max_n = 2**31
    # the density points are keyed by realization only: an offset start would move the
    # starting sites but not the density, a set that belongs to no realization
    accepts_start = False

    def __init__(self, d=2, seed=0, backend="opencl"):
        super().__init__(d=d, seed=seed, backend=backend)
        self.energy_history = None
        self.normalized_energy = None
        self._points = None

    @property
    def relative_radius(self):
        """rho of the last sampled set(s): minimum distance over the hexagonal packing's."""
        if self._points is None:
            return None
        return point_metrics.relative_radius(self._points)

    def sample(self, n=None, realizations=None, start=0):
        n, r, start = self._check_call(n, realizations, start)
        result = self._optimize(initial_sites(self.seed, np.arange(r), n, start), range(r))
        single = realizations is None
        self._keep(result, single)
        return result.points[0] if single else result.points

    def _keep(self, result, single):
        self._points = result.points[0] if single else result.points
        history = result.energy_history
        self.energy_history = history[0] if single else history
        ne = result.points.shape[1] * history[:, -1]
        self.normalized_energy = float(ne[0]) if single else ne

    def _reference(self, n, realizations, start):
        return self._optimize(initial_sites(self.seed, np.arange(realizations.start,
                                                                 realizations.stop), n, start),
                              realizations, backend="numpy").points

    def _device(self, n, realizations, start):
        import pyopencl.array as cla

        from .. import runtime
        points = self._optimize(initial_sites(self.seed, np.arange(realizations.start,
                                                                   realizations.stop), n, start),
                                realizations, backend="opencl").points
        return cla.to_device(runtime.queue(), np.ascontiguousarray(points))

    def _optimize(self, sites, realizations, backend=None):
        raise NotImplementedError


def check_sites(sites, name="sites"):
    """Starting sites (n, 2) or (r, n, 2) in [0, 1) as integer torus coordinates (r, n, 2)."""
    batch, single = check_points(sites, name, d=2)
    return to_torus(batch), single
