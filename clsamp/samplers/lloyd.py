"""The ``lloyd`` sampler: periodic Lloyd relaxation towards a centroidal Voronoi tessellation.

OpenCL: ``kernels/voronoi.cl`` (all realizations in one launch per step); NumPy
reference: :func:`lloyd_reference` here (``backend="numpy"``), the same integers.
"""

import dataclasses
import math

import numpy as np

from .. import runtime
from ..errors import InvalidArgumentError
from ..validation import check_positive_int
from . import voronoi
from .base import register

LLOYD_SEGMENT = 16   # density points per work-item (LLOYD_SEGMENT in kernels/voronoi.cl)


@dataclasses.dataclass
class LloydResult:
    """What :func:`lloyd_relax` returns.

    Attributes
    ----------
    points : ndarray (r, n, 2)
        The relaxed sites, float64 in [0, 1).
    energy_history : ndarray (r, iterations)
        Mean squared toroidal distance of the density points to their nearest site,
        for the sites after each iteration (entry t: after t + 1 moves), float64.
    counts : ndarray (r, n)
        Density points in each returned site's Voronoi cell.
    initial_energy : ndarray (r,)
        The same energy for the starting sites.
    """

    points: np.ndarray
    energy_history: np.ndarray
    counts: np.ndarray
    initial_energy: np.ndarray


def lloyd_grid_size(n):
    """Cells per axis of the site grid: the largest power of two G with G^2 <= n (1 to 4
    sites a cell); a power of two makes every cell exactly 2^BITS / G wide."""
    G = 1
    while 4 * G * G <= n:
        G *= 2
    return G


def density_side(n, density):
    """Side g of the regular g x g density grid: the smallest with g^2 >= n * density."""
    return math.isqrt(n * density - 1) + 1


def density_coordinates(g):
    """Integer coordinates of the density grid's cell centres along one axis (length g)."""
    k = np.arange(g, dtype=np.int64)
    return ((2 * k + 1) << voronoi.BITS) // (2 * g)


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
    coords = density_coordinates(g)
    for site, seg in zip(empty, order, strict=False):
        m = int(far_index[seg])
        sites[site] = (coords[m % g], coords[m // g])


def _assign_reference(sites, g):
    """Nearest site (ties to the lower index) of every density point of one realization:
    (label, d2, dx, dy), all int64, brute force in chunks."""
    coords = density_coordinates(g)
    M = g * g
    m = np.arange(M, dtype=np.int64)
    X, Y = coords[m % g], coords[m // g]
    n = sites.shape[0]
    label = np.empty(M, dtype=np.int64)
    best = np.empty(M, dtype=np.int64)
    step = max(1, (1 << 21) // n)
    sx, sy = sites[:, 0].astype(np.int64), sites[:, 1].astype(np.int64)
    for lo in range(0, M, step):
        hi = min(M, lo + step)
        d2 = voronoi.distance2(X[lo:hi, None], Y[lo:hi, None], sx[None, :], sy[None, :])
        label[lo:hi] = np.argmin(d2, axis=1)
        best[lo:hi] = d2[np.arange(hi - lo), label[lo:hi]]
    return label, best, voronoi.delta(X, sx[label]), voronoi.delta(Y, sy[label])


def segment_count(g):
    """Work-items of lloyd_assign per realization: each row of the g x g density grid in
    pieces of LLOYD_SEGMENT points."""
    return g * (-(-g // LLOYD_SEGMENT))


def _segment_far(d2, g):
    """Each segment's farthest density point (d2, index): the kernel's far_d2/far_index."""
    per_row = -(-g // LLOYD_SEGMENT)
    padded = np.full((g, per_row * LLOYD_SEGMENT), -1, dtype=np.int64)
    padded[:, :g] = d2.reshape(g, g)
    blocks = padded.reshape(g * per_row, LLOYD_SEGMENT)
    arg = np.argmax(blocks, axis=1)
    seg = np.arange(g * per_row)
    return blocks[seg, arg], (seg // per_row) * g + (seg % per_row) * LLOYD_SEGMENT + arg


def lloyd_reference(sites, g, iterations):
    """NumPy twin of :func:`_lloyd_device`: integer sites (r, n, 2) -> (sites, energies, counts),
    energies as Python ints (sums of squared distances) for passes 0..iterations."""
    sites = np.array(sites, dtype=np.int64)
    r, n, _ = sites.shape
    energies = [[0] * (iterations + 1) for _ in range(r)]
    counts = np.zeros((r, n), dtype=np.int64)
    for k in range(r):
        s = sites[k]
        for t in range(iterations + 1):
            label, d2, dx, dy = _assign_reference(s, g)
            energies[k][t] = voronoi.split_total(d2)
            c = np.bincount(label, minlength=n).astype(np.int64)
            if t == iterations:
                counts[k] = c
                break
            # exact: |sums| < 2^53, which float64 bincount holds exactly
            sumx = np.bincount(label, weights=dx, minlength=n).astype(np.int64)
            sumy = np.bincount(label, weights=dy, minlength=n).astype(np.int64)
            full = c > 0
            s[full, 0] = (s[full, 0] + voronoi.round_mean(sumx[full], c[full])) & voronoi.MASK
            s[full, 1] = (s[full, 1] + voronoi.round_mean(sumy[full], c[full])) & voronoi.MASK
            if not full.all():
                far_d2, far_index = _segment_far(d2, g)
                _reseed(s, c, far_d2, far_index, g)
    return sites.astype(np.uint32), energies, counts


def _lloyd_device(sites, g, iterations):
    """OpenCL Lloyd on integer sites (r, n, 2): (sites, energies, counts) as the reference."""
    import pyopencl.array as cla
    runtime.require_fp64()
    q = runtime.queue()
    r, n, _ = sites.shape
    G = lloyd_grid_size(n)
    segments = segment_count(g)
    d_sites = cla.to_device(q, np.ascontiguousarray(sites, dtype=np.uint32))
    cell_start = cla.empty(q, (r, G * G + 1), np.uint32)
    cell_sites = cla.empty(q, (r, n), np.uint32)
    acc = cla.zeros(q, (r, n, 3), np.int64)
    energy = cla.zeros(q, (r, iterations + 1, 2), np.int64)
    far_d2 = cla.empty(q, (r, segments), np.int64)
    far_index = cla.empty(q, (r, segments), np.uint32)
    counts = cla.empty(q, (r, n), np.uint32)
    empty = cla.zeros(q, (r,), np.uint32)
    build = runtime.kernel("voronoi.cl", "voronoi_build_grid")
    assign = runtime.kernel("voronoi.cl", "lloyd_assign")
    move = runtime.kernel("voronoi.cl", "lloyd_move")
    u32 = np.uint32
    for t in range(iterations + 1):
        build(q, (r,), None, d_sites.data, u32(n), u32(G), cell_start.data, cell_sites.data, u32(r))
        assign(q, (segments, r), None, d_sites.data, u32(n), u32(G), cell_start.data,
               cell_sites.data, u32(g), u32(segments), acc.data, energy.data,
               u32(2 * (iterations + 1)), u32(2 * t), far_d2.data, far_index.data)
        if t == iterations:
            break
        move(q, (n, r), None, d_sites.data, u32(n), acc.data, counts.data, empty.data)
        holes = empty.get()
        if holes.any():
            host_sites = d_sites.get().astype(np.int64)
            c, fd, fi = counts.get(), far_d2.get(), far_index.get()
            for k in np.flatnonzero(holes):
                _reseed(host_sites[k], c[k], fd[k], fi[k], g)
            d_sites.set(host_sites.astype(np.uint32))
            empty.fill(0)
    e = energy.get()
    energies = [voronoi.exact_total(e[k, :, 0], e[k, :, 1]) for k in range(r)]
    final_counts = acc.get()[:, :, 2]
    return d_sites.get(), energies, final_counts


def lloyd_relax(sites, density=256, iterations=50, backend="opencl"):
    """Periodic Lloyd relaxation of given starting sites on the unit torus.

    Parameters
    ----------
    sites : ndarray (n, 2) or (r, n, 2)
        Starting sites in [0, 1) (duplicates and clusters are fine).
    density : int
        Density points per site: the density is the regular g x g grid of cell centres
        with g = ceil(sqrt(n * density)).
    iterations : int
        Lloyd steps (assign, then move every site to its cell's centroid).
    backend : {"opencl", "numpy"}

    Returns
    -------
    LloydResult
        Batch-shaped (r, ...) even for one set.
    """
    batch, _ = voronoi.check_sites(sites)
    n = batch.shape[1]
    density = check_positive_int(density, "density")
    iterations = check_positive_int(iterations, "iterations")
    return _run(batch, n, density, iterations, backend)


def _run(sites, n, density, iterations, backend):
    g = density_side(n, density)
    if backend == "numpy":
        final, energies, counts = lloyd_reference(sites, g, iterations)
    else:
        final, energies, counts = _lloyd_device(sites, g, iterations)
    scale = float(g * g) * float(voronoi.SIZE) ** 2
    e = np.array([[float(v) for v in row] for row in energies]) / scale
    return LloydResult(points=voronoi.to_unit(final), energy_history=e[:, 1:],
                       counts=np.asarray(counts, dtype=np.int64), initial_energy=e[:, 0])


@register("lloyd")
class LloydSampler(voronoi.VoronoiSampler):
    """Periodic Lloyd relaxation: sites moved to the centroids of their Voronoi cells.

    Parameters
    ----------
    d : int
        Must be 2 (the unit torus [0, 1)^2; distances wrap).
    seed : int
        Seeds the starting sites (Philox, ``Stream.INIT``; realization k's start does not
        depend on how many realizations are drawn).
    iterations : int
        Lloyd steps (default 50).
    density : int
        Density points per site (default 256): a regular g x g grid of cell centres,
        g = ceil(sqrt(n * density)).
    backend : {"opencl", "numpy"}

    Attributes
    ----------
    energy_history : ndarray
        After ``sample``: E after each iteration, (iterations,) or (r, iterations).
    normalized_energy : float or ndarray (r,)
        N*E of the returned set(s).
    relative_radius : float or ndarray (r,)
        rho of the returned set(s) (:func:`clsamp.point_metrics.relative_radius`).
    counts : ndarray (n,) or (r, n)
        Density points in each returned site's Voronoi cell (none is empty).

    Notes
    -----
    Lloyd's method (Lloyd 1982; Du, Faber, Gunzburger 1999) alternates two steps that
    each lower the CVT energy E = mean over density points of the squared toroidal
    distance to the nearest site: assign every density point to its nearest site, then
    move every site to the centroid of its cell. On the torus the centroid is taken with
    the cell's points unwrapped relative to the site (its own image nearest the site).

    Every iteration runs in OpenCL: the sites are counting-sorted into a grid of power-
    of-two cells, each density point finds its nearest site by searching rings of cells
    until no unvisited cell can hold a nearer one (exact), and per-site centroid sums are
    accumulated with integer atomics. Positions are integers on a 2^22 torus
    (:mod:`clsamp.samplers.voronoi`), so the result is the same on every device and in
    the NumPy reference.

    ``energy_history[t]`` is E of the sites after t + 1 iterations, measured by a fresh
    nearest-site assignment (the last entry is the energy of the returned points). It
    never rises, exactly: moving a site by the rounded mean of its cell's offsets does not
    raise that cell's energy (see ``vor_round_mean``), and re-assigning points to their
    nearest site can only lower it. A site whose cell is empty (possible after a
    degenerate start: duplicate sites, a cluster) is moved onto the density point
    farthest from its site, which it then captures; that cannot raise E either.
    ``normalized_energy`` is N*E (0.160375 for the hexagonal lattice, about 1/pi for
    white noise).

    References
    ----------
    S. Lloyd, "Least squares quantization in PCM", IEEE Trans. Inf. Theory 28(2), 1982.
    Q. Du, V. Faber, M. Gunzburger, "Centroidal Voronoi tessellations: applications and
    algorithms", SIAM Review 41(4), 1999.

    Examples
    --------
    >>> import clsamp
    >>> s = clsamp.make_sampler("lloyd", seed=1, iterations=10, density=64)
    >>> pts = s.sample(64)
    >>> pts.shape, s.energy_history.shape
    ((64, 2), (10,))
    >>> bool(s.normalized_energy < 0.2)
    True
    """

    def __init__(self, d=2, seed=0, iterations=50, density=256, backend="opencl"):
        super().__init__(d=d, seed=seed, backend=backend)
        self.iterations = check_positive_int(iterations, "iterations")
        self.density = check_positive_int(density, "density")
        self.counts = None

    def _optimize(self, sites, realizations, backend=None):
        n = sites.shape[1]
        if n * self.density > 2**32 - 1:
            raise InvalidArgumentError(
                f"'density' * n must stay below 2^32 density points, got {self.density} * {n}")
        return _run(sites, n, self.density, self.iterations, backend or self.backend)

    def _keep(self, result, single):
        super()._keep(result, single)
        self.counts = result.counts[0] if single else result.counts
