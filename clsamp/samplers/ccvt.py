"""The ``ccvt`` sampler: capacity-constrained Voronoi tessellation (Balzer et al. 2009).

OpenCL: ``kernels/ccvt.cl`` (all realizations in one launch per step); NumPy reference:
:func:`ccvt_reference` here (``backend="numpy"``), the same integers.
"""

import dataclasses
import math

import numpy as np

from .. import philox, runtime
from ..errors import InvalidArgumentError
from ..validation import check_choice, check_positive_int
from . import voronoi
from .base import register

CCVT_TOP = 16          # candidates per site and round (CCVT_TOP in kernels/ccvt.cl)
MAX_POINTS_PER_SITE = voronoi.MAX_CELL_POINTS
# The swap phases of one iteration: (ox, oy, parity); (0, 0) pairs the sites inside a cell.
PHASES = ((0, 0, 0),) + tuple((ox, oy, parity) for ox, oy in ((1, 0), (0, 1), (1, 1), (1, -1))
                              for parity in (0, 1))


@dataclasses.dataclass
class CCVTResult:
    """What :func:`ccvt_optimize` returns.

    Attributes
    ----------
    points : ndarray (r, n, 2)
        The sites, float64 in [0, 1).
    energy_history : ndarray (r, iterations)
        Mean squared toroidal distance of the density points to the site owning them,
        after each iteration (swaps, then sites to centroids). A realization that
        converged early repeats its final value (further iterations change nothing).
    capacities : ndarray (r, n)
        Density points owned by each site at the end, counted from the ownership.
    iterations : ndarray (r,)
        Iterations each realization ran (the last one made no exchange if it converged).
    converged : ndarray (r,) of bool
        Whether an iteration made no exchange (a local optimum) within the cap.
    """

    points: np.ndarray
    energy_history: np.ndarray
    capacities: np.ndarray
    iterations: np.ndarray
    converged: np.ndarray


NEAR = 2   # neighbours: sites closer than NEAR / sqrt(n) (about twice the hexagonal spacing)


def ccvt_near2(n):
    """Squared distance (integer torus units) below which two sites are neighbours and
    exchange points: (NEAR / sqrt(n))^2. A site's Voronoi neighbours in a CCVT lie within
    about 1.4 / sqrt(n); this is the pair graph, found through the grid, never all pairs."""
    return (NEAR * NEAR * voronoi.SIZE * voronoi.SIZE) // n


def ccvt_grid_size(n):
    """Cells per axis of the site grid: even, at least 2, and with cells at least NEAR /
    sqrt(n) wide, so every neighbour pair is in the same or adjacent cells."""
    return max(2, (math.isqrt(n) // NEAR) // 2 * 2)


DENSITIES = ("jittered", "random")


def density_rows(M):
    """Rows of the jittered density: isqrt(M). Row i holds points floor(i M / k) to
    floor((i+1) M / k) - 1, so every row has isqrt(M) to isqrt(M) + 2 cells and every
    cell is within a factor (1 + 2 / isqrt(M))^2 of square."""
    return max(1, math.isqrt(M))


def density_points(seed, realizations, M, density="jittered"):
    """The density, uint32 (r, M, 2) on the integer torus.

    ``"random"``: M i.i.d. uniform points from words 4, 5 (Philox block 1) of
    (seed, Stream.INIT, r, j). ``"jittered"``: the same words place point j uniformly in
    its own stratum of an equal-area partition of the torus into exactly M cells:
    k = :func:`density_rows` rows, row i of height c_i / M cut into c_i cells of width
    1 / c_i, c_i = floor((i+1) M / k) - floor(i M / k) (Bresenham: any M, near-square
    cells, unlike a kx-by-ky grid that needs a divisor of M and degenerates into 1 x M
    strips for prime M); then the whole set is shifted by a random toroidal offset (words
    6, 7 of (seed, Stream.INIT, r, 0)), which makes the density, hence the optimized
    sites, stationary on the torus. All integer arithmetic, exact in 64 bits. The sites'
    starting positions use words 0, 1 of block 0."""
    check_choice(density, "density", DENSITIES)
    r = np.asarray(realizations, dtype=np.uint32)[:, None, None]
    j = np.arange(M, dtype=np.uint32)[None, :, None]
    w = np.arange(4, 6, dtype=np.uint32)[None, None, :]
    u = philox.random_words(seed, philox.Stream.INIT, r, j, w) >> np.uint32(32 - voronoi.BITS)
    if density == "random":
        return u
    k = np.uint64(density_rows(M))
    M64, bits = np.uint64(M), np.uint64(voronoi.BITS)
    j = np.arange(M, dtype=np.uint64)
    row = ((j + np.uint64(1)) * k - np.uint64(1)) // M64
    start = row * M64 // k
    c = ((row + np.uint64(1)) * M64 // k - start)[None, :]
    u = u.astype(np.uint64)
    x = (((j - start)[None, :] << bits) + u[..., 0]) // c
    y = ((start[None, :] << bits) + u[..., 1] * c) // M64
    shift = philox.random_words(seed, philox.Stream.INIT, r[:, :, 0], np.uint32(0),
                                np.arange(6, 8, dtype=np.uint32)[None, :])
    shift = (shift >> np.uint32(32 - voronoi.BITS)).astype(np.uint64)
    mask = np.uint64(voronoi.MASK)
    return np.stack([(x + shift[:, 0:1]) & mask, (y + shift[:, 1:2]) & mask],
                    axis=-1).astype(np.uint32)


def density_points_device(seed, realizations, M, density="jittered"):
    """:func:`density_points` made by the ``ccvt_density`` / ``ccvt_density_jittered``
    kernels (the same integers)."""
    import pyopencl.array as cla
    check_choice(density, "density", DENSITIES)
    realizations = np.asarray(realizations)
    r = len(realizations)
    out = cla.empty(runtime.queue(), (r, M, 2), np.uint32)
    if r and not np.array_equal(realizations, realizations[0] + np.arange(r)):
        raise ValueError("realizations must be consecutive")
    if r == 0:
        return out.get()
    key = (*runtime.key_args(seed), np.uint32(philox.Stream.INIT))
    if density == "random":
        kernel = runtime.kernel("ccvt.cl", "ccvt_density")
        kernel(runtime.queue(), (M, r), None, out.data, np.uint32(M),
               np.uint32(realizations[0]), *key)
    else:
        kernel = runtime.kernel("ccvt.cl", "ccvt_density_jittered")
        kernel(runtime.queue(), (M, r), None, out.data, np.uint32(M),
               np.uint32(density_rows(M)), np.uint32(realizations[0]), *key)
    return out.get()


def kd_partition(sites, points, p):
    """A starting ownership with exact capacities that follows the sites: a principal-axis
    k-d tree. The points of a node are cut perpendicular to their principal axis, the
    sites at their median along it and the points at the matching count (k_left * p), and
    so on down to one site with p points. Cutting across the longest extent keeps the
    parts compact, and the cut directions vary from realization to realization (the top
    one is the noise of a square's covariance), so the start has none of the axis-aligned
    grid structure a plain x/y k-d tree imposes. Keys are made unique by the index, so
    the split is canonical. Vectorized over realizations (the tree's sizes depend only
    on n).

    Returns members (r, n, p), point indices.
    """
    r, n, _ = sites.shape
    rows = np.arange(r)[:, None]
    members = np.empty((r, n, p), dtype=np.uint32)
    sites = sites.astype(np.float64)
    points = points.astype(np.float64)
    stack = [(np.broadcast_to(np.arange(n, dtype=np.int64), (r, n)),
              np.broadcast_to(np.arange(points.shape[1], dtype=np.int64), (r, points.shape[1]))),
             ]
    while stack:
        S, P = stack.pop()
        k = S.shape[1]
        if k == 1:
            members[np.arange(r), S[:, 0]] = P
            continue
        left = k // 2
        px, py = points[rows, P, 0], points[rows, P, 1]
        dx = px - px.mean(axis=1, keepdims=True)
        dy = py - py.mean(axis=1, keepdims=True)
        angle = 0.5 * np.arctan2(2.0 * (dx * dy).mean(axis=1, keepdims=True),
                                 (dx * dx).mean(axis=1, keepdims=True)
                                 - (dy * dy).mean(axis=1, keepdims=True))
        c, s = np.cos(angle), np.sin(angle)
        skey = (np.floor(sites[rows, S, 0] * c + sites[rows, S, 1] * s).astype(np.int64) << 32) | S
        smask = skey <= np.partition(skey, left - 1, axis=1)[:, left - 1:left]
        pkey = (np.floor(px * c + py * s).astype(np.int64) << 32) | P
        cut = left * p
        pmask = pkey <= np.partition(pkey, cut - 1, axis=1)[:, cut - 1:cut]
        stack.append((S[~smask].reshape(r, k - left), P[~pmask].reshape(r, -1)))
        stack.append((S[smask].reshape(r, left), P[pmask].reshape(r, cut)))
    return members


def _centroids_reference(sites, points, members, site_energy, which):
    """One realization's centroid step for the sites ``which`` (``ccvt_centroids``): moves
    them, refreshes their entries of site_energy, returns the total energy (int)."""
    px = points[members[which], 0].astype(np.int64)
    py = points[members[which], 1].astype(np.int64)
    p = members.shape[1]
    s = sites[which]
    x = (s[:, 0] + voronoi.round_mean(voronoi.delta(px, s[:, 0:1]).sum(1), p)) & voronoi.MASK
    y = (s[:, 1] + voronoi.round_mean(voronoi.delta(py, s[:, 1:2]).sum(1), p)) & voronoi.MASK
    sites[which] = np.stack([x, y], axis=1)
    site_energy[which] = voronoi.distance2(px, py, x[:, None], y[:, None]).sum(axis=1)
    return voronoi.split_total(site_energy)


def _gains(x, a, b):
    """Gains 2 u.D - |D|^2 of the points x (owned by the site at a) toward the site at b:
    u = delta(x, a), D = delta(b, a) (``ccvt_top``)."""
    dx, dy = voronoi.delta(b[0], a[0]), voronoi.delta(b[1], a[1])
    u = voronoi.delta(x[:, 0], a[0]), voronoi.delta(x[:, 1], a[1])
    return 2 * (u[0] * dx + u[1] * dy) - (dx * dx + dy * dy)


def _pair_reference(mi, mj, points, si, sj):
    """Balzer's swap of one pair, in place on the member rows mi, mj (the kernel's ccvt_pair)."""
    total = 0
    while True:
        gi = _gains(points[mi], si, sj)
        gj = _gains(points[mj], sj, si)
        oi = np.lexsort((mi, -gi))[:CCVT_TOP]
        oj = np.lexsort((mj, -gj))[:CCVT_TOP]
        positive = (gi[oi] + gj[oj]) > 0
        done = int(np.argmin(positive)) if not positive.all() else positive.size
        a, b = oi[:done], oj[:done]
        mi[a], mj[b] = mj[b].copy(), mi[a].copy()
        total += done
        if done < CCVT_TOP:
            return total


def _sweep_reference(sites, points, members, G, touched):
    """One realization's swap phases; returns the number of exchanges and marks the sites
    whose members changed in ``touched``."""
    start, order = voronoi.build_grid(sites, G)

    def cell(cx, cy):
        c = cy * G + cx
        return order[start[c]:start[c + 1]]

    near2 = ccvt_near2(len(sites))

    def pair(i, j):
        if voronoi.distance2(sites[i, 0], sites[i, 1], sites[j, 0], sites[j, 1]) >= near2:
            return 0
        made = _pair_reference(members[i], members[j], points, sites[i], sites[j])
        if made:
            touched[i] = touched[j] = True
        return made

    total = 0
    for ox, oy, parity in PHASES:
        if ox == 0 and oy == 0:
            for cy in range(G):
                for cx in range(G):
                    inside = cell(cx, cy)
                    for qa in range(len(inside)):
                        for qb in range(qa + 1, len(inside)):
                            total += pair(inside[qa], inside[qb])
            continue
        for a in range(G // 2):
            for b in range(G):
                ax, ay = (2 * a + parity, b) if ox else (b, 2 * a + parity)
                bx, by = (ax + ox) % G, (ay + oy) % G
                for i in cell(ax, ay):
                    for j in cell(bx, by):
                        total += pair(i, j)
    return total


def ccvt_reference(sites, points, members, iterations, callback=None):
    """NumPy twin of :func:`_ccvt_device`: (sites, energies, members, converged), energies as
    Python ints (sums of squared distances), one per iteration run."""
    sites = np.array(sites, dtype=np.int64)
    members = np.array(members, dtype=np.int64)
    r, n, p = members.shape
    G = ccvt_grid_size(n)
    energies = [[] for _ in range(r)]
    converged = np.zeros(r, dtype=bool)
    for k in range(r):
        site_energy = np.zeros(n, dtype=np.int64)
        _centroids_reference(sites[k], points[k], members[k], site_energy, np.ones(n, bool))
        for _ in range(iterations):
            touched = np.zeros(n, dtype=bool)
            swaps = _sweep_reference(sites[k], points[k], members[k], G, touched)
            e = _centroids_reference(sites[k], points[k], members[k], site_energy, touched)
            energies[k].append(e)
            if swaps == 0:
                converged[k] = True
                break
    if callback is not None:
        callback(members.astype(np.uint32), sites.astype(np.uint32))
    return sites.astype(np.uint32), energies, members.astype(np.uint32), converged


def _ccvt_device(sites, points, members, iterations, callback=None, fused=None):
    """OpenCL CCVT: integer sites (r, n, 2), points (r, M, 2), members (r, n, p).

    With ``fused`` (default: when there are at least twice as many realizations as compute
    units and no callback) each realization runs whole in one work-group (``ccvt_solve``,
    one launch); otherwise every step is its own launch over all realizations, which keeps
    a single large realization spread over the whole device. Both give the same bits.
    """
    import pyopencl.array as cla
    runtime.require_fp64()
    q = runtime.queue()
    r, n, p = members.shape
    if fused is None:
        fused = callback is None and r >= 2 * runtime.current_device().compute_units
    if fused:
        return _ccvt_solve_device(sites, points, members, iterations)
    G = ccvt_grid_size(n)
    near2 = ccvt_near2(n)
    u32 = np.uint32
    d_sites = cla.to_device(q, np.ascontiguousarray(sites, dtype=np.uint32))
    members = np.ascontiguousarray(members, dtype=np.uint32)
    d_members = cla.to_device(q, members)
    # each slot carries its point's coordinates, so the kernels stream instead of gathering
    d_xy = cla.to_device(q, np.ascontiguousarray(
        np.asarray(points, dtype=np.uint32)[np.arange(r)[:, None, None], members]))
    cell_start = cla.empty(q, (r, G * G + 1), np.uint32)
    cell_sites = cla.empty(q, (r, n), np.uint32)
    active_host = np.ones(r, dtype=np.uint32)
    active = cla.to_device(q, active_host)
    reach2 = cla.zeros(q, (r, n), np.int64)
    dirty = cla.zeros(q, (r, n), np.uint32)
    touched = cla.zeros(q, (r, n), np.uint32)
    energy = cla.zeros(q, (r, 2), np.int64)
    site_energy = cla.zeros(q, (r, n), np.int64)
    swaps = cla.zeros(q, (r,), np.uint32)
    build = runtime.kernel("ccvt.cl", "voronoi_build_grid")
    swap = runtime.kernel("ccvt.cl", "ccvt_swap")
    centroids = runtime.kernel("ccvt.cl", "ccvt_centroids")

    def centroid_step(everything):
        centroids(q, (n, r), None, d_sites.data, u32(n), u32(p), d_xy.data, active.data,
                  reach2.data, dirty.data, touched.data, site_energy.data, energy.data,
                  u32(everything))

    centroid_step(True)      # the sites to the centroids of the starting partition
    dirty.fill(1)        # every pair meets in the first iteration
    energies = [[] for _ in range(r)]
    converged = np.zeros(r, dtype=bool)
    for _ in range(iterations):
        build(q, (r,), None, d_sites.data, u32(n), u32(G), cell_start.data, cell_sites.data, u32(r))
        swaps.fill(0)
        for ox, oy, parity in PHASES:
            size = (G if ox == 0 and oy == 0 else G // 2, G, r)
            swap(q, size, None, d_members.data, d_xy.data, u32(n), u32(p),
                 d_sites.data, cell_start.data, cell_sites.data, u32(G), np.int32(ox),
                 np.int32(oy), u32(parity), active.data, reach2.data, dirty.data,
                 touched.data, swaps.data, np.int64(near2))
        centroid_step(False)
        made = swaps.get()
        totals = voronoi.exact_total(*energy.get().T)
        for k in np.flatnonzero(active_host):
            energies[k].append(totals[k])
        if callback is not None:
            callback(d_members.get(), d_sites.get())
        done = (active_host == 1) & (made == 0)
        if done.any():
            converged |= done
            active_host[done] = 0
            if not active_host.any():
                break
            active.set(active_host)
    return d_sites.get(), energies, d_members.get(), converged


def _ccvt_solve_device(sites, points, members, iterations):
    """``ccvt_solve``: one work-group per realization, one launch for everything."""
    import pyopencl.array as cla
    q = runtime.queue()
    r, n, p = members.shape
    G = ccvt_grid_size(n)
    members = np.ascontiguousarray(members, dtype=np.uint32)
    d_members = cla.to_device(q, members)
    d_xy = cla.to_device(q, np.ascontiguousarray(
        np.asarray(points, dtype=np.uint32)[np.arange(r)[:, None, None], members]))
    d_sites = cla.to_device(q, np.ascontiguousarray(sites, dtype=np.uint32))
    cell_start = cla.empty(q, (r, G * G + 1), np.uint32)
    cell_sites = cla.empty(q, (r, n), np.uint32)
    reach2 = cla.zeros(q, (r, n), np.int64)
    dirty = cla.zeros(q, (r, n), np.uint32)
    touched = cla.zeros(q, (r, n), np.uint32)
    site_energy = cla.zeros(q, (r, n), np.int64)
    history = cla.zeros(q, (r, iterations, 2), np.int64)
    state = cla.zeros(q, (r, 2), np.uint32)
    local = runtime.local_size(64)
    solve = runtime.kernel("ccvt.cl", "ccvt_solve")
    solve(q, (local * r,), (local,), d_members.data, d_xy.data, np.uint32(n), np.uint32(p),
          d_sites.data, cell_start.data, cell_sites.data, np.uint32(G), reach2.data, dirty.data,
          touched.data, site_energy.data, np.int64(ccvt_near2(n)), np.uint32(iterations),
          history.data, state.data)
    h, st = history.get(), state.get()
    energies = [voronoi.exact_total(h[k, :st[k, 0], 0], h[k, :st[k, 0], 1]) for k in range(r)]
    return d_sites.get(), energies, d_members.get(), st[:, 1].astype(bool)


def ccvt_optimize(sites, points_per_site=1024, iterations=200, seed=0, backend="opencl",
                  callback=None, density="jittered"):
    """CCVT from given starting sites on the unit torus.

    Parameters
    ----------
    sites : ndarray (n, 2) or (r, n, 2)
        Starting sites in [0, 1) (duplicates and clusters are fine).
    points_per_site : int
        Capacity: density points per site (M = n * points_per_site in all).
    iterations : int
        Cap on the iterations; the optimization stops earlier when an iteration makes
        no exchange.
    seed : int
        Seeds the density points (realization k uses (seed, Stream.INIT, k)).
    backend : {"opencl", "numpy"}
    callback : callable, optional
        ``callback(members, sites)`` with the ownership (r, n, p) and the integer sites
        after every iteration (OpenCL) or at the end (NumPy); for tests.
    density : {"jittered", "random"}
        The density points: one per cell of an equal-area stratification (default) or
        i.i.d. uniform (:func:`density_points`; see :class:`CCVTSampler`).

    Returns
    -------
    CCVTResult
        Batch-shaped (r, ...) even for one set.
    """
    batch, _ = voronoi.check_sites(sites)
    points_per_site = _check_points_per_site(points_per_site, batch.shape[1])
    iterations = check_positive_int(iterations, "iterations")
    check_choice(density, "density", DENSITIES)
    return _run(batch, np.arange(batch.shape[0]), points_per_site, iterations, seed,
                backend, callback, density)


def _check_points_per_site(points_per_site, n):
    p = check_positive_int(points_per_site, "points_per_site", maximum=MAX_POINTS_PER_SITE)
    if n * p > 2**32 - 1:
        raise InvalidArgumentError(
            f"'points_per_site' * n must stay below 2^32 density points, got {p} * {n}")
    return p


def _run(sites, realizations, p, iterations, seed, backend, callback=None, density="jittered"):
    r, n, _ = sites.shape
    M = n * p
    results = []
    for lo, hi in runtime.chunk_ranges(r, 16 * M + 64 * n):
        make = density_points if backend == "numpy" else density_points_device
        points = make(seed, realizations[lo:hi], M, density)
        members = kd_partition(sites[lo:hi], points, p)
        run = ccvt_reference if backend == "numpy" else _ccvt_device
        results.append((points,) + run(sites[lo:hi], points, members, iterations, callback))
    length = max(len(e) for part in results for e in part[2])
    history, capacities, counts = [], [], []
    for _, _, energies, members, _ in results:
        for k, e in enumerate(energies):
            counts.append(len(e))
            history.append([float(v) for v in e] + [float(e[-1])] * (length - len(e)))
            # counted from the ownership itself: a point listed twice would leave another unowned
            owner = np.full(M, n, dtype=np.int64)
            owner[members[k].ravel().astype(np.int64)] = np.repeat(np.arange(n), p)
            capacities.append(np.bincount(owner, minlength=n + 1)[:n])
    scale = float(M) * float(voronoi.SIZE) ** 2
    return CCVTResult(points=voronoi.to_unit(np.concatenate([part[1] for part in results])),
                      energy_history=np.asarray(history) / scale,
                      capacities=np.asarray(capacities), iterations=np.asarray(counts),
                      converged=np.concatenate([part[4] for part in results]))


@register("ccvt")
class CCVTSampler(voronoi.VoronoiSampler):
    """Capacity-constrained Voronoi tessellation: blue noise with exactly equal cells.

    Parameters
    ----------
    d : int
        Must be 2 (the unit torus [0, 1)^2; distances wrap).
    seed : int
        Seeds the starting sites and the density points (Philox, ``Stream.INIT``;
        realization k does not depend on how many realizations are drawn).
    points_per_site : int
        Capacity of every site, default 1024: M = n * points_per_site density points are
        drawn and each site owns exactly that many at every moment.
    iterations : int
        Cap on the iterations (default 200); each realization stops at the first
        iteration in which no exchange lowers the energy.
    backend : {"opencl", "numpy"}
    density : {"jittered", "random"}
        How the M density points are drawn. ``"jittered"`` (default): one uniform point
        in each cell of an equal-area partition of the torus into exactly M near-square
        cells, the whole set shifted by a random toroidal offset per realization.
        ``"random"``: M i.i.d. uniform points, as in Balzer et al. (see Notes for why
        that is not the default).

    Attributes
    ----------
    energy_history : ndarray
        After ``sample``: E after each iteration, (iterations,) or (r, iterations); a
        realization that converged before the others repeats its final value.
    capacities : ndarray (n,) or (r, n)
        Density points owned by each site, counted from the final ownership.
    normalized_energy : float or ndarray (r,)
        N*E of the returned set(s).
    relative_radius : float or ndarray (r,)
        rho of the returned set(s) (:func:`clsamp.point_metrics.relative_radius`).
    iterations_run, converged : int / bool, or ndarray (r,)
        Iterations each realization ran; whether it stopped because no exchange improved.

    Notes
    -----
    Balzer, Schloemer and Deussen minimize the energy E = mean over density points of
    the squared toroidal distance to the site owning them, under the constraint that
    every site owns the same number of points. The start is a principal-axis k-d
    partition of the points that follows the random starting sites, exact in capacity
    (:func:`kd_partition`; the sites then move to its centroids). Each iteration then
    (1) exchanges points between neighbouring sites i, j: the candidates of each are
    ordered by the gain of moving to the other site, and pairs are exchanged in order
    while the two gains sum to more than zero (the paper's heap-based swap, here in
    rounds of the 16 best candidates a side); (2) moves every site whose points changed
    to the periodic centroid of its points. Both steps lower E, so ``energy_history``
    never rises, and since an exchange is one point for one point, ``capacities`` are all
    equal at every moment. The optimization stops at the first iteration that makes no
    exchange (a local optimum: no neighbour pair can improve), or at ``iterations``.

    Neighbours are sites closer than 2 / sqrt(n) (about twice the hexagonal spacing;
    Voronoi neighbours of a CCVT lie within about 1.4 / sqrt(n)), found through an even
    grid of cells at least that wide: never all n^2 pairs. The gain of a point x of i
    is ``2 u.D - |D|^2`` (u: x relative to s_i, D: s_j relative to s_i), its exact
    change of squared distance unless the torus brings another image of s_j nearer, in
    which case the true change is larger: exchanges accepted on these gains lower E at
    least as much. In OpenCL the pairs of one launch are disjoint: nine phases pair
    the sites inside each cell, then each cell with its neighbour along (1,0), (0,1),
    (1,1), (1,-1), cells of one parity at a time, so no site is in two pairs at once (a
    deterministic matching of the neighbour graph). Pairs that cannot have changed since
    they last met, and pairs farther apart than twice the reach of both sites, are
    skipped (both exact), so an iteration costs O(n p). A batch runs one realization
    per work-group in a single launch; one large set runs step by step over the whole
    device; both give the same bits, as does the NumPy reference. Positions are
    integers on a 2^22 torus (:mod:`clsamp.samplers.voronoi`): energies are exact sums
    and E never rises exactly, not up to rounding.

    Why the density is stratified: a site owns exactly p = ``points_per_site`` density
    points, so its cell's true area is whatever area those p points happen to cover.
    With i.i.d. points that area is a random count, relative spread about 1 / sqrt(p),
    and it never averages out: every cell's share of an integral is off by that much,
    which puts an N^-1 floor under the Monte Carlo MSE (measured with
    :func:`clsamp.convergence`, p = 64, Gaussian integrand: slope -0.97, against the
    N^-3 best case / N^-1.5 worst case Pilleboue et al. give for CCVT). One point per
    equal-area stratum (jittered sampling) makes the covered area nearly exact; the
    same measurement then falls at -2.5 (MSE at N = 1024 four orders of magnitude
    lower), the disk integrand at -1.47 instead of -1.16. The strata are rows of
    equal-area cells, isqrt(M) rows of isqrt(M) to isqrt(M) + 2 cells (Bresenham
    split), so any M works and no cell is far from square (a kx-by-ky grid needs a
    divisor of M and degenerates into strips when M is prime); the per-realization
    shift makes the point process stationary. The optimizer also converges in fewer
    iterations and to a lower energy (1024 x 1024: about 200 iterations and N*E 0.1673,
    against 380 and 0.1684 with i.i.d. points). The cost is regularity: the noise of
    i.i.d. points is what keeps Balzer's CCVT from settling into Lloyd-like lattice
    patches, and with the stratified density the sets are more regular (rho 0.72 against
    0.63 at 96 x 64) with peaks of the power spectrum along the axes near the site
    frequency (about 3 against 1.2 at |k| 7 to 9; the torus favours lattices aligned with
    it; a tilted stratification gives the same peaks). Integrands with strong edges feel
    that: the disk gains little below N = 1024, and ambient occlusion at 96 rays (render
    test, 64 per site, six seeds) has 10 % more error than with i.i.d. points.
    ``density="random"`` keeps the i.i.d. density (bit for bit the earlier results).

    ``normalized_energy`` is N*E over the density points: 0.160375 for the hexagonal
    lattice, about 1/pi for white noise; Balzer et al.'s code reaches about 0.1677 at
    1024 sites x 1024 points. Fewer points per site make the optimum coarser (about
    0.171 to 0.175 at 64 to 256 per site, realizations of one size spreading by about
    +-0.003 across local optima).

    Cost: iterations until convergence grow with ``points_per_site`` (about 100 to 200 at
    1024 per site, 10 to 25 at 64); at the default 1024 per site a 1024-point set takes
    about 7 to 12 s here (PoCL, 2 shared cores), as with i.i.d. density points: the
    stratified density needs about half the iterations but makes more exchanges in each.

    References
    ----------
    M. Balzer, T. Schloemer, O. Deussen, "Capacity-constrained point distributions:
    a variant of Lloyd's method", ACM Trans. Graph. 28(3) (SIGGRAPH), 2009.

    A. Pilleboue, G. Singh, D. Coeurjolly, M. Kazhdan, V. Ostromoukhov, "Variance
    analysis for Monte Carlo integration", ACM Trans. Graph. 34(4) (SIGGRAPH), 2015.

    Examples
    --------
    >>> import clsamp
    >>> s = clsamp.make_sampler("ccvt", seed=3, points_per_site=32)
    >>> pts = s.sample(64)
    >>> int(s.capacities.min()), int(s.capacities.max())
    (32, 32)
    >>> bool(s.normalized_energy < 0.2)
    True
    """

    def __init__(self, d=2, seed=0, points_per_site=1024, iterations=200, backend="opencl",
                 density="jittered"):
        super().__init__(d=d, seed=seed, backend=backend)
        self.points_per_site = check_positive_int(points_per_site, "points_per_site",
                                                  maximum=MAX_POINTS_PER_SITE)
        self.iterations = check_positive_int(iterations, "iterations")
        self.density = check_choice(density, "density", DENSITIES)
        self.capacities = None
        self.iterations_run = None
        self.converged = None

    def _optimize(self, sites, realizations, backend=None):
        p = _check_points_per_site(self.points_per_site, sites.shape[1])
        return _run(sites, np.asarray(realizations, dtype=np.int64), p, self.iterations,
                    self.seed, backend or self.backend, density=self.density)

    def _keep(self, result, single):
        super()._keep(result, single)
        pick = (lambda a: a[0]) if single else (lambda a: a)
        self.capacities = pick(result.capacities)
        self.iterations_run = pick(result.iterations)
        self.converged = pick(result.converged)
