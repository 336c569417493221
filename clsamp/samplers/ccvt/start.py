"""The start of CCVT: power weights that balance the cells' areas, an optional relaxation
of the starting sites, and the exact-capacity starting partition.

Everything here is host arithmetic shared by both backends, around the power pass of
:mod:`.power` (OpenCL or its NumPy twin), so the start is the same integers either way.
"""

import math

import numpy as np

from ...geometry import integer_torus as it
from ...validation import check_choice
from .power import NO_OWNER, PowerPass, nearest_site2, power_counts, start_grid_size
from .relay import members_matrix, relay

START_CROWD = 16       # more sites in one cell: the sites are clustered (kd_partition)
START_LATTICE = 8      # the weights' proxy density: up to 8 x 8 lattice points per site
START_SHARE = 8        # ... and never more than p / START_SHARE per site
START_MIN_SIDE = 4     # ... but at least 4 x 4
START_SWEEPS = 10      # weight updates on the proxy lattice
START_STEP = 0.3       # fraction of each site's own (diagonal Newton) weight step
START_SMOOTH = 1.0     # Gaussian width of the large-scale weight correction, in site spacings
START_SLOPE = 0.25     # margin, in squared site spacings, of the points that measure dc/dw
RELAX_STEPS = 8        # start_sites's default: moves of the sites on the lattice
MAX_RELAX = 64         # the most relaxation steps accepted
START_RELAX_SWEEPS = 2  # weight updates before each of those moves
START_FINAL_SWEEPS = 1  # ... and after the last, from the weights they leave


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

    Parameters
    ----------
    sites : ndarray
        (r, n, 2) integer coordinates.
    points : ndarray
        (r, n p, 2) density points.
    p : int
        Points per site.

    Returns
    -------
    ndarray of uint32
        (r, n, p): the point indices each site owns.
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


def start_lattice(n, p):
    """The proxy density of the start's weights: a regular lattice of up to
    ``START_LATTICE ** 2`` points per site (at most p / START_SHARE, at least
    ``START_MIN_SIDE ** 2``: the relaxation of :func:`start_sites` moves the sites to means
    of these).

    Parameters
    ----------
    n : int
        Sites.
    p : int
        Points per site.

    Returns
    -------
    ndarray of uint32
        (1, m, 2) integer coordinates, one set for every realization.
    """
    side = max(START_MIN_SIDE, min(START_LATTICE, math.isqrt(p // START_SHARE)))
    side *= max(1, math.isqrt(n))
    g = ((2 * np.arange(side, dtype=np.int64) + 1) << it.BITS) // (2 * side)
    return np.stack(np.meshgrid(g, g), axis=-1).reshape(1, -1, 2).astype(np.uint32)


def start_weights(sites, p, G, power, weight=None, sweeps=START_SWEEPS, with_owner=False):
    """Power weights under which the power cells of the sites hold nearly equal shares
    of the unit torus.

    ``sweeps`` updates, from ``weight`` (default 0), each measured on the lattice of
    :func:`start_lattice`. Each update adds two parts. Large scale: cells whose sites are
    crowded are too small, and a smooth weight field f with Laplacian 2 (c / c_mean - 1)
    (the excess count density, Gaussian-smoothed over START_SMOOTH site spacings, solved
    by FFT on the torus) moves every boundary so that the areas balance to first order
    (the power diagram under a smooth f is the Voronoi diagram displaced by -grad f / 2);
    a purely local update would need about n sweeps to spread that. Small scale: each
    site's own Newton step -(c_i - c_mean) / (dc_i/dw_i), times START_STEP, the
    derivative counted from the lattice points whose margin to a neighbour is below
    START_SLOPE, and the step capped so that it moves the boundary with the nearest other
    site by at most a quarter of their distance (a near-duplicate pair needs tiny weight
    differences to share). Host arithmetic shared by both backends.

    Parameters
    ----------
    sites : ndarray (r, n, 2)
        Integer torus coordinates.
    p : int
        Capacity of every site (sizes the lattice).
    G : int
        Cells per axis of the start's candidate grid (:func:`start_grid_size`).
    power : PowerPass
        The power passes over ``sites`` (:class:`~clsamp.samplers.ccvt.power.PowerPass`).
    weight : ndarray (r, n), optional
        Weights to start from (default 0).
    sweeps : int
        Updates to make.
    with_owner : bool
        Also return the lattice's owners in the last sweep (under the weights before
        its update).

    Returns
    -------
    weight : ndarray (r, n) of int64
    owner : ndarray (r, m) of uint32
        Only with ``with_owner``.

    Raises
    ------
    ValueError
        ``with_owner`` with no sweep.
    """
    r, n, _ = sites.shape
    if with_owner and sweeps < 1:
        raise ValueError("start_weights: with_owner needs at least one sweep")
    lattice = start_lattice(n, p)
    per = lattice.shape[1] / n
    unit2 = float(it.SIZE) ** 2
    spacing2 = unit2 / n
    tau = START_SLOPE * spacing2
    K = 1 << max(3, math.ceil(math.log2(max(1.0, math.sqrt(n)))))
    freq = np.fft.fftfreq(K) * K
    k2 = (2 * np.pi) ** 2 * (freq[:, None] ** 2 + freq[None, :] ** 2)
    k2[0, 0] = 1.0
    solve = 2.0 * np.exp(-0.5 * k2 * START_SMOOTH ** 2 / n) / k2
    solve[0, 0] = 0.0
    u = sites.astype(np.float64) * (K / it.SIZE) - 0.5    # cell centres at (c + 1/2) / K
    c0 = np.floor(u).astype(np.int64)
    fx, fy = u[..., 0] - c0[..., 0], u[..., 1] - c0[..., 1]
    x0, y0 = c0[..., 0] % K, c0[..., 1] % K
    x1, y1 = (x0 + 1) % K, (y0 + 1) % K
    rows = np.arange(r)[:, None]
    cell = rows * K * K + (sites[..., 1].astype(np.int64) * K >> it.BITS) * K \
        + (sites[..., 0].astype(np.int64) * K >> it.BITS)
    cap = 0.5 * np.sqrt(nearest_site2(sites, G, power.tables) * spacing2)
    w = np.zeros((r, n)) if weight is None else np.asarray(weight, dtype=np.float64).copy()
    for _ in range(sweeps):
        owner, second, margin = power(lattice, np.rint(w).astype(np.int64))
        excess = power_counts(owner, n) / per - 1.0
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
    (:func:`start_lattice`): a capacity-constrained Lloyd on a coarse proxy of the
    density, the optional first step of the start (``relax`` of :class:`CCVTSampler`).

    ``steps`` times, the power weights get START_RELAX_SWEEPS updates
    (:func:`start_weights`, from the last ones) and every site moves 3/2 of the way to
    the periodic mean of the lattice points of its power cell in the last of those
    sweeps, rounded (a site with none stays); the over-relaxed step does more per step
    than a plain move to the mean. Random sites crowd in places and leave gaps in others;
    the swaps of the optimization spread them one exchange at a time, the relaxation in a
    few coarse steps, so the optimization then has far less to do and ends at a lower
    energy. The price is regularity: relaxed sets show rows of hexagonal order (a higher,
    narrower peak of the spectrum's radial mean), the structure Lloyd's method settles
    into and CCVT exists to avoid, and more steps make it stronger.

    Exact integers, the same with both backends. Sites crowded into one cell of the
    start's grid (:func:`start_partition`) stay as they are. The weights of the last
    sweep come back too: START_FINAL_SWEEPS updates from them balance the cells of the
    moved sites about as well as START_SWEEPS from zero do.

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
    G = start_grid_size(n)
    spread = np.flatnonzero(~_crowded(out, G))
    if not spread.size or not steps:
        return out, None
    sub = out[spread]
    lattice = start_lattice(n, p)
    lx, ly = (lattice[0, :, k].astype(np.int64) for k in (0, 1))
    rows = np.arange(len(spread))[:, None]
    weight = None
    for _ in range(steps):
        power = PowerPass(sub, G, backend)
        weight, owner = start_weights(sub, p, G, power, weight, START_RELAX_SWEEPS, True)
        owner = owner.astype(np.int64)
        ok = owner != NO_OWNER
        flat = (owner + rows * n)[ok]
        xy = sub.astype(np.int64)
        count = np.bincount(flat, minlength=len(spread) * n)
        moved = []
        for axis, coord in ((0, lx), (1, ly)):
            s = xy[..., axis].ravel()
            u = it.delta(np.broadcast_to(coord, owner.shape)[ok], s[flat])
            total = np.bincount(flat, u, len(spread) * n)      # exact: |sum| < 2^53
            # 3/2 of the way to the centroid, rounded (over-relaxed: fewer steps do more)
            step = it.round_mean(3 * np.rint(total).astype(np.int64),
                                      2 * np.maximum(count, 1))
            moved.append((s + np.where(count > 0, step, 0)) & it.MASK)
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
    cells = it.cell_of(sites[..., 1], G) * G + it.cell_of(sites[..., 0], G)
    return np.array([np.bincount(c, minlength=G * G).max() > START_CROWD for c in cells])


def start_partition(sites, points, p, backend="opencl", weight=None, device_points=None):
    """The starting ownership of CCVT: every site owns exactly p density points, near it,
    with no seam and no preferred direction on the torus.

    Three steps, all deterministic (integers, and host arithmetic shared by the backends):

    1. Power weights w (:func:`start_weights`): START_SWEEPS updates measured on a
       lattice proxy of the density (START_FINAL_SWEEPS from ``weight``, those of
       :func:`start_sites`, when given), so that the power cells
       {x : |x - s_i|^2 - w_i <= |x - s_j|^2 - w_j for all j} hold nearly equal shares.
       Random sites crowd in some places and leave gaps in others, so equal cells need
       boundaries shifted over several site spacings; the weights shift them all at
       once, leaving a small excess for step 3.
    2. Every point goes to its power-nearest site (the ``ccvt_power`` kernel, or
       :func:`power_pass_reference` with ``backend="numpy"``: the same integers) among
       the sites in the 3 x 3 cells of a grid of about ``START_OCCUPANCY`` sites per cell
       around it (all sites when n < 32), ties to the smaller site index. A site given
       more than p keeps its first p in index order; the rest, and points with no
       candidate, are carried on.
    3. Excess is passed along to neighbouring sites (:func:`relay`): a site holding k
       carried points hands on the k of its points (the carried ones included) that
       lose least by moving, to its neighbour b (closer than NEAR / sqrt(n)) nearest to
       the nearest site with room, until every carried point rests at a site with room.
       Every hand-over moves a point one neighbour on, so the excess travels as a shift
       of boundaries, never as a jump of a point to a far site: every point stays
       within a few site spacings of its site.

    The cells are power cells trimmed at their boundaries: no cut along x = 0 or y = 0
    and no axis-aligned structure (a k-d partition of the unit square leaves a cross in
    the power spectrum that the optimization keeps). Vectorized over realizations.
    Sites crowded into one cell of the grid (more than ``START_CROWD``: duplicates,
    clusters) take :func:`kd_partition` instead: power weights cannot separate a pile of
    coincident sites.

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
    device_points : pyopencl.array.Array, optional
        ``points`` already on the device (OpenCL), read there instead of copied again.

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
    G = start_grid_size(n)
    crowded = _crowded(sites, G)
    spread = np.flatnonzero(~crowded)
    owner = np.empty((r, M), dtype=np.int64)
    if crowded.any():
        owner[crowded] = np.repeat(np.arange(n), p)     # a placeholder where kd_partition runs
    if spread.size:
        sub = sites[spread]
        power = PowerPass(sub, G, backend)
        if weight is None:
            w = start_weights(sub, p, G, power)
        else:
            w = start_weights(sub, p, G, power, weight[spread], START_FINAL_SWEEPS)
        whole = device_points is not None and spread.size == r   # no host-to-device copy
        best = power(device_points if whole else points[spread], w, owner_only=True)[0]
        owner[spread] = np.where(best == NO_OWNER, -1, best)
    owner += (np.arange(r) * n)[:, None] * (owner >= 0)
    owner = owner.ravel()
    mat, over = members_matrix(owner, S, p)
    if spread.size:
        left = np.union1d(np.flatnonzero(owner < 0), over)
        relay(sites, points, mat, (mat < 0).sum(axis=1), left, owner[left])
    members = (mat.reshape(r, n, p) - (np.arange(r) * M)[:, None, None]).astype(np.uint32)
    if crowded.any():
        members[crowded] = kd_partition(sites[crowded], points[crowded], p)
    return members
