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
CCVT_BUCKETS = 64      # buckets per site: 16 sectors x 4 bands (CCVT_BUCKETS in kernels/ccvt.cl)
CCVT_META = 7 + CCVT_BUCKETS + 16   # int64 record per site (CCVT_META in kernels/ccvt.cl)
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


START_OCCUPANCY = 2    # sites per cell of the start's grid: a 3 x 3 block offers about 18
START_CHUNK = 1 << 16  # candidate distances computed at once (in cache, and bounded)
START_CROWD = 16      # more sites in one cell: the sites are clustered (kd_partition)


def _start_table(xy, ids, G, pad):
    """Candidate table of one realization for :func:`greedy_partition`: row c lists the
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


def _keep_order(q, d2, s, sites_total):
    """Order of the entries by (site, d2, point): composite keys where they fit in int64."""
    qb = max(1, int(q.max()).bit_length())
    if int(d2.max()).bit_length() + qb <= 63:
        o = np.argsort((d2 << qb) | q)
        by = s[o].astype(np.uint16 if sites_total <= 1 << 16 else np.int64)
        return o[np.argsort(by, kind="stable")]
    return np.lexsort((q, d2, s))


def _square_delta(h, t):
    """Squared toroidal differences (float64, exact) of x = h - HALF and the sites t."""
    d = h - t
    np.bitwise_and(d, voronoi.MASK, out=d)
    d -= voronoi.HALF
    d2 = d.astype(np.float64)
    return np.multiply(d2, d2, out=d2)


def _start_phase(px, py, sx, sy, cap, table, lengths, cell, left):
    """Deferred acceptance of the points ``left`` (global ids) by the sites (global ids,
    capacities ``cap``; the last site is the padding) over the candidate table rows
    ``cell[left]``. Returns the owner of every point (-1: left over, or not in ``left``)."""
    S = len(cap) - 1
    thr_d = np.full(S + 1, np.inf)                  # key (d2, point) of a full site's worst point
    thr_q = np.zeros(S + 1, dtype=np.int64)
    thr_d[S] = -np.inf                              # the padding accepts nothing
    owner = np.full(len(px), S, dtype=np.int64)
    own_d = np.zeros(len(px), dtype=np.int64)
    count = np.zeros(S + 1, dtype=np.int64)
    hx = (px + voronoi.HALF).astype(np.int32)
    hy = (py + voronoi.HALF).astype(np.int32)
    tx = sx[table].astype(np.int32)                 # the candidates' coordinates, row by row
    ty = sy[table].astype(np.int32)
    active = left
    while active.size:
        # each active point proposes to its nearest candidate that would keep it
        active = active[np.argsort(lengths[cell[active]].astype(np.uint16 if lengths.max() < 1 << 16
                                                                 else np.int64), kind="stable")]
        site = np.full(active.size, S, dtype=np.int64)
        dist = np.zeros(active.size, dtype=np.int64)
        width = max(1, START_CHUNK // max(1, int(lengths.max())))
        full = bool((thr_d[:S] < np.inf).any())     # before any site fills, only padding is out
        for lo in range(0, active.size, width):
            q = active[lo:lo + width]
            rows = cell[q]
            L = max(1, int(lengths[rows].max()))
            cand = table[rows, :L]
            # toroidal differences, computed as (x - s + HALF) mod SIZE - HALF in int32
            d2 = _square_delta(hx[q, None], tx[rows, :L])
            d2 += _square_delta(hy[q, None], ty[rows, :L])   # exact: integers below 2^44
            if full:
                t = thr_d[cand]
                ok = d2 < t
                tie = d2 == t
                if tie.any():
                    ok |= tie & (q[:, None] < thr_q[cand])
                d2[~ok] = np.inf
            else:
                d2[np.arange(L)[None, :] >= lengths[rows][:, None]] = np.inf
            best = np.argmin(d2, axis=1)
            bd = d2[np.arange(len(q)), best]
            found = bd < np.inf
            site[lo:lo + width][found] = cand[found, best[found]]
            dist[lo:lo + width][found] = bd[found].astype(np.int64)
        go = site < S
        q, s, d = active[go], site[go], dist[go]
        if not q.size:
            break
        new = np.bincount(s, minlength=S + 1)
        over = (new > 0) & (count + new >= cap)     # the sites that fill up or overflow now
        easy = ~over[s]
        owner[q[easy]] = s[easy]
        own_d[q[easy]] = d[easy]
        count += np.bincount(s[easy], minlength=S + 1)
        if not over.any():
            break
        # a site given more than its room keeps its nearest points, old or new
        held = np.flatnonzero(over[owner])
        aq = np.concatenate([held, q[~easy]])
        as_ = np.concatenate([owner[held], s[~easy]])
        ad = np.concatenate([own_d[held], d[~easy]])
        o = _keep_order(aq, ad, as_, S + 1)
        aq, as_, ad = aq[o], as_[o], ad[o]
        idx = np.arange(len(aq))
        first = np.ones(len(aq), dtype=bool)
        first[1:] = as_[1:] != as_[:-1]
        rank = idx - np.maximum.accumulate(np.where(first, idx, 0))
        keep = rank < cap[as_]
        owner[aq] = np.where(keep, as_, S)
        own_d[aq[keep]] = ad[keep]
        last = rank == cap[as_] - 1
        thr_d[as_[last]] = ad[last]
        thr_q[as_[last]] = aq[last]
        count[over] = cap[over]
        active = np.sort(aq[~keep])
    owner[owner == S] = -1
    return owner


def kd_partition(sites, points, p):
    """The starting ownership where sites are too crowded for :func:`greedy_partition`
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


def greedy_partition(sites, points, p):
    """A seam-free starting ownership with exact capacities: every density point goes to
    its nearest site that still has room, the pairs taken in order of increasing toroidal
    distance (ties by point index, then site index).

    The greedy is computed as point-proposing deferred acceptance (Gale and Shapley
    1962): each unplaced point proposes to its nearest candidate site that would keep it,
    and a site offered more than its room keeps its nearest points, old or new. Points
    and sites rank each other by one and the same order of the pairs, so the stable
    assignment is unique and is the greedy one (the first pair of the order must be in
    every stable assignment, else it blocks; by induction so must every pair the greedy
    takes), and the rounds compute it in parallel.
    The candidates of a point are the sites in the 3 x 3 cells of a grid of about
    ``START_OCCUPANCY`` sites per cell around it; points that every candidate turns away
    are placed the same way in a next phase, among the sites that still have room (on a
    grid of those), and a phase that places none of them uses all of them. Unlike a
    partition of the unit square (a k-d tree), this has no seam at x = 0 or y = 0, and no
    preferred direction: cells are Voronoi cells trimmed to their nearest points, and
    the optimization that follows does not inherit a cut along the axes (an axis-aligned
    cut is a local optimum of the exchanges, and shows as a cross in the power spectrum).
    Vectorized over realizations (disjoint sites, one problem). Sites crowded into one
    cell (more than ``START_CROWD``: duplicates, clusters) would need about one round per
    site sharing the spot, so such realizations take :func:`kd_partition`.

    Parameters
    ----------
    sites : ndarray (r, n, 2)
        Integer torus coordinates.
    points : ndarray (r, n * p, 2)
        Integer torus coordinates of the density points.
    p : int
        Capacity of every site.

    Returns
    -------
    ndarray (r, n, p) of uint32
        Point indices owned by each site, ascending.

    References
    ----------
    D. Gale, L. S. Shapley, "College admissions and the stability of marriage",
    Amer. Math. Monthly 69(1), 1962.
    """
    r, n, _ = sites.shape
    M = points.shape[1]
    S = r * n
    sx = np.append(sites[..., 0].ravel().astype(np.int64), 0)
    sy = np.append(sites[..., 1].ravel().astype(np.int64), 0)
    px = points[..., 0].ravel().astype(np.int64)
    py = points[..., 1].ravel().astype(np.int64)
    owner = np.repeat(np.arange(S), p)              # a placeholder where the greedy does not run
    room = np.append(np.full(S, p, dtype=np.int64), 0)
    # deferred acceptance needs about as many rounds as sites share a spot: crowded
    # realizations (never random sites: 16 in a cell of mean 2 has odds ~1e-9) take the
    # k-d partition instead
    G = math.isqrt(n // START_OCCUPANCY)
    crowded = np.zeros(r, dtype=bool)
    if G >= 4:
        cells = voronoi.cell_of(sites[..., 1], G) * G + voronoi.cell_of(sites[..., 0], G)
        crowded = np.array([np.bincount(c, minlength=G * G).max() > START_CROWD for c in cells])
    room[:S].reshape(r, n)[crowded] = 0
    left = np.flatnonzero(~np.repeat(crowded, M))
    everything = np.zeros(r, dtype=bool)            # last phase placed none: all open sites
    while left.size:
        tables, lengths, cell = [], [], np.zeros(r * M, dtype=np.int64)
        realization = left // M
        bounds = np.searchsorted(realization, np.arange(r + 1))
        base = 0
        for k in np.flatnonzero(np.diff(bounds)):
            ids = k * n + np.flatnonzero(room[k * n:(k + 1) * n] > 0)
            G = math.isqrt(len(ids) // START_OCCUPANCY)
            G = 1 if G < 4 or everything[k] else G
            xy = np.stack([sx[ids], sy[ids]], axis=1)
            t, length = _start_table(xy, ids, G, S)
            q = left[bounds[k]:bounds[k + 1]]
            cell[q] = base + (voronoi.cell_of(py[q], G) * G + voronoi.cell_of(px[q], G))
            tables.append(t)
            lengths.append(length)
            base += len(t)
        width = max(t.shape[1] for t in tables)
        table = np.concatenate([np.pad(t, ((0, 0), (0, width - t.shape[1])), constant_values=S)
                                for t in tables])
        got = _start_phase(px, py, sx, sy, room, table, np.concatenate(lengths), cell, left)
        placed = left[got[left] >= 0]
        owner[placed] = got[placed]
        room -= np.bincount(got[placed], minlength=S + 1)
        everything = np.bincount(realization, minlength=r) > 0
        everything &= np.bincount(placed // M, minlength=r) == 0
        left = left[got[left] < 0]
    # points ascending within each site (a radix sort where the site ids fit in 16 bits)
    order = np.argsort(owner.astype(np.uint16) if S <= 1 << 16 else owner, kind="stable")
    members = (order.reshape(r, n, p) - (np.arange(r) * M)[:, None, None]).astype(np.uint32)
    if crowded.any():
        members[crowded] = kd_partition(sites[crowded], points[crowded], p)
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
    p = members.shape[1]

    def pair(i, j):
        if voronoi.distance2(sites[i, 0], sites[i, 1], sites[j, 0], sites[j, 1]) >= near2:
            return 0
        made = _pair_reference(members[i], members[j], points, sites[i], sites[j])
        if made:
            touched[i] = touched[j] = True
            for k in (i, j):
                for axis in (0, 1):
                    u = voronoi.delta(points[members[k], axis], sites[k, axis]).sum()
                    sites[k, axis] = (sites[k, axis] + voronoi.round_mean(u, p)) & voronoi.MASK
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
    members = np.ascontiguousarray(members, dtype=np.uint32)
    # each slot carries its point's coordinates, so the kernels stream instead of gathering
    xy = np.ascontiguousarray(np.asarray(points, dtype=np.uint32)[np.arange(r)[:, None, None],
                                                                  members])
    return dict(ids=cla.to_device(q, members), xy=cla.to_device(q, xy),
                tids=cla.empty(q, (r, n, p), np.uint32), txy=cla.empty(q, (r, n, p, 2), np.uint32),
                sites=cla.to_device(q, np.ascontiguousarray(sites, dtype=np.uint32)),
                meta=cla.zeros(q, (r, n, CCVT_META), np.int64),
                bstart=cla.zeros(q, (r, n, CCVT_BUCKETS + 1), np.uint32))


def _ccvt_device(sites, points, members, iterations, callback=None, fused=None):
    """OpenCL CCVT: integer sites (r, n, 2), points (r, M, 2), members (r, n, p).

    With ``fused`` (default: when there are at least twice as many realizations as compute
    units and no callback) each realization runs whole in one work-group (``ccvt_solve``,
    one launch); otherwise every step is its own launch over all realizations, which keeps
    a single large realization spread over the whole device. Both give the same bits. The
    members come back as sets: the kernels keep each site's slots grouped by bucket.
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
    b = _ccvt_buffers(q, sites, points, members)
    slots = (b["ids"].data, b["xy"].data, b["tids"].data, b["txy"].data)
    cell_start = cla.empty(q, (r, G * G + 1), np.uint32)
    cell_sites = cla.empty(q, (r, n), np.uint32)
    active_host = np.ones(r, dtype=np.uint32)
    active = cla.to_device(q, active_host)
    dirty = cla.zeros(q, (r, n), np.uint32)
    touched = cla.zeros(q, (r, n), np.uint32)
    energy = cla.zeros(q, (r, 2), np.int64)
    site_energy = cla.zeros(q, (r, n), np.int64)
    swaps = cla.zeros(q, (r,), np.uint32)
    build = runtime.kernel("ccvt.cl", "voronoi_build_grid")
    swap = runtime.kernel("ccvt.cl", "ccvt_swap")
    centroids = runtime.kernel("ccvt.cl", "ccvt_centroids")

    def centroid_step(everything):
        centroids(q, (n, r), None, *slots, b["sites"].data, u32(n), u32(p), b["meta"].data,
                  b["bstart"].data, active.data, dirty.data, touched.data, site_energy.data,
                  energy.data, u32(everything))

    centroid_step(True)      # the sites to the centroids of the starting partition
    dirty.fill(1)        # every pair meets in the first iteration
    energies = [[] for _ in range(r)]
    converged = np.zeros(r, dtype=bool)
    for _ in range(iterations):
        build(q, (r,), None, b["sites"].data, u32(n), u32(G), cell_start.data, cell_sites.data,
              u32(r))
        swaps.fill(0)
        for ox, oy, parity in PHASES:
            size = (G if ox == 0 and oy == 0 else G // 2, G, r)
            swap(q, size, None, *slots, u32(n), u32(p), b["sites"].data, b["meta"].data,
                 b["bstart"].data, cell_start.data, cell_sites.data, u32(G), np.int32(ox),
                 np.int32(oy), u32(parity), active.data, dirty.data, touched.data, swaps.data,
                 np.int64(near2))
        centroid_step(False)
        made = swaps.get()
        totals = voronoi.exact_total(*energy.get().T)
        for k in np.flatnonzero(active_host):
            energies[k].append(totals[k])
        if callback is not None:
            callback(b["ids"].get(), b["sites"].get())
        done = (active_host == 1) & (made == 0)
        if done.any():
            converged |= done
            active_host[done] = 0
            if not active_host.any():
                break
            active.set(active_host)
    return b["sites"].get(), energies, b["ids"].get(), converged


def _ccvt_solve_device(sites, points, members, iterations):
    """``ccvt_solve``: one work-group per realization, one launch for everything."""
    import pyopencl.array as cla
    q = runtime.queue()
    r, n, p = members.shape
    G = ccvt_grid_size(n)
    b = _ccvt_buffers(q, sites, points, members)
    cell_start = cla.empty(q, (r, G * G + 1), np.uint32)
    cell_sites = cla.empty(q, (r, n), np.uint32)
    dirty = cla.zeros(q, (r, n), np.uint32)
    touched = cla.zeros(q, (r, n), np.uint32)
    site_energy = cla.zeros(q, (r, n), np.int64)
    history = cla.zeros(q, (r, iterations, 2), np.int64)
    state = cla.zeros(q, (r, 2), np.uint32)
    local = runtime.local_size(64)
    solve = runtime.kernel("ccvt.cl", "ccvt_solve")
    solve(q, (local * r,), (local,), b["ids"].data, b["xy"].data, b["tids"].data,
          b["txy"].data, np.uint32(n), np.uint32(p), b["sites"].data, b["meta"].data,
          b["bstart"].data, cell_start.data, cell_sites.data, np.uint32(G), dirty.data,
          touched.data, site_energy.data, np.int64(ccvt_near2(n)), np.uint32(iterations),
          history.data, state.data)
    h, st = history.get(), state.get()
    energies = [voronoi.exact_total(h[k, :st[k, 0], 0], h[k, :st[k, 0], 1]) for k in range(r)]
    return b["sites"].get(), energies, b["ids"].get(), st[:, 1].astype(bool)


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
    for lo, hi in runtime.chunk_ranges(r, 32 * M + (64 + 8 * CCVT_META) * n):
        make = density_points if backend == "numpy" else density_points_device
        points = make(seed, realizations[lo:hi], M, density)
        members = greedy_partition(sites[lo:hi], points, p)
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
    every site owns the same number of points. The start gives every density point to
    its nearest random starting site that still has room, pairs in order of increasing
    toroidal distance (:func:`greedy_partition`: exact in capacity and, unlike a
    partition of the unit square, without seams on the axes; the sites then move to its
    centroids). Each iteration then
    (1) exchanges points between neighbouring sites i, j: the candidates of each are
    ordered by the gain of moving to the other site, and pairs are exchanged in order
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
    exact, and the reference, which reads everything, gives the same bits. A batch runs one realization
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
    0.93 at 256 sites, 32 sets).
    ``density="random"`` keeps Balzer et al.'s i.i.d. density.

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
