"""The ``ccvt`` sampler: capacity-constrained Voronoi tessellation (Balzer et al. 2009).

OpenCL: ``kernels/ccvt.cl`` (all realizations in one launch per step); NumPy reference:
:func:`ccvt_reference` here (``backend="numpy"``), the same integers.
The start's power pass: ``kernels/ccvt_start.cl``, twin :func:`power_pass_reference`.
"""

import dataclasses
import math

import numpy as np

from .. import philox, runtime
from ..errors import InvalidArgumentError
from ..validation import check_choice, check_int, check_positive_int
from . import voronoi
from .base import register

CCVT_TOP = 16          # candidates per site and round (CCVT_TOP in kernels/ccvt.cl)
CCVT_SECTORS = 16      # angular sectors of a site's buckets (CCVT_SECTORS in kernels/ccvt.cl)
CCVT_BUCKETS = 64      # buckets per site: 16 sectors x 4 bands (CCVT_BUCKETS in kernels/ccvt.cl)
CCVT_META = 7 + CCVT_BUCKETS + CCVT_SECTORS   # int64 record per site (CCVT_META in ccvt.cl)
MAX_POINTS_PER_SITE = voronoi.MAX_CELL_POINTS
TAIL_SHARE = 8    # the last iterations, from n / TAIL_SHARE exchanges or fewer, in one launch
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
        kernel = runtime.kernel("ccvt.cl", "ccvt_density", _defines())
        kernel(runtime.queue(), (M, r), None, out.data, np.uint32(M),
               np.uint32(realizations[0]), *key)
    else:
        kernel = runtime.kernel("ccvt.cl", "ccvt_density_jittered", _defines())
        kernel(runtime.queue(), (M, r), None, out.data, np.uint32(M),
               np.uint32(density_rows(M)), np.uint32(realizations[0]), *key)
    return out.get()


START_OCCUPANCY = 2    # sites per cell of the start's grid: a 3 x 3 block offers about 18
START_CHUNK = 1 << 16  # candidate distances computed at once by the NumPy twin
START_CROWD = 16       # more sites in one cell: the sites are clustered (kd_partition)
START_LATTICE = 8      # the weights' proxy density: up to 8 x 8 lattice points per site
START_SHARE = 8        # ... and never more than p / START_SHARE per site
START_MIN_SIDE = 4     # ... but at least 4 x 4
START_SWEEPS = 10      # weight updates on the proxy lattice
START_STEP = 0.3       # fraction of each site's own (diagonal Newton) weight step
START_SMOOTH = 1.0     # Gaussian width of the large-scale weight correction, in site spacings
START_SLOPE = 0.25     # margin, in squared site spacings, of the points that measure dc/dw
RELAX_STEPS = 8        # the relaxation the docs measure: moves of the sites on the lattice
MAX_RELAX = 64         # the most relaxation steps accepted
START_RELAX_SWEEPS = 2  # weight updates before each of those moves
START_FINAL_SWEEPS = 1  # ... and after the last, from the weights they leave
RELAY_BATCH = 128      # carried points a site hands on per round (more wait a round)
NO_OWNER = 0xFFFFFFFF  # a point with no candidate site (ccvt_power's owner then)
NO_SECOND = (1 << 63) - 1


def _start_table(xy, ids, G, pad):
    """Candidate table of one realization for :func:`start_partition`: row c lists the
    sites (global ids, ascending, padded with ``pad``) of the 3 x 3 cells of a G x G grid
    around cell c, or all the sites when G == 1. Returns (table, lengths)."""
    if G == 1:
        return ids[None, :].copy(), np.array([len(ids)])
    start, order = voronoi.build_grid(xy, G)
    count = np.diff(start)
    cy, cx = np.divmod(np.arange(G * G), G)
    near = np.stack([((cy + oy) % G) * G + (cx + ox) % G
                     for oy in (-1, 0, 1) for ox in (-1, 0, 1)], axis=1).ravel()
    each = count[near]                              # sites in each (cell, neighbour) pair
    lengths = each.reshape(G * G, 9).sum(axis=1)
    total = int(each.sum())
    within = np.arange(total) - np.repeat(np.cumsum(each) - each, each)
    site = ids[order[np.repeat(start[near], each) + within]]
    col = np.arange(total) - np.repeat(np.cumsum(lengths) - lengths, lengths)
    table = np.full((G * G, max(1, int(lengths.max()))), pad, dtype=np.int64)
    table[np.repeat(np.arange(G * G), lengths), col] = site
    table.sort(axis=1)                              # index order: argmin breaks ties by index
    return table, lengths


def kd_partition(sites, points, p):
    """The starting ownership where sites are too crowded for :func:`start_partition`
    (duplicates, tight clusters): exact capacities that follow the sites, from a
    principal-axis k-d tree. It cuts the unit square, not the torus, so its cells meet
    seams on x = 0 and y = 0; that is why it is not the start for spread-out sites.
    The points of a node are cut perpendicular to their principal axis, the
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


def _start_grid_size(n):
    """Cells per axis of the start's candidate grid: about START_OCCUPANCY sites per cell,
    and 1 (every site a candidate) below 4, where 3 x 3 cells would repeat."""
    G = math.isqrt(n // START_OCCUPANCY)
    return G if G >= 4 else 1


def power_pass_reference(points, sites, weight, G):
    """NumPy twin of the ``ccvt_power`` kernel (``kernels/ccvt_start.cl``).

    For every point, the two smallest power distances ``|x - s_i|^2 - w_i`` (exact int64
    on the integer torus) among the sites of the 3 x 3 cells of a G x G grid around it
    (every site when G == 1), in the order (power distance, site index).

    Parameters
    ----------
    points : ndarray (r, M, 2) or (1, M, 2)
        Integer torus coordinates; one set of shape (1, M, 2) serves every realization.
    sites : ndarray (r, n, 2)
    weight : ndarray (r, n) of int64
    G : int
        1, or at least 4 (:func:`_start_grid_size`).

    Returns
    -------
    owner, second : ndarray (r, M) of uint32
        Site indices; ``owner`` is ``NO_OWNER`` where no site is a candidate, ``second``
        equals ``owner`` where only one is.
    margin : ndarray (r, M) of int64
        Power distance to ``second`` minus that to ``owner`` (``NO_SECOND`` if none).
    """
    return _PowerPass(sites, G, "numpy")(points, weight)


def _power_pass_device(points, sites, weight, G):
    """:func:`power_pass_reference` by the ``ccvt_power`` kernel (the same integers)."""
    return _PowerPass(sites, G, "opencl")(points, weight)


class _PowerPass:
    """The power passes over one set of sites (:func:`power_pass_reference`), their
    candidate tables (and, in OpenCL, their buffers and the last point set's) prepared
    once."""

    def __init__(self, sites, G, backend):
        self.sites, self.G, self.backend = sites, G, backend
        r, n, _ = sites.shape
        self.tables = [_start_table(sites[k].astype(np.int64), np.arange(n), G, n)[0]
                       for k in range(r)]
        if backend == "numpy":
            return
        import pyopencl.array as cla
        q = runtime.queue()
        # every realization's table padded to one width W, as (r, cells, W)
        W = max(t.shape[1] for t in self.tables) if r else 1
        self.table = np.stack([np.pad(t, ((0, 0), (0, W - t.shape[1])), constant_values=n)
                               for t in self.tables]) if r else np.zeros((0, 1, 1), np.int64)
        padded = np.concatenate([np.asarray(sites, dtype=np.uint32),
                                 np.zeros((r, 1, 2), dtype=np.uint32)], axis=1)
        xy = padded[np.arange(r)[:, None, None], self.table]
        self.buffers = [cla.to_device(q, np.ascontiguousarray(a)) for a in
                        (self.table.astype(np.uint32), xy)]
        self.points = (None, None)

    def __call__(self, points, weight, owner_only=False):
        """(owner, second, margin) of ``points`` under ``weight``; ``owner_only``: owner."""
        if self.backend == "numpy":
            out = self._reference(points, weight)
        else:
            out = self._device(points, weight, owner_only)
        return out[:1] if owner_only else out

    def _device(self, points, weight, owner_only):
        import pyopencl.array as cla
        q = runtime.queue()
        r, n, _ = self.sites.shape
        M = points.shape[1]
        if self.points[0] is not points:            # the lattice serves every sweep
            self.points = (points, cla.to_device(q, np.ascontiguousarray(points, dtype=np.uint32)))
        owner = cla.empty(q, (r, M), np.uint32)
        second = cla.empty(q, (r, M), np.uint32)
        margin = cla.empty(q, (r, M), np.int64)
        if r and M:
            ids, xy = self.buffers
            w = np.concatenate([np.asarray(weight, dtype=np.int64), np.zeros((r, 1), np.int64)],
                               axis=1)[np.arange(r)[:, None, None], self.table]
            kernel = runtime.kernel("ccvt_start.cl", "ccvt_power")
            kernel(q, (M, r), None, self.points[1].data, np.uint32(M),
                   np.uint32(M if points.shape[0] > 1 else 0), ids.data, xy.data,
                   cla.to_device(q, np.ascontiguousarray(w)).data, np.uint32(n),
                   np.uint32(self.G), np.uint32(self.table.shape[2]),
                   owner.data, second.data, margin.data)
        if owner_only:
            return (owner.get(),)
        return owner.get(), second.get(), margin.get()

    def _reference(self, points, weight):
        sites = self.sites
        r, n, _ = sites.shape
        G = self.G
        M = points.shape[1]
        owner = np.empty((r, M), dtype=np.uint32)
        second = np.empty((r, M), dtype=np.uint32)
        margin = np.empty((r, M), dtype=np.int64)
        for k in range(r):
            xy = sites[k].astype(np.int64)
            table = self.tables[k]
            sx, sy = np.append(xy[:, 0], 0), np.append(xy[:, 1], 0)
            w = np.append(np.asarray(weight[k], dtype=np.int64), 0)
            pts = points[k if points.shape[0] > 1 else 0].astype(np.int64)
            cell = voronoi.cell_of(pts[:, 1], G) * G + voronoi.cell_of(pts[:, 0], G)
            width = max(1, START_CHUNK // table.shape[1])
            for lo in range(0, M, width):
                cand = table[cell[lo:lo + width]]
                dx = voronoi.delta(pts[lo:lo + width, 0:1], sx[cand])
                dy = voronoi.delta(pts[lo:lo + width, 1:2], sy[cand])
                c = dx * dx + dy * dy - w[cand]
                c[cand == n] = NO_SECOND
                rows = np.arange(len(cand))
                # rows are in ascending site order: the first minimum has the smallest index
                b1 = np.argmin(c, axis=1)
                c1 = c[rows, b1]
                c[rows, b1] = NO_SECOND
                b2 = np.argmin(c, axis=1)
                c2 = c[rows, b2]
                i1 = np.where(c1 == NO_SECOND, NO_OWNER, cand[rows, b1])
                lone = c2 == NO_SECOND
                owner[k, lo:lo + width] = i1
                second[k, lo:lo + width] = np.where(lone, i1, cand[rows, b2])
                margin[k, lo:lo + width] = np.where(lone, NO_SECOND, c2 - c1)
        return owner, second, margin


def _power_counts(owner, n):
    """Points per site (r, n) from a power pass's owners (points with none left out)."""
    r = owner.shape[0]
    flat = owner.astype(np.int64) + (np.arange(r) * n)[:, None]
    flat = flat[owner != NO_OWNER]
    return np.bincount(flat, minlength=r * n).reshape(r, n)


def _nearest_site2(sites, G, tables=None):
    """Squared distance (r, n) from each site to its nearest other site among the 3 x 3
    cells around it (every site when G == 1; SIZE^2 when it has none there); ``tables``:
    the sites' :func:`_start_table` rows, when already built."""
    r, n, _ = sites.shape
    out = np.full((r, n), float(voronoi.SIZE) ** 2)
    for k in range(r):
        xy = sites[k].astype(np.int64)
        table = _start_table(xy, np.arange(n), G, n)[0] if tables is None else tables[k]
        cell = voronoi.cell_of(xy[:, 1], G) * G + voronoi.cell_of(xy[:, 0], G)
        nb = table[cell]
        ext = np.append(xy, [[0, 0]], axis=0)
        d2 = voronoi.distance2(xy[:, 0:1], xy[:, 1:2], ext[nb, 0], ext[nb, 1]).astype(np.float64)
        d2[(nb == n) | (nb == np.arange(n)[:, None])] = np.inf
        out[k] = np.minimum(d2.min(axis=1), out[k])
    return out


def _start_lattice(n, p):
    """The proxy density of the start's weights: a regular lattice of up to
    ``START_LATTICE``^2 points per site (at most p / START_SHARE, at least
    ``START_MIN_SIDE``^2: the relaxation of :func:`start_sites` moves the sites to means
    of these), (1, m, 2)."""
    side = max(START_MIN_SIDE, min(START_LATTICE, math.isqrt(p // START_SHARE)))
    side *= max(1, math.isqrt(n))
    g = ((2 * np.arange(side, dtype=np.int64) + 1) << voronoi.BITS) // (2 * side)
    return np.stack(np.meshgrid(g, g), axis=-1).reshape(1, -1, 2).astype(np.uint32)


def start_weights(sites, p, G, power, weight=None, sweeps=START_SWEEPS, with_owner=False):
    """Power weights (r, n) int64 under which the power cells of the sites hold nearly
    equal shares of the unit torus: ``sweeps`` updates, from ``weight`` (default 0),
    measured on the lattice of :func:`_start_lattice` (``power``: a :class:`_PowerPass`
    of the sites); ``with_owner``: also the lattice's owners (r, m) in the last of them
    (under the weights before its update). Each update adds two parts. Large scale: cells
    whose sites are crowded are too small, and a smooth weight field f with Laplacian
    2 (c / c_mean - 1) (the excess count density, Gaussian-smoothed over START_SMOOTH
    site spacings, solved by FFT on the torus) moves every boundary so that the areas
    balance to first order (the power diagram under a smooth f is the Voronoi diagram
    displaced by -grad f / 2); a purely local update would need about n iterations to
    spread that. Small scale: each site's own Newton step -(c_i - c_mean) / (dc_i/dw_i),
    times START_STEP, the derivative counted from the lattice points whose margin to a
    neighbour is below START_SLOPE, and the step capped so that it moves the boundary
    with the nearest other site by at most a quarter of their distance (a near-duplicate
    pair needs tiny weight differences to share). Host arithmetic shared by both
    backends."""
    r, n, _ = sites.shape
    if with_owner and sweeps < 1:
        raise ValueError("start_weights: with_owner needs at least one sweep")
    lattice = _start_lattice(n, p)
    per = lattice.shape[1] / n
    unit2 = float(voronoi.SIZE) ** 2
    spacing2 = unit2 / n
    tau = START_SLOPE * spacing2
    K = 1 << max(3, math.ceil(math.log2(max(1.0, math.sqrt(n)))))
    freq = np.fft.fftfreq(K) * K
    k2 = (2 * np.pi) ** 2 * (freq[:, None] ** 2 + freq[None, :] ** 2)
    k2[0, 0] = 1.0
    solve = 2.0 * np.exp(-0.5 * k2 * START_SMOOTH ** 2 / n) / k2
    solve[0, 0] = 0.0
    u = sites.astype(np.float64) * (K / voronoi.SIZE) - 0.5    # cell centres at (c + 1/2) / K
    c0 = np.floor(u).astype(np.int64)
    fx, fy = u[..., 0] - c0[..., 0], u[..., 1] - c0[..., 1]
    x0, y0 = c0[..., 0] % K, c0[..., 1] % K
    x1, y1 = (x0 + 1) % K, (y0 + 1) % K
    rows = np.arange(r)[:, None]
    cell = rows * K * K + (sites[..., 1].astype(np.int64) * K >> voronoi.BITS) * K \
        + (sites[..., 0].astype(np.int64) * K >> voronoi.BITS)
    cap = 0.5 * np.sqrt(_nearest_site2(sites, G, power.tables) * spacing2)
    w = np.zeros((r, n)) if weight is None else np.asarray(weight, dtype=np.float64).copy()
    for _ in range(sweeps):
        owner, second, margin = power(lattice, np.rint(w).astype(np.int64))
        excess = _power_counts(owner, n) / per - 1.0
        near = (margin < tau) & (owner != NO_OWNER)
        ends = np.concatenate([(owner.astype(np.int64) + rows * n)[near],
                               (second.astype(np.int64) + rows * n)[near]])
        slope = np.bincount(ends, minlength=r * n).reshape(r, n) / (2.0 * tau * per)
        slope = np.maximum(slope, 0.5 / spacing2)     # a site with no boundary points yet
        density = np.bincount(cell.ravel(), excess.ravel(), r * K * K).reshape(r, K, K) * (K * K / n)
        f = np.real(np.fft.ifft2(np.fft.fft2(density) * solve)) * unit2
        smooth = (f[rows, y0, x0] * (1 - fx) * (1 - fy) + f[rows, y0, x1] * fx * (1 - fy)
                  + f[rows, y1, x0] * (1 - fx) * fy + f[rows, y1, x1] * fx * fy)
        w -= smooth + np.clip(START_STEP * excess / slope, -cap, cap)
        w -= w.mean(axis=1, keepdims=True)
    if with_owner:
        return np.rint(w).astype(np.int64), owner
    return np.rint(w).astype(np.int64)


def start_sites(sites, p, backend="opencl", steps=RELAX_STEPS):
    """The given sites relaxed on the lattice of the start's weights
    (:func:`_start_lattice`): a capacity-constrained Lloyd on a coarse proxy of the
    density, the optional first step of the start (``relax`` of :class:`CCVTSampler`).

    ``steps`` times, the power weights get START_RELAX_SWEEPS updates
    (:func:`start_weights`, from the last ones) and every site moves 3/2 of the way to
    the periodic mean of the lattice points of its power cell in the last of those
    sweeps, rounded (a site with none stays). Random sites crowd in places and leave
    gaps in others; the swaps of the optimization spread them one exchange at a time, the
    relaxation in a few coarse steps, so the optimization then has far less to do and
    ends lower, but the set it ends at is more regular. At 1024 x 1024 with 8 steps,
    seed 1: 114 iterations instead of 311, capacity N*E 0.16618 against 0.16821, the
    set's 0.16549 against 0.16717; seeds 1 to 3: 137 iterations against 267 on average,
    0.16631 against 0.16831 and 0.16557 against 0.16721, rho 0.755 against 0.745. The
    radial mean of the expected spectrum (8 sets of 1024 sites x 256 points, seed 1)
    peaks at 2.89 instead of 2.09 and dips to 0.43 instead of 0.59 beyond the peak; the
    sets show rows of hexagonal order, the structure Lloyd's method settles into and
    CCVT exists to avoid. 2 steps leave the spectrum as it was (peak 2.13) and the
    iterations too (271 against 267); 4 steps: peak 2.40, 190 iterations. The
    over-relaxed step (plain steps go all the way) does more per step: seeds 1 to 9 at 8
    steps, 119 iterations on average against 158, capacity N*E 0.16637 against 0.16717.

    Exact integers, the same with both backends. Sites crowded into one cell of the
    start's grid (:func:`start_partition`) stay as they are. The weights of the last
    sweep come back too: START_FINAL_SWEEPS updates from them balance the cells of the
    moved sites as well as START_SWEEPS from zero do (1024 x 1024, seed 1: 8680 density
    points over capacity against 8878).

    Parameters
    ----------
    sites : ndarray (r, n, 2)
        Integer torus coordinates.
    p : int
        Capacity of every site (sizes the lattice).
    backend : {"opencl", "numpy"}
        Where the power passes run (the same result).
    steps : int
        Relaxation steps (0: the sites as they are).

    Returns
    -------
    sites : ndarray (r, n, 2) of uint32
    weight : ndarray (r, n) of int64 or None
        The power weights for :func:`start_partition` (None when nothing was relaxed).
    """
    check_choice(backend, "backend", ("opencl", "numpy"))
    r, n, _ = sites.shape
    out = np.array(sites, dtype=np.uint32)
    G = _start_grid_size(n)
    spread = np.flatnonzero(~_crowded(out, G))
    if not spread.size or not steps:
        return out, None
    sub = out[spread]
    lattice = _start_lattice(n, p)
    lx, ly = (lattice[0, :, k].astype(np.int64) for k in (0, 1))
    rows = np.arange(len(spread))[:, None]
    weight = None
    for _ in range(steps):
        power = _PowerPass(sub, G, backend)
        weight, owner = start_weights(sub, p, G, power, weight, START_RELAX_SWEEPS, True)
        owner = owner.astype(np.int64)
        ok = owner != NO_OWNER
        flat = (owner + rows * n)[ok]
        xy = sub.astype(np.int64)
        count = np.bincount(flat, minlength=len(spread) * n)
        moved = []
        for axis, coord in ((0, lx), (1, ly)):
            s = xy[..., axis].ravel()
            u = voronoi.delta(np.broadcast_to(coord, owner.shape)[ok], s[flat])
            total = np.bincount(flat, u, len(spread) * n)      # exact: |sum| < 2^53
            # 3/2 of the way to the centroid, rounded (over-relaxed: fewer steps do more)
            step = voronoi.round_mean(3 * np.rint(total).astype(np.int64),
                                      2 * np.maximum(count, 1))
            moved.append((s + np.where(count > 0, step, 0)) & voronoi.MASK)
        sub = np.stack(moved, axis=-1).reshape(len(spread), n, 2).astype(np.uint32)
    out[spread] = sub
    full = np.zeros((r, n), dtype=np.int64)
    full[spread] = weight
    return out, full


def _crowded(sites, G):
    """Which realizations have more than START_CROWD sites in one cell of the start's grid
    (duplicates, clusters: power weights cannot separate a pile of coincident sites)."""
    if G < 4:
        return np.zeros(sites.shape[0], dtype=bool)
    cells = voronoi.cell_of(sites[..., 1], G) * G + voronoi.cell_of(sites[..., 0], G)
    return np.array([np.bincount(c, minlength=G * G).max() > START_CROWD for c in cells])


def start_partition(sites, points, p, backend="opencl", weight=None):
    """The starting ownership of CCVT: every site owns exactly p density points, near it,
    with no seam and no preferred direction on the torus.

    Three steps, all deterministic (integers, and host arithmetic shared by the backends):

    1. Power weights w (:func:`start_weights`): START_SWEEPS updates measured on a
       lattice proxy of the density (START_FINAL_SWEEPS from ``weight``, those of
       :func:`start_sites`, when given), so that the power cells
       {x : |x - s_i|^2 - w_i <= |x - s_j|^2 - w_j for all j} hold nearly equal shares.
       Random sites crowd in some places and leave gaps in others, so equal cells need
       boundaries shifted over several site spacings; the weights shift them all at once
       (at 1024 x 1024, seed 1, mean |count - p| falls from 42% of p for the Voronoi
       cells to 3%, and the points over capacity from 21% to 1.4%).
    2. Every point goes to its power-nearest site (the ``ccvt_power`` kernel, or
       :func:`power_pass_reference` with ``backend="numpy"``: the same integers) among
       the sites in the 3 x 3 cells of a grid of about ``START_OCCUPANCY`` sites per cell
       around it (all sites when n < 32), ties to the smaller site index. A site given
       more than p keeps its first p in index order; the rest, and points with no
       candidate, are carried on.
    3. Excess is passed along to neighbouring sites (:func:`_relay`): a site holding k
       carried points hands on the k of its points (the carried ones included) that
       lose least by moving, to its neighbour b (closer than NEAR / sqrt(n)) nearest to
       the nearest site with room, until every carried point rests at a site with room.
       Every hand-over moves a point one neighbour on, so the excess travels as a shift
       of boundaries, never as a jump of a point to a far site (reach at 1024 x 1024,
       seed 1, in units of 1 / sqrt(n): median 0.66, 99% 1.67, 99.9% 2.0, max 2.9; the
       deferred-acceptance greedy this replaced, which placed the points all nearby
       sites turned away at any site with room: 0.47, 7.9, 17.0, 19.6).

    The cells are power cells trimmed at their boundaries: no cut along x = 0 or y = 0
    and no axis-aligned structure (a k-d partition of the unit square leaves a cross in
    the power spectrum that the optimization keeps). Vectorized over realizations.
    Sites crowded into one cell of the grid (more than ``START_CROWD``: duplicates,
    clusters) take :func:`kd_partition` instead: power weights cannot separate a pile of
    coincident sites.

    The optimization from this start ends at about the N*E it reached from the greedy
    start (64 sets of 256 sites x 64 points, seeds 1 and 2: 0.17494 against 0.17493;
    eight of 128 x 256, seed 4: 0.1717 against 0.1715; one set of 1024 x 1024, seeds 1 to
    8: 0.16835 against 0.16828, a paired difference of 0.00007 +- 0.00008 where seeds
    spread by 0.0002), in about as many iterations (1024 x 1024: 237 against 251 on
    average).

    Parameters
    ----------
    sites : ndarray (r, n, 2)
        Integer torus coordinates.
    points : ndarray (r, n * p, 2)
        Integer torus coordinates of the density points.
    p : int
        Capacity of every site.
    backend : {"opencl", "numpy"}
        Where the power passes run (the same result).
    weight : ndarray (r, n) of int64, optional
        Power weights to start the updates from (:func:`start_sites`).

    Returns
    -------
    ndarray (r, n, p) of uint32
        Point indices owned by each site, ascending.

    References
    ----------
    F. Aurenhammer, F. Hoffmann, B. Aronov, "Minkowski-type theorems and least-squares
    clustering", Algorithmica 20, 1998 (power diagrams with prescribed cell sizes).
    """
    check_choice(backend, "backend", ("opencl", "numpy"))
    r, n, _ = sites.shape
    M = points.shape[1]
    S = r * n
    G = _start_grid_size(n)
    crowded = _crowded(sites, G)
    spread = np.flatnonzero(~crowded)
    owner = np.empty((r, M), dtype=np.int64)
    if crowded.any():
        owner[crowded] = np.repeat(np.arange(n), p)     # a placeholder where kd_partition runs
    if spread.size:
        sub = sites[spread]
        power = _PowerPass(sub, G, backend)
        if weight is None:
            w = start_weights(sub, p, G, power)
        else:
            w = start_weights(sub, p, G, power, weight[spread], START_FINAL_SWEEPS)
        best = power(points[spread], w, owner_only=True)[0]
        owner[spread] = np.where(best == NO_OWNER, -1, best)
    owner += (np.arange(r) * n)[:, None] * (owner >= 0)
    owner = owner.ravel()
    mat, over = _members_matrix(owner, S, p)
    if spread.size:
        left = np.union1d(np.flatnonzero(owner < 0), over)
        _relay(sites, points, mat, (mat < 0).sum(axis=1), left, owner[left])
    members = (mat.reshape(r, n, p) - (np.arange(r) * M)[:, None, None]).astype(np.uint32)
    if crowded.any():
        members[crowded] = kd_partition(sites[crowded], points[crowded], p)
    return members


def _members_matrix(owner, S, p):
    """Owners (-1: none yet) as a (S, p) matrix of point ids, ascending in each row, rows
    of sites with room ending in -1. A site given more than p keeps its first p (in id
    order). Returns (matrix, the ids it could not keep, ascending)."""
    key = np.where(owner < 0, S, owner)
    # a radix sort where the site ids fit in 16 bits; each site's ids are then one run of
    # `order`, ascending, and a row is the first p of its run, gathered in one go
    order = np.argsort(key.astype(np.uint16) if S < 1 << 16 else key, kind="stable")
    count = np.bincount(key, minlength=S + 1)[:S]
    start = np.cumsum(count) - count
    take = np.minimum(count, p)
    col = np.arange(p)
    mat = order[np.minimum(start[:, None] + col, max(len(order) - 1, 0))]
    mat = np.where(col < take[:, None], mat, -1)
    extra = count - take
    over = np.flatnonzero(extra)
    ends = np.cumsum(extra[over])
    pos = np.repeat(start[over] + p - ends + extra[over], extra[over]) + np.arange(ends[-1] if
                                                                              over.size else 0)
    return mat, np.sort(order[pos])


def _runs(sorted_ids):
    """Values, first positions and lengths of the runs of a sorted array (np.unique's)."""
    if not len(sorted_ids):
        return sorted_ids, sorted_ids, sorted_ids
    first = np.flatnonzero(np.concatenate([[True], sorted_ids[1:] != sorted_ids[:-1]]))
    return sorted_ids[first], first, np.diff(np.append(first, len(sorted_ids)))


def _relay(sites, points, mat, room, left, start):
    """Places the carried points ``left`` (global ids) by passing excess along
    neighbouring sites (:func:`start_partition`, step 3).

    ``mat`` (S, p) holds the point ids of every site (-1: room), ``room`` its free slots;
    a carried point starts at ``start`` (its power owner; -1: none, then at the site with
    room nearest to it). Each round, a site a holding carried points fills its room with
    them (in id order); if k remain (at most RELAY_BATCH; more wait a round), it picks
    its target, the site with room nearest to it (ties: smaller index), and its next hop
    b: of its neighbours (sites closer than NEAR / sqrt(n), the optimizer's pairs), the
    one nearest to the target, or, where none is nearer to it than a (a gap in the
    sites), the site nearest to a of those nearer to the target. Of its p points and the
    k carried, the k with the smallest gain |u - D|^2 - |u|^2 of moving to b (u, D: the
    toroidal offsets of the point and of s_b from s_a; ties: the earlier slot, the
    carried last) are carried on to b, and the carried ones not chosen take the freed
    slots. The distance to the target falls with every hop and room is never lost, so
    every point comes to rest; the capacities stay
    exact at every step. Updates ``mat`` (rows left ascending) and ``room`` in place."""
    if not left.size:
        return
    r, n, _ = sites.shape
    M = points.shape[1]
    S, p = mat.shape
    sx = sites[..., 0].ravel().astype(np.int64)
    sy = sites[..., 1].ravel().astype(np.int64)
    px = points[..., 0].ravel().astype(np.int64)
    py = points[..., 1].ravel().astype(np.int64)
    # neighbours: the sites of the 3 x 3 cells around each site's cell
    G = _start_grid_size(n)
    near = []
    for k in range(r):
        xy = np.stack([sx[k * n:(k + 1) * n], sy[k * n:(k + 1) * n]], axis=1)
        table, _ = _start_table(xy, k * n + np.arange(n), G, -1)
        cell = voronoi.cell_of(xy[:, 1], G) * G + voronoi.cell_of(xy[:, 0], G) if G > 1 \
            else np.zeros(n, dtype=np.int64)
        near.append(table[cell])
    width = max(t.shape[1] for t in near)
    near = np.concatenate([np.pad(t, ((0, 0), (0, width - t.shape[1])), constant_values=-1)
                           for t in near])
    own = np.arange(S)[:, None]
    near = np.where(near < 0, own, near)              # padding: the site itself
    # neighbours as the optimizer's pairs: closer than NEAR / sqrt(n)
    far = voronoi.distance2(sx[near], sy[near], sx[own], sy[own]) >= ccvt_near2(n)
    near = np.where(far, own, near)

    def nearest_room(x, y, realization):
        # the sites with room of every realization, ascending, padded (all at once)
        has = room.reshape(r, n) > 0
        count = has.sum(axis=1)
        width = max(1, int(count.max()))
        ids = np.argsort(~has, axis=1, kind="stable")[:, :width] + (np.arange(r) * n)[:, None]
        cand = ids[realization]
        d2 = voronoi.distance2(x[:, None], y[:, None], sx[cand], sy[cand])
        d2[np.arange(width)[None, :] >= count[realization][:, None]] = np.iinfo(np.int64).max
        return cand[np.arange(len(x)), np.argmin(d2, axis=1)]   # ties: the smaller index

    # a site's 3 x 3 cells hold every site within one cell width of it, so a room found
    # among its neighbours nearer than that (or than NEAR / sqrt(n) with one cell) is the
    # nearest room of all, ties included (rows ascending); the rest search everything
    reach2 = ccvt_near2(n) if G == 1 else (voronoi.SIZE // G) ** 2

    def nearest_room_of_sites(a):
        nb = near[a]
        d2 = voronoi.distance2(sx[nb], sy[nb], sx[a, None], sy[a, None])
        d2[room[nb] <= 0] = np.iinfo(np.int64).max
        pick = np.argmin(d2, axis=1)
        rows = np.arange(len(a))
        out = nb[rows, pick]
        miss = d2[rows, pick] >= reach2
        if miss.any():
            out[miss] = nearest_room(sx[a[miss]], sy[a[miss]], a[miss] // n)
        return out

    carry = left.copy()
    realization = carry // M
    target = np.full(S, -1, dtype=np.int64)         # each site's target, while it has room
    wide = S * r * M < 1 << 62                      # (site, point) keys fit in one int64
    cur = np.asarray(start, dtype=np.int64).copy()
    lost = cur < 0
    if lost.any():                                  # no candidate at all: straight to room
        cur[lost] = nearest_room(px[carry[lost]], py[carry[lost]], realization[lost])
    while carry.size:
        # the carried points by site, in the order of the points: groups of one site
        order = np.argsort(cur * (r * M) + carry) if wide else np.lexsort((carry, cur))
        carry, cur, realization = carry[order], cur[order], realization[order]
        sites_at, first, size = _runs(cur)
        rank = np.arange(len(carry)) - np.repeat(first, size)
        free = np.repeat(room[sites_at], size)
        settle = rank < free                        # a site with room keeps what it can hold
        if settle.any():
            a = cur[settle]
            mat[a, p - free[settle] + rank[settle]] = carry[settle]
            room[sites_at] -= np.minimum(size, room[sites_at])
        # the rest hand on at most RELAY_BATCH a round (the others wait their turn)
        hand = ~settle & (rank < free + RELAY_BATCH)
        wait = ~settle & ~hand
        g = np.flatnonzero(hand)
        nxt_carry, nxt_cur = [carry[wait]], [cur[wait]]
        if g.size:
            a_all = cur[g]
            a, _, k = _runs(a_all)
            stale = (target[a] < 0) | (room[np.maximum(target[a], 0)] <= 0)
            if stale.any():                             # a target is kept while it has room
                target[a[stale]] = nearest_room_of_sites(a[stale])
            z = target[a]
            nb = near[a]
            d2 = voronoi.distance2(sx[nb], sy[nb], sx[z, None], sy[z, None])
            b = nb[np.arange(len(a)), np.argmin(d2, axis=1)]
            closer = (voronoi.distance2(sx[b], sy[b], sx[z], sy[z])
                      < voronoi.distance2(sx[a], sy[a], sx[z], sy[z]))
            # no neighbour nearer to the target (a gap in the sites): the nearest site that
            # is nearer to it, the target itself at worst
            stuck = np.flatnonzero(~closer)
            b[stuck] = z[stuck]
            step = max(1, (1 << 22) // n)
            for lo in range(0, len(stuck), step):
                q = stuck[lo:lo + step]
                every = (a[q] // n * n)[:, None] + np.arange(n)[None, :]
                toward = voronoi.distance2(sx[every], sy[every], sx[z[q], None], sy[z[q], None]) \
                    < voronoi.distance2(sx[a[q]], sy[a[q]], sx[z[q]], sy[z[q]])[:, None]
                d2 = voronoi.distance2(sx[every], sy[every], sx[a[q], None], sy[a[q], None])
                d2[~toward] = np.iinfo(np.int64).max
                pick = np.argmin(d2, axis=1)
                found = toward[np.arange(len(q)), pick]
                b[q[found]] = every[np.arange(len(q)), pick][found]
            kmax = int(k.max())
            # candidates: the site's points, then the carried ones (padding: -1)
            col = np.arange(kmax)
            have = col[None, :] < k[:, None]
            extra = np.full((len(a), kmax), -1, dtype=np.int64)
            extra[have] = carry[g]                  # g is grouped by site, ids ascending
            cand = np.concatenate([mat[a], extra], axis=1)
            safe = np.maximum(cand, 0)
            # gain |u - D|^2 - |u|^2 = |D|^2 - 2 u.D of handing y to b (u, D: the toroidal
            # offsets of y and s_b from s_a): in the order of -u.D, ties to the earlier slot
            dx = voronoi.delta(sx[b], sx[a])[:, None]
            dy = voronoi.delta(sy[b], sy[a])[:, None]
            ux = voronoi.delta(px[safe], sx[a, None])
            uy = voronoi.delta(py[safe], sy[a, None])
            gain = -(ux * dx + uy * dy)
            width = cand.shape[1]
            bits = width.bit_length()
            top = np.iinfo(np.int64).max
            if voronoi.BITS * 2 + 2 + bits <= 62:
                key = np.where(cand < 0, top, (gain << bits) | np.arange(width)[None, :])
            else:                                   # huge p: ranks of (gain, slot) instead
                key = np.empty_like(gain)
                rank_of = np.lexsort((np.broadcast_to(np.arange(width), gain.shape).ravel(),
                                      np.where(cand < 0, top, gain).ravel(),
                                      np.repeat(np.arange(len(a)), width)))
                key.ravel()[rank_of] = np.arange(gain.size)
            chosen = np.argpartition(key, kmax - 1, axis=1)[:, :kmax] if kmax < width \
                else np.broadcast_to(np.arange(width), key.shape).copy()
            chosen = np.take_along_axis(chosen, np.argsort(
                np.take_along_axis(key, chosen, axis=1), axis=1), axis=1)
            moved = np.take_along_axis(cand, chosen, axis=1)
            picked = np.zeros(cand.shape, dtype=bool)
            np.put_along_axis(picked, chosen, have, axis=1)
            # the carried points not handed on take the slots of the site's points that are
            row, slot = np.nonzero(picked[:, :p])
            mat[a[row], slot] = extra[~picked[:, p:] & have]
            nxt_carry.append(moved[have])
            nxt_cur.append(np.repeat(b, k))
        carry = np.concatenate(nxt_carry)
        cur = np.concatenate(nxt_cur)
        realization = carry // M
    changed = np.flatnonzero((np.diff(mat, axis=1) < 0).any(axis=1))
    mat[changed] = np.sort(mat[changed], axis=1)


def _recenter_reference(sites, points, members, which):
    """The sites ``which`` of one realization to the rounded periodic means of their
    members, unwrapped relative to each site (``ccvt_recenter``), in place."""
    px = points[members[which], 0].astype(np.int64)
    py = points[members[which], 1].astype(np.int64)
    p = members.shape[1]
    s = sites[which]
    x = (s[:, 0] + voronoi.round_mean(voronoi.delta(px, s[:, 0:1]).sum(1), p)) & voronoi.MASK
    y = (s[:, 1] + voronoi.round_mean(voronoi.delta(py, s[:, 1:2]).sum(1), p)) & voronoi.MASK
    sites[which] = np.stack([x, y], axis=1)


def _centroids_reference(sites, points, members, site_energy, which):
    """One realization's centroid step for the sites ``which`` (``ccvt_centroids``): moves
    them, refreshes their entries of site_energy, returns the total energy (int)."""
    _recenter_reference(sites, points, members, which)
    px = points[members[which], 0].astype(np.int64)
    py = points[members[which], 1].astype(np.int64)
    s = sites[which]
    site_energy[which] = voronoi.distance2(px, py, s[:, 0:1], s[:, 1:2]).sum(axis=1)
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
            _recenter_reference(sites, points, members, [i, j])
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


def _ccvt_buffers(q, sites, points, members):
    """Device buffers of both OpenCL paths: members (ids) and their coordinates (xy), the
    scratch slots of the rebuilds, the sites, the per-site records and bucket ranges."""
    import pyopencl.array as cla
    r, n, p = members.shape
    ids = cla.to_device(q, np.ascontiguousarray(members, dtype=np.uint32))
    # each slot carries its point's coordinates (ccvt_gather), so the kernels stream
    # instead of gathering
    xy = cla.empty(q, (r, n, p, 2), np.uint32)
    if r and n * p:
        runtime.kernel("ccvt.cl", "ccvt_gather", _defines())(
            q, (n * p, r), None,
            cla.to_device(q, np.ascontiguousarray(points, dtype=np.uint32)).data, ids.data,
            xy.data, np.uint32(n * p))
    return dict(ids=ids, xy=xy,
                tids=cla.empty(q, (r, n, p), np.uint32), txy=cla.empty(q, (r, n, p, 2), np.uint32),
                sites=cla.to_device(q, np.ascontiguousarray(sites, dtype=np.uint32)),
                meta=cla.zeros(q, (r, n, CCVT_META), np.int64),
                bstart=cla.zeros(q, (r, n, CCVT_BUCKETS + 1), np.uint32))


def _defines():
    """Build options of ``kernels/ccvt.cl`` on the current device: CCVT_PREFETCH (software
    prefetch of the records and points a pair reads) on CPU devices, where the scans wait
    on memory; it never changes a result."""
    return {"CCVT_PREFETCH": runtime.current_device().type == "cpu"}


def _divisor(x, most):
    """The largest divisor of x that is at most ``most``."""
    return max(d for d in range(1, most + 1) if x % d == 0)


_KERNELS = {}   # program -> the stepwise loop's kernel objects (creating one costs 0.5 ms)


def _ccvt_kernels():
    """The kernel objects of the stepwise loop, one per phase (each keeps its own
    arguments), made once per program: (build, swap phases, centroids)."""
    import pyopencl as cl
    prog = runtime.program("ccvt.cl", _defines())
    if prog not in _KERNELS:
        _KERNELS[prog] = (cl.Kernel(prog, "voronoi_build_grid"),
                          [cl.Kernel(prog, "ccvt_swap") for _ in PHASES],
                          cl.Kernel(prog, "ccvt_centroids"))
    return _KERNELS[prog]


def _ccvt_device(sites, points, members, iterations, callback=None, fused=None, tail=None):
    """OpenCL CCVT: integer sites (r, n, 2), points (r, M, 2), members (r, n, p).

    With ``fused`` (default: when there are at least twice as many realizations as compute
    units and no callback) each realization runs whole in one work-group (``ccvt_solve``,
    one launch); otherwise every step is its own launch over all realizations, which keeps
    a single large realization spread over the whole device, until the iteration's
    exchanges fall to ``tail`` or fewer in every realization still running (default
    n / TAIL_SHARE; -1: never, and never with a callback): then ``ccvt_solve`` takes
    the rest in one launch, since a dozen launches cost more than the few exchanges left.
    All of these give the same bits. The members come back as sets: the kernels keep
    each site's slots grouped by bucket.
    """
    import pyopencl as cl
    import pyopencl.array as cla
    runtime.require_fp64()
    q = runtime.queue()
    r, n, p = members.shape
    if fused is None:
        fused = callback is None and r >= 2 * runtime.current_device().compute_units
    if tail is None:
        tail = n // TAIL_SHARE
    if callback is not None:
        tail = -1
    G = ccvt_grid_size(n)
    near2 = ccvt_near2(n)
    u32 = np.uint32
    b = _ccvt_buffers(q, sites, points, members)
    b.update(cell_start=cla.empty(q, (r, G * G + 1), np.uint32),
             cell_sites=cla.empty(q, (r, n), np.uint32),
             dirty=cla.zeros(q, (r, n), np.uint32), touched=cla.zeros(q, (r, n), np.uint32),
             site_energy=cla.zeros(q, (r, n), np.int64),
             status=cla.zeros(q, (r, 3), np.int64))
    active_host = np.ones(r, dtype=np.uint32)
    active = cla.to_device(q, active_host)
    energies = [[] for _ in range(r)]
    if fused:
        converged = _ccvt_solve_device(b, n, p, iterations, active, np.arange(r), 0, energies)
        return b["sites"].get(), energies, b["ids"].get(), converged
    slots = (b["ids"].data, b["xy"].data, b["tids"].data, b["txy"].data)
    swaps = cla.zeros(q, (r,), np.uint32)
    # every launch of the loop gets its arguments once, here: an iteration is a dozen
    # launches, and setting twenty arguments each time cost more than some of them run.
    # The phases run in work-groups of at most 4 x 4 cell pairs, so that the uneven work
    # of the pairs spreads over the compute units (one group per launch keeps it on one
    # core: 1.8-2.2 s at 1024 x 1024 against 1.15-1.35 s; results are the same)
    build, swap, centroids = _ccvt_kernels()
    build.set_args(b["sites"].data, u32(n), u32(G), b["cell_start"].data,
                   b["cell_sites"].data, u32(r))
    phases = []
    for k, (ox, oy, parity) in zip(swap, PHASES, strict=True):
        k.set_args(*slots, u32(n), u32(p), b["sites"].data, b["meta"].data, b["bstart"].data,
                   b["cell_start"].data, b["cell_sites"].data, u32(G), np.int32(ox),
                   np.int32(oy), u32(parity), active.data, b["dirty"].data,
                   b["touched"].data, swaps.data, np.int64(near2))
        size = (G if ox == 0 and oy == 0 else G // 2, G, r)
        phases.append((k, size, (_divisor(size[0], 4), _divisor(size[1], 4), 1)))
    centroids.set_args(*slots, b["sites"].data, u32(n), u32(p), b["meta"].data,
                       b["bstart"].data, active.data, b["dirty"].data, b["touched"].data,
                       b["site_energy"].data, b["status"].data, swaps.data, u32(1))
    cl.enqueue_nd_range_kernel(q, centroids, (n, r), None)   # the sites to the start's centroids
    centroids.set_arg(15, u32(0))
    b["dirty"].fill(1)        # every pair meets in the first iteration
    status = np.zeros((r, 3), dtype=np.int64)
    converged = np.zeros(r, dtype=bool)
    for t in range(iterations):
        cl.enqueue_nd_range_kernel(q, build, (r,), None)
        for k, size, local in phases:
            cl.enqueue_nd_range_kernel(q, k, size, local)
        cl.enqueue_nd_range_kernel(q, centroids, (n, r), None)
        cl.enqueue_copy(q, status, b["status"].data)
        totals = voronoi.exact_total(status[:, 0], status[:, 1])
        running = np.flatnonzero(active_host)
        for k in running:
            energies[k].append(totals[k])
        if callback is not None:
            callback(b["ids"].get(), b["sites"].get())
        made = status[:, 2]
        done = (active_host == 1) & (made == 0)
        if done.any():
            converged |= done
            active_host[done] = 0
            if not active_host.any():
                break
            active.set(active_host)
        if t + 1 < iterations and made[active_host == 1].max() <= tail:
            tail_converged = _ccvt_solve_device(b, n, p, iterations - t - 1, active,
                                                np.flatnonzero(active_host), 1, energies)
            converged |= tail_converged & (active_host == 1)
            break
    return b["sites"].get(), energies, b["ids"].get(), converged


def _ccvt_solve_device(b, n, p, iterations, active, running, resume, energies):
    """``ccvt_solve`` over the buffers ``b`` of :func:`_ccvt_device`: one work-group per
    active realization (``active`` on the device, ``running`` their indices), one launch
    for ``iterations`` at most; from the start, or with ``resume`` from where the
    stepwise launches left them. Appends each iteration's energy to ``energies`` and
    returns which realizations converged (the sites and members stay on the device)."""
    import pyopencl.array as cla
    q = runtime.queue()
    r = b["ids"].shape[0]
    G = ccvt_grid_size(n)
    history = cla.zeros(q, (r, iterations, 2), np.int64)
    state = cla.zeros(q, (r, 2), np.uint32)
    local = runtime.local_size(64)
    solve = runtime.kernel("ccvt.cl", "ccvt_solve", _defines())
    solve(q, (local * r,), (local,), b["ids"].data, b["xy"].data, b["tids"].data,
          b["txy"].data, np.uint32(n), np.uint32(p), b["sites"].data, b["meta"].data,
          b["bstart"].data, b["cell_start"].data, b["cell_sites"].data, np.uint32(G),
          b["dirty"].data, b["touched"].data, b["site_energy"].data,
          np.int64(ccvt_near2(n)), np.uint32(iterations), np.uint32(resume), active.data,
          b["status"].data, history.data, state.data)
    h, st = history.get(), state.get()
    for k in running:
        energies[k].extend(voronoi.exact_total(h[k, :st[k, 0], 0], h[k, :st[k, 0], 1]))
    return st[:, 1].astype(bool)


def ccvt_optimize(sites, points_per_site=1024, iterations=1000, seed=0, backend="opencl",
                  callback=None, density="jittered", relax=0):
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
    relax : int
        Relaxation steps of the starting sites before the partition (:func:`start_sites`;
        see :class:`CCVTSampler`), default 0.

    Returns
    -------
    CCVTResult
        Batch-shaped (r, ...) even for one set.
    """
    batch, _ = voronoi.check_sites(sites)
    points_per_site = _check_points_per_site(points_per_site, batch.shape[1])
    iterations = check_positive_int(iterations, "iterations")
    check_choice(density, "density", DENSITIES)
    relax = check_int(relax, "relax", minimum=0, maximum=MAX_RELAX)
    return _run(batch, np.arange(batch.shape[0]), points_per_site, iterations, seed,
                backend, callback, density, relax)


def _check_points_per_site(points_per_site, n):
    p = check_positive_int(points_per_site, "points_per_site", maximum=MAX_POINTS_PER_SITE)
    if n * p > 2**32 - 1:
        raise InvalidArgumentError(
            f"'points_per_site' * n must stay below 2^32 density points, got {p} * {n}")
    return p


def _run(sites, realizations, p, iterations, seed, backend, callback=None, density="jittered",
         relax=0):
    r, n, _ = sites.shape
    M = n * p
    results = []
    for lo, hi in runtime.chunk_ranges(r, 32 * M + (64 + 8 * CCVT_META) * n):
        make = density_points if backend == "numpy" else density_points_device
        points = make(seed, realizations[lo:hi], M, density)
        start, weight = start_sites(sites[lo:hi], p, backend, relax)
        members = start_partition(start, points, p, backend, weight)
        run = ccvt_reference if backend == "numpy" else _ccvt_device
        results.append((points,) + run(start, points, members, iterations, callback))
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
        Cap on the iterations (default 1000, above the 150 to 320 that 1024 points per
        site take); each realization stops at the first iteration in which no exchange
        lowers the energy.
    backend : {"opencl", "numpy"}
    density : {"jittered", "random"}
        How the M density points are drawn. ``"jittered"`` (default): one uniform point
        in each cell of an equal-area partition of the torus into exactly M near-square
        cells, the whole set shifted by a random toroidal offset per realization.
        ``"random"``: M i.i.d. uniform points, as in Balzer et al. (see Notes for why
        that is not the default).
    relax : int
        Steps of a capacity-constrained Lloyd relaxation of the random starting sites on
        a coarse lattice proxy of the density before the optimization
        (:func:`start_sites`), default 0: Balzer et al.'s random start. Relaxed sites
        leave the optimization far less to do and end at a lower energy, but more
        regular: at 1024 sites x 1024 points, ``relax=8`` takes 114 iterations instead
        of 311 and 50 to 60% of the time, capacity N*E 0.1662 against 0.1682, while the
        radial mean of the spectrum peaks at 2.9 instead of 2.1 and rows of hexagonal
        order appear, the structure CCVT exists to avoid. At most MAX_RELAX (64).

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
    every site owns the same number of points. The start (:func:`start_partition`;
    with ``relax``, after :func:`start_sites` has moved the random sites) gives every
    density point to its nearest site in the power distance |x - s_i|^2 - w_i, the
    weights balancing the cells' areas (measured on a lattice proxy of the density: a
    smooth correction, solved by FFT, for the large-scale
    crowding of random sites, and a damped Newton step per site), then passes the excess
    of overfull sites along neighbouring sites to the nearest ones with room. It is
    exact in capacity, compact (at 1024 x 1024, 99% of the points lie within 1.7 site
    spacings of their site and none beyond about 3; from relaxed sites 0.67 and 2.0)
    and, unlike a partition of the unit square, without seams on the axes; the sites
    then move to its centroids. Each iteration then (1) exchanges points between
    neighbouring sites i, j: the candidates of each are ordered by the gain of moving to
    the other site, and pairs are exchanged in order
    while the two gains sum to more than zero (the paper's heap-based swap, here in
    rounds of the 16 best candidates a side), and a pair that exchanged moves both its
    sites to the periodic centroids of their points at once, before the next pair (as
    Balzer et al.'s code does: later pairs see the moved sites, which takes fewer
    iterations than moving all sites at the end); (2) moves every site whose points
    changed to its periodic centroid. Both steps lower E, so ``energy_history``
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
    they last met, and pairs farther apart than the sum of their reaches (the farthest
    member of each; the two gains then sum to at most 2 |D| (R_i + R_j - |D|) <= 0), are
    skipped. The points that can change hands are a thin strip along the common edge of
    two cells, so each site keeps its points in 64 buckets (16 angular sectors times 4
    radial bands around it, each with its largest radius); that bounds the gains of a
    bucket toward any neighbour without reading it, and a pair reads only the buckets
    that can hold a candidate (a few per cent of the points). The sums that give a
    site's centroid and energy are kept up to date by the exchanges and moves, exactly
    (integers), instead of recomputed. None of this changes a result: every skip is
    exact, and the reference, which reads everything, gives the same bits. A batch runs
    one realization per work-group in a single launch; one large set runs step by step
    over the whole device, and its last iterations, once an iteration makes n / 8
    exchanges or fewer, in one such launch (a dozen launches an iteration cost more than
    the exchanges left); all give the same bits, as does the NumPy reference. Positions are
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
    lower). The strata are rows of
    equal-area cells, isqrt(M) rows of isqrt(M) to isqrt(M) + 2 cells (Bresenham
    split), so any M works and no cell is far from square (a kx-by-ky grid needs a
    divisor of M and degenerates into strips when M is prime); the per-realization
    shift makes the point process stationary. The optimizer also converges in fewer
    iterations and to a lower energy with the same start. Measured with the seam-free
    start (seed 2, 64 per site, 64 sets, N = 16..1024): Gaussian slope -2.55 against -0.97
    for i.i.d. points, disk -1.39 against -1.55 (both within the published ranges);
    ambient occlusion at 96 rays (48^2, three seeds) MSE 1.98e-4 against 2.00e-4 with
    i.i.d. points and 2.33e-4 for Poisson disk. The axis-aligned spectral peaks that an
    earlier version showed came from the k-d start's seams, not from the density: with
    the greedy start the power on the axes equals the power beside them (0.88 against
    0.93 at 256 sites, 32 sets; 0.88 against 0.90 from the power start).
    ``density="random"`` keeps Balzer et al.'s i.i.d. density.

    ``normalized_energy`` is N*E over the density points, each counted at the site that
    owns it (the objective): 0.160375 for the hexagonal lattice, about 1/pi for white
    noise; Balzer et al.'s code reaches about 0.1677 at 1024 sites x 1024 points. Fewer
    points per site make the optimum coarser (about 0.171 to 0.175 at 64 to 256 per
    site, realizations of one size spreading by about +-0.003 across local optima). The
    same figure for the sites alone, each point of the torus counted at its nearest
    site, is :func:`clsamp.point_metrics.normalized_energy`, on the scale of every other
    sampler; it is never higher (1024 x 1024, seed 1: 0.1672 against 0.1682).

    Cost: iterations until convergence grow with ``points_per_site`` (about 150 to 320 at
    1024 per site, 237 on average over seeds 1 to 8, 10 to 25 at 64); at the default 1024
    per site a 1024-point set (seed 1: 311 iterations) takes 0.8 to 0.9 s here while the
    machine runs at the speed at which Balzer et al.'s code took 4.9 s, and 1.0 to 1.5 s
    while it is loaded (PoCL, 2 cores: the start 0.23 to 0.46 s, then a few ms an
    iteration while many exchanges are left, under 1 ms at the end), against 7 s before
    the buckets and the power start, and 0.43 to 0.73 s with ``relax=8``; time grows about
    linearly with n at a given ``points_per_site`` (``benchmarks/bench_voronoi.py``, which
    times the machine gauge beside it).

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

    def __init__(self, d=2, seed=0, points_per_site=1024, iterations=1000, backend="opencl",
                 density="jittered", relax=0):
        super().__init__(d=d, seed=seed, backend=backend)
        self.points_per_site = check_positive_int(points_per_site, "points_per_site",
                                                  maximum=MAX_POINTS_PER_SITE)
        self.iterations = check_positive_int(iterations, "iterations")
        self.density = check_choice(density, "density", DENSITIES)
        self.relax = check_int(relax, "relax", minimum=0, maximum=MAX_RELAX)
        self.capacities = None
        self.iterations_run = None
        self.converged = None

    def _optimize(self, sites, realizations, backend=None):
        p = _check_points_per_site(self.points_per_site, sites.shape[1])
        return _run(sites, np.asarray(realizations, dtype=np.int64), p, self.iterations,
                    self.seed, backend or self.backend, density=self.density,
                    relax=self.relax)

    def _keep(self, result, single):
        super()._keep(result, single)
        pick = (lambda a: a[0]) if single else (lambda a: a)
        self.capacities = pick(result.capacities)
        self.iterations_run = pick(result.iterations)
        self.converged = pick(result.converged)
