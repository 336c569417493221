"""The ``lloyd`` sampler: periodic Lloyd relaxation towards a centroidal Voronoi tessellation,
in d = 1 .. 4 dimensions.

OpenCL: the assignment pass of :mod:`clsamp.geometry.voronoi` and ``lloyd_move``
(``kernels/lloyd.cl``), all realizations in one launch per step; NumPy reference:
:func:`lloyd_reference` here (``backend="numpy"``), the same integers.
"""

import dataclasses

import numpy as np

from .. import runtime
from ..errors import InvalidArgumentError
from ..geometry import integer_torus as it
from ..geometry import voronoi
from ..validation import MAX_ITERATIONS, check_positive_int
from .base import SampleInfo, register
from .optimizer import OptimizerSampler, check_sites


@dataclasses.dataclass(frozen=True)
class LloydInfo(SampleInfo):
    """What a Lloyd relaxation did, per realization (first axis).

    Attributes
    ----------
    realizations : ndarray (r,)
        The realization indices.
    energy_history : ndarray (r, iterations)
        The CVT energy E (mean squared toroidal distance of the density points to their
        nearest site) of the sites after each iteration: entry t after t + 1 moves.
        Never rising; the last entry is the energy of the returned points.
    initial_energy : ndarray (r,)
        E of the starting sites.
    counts : ndarray (r, n)
        Density points in each returned site's Voronoi cell: none empty where the sites'
        cells can each hold a point, but with few density points a site (``density`` of
        1 or 2) some can be empty.
    """

    energy_history: np.ndarray
    initial_energy: np.ndarray
    counts: np.ndarray


def _reseed(sites, counts, far_d2, far_index, g):
    """Move the empty sites of one realization onto the density points farthest from their
    site (one point per segment, farthest first, ties to the lower index), so each captures
    at least that point at the next assignment. An empty site holds no density point, so
    where it goes cannot raise the energy."""
    empty = np.flatnonzero(counts == 0)
    if empty.size == 0:
        return
    order = np.lexsort((far_index, -far_d2))
    order = order[far_d2[order] > 0][:empty.size]
    for site, seg in zip(empty, order, strict=False):
        sites[site] = voronoi.density_point(int(far_index[seg]), g, sites.shape[1])


def lloyd_reference(sites, g, iterations):
    """NumPy twin of :func:`lloyd_device`: the same integers, one realization at a time.

    Parameters
    ----------
    sites : ndarray
        (r, n, d) integer coordinates, d = 1 .. 4.
    g : int
        Side of the g^d density grid.
    iterations : int

    Returns
    -------
    sites : ndarray of uint32
        (r, n, d), after the iterations.
    energies : list of list of int
        Per realization, the exact energy sums of passes 0 .. iterations.
    counts : ndarray of int64
        (r, n): density points per site in the last pass.
    """
    sites = np.array(sites, dtype=np.int64)
    r, n, d = sites.shape
    energies = [[0] * (iterations + 1) for _ in range(r)]
    counts = np.zeros((r, n), dtype=np.int64)
    for k in range(r):
        s = sites[k]
        for t in range(iterations + 1):
            label, d2, offsets = voronoi.assign_reference(s, g)
            energies[k][t] = it.split_total(d2)
            c = np.bincount(label, minlength=n).astype(np.int64)
            if t == iterations:
                counts[k] = c
                break
            full = c > 0
            for a in range(d):
                # exact: |sums| < 2^53, which float64 bincount holds exactly
                sums = np.bincount(label, weights=offsets[:, a], minlength=n).astype(np.int64)
                s[full, a] = (s[full, a] + it.round_mean(sums[full], c[full])) & it.MASK
            if not full.all():
                far_d2, far_index = voronoi.segment_far(d2, g)
                _reseed(s, c, far_d2, far_index, g)
    return sites.astype(np.uint32), energies, counts


def lloyd_device(sites, g, iterations):
    """Lloyd's iterations on the device, on integer sites.

    Parameters
    ----------
    sites, g, iterations
        As :func:`lloyd_reference`.

    Returns
    -------
    sites, energies, counts
        As :func:`lloyd_reference`, the same bits.

    Raises
    ------
    NoDeviceError
        The device lacks 64-bit integer atomics or stops long loops.
    """
    import pyopencl.array as cla
    voronoi.require_device("lloyd")
    q = runtime.queue()
    r, n, d = sites.shape
    d_sites = cla.to_device(q, np.ascontiguousarray(sites, dtype=np.uint32))
    assign = voronoi.DeviceAssignment(r, n, g, iterations + 1, d)
    counts = cla.empty(q, (r, n), np.uint32)
    empty = cla.zeros(q, (r,), np.uint32)
    move = runtime.kernel("lloyd.cl", "lloyd_move", voronoi.defines(d))
    u32 = np.uint32
    for t in range(iterations + 1):
        assign(d_sites, t)
        if t == iterations:
            break
        move(q, (n, r), None, d_sites.data, u32(n), assign.acc.data, counts.data, empty.data)
        holes = empty.get()
        if holes.any():
            host_sites = d_sites.get().astype(np.int64)
            c, fd, fi = counts.get(), assign.far_d2.get(), assign.far_index.get()
            for k in np.flatnonzero(holes):
                _reseed(host_sites[k], c[k], fd[k], fi[k], g)
            d_sites.set(host_sites.astype(np.uint32))
            empty.fill(0)
    final_counts = assign.acc.get()[:, :, d]
    return d_sites.get(), assign.energies(), final_counts


def _run(sites, realizations, density, iterations, backend):
    _, n, d = sites.shape
    g = voronoi.density_side(n, density, d)
    if backend == "numpy":
        final, energies, counts = lloyd_reference(sites, g, iterations)
    else:
        final, energies, counts = lloyd_device(sites, g, iterations)
    e = np.array([[float(v) for v in row] for row in energies]) / voronoi.energy_scale(g, d)
    info = LloydInfo(realizations=np.asarray(realizations, dtype=np.int64),
                     energy_history=e[:, 1:], initial_energy=e[:, 0],
                     counts=np.asarray(counts, dtype=np.int64))
    return it.to_unit(final), info


def _fits(density, n, d):
    """Whether n sites' density grid, g^d >= n * density points, has 32-bit counts."""
    return n * density <= 2**32 - 1 and voronoi.density_side(n, density, d) ** d <= 2**32


def _check_density(density, n, d=2):
    density = check_positive_int(density, "density")
    if not _fits(density, n, d):
        raise InvalidArgumentError(
            f"'density' * n must stay below 2^32 density points (the grid g^{d} with g^{d} >= "
            f"n * density), got {density} * {n}")
    return density


def lloyd_relax(sites, density=256, iterations=50, backend="opencl"):
    """Periodic Lloyd relaxation of given starting sites on the unit torus.

    Parameters
    ----------
    sites : ndarray (n, d) or (r, n, d), d = 1 .. 4
        Starting sites in [0, 1) (duplicates and clusters are fine).
    density : int
        Density points per site: the density is the regular g^d grid of cell centres
        with g the smallest side with g^d >= n * density.
    iterations : int
        Lloyd steps (assign, then move every site to its cell's centroid).
    backend : {"opencl", "numpy"}

    Returns
    -------
    points : ndarray (r, n, d)
        The relaxed sites, float64 in [0, 1) (batch-shaped even for one set).
    info : LloydInfo
        Realizations 0..r-1 standing for the given sets.

    Examples
    --------
    >>> import numpy as np
    >>> from clsamp.samplers.lloyd import lloyd_relax
    >>> start = np.random.default_rng(1).random((32, 2))
    >>> points, info = lloyd_relax(start, density=64, iterations=5)
    >>> points.shape, bool(info.energy_history[0, -1] < info.initial_energy[0])
    ((1, 32, 2), True)
    """
    batch, _ = check_sites(sites, d=voronoi.DIMENSIONS)
    _, n, d = batch.shape
    density = _check_density(density, n, d)
    iterations = check_positive_int(iterations, "iterations", maximum=MAX_ITERATIONS)
    return _run(batch, np.arange(batch.shape[0]), density, iterations, backend)


@register("lloyd")
class LloydSampler(OptimizerSampler):
    """Periodic Lloyd relaxation: sites moved to the centroids of their Voronoi cells.

    Parameters
    ----------
    d : int
        1, 2, 3 or 4 (the unit torus [0, 1)^d; distances wrap).
    seed : int
        Seeds the starting sites (Philox, ``Stream.INIT``; realization k's start does not
        depend on how many realizations are drawn).
    iterations : int
        Lloyd steps (default 50).
    density : int
        Density points per site (default 256): a regular g^d grid of cell centres, g the
        smallest side with g^d >= n * density (in 2-D ceil(sqrt(n * density))).
    backend : {"opencl", "numpy"}

    Notes
    -----
    Lloyd's method alternates two steps that each lower the CVT energy E = mean over
    density points of the squared toroidal distance to the nearest site: assign every
    density point to its nearest site, then move every site to the centroid of its cell.
    On the torus the centroid is taken with the cell's points unwrapped relative to the
    site (its own image nearest the site).

    Every iteration runs in OpenCL: the nearest-site assignment of
    :mod:`clsamp.geometry.voronoi` (exact, through a grid of the sites), per-site
    centroid sums with integer atomics, then the move. Positions are integers on a 2^22
    torus (:mod:`clsamp.geometry.integer_torus`), so the result is the same on every
    device and in the NumPy reference. The same holds in 1-D, 3-D and 4-D (the
    depth-of-field case of a renderer): the density grid has g^d points, the sites' grid
    2^(kd) cells, and each density point searches rings of cells around its own.

    ``sample(..., return_info=True)`` also returns a :class:`LloydInfo`: E after every
    iteration, measured by a fresh assignment, which never rises -- exactly: moving a site
    by the rounded mean of its cell's offsets does not raise that cell's energy, and
    re-assigning points to their nearest site can only lower it. A site whose cell is
    empty (possible after a degenerate start: duplicate sites, a cluster) is moved onto
    the density point farthest from its site, one such point a site, farthest first; that
    cannot raise E either. With few density points a site (``density`` 1 or 2) there can
    be fewer such points than empty sites, and some sites stay empty. N*E of the returned
    set is :func:`clsamp.metrics.normalized_energy` (0.160375 for the hexagonal lattice,
    about 1/pi for white noise).

    References
    ----------
    .. [1] S. Lloyd, "Least squares quantization in PCM", IEEE Trans. Inf. Theory 28(2),
       1982.
    .. [2] Q. Du, V. Faber, M. Gunzburger, "Centroidal Voronoi tessellations: applications
       and algorithms", SIAM Review 41(4), 1999.

    Examples
    --------
    >>> import clsamp
    >>> s = clsamp.make_sampler("lloyd", seed=1, iterations=10, density=64)
    >>> pts, info = s.sample(64, return_info=True)
    >>> pts.shape, info.energy_history.shape
    ((64, 2), (1, 10))
    >>> bool(64 * info.energy_history[0, -1] < 0.2)
    True
    """

    info = LloydInfo
    dimensions = voronoi.DIMENSIONS
    needs_fp64 = False        # exact integers on the torus: 64-bit atomics, no double

    def __init__(self, d=2, seed=0, iterations=50, density=256, backend="opencl"):
        super().__init__(d=d, seed=seed, backend=backend)
        self.iterations = check_positive_int(iterations, "iterations", maximum=MAX_ITERATIONS)
        self.density = check_positive_int(density, "density")

    def _most_sites(self):
        # the largest n whose density grid (g^d >= n * density points) has 32-bit counts
        if _fits(self.density, self.max_n, self.d):
            return self.max_n
        lo, hi = 1, self.max_n
        while hi - lo > 1:
            mid = (lo + hi) // 2
            lo, hi = (mid, hi) if _fits(self.density, mid, self.d) else (lo, mid)
        return lo

    def _check_n(self, n):
        _check_density(self.density, n, self.d)     # its message, before the sites
        return super()._check_n(n)

    def _optimize(self, sites, realizations, backend):
        density = _check_density(self.density, sites.shape[1], self.d)
        return _run(sites, np.arange(realizations.start, realizations.stop), density,
                    self.iterations, backend)
