"""The ``bnot`` sampler: blue noise through optimal transport (de Goes, Breeden,
Ostromoukhov, Desbrun 2012) on the unit torus, over the density points of CCVT.

One iteration: the power weights that give every site's power cell exactly its share of
the density points (Newton's method on the concave dual of the semi-discrete transport
problem), the exact-capacity assignment those cells give, and every site moved to the
centroid of its cell. The power passes run on the device (``ccvt_power`` in
``kernels/ccvt_start.cl``, the pass CCVT's start uses) or in NumPy
(:func:`clsamp.samplers.ccvt.power.power_pass_reference`), the same integers; everything
else is exact integer or shared host arithmetic (:func:`bnot_optimize`), so both backends
give the same bits.
"""

import dataclasses

import numpy as np

from .. import runtime
from ..density import as_density
from ..errors import InvalidArgumentError
from ..geometry import integer_torus as it
from ..validation import MAX_ITERATIONS, check_bool, check_choice, check_int, check_positive_int, check_real
from .base import SampleInfo, info_field, register
from .bnot_cells import exact_optimize
from .ccvt.density import DENSITIES, density_points, density_points_device
from .ccvt.pairs import MAX_POINTS_PER_SITE, NO_OWNER
from .ccvt.power import PowerPass, start_grid_size
from .ccvt.relay import members_matrix, relay
from .ccvt.sampler import check_points_per_site
from .ccvt.start import start_weights
from .optimizer import OptimizerSampler

POINTS_PER_SITE = 256   # density points per site (M = n * POINTS_PER_SITE)
ITERATIONS = 64         # cap on the outer iterations (weights, then centroids)
NEWTON = 16              # cap on the Newton steps of one weight solve
HALVINGS = 6           # step halvings before a Newton step gives up
BAND = 0.25             # margin band, in squared site spacings, that measures the Hessian
REGULAR = 0.5           # least diagonal of the Hessian, in p / spacing^2 (a cell with no boundary)
SLACK = 1 / 128         # Newton stops when every count is within SLACK p of p (the rest: relay)
TOL = 1e-5              # stop when an iteration lowers the cost by at most this fraction
CELLS = ("points", "exact")     # the cells' measure: CCVT's density points, or exact areas


@dataclasses.dataclass(frozen=True)
class BNOTInfo(SampleInfo):
    """What a BNOT optimization did, per realization (first axis).

    Attributes
    ----------
    realizations : ndarray (r,)
        The realization indices.
    energy_history : ndarray (r, T)
        The transport cost after each iteration: the mean squared toroidal distance of the
        density points (``cells="exact"``: of the torus) to the site whose cell holds
        them, after the sites moved to their cells' centroids. Never rising (exact cells:
        within the capacities' tolerance); T is the longest run's iterations, and a
        realization that converged before the others repeats its final value.
    dual_history : ndarray (r, T)
        The dual F(w) of each iteration's weight solve at its end, per density point
        (same units; :func:`solve_weights`): the transport cost the power cells would
        have if their counts were exact.
    newton_steps : ndarray (r,)
        Newton steps taken in all.
    capacities : ndarray (r, n)
        Density points in each site's final cell, counted from the assignment: all equal
        to ``points_per_site``. With ``cells="exact"``, each final cell's area times n
        (floats, within 1e-5 of 1 wherever the last weight solve converged).
    iterations : ndarray (r,)
        Iterations each realization ran.
    converged : ndarray (r,) of bool
        Whether an iteration lowered the cost by at most ``tol`` of it within the cap.
    """

    energy_history: np.ndarray = info_field("pad")
    dual_history: np.ndarray = info_field("pad")
    newton_steps: np.ndarray = info_field()
    capacities: np.ndarray = info_field()
    iterations: np.ndarray = info_field()
    converged: np.ndarray = info_field()


def _dual(points, sites, owner, w, p):
    """The dual sum_m (|y_m - s_owner|^2 - w_owner) + p sum_i w_i of one realization,
    exact (Python int); points with no candidate count nowhere."""
    ok = owner != NO_OWNER
    o = owner[ok].astype(np.int64)
    d2 = it.distance2(points[ok, 0], points[ok, 1], sites[o, 0], sites[o, 1])
    return int(d2.sum()) - int(w[o].sum()) + p * int(w.sum())


def _hessian(owner, second, margin, n, tau, diagonal):
    """The Hessian of the cell counts in the weights, measured from the margins: points of
    i whose runner-up is j within ``tau`` (``N_ij``) give d c_j / d w_j ~ (N_ij + N_ji) /
    (2 tau) and -that off the diagonal (the counts' first-order change as the boundary
    between i and j moves), plus ``diagonal`` on the diagonal."""
    import scipy.sparse as sp
    near = (margin < tau) & (owner != NO_OWNER) & (owner != second)
    i = owner[near].astype(np.int64)
    j = second[near].astype(np.int64)
    edge = sp.coo_matrix((np.full(i.size, 1.0 / (2.0 * tau)), (i, j)), shape=(n, n)).tocsr()
    edge = edge + edge.T
    # the Laplacian is singular along the constants, to which the gradient is orthogonal
    degree = np.maximum(np.asarray(edge.sum(axis=1)).ravel(), diagonal) + 1e-3 * diagonal
    return (sp.diags(degree) - edge).tocsc()


def solve_weights(points, sites, w, p, power, newton=NEWTON, slack=None):
    """Newton's method on the dual of the semi-discrete transport problem of one
    realization: weights whose power cells hold p density points each, as far as the
    points allow (de Goes et al. 2012, section 4).

    The dual F(w) = sum_m min_i (|y_m - s_i|^2 - w_i) + p sum_i w_i is concave, its
    gradient is p - c(w) (c: the points in each power cell), and its Hessian the
    negative of the counts' Jacobian, a graph Laplacian over neighbouring cells measured
    from the margins (:func:`_hessian`). A step w + alpha delta (rounded: the weights are
    integers) is accepted for the largest alpha in a0, a0/2, ... (``HALVINGS`` tries; a0 = 1
    for the first step, then the last accepted alpha) that lowers the gradient's norm
    sum |p - c| (the damped Newton method of Kitagawa, Merigot and Thibert); the solve
    stops when no step does, or when every count is within ``slack`` of p (the few
    points left over are passed on by the exact assignment that follows). It starts
    from ``w`` or from zero weights (Voronoi cells), whichever has the smaller gradient:
    sites that moved far leave the last weights worse than none.

    Parameters
    ----------
    points : ndarray (M, 2) of int64
    sites : ndarray (n, 2) of int64
    w : ndarray (n,) of int64
        The weights to start from.
    p : int
    power : callable
        ``power(weights)`` -> (owner, second, margin) of the points, the power pass
        (:class:`~clsamp.samplers.ccvt.power.PowerPass`) over the sites.
    newton : int
        Cap on the steps.
    slack : int, optional
        Stop once every count is within ``slack`` of p (default ``SLACK`` p, at least 1).

    Returns
    -------
    w : ndarray of int64
    owner : ndarray (M,) of uint32
        The power cells under ``w``.
    dual : int
        F(w), exact.
    steps : int
        Newton steps accepted.
    """
    from scipy.sparse.linalg import spsolve
    n = sites.shape[0]
    spacing2 = float(it.SIZE) ** 2 / n
    tau = BAND * spacing2
    diagonal = REGULAR * p / spacing2
    slack = max(1, int(SLACK * p)) if slack is None else slack

    def evaluate(weights):
        owner, second, margin = power(weights)
        c = np.bincount(owner[owner != NO_OWNER].astype(np.int64), minlength=n)
        return owner, second, margin, p - c

    owner, second, margin, grad = evaluate(w)
    if w.any():
        zero = evaluate(np.zeros_like(w))
        if int(np.abs(zero[3]).sum()) < int(np.abs(grad).sum()):
            w = np.zeros_like(w)
            owner, second, margin, grad = zero
    steps, start = 0, 1.0
    for _ in range(newton):
        error = int(np.abs(grad).sum())
        if n == 1 or int(np.abs(grad).max()) <= slack:
            break
        delta = spsolve(_hessian(owner, second, margin, n, tau, diagonal),
                        grad.astype(np.float64))
        delta -= delta.mean()       # a constant moves no boundary
        alpha, taken = start, None
        for _ in range(HALVINGS):
            trial = w + np.rint(alpha * delta).astype(np.int64)
            out = evaluate(trial)
            if int(np.abs(out[3]).sum()) < error:
                taken = trial, out
                break
            alpha *= 0.5
        if taken is None:
            break
        w, (owner, second, margin, grad) = taken[0], taken[1]
        start = alpha                   # the next step starts from this one
        steps += 1
    return w, owner, _dual(points, sites, owner, w, p), steps


def _exact_cells(sites, points, owner, p):
    """Power cells made exact in capacity: a site given more than p keeps its first p
    (in point order) and the excess is passed along neighbouring sites to the nearest ones
    with room (:func:`clsamp.samplers.ccvt.relay.relay`, CCVT's start)."""
    n, M = sites.shape[0], points.shape[0]
    own = np.where(owner == NO_OWNER, -1, owner.astype(np.int64))
    mat, over = members_matrix(own, n, p)
    left = np.union1d(np.flatnonzero(own < 0), over)
    relay(sites[None], points[None], mat, (mat < 0).sum(axis=1), left, own[left])
    label = np.empty(M, dtype=np.int64)
    label[mat.ravel()] = np.repeat(np.arange(n), p)
    return label


def _cost_and_centroids(sites, points, label, n):
    """The exact transport cost of an assignment and the sites moved to the periodic
    centroids of their cells (the integer nearest the mean offset, halves up: the cost of
    every cell does not rise)."""
    xy = sites[label]
    dx = it.delta(points[:, 0], xy[:, 0])
    dy = it.delta(points[:, 1], xy[:, 1])
    count = np.maximum(np.bincount(label, minlength=n), 1)
    moved = []
    for axis, d in ((0, dx), (1, dy)):
        total = np.bincount(label, d.astype(np.float64), n)     # exact: |sum| < 2^53
        step = it.round_mean(np.rint(total).astype(np.int64), count)
        moved.append((sites[:, axis] + step) & it.MASK)
    new = np.stack(moved, axis=1)
    nxy = new[label]
    cost = int(it.distance2(points[:, 0], points[:, 1], nxy[:, 0], nxy[:, 1]).sum())
    return int((dx * dx + dy * dy).sum()), new, cost


def bnot_optimize(sites, points, p, iterations=ITERATIONS, tol=TOL, backend="opencl",
                  realizations=None, newton=NEWTON, progress=False):
    """BNOT from given integer sites over given density points (both backends: the same
    bits).

    Parameters
    ----------
    sites : ndarray (r, n, 2) of uint32
        Starting sites on the integer torus.
    points : ndarray (r, n * p, 2) of uint32
        The density points of each realization.
    p : int
        Capacity: density points per site.
    iterations : int
        Cap on the iterations.
    tol : float
        Stop once an iteration lowers the cost by at most this fraction of it (0: run
        every iteration).
    backend : {"opencl", "numpy"}
        Where the power passes run.
    realizations : array_like of int, optional
        The realizations' indices, for the info (default 0..r-1).
    newton : int
        Cap on the Newton steps of each weight solve.
    progress : bool
        Show a bar over the iterations (after 2 s).

    Returns
    -------
    sites : ndarray (r, n, 2) of int64
    info : BNOTInfo
    """
    r, n, _ = sites.shape
    M = n * p
    scale = float(M) * float(it.SIZE) ** 2
    G = start_grid_size(n)
    out = np.array(sites, dtype=np.int64)
    histories, duals, steps, counts, capacities, converged = [], [], [], [], [], []
    from tqdm import tqdm
    bar = tqdm(total=r * iterations, desc=f"bnot {r} x {n} sites", unit="it",
               disable=not progress, delay=2)
    for k in range(r):
        pts = points[k].astype(np.int64)
        pts32 = np.ascontiguousarray(points[k:k + 1], dtype=np.uint32)   # uploaded once a pass set
        s = out[k]
        w = np.zeros(n, dtype=np.int64)
        label, history, dual_history, taken, done = None, [], [], 0, False
        for t in range(iterations):
            sites32 = s[None].astype(np.uint32)
            power = PowerPass(sites32, G, backend)
            if t == 0 and n > 1:
                # random sites: CCVT's start weights balance the cells to first order
                w = start_weights(sites32, p, G, power)[0]

            def cells(weights, power=power, pts32=pts32):
                return tuple(a[0] for a in power(pts32, weights[None]))

            slack = max(1, int(SLACK * p))
            while True:
                w, owner, dual, used = solve_weights(pts, s, w, p, cells, newton, slack)
                taken += used
                fresh = _exact_cells(s, pts, owner, p)
                _, moved, cost = _cost_and_centroids(s, pts, fresh, n)
                if label is None:
                    break
                # the previous cells end cheaper: solve the weights more closely, or keep
                # those cells when that cannot be done, so that the cost never rises
                _, old_moved, old_after = _cost_and_centroids(s, pts, label, n)
                if cost <= old_after:
                    break
                if slack == 1:
                    fresh, moved, cost = label, old_moved, old_after
                    break
                slack = max(1, slack // 2)
            label, s = fresh, moved
            history.append(cost / scale)
            dual_history.append(dual / scale)
            bar.update()
            if tol > 0 and len(history) > 1 and history[-2] - history[-1] <= tol * history[-1]:
                done = True
                break
        bar.update(iterations - len(history))      # a converged run has done its work
        out[k] = s
        histories.append(history)
        duals.append(dual_history)
        steps.append(taken)
        counts.append(len(history))
        capacities.append(np.bincount(label, minlength=n) if label is not None
                          else np.zeros(n, dtype=np.int64))
        converged.append(done)
    bar.close()
    index = np.arange(r) if realizations is None else np.asarray(realizations)
    return out, _info(index, histories, duals, steps, counts,
                      np.asarray(capacities, dtype=np.int64).reshape(r, n), converged)


def _info(realizations, histories, duals, steps, counts, capacities, converged):
    """A :class:`BNOTInfo` from per-realization lists, the histories padded with their
    last values to the longest."""
    length = max((len(h) for h in histories), default=0)

    def padded(rows):
        return np.array([h + [h[-1]] * (length - len(h)) for h in rows]).reshape(
            len(rows), length)

    return BNOTInfo(realizations=np.asarray(realizations, dtype=np.int64),
                    energy_history=padded(histories), dual_history=padded(duals),
                    newton_steps=np.asarray(steps, dtype=np.int64), capacities=capacities,
                    iterations=np.asarray(counts, dtype=np.int64),
                    converged=np.asarray(converged, dtype=bool))


IMAGE_SIDE = 256        # the least pixels a side of the image a density is warped by


def check_density(density, name="density"):
    """A density as ``bnot`` takes it: one of CCVT's names, or a target density as every
    sampler takes one (:func:`clsamp.density.as_density`), as the image
    :func:`warp_to_image` warps the density points by.

    Parameters
    ----------
    density : str, callable or array_like (a, b)
        ``"jittered"`` or ``"random"`` (:func:`clsamp.samplers.ccvt.density.density_points`),
        or a non-negative density on the unit torus as ``gbn`` takes one: a callable on
        points (m, 2) returning m values, or an array with 2 axes whose entry [i, j] is
        the density at ((i + 1/2) / a, (j + 1/2) / b), multilinear between those centres
        (the first axis is x: an image shown with rows going down the screen is
        ``image[::-1].T``).
    name : str
        The argument's name, for messages.

    Returns
    -------
    str or ndarray (h, w) of float64
        The name, or the density at the centres of h x w pixels, row i covering y in
        [i / h, (i + 1) / h) and column j x in [j / w, (j + 1) / w): w = max(a,
        ``IMAGE_SIDE``) and h = max(b, ``IMAGE_SIDE``) for an array (one at least
        ``IMAGE_SIDE`` a side gives its transpose, normalized), ``IMAGE_SIDE`` a side for a
        callable.

    Raises
    ------
    InvalidArgumentError
        Another name; a callable or an array that :func:`~clsamp.density.as_density`
        refuses; a density that is zero at every pixel centre.

    Examples
    --------
    >>> import numpy as np
    >>> a = np.arange(1.0, 65537.0).reshape(256, 256)     # a[i, j]: x = (i + 1/2) / 256
    >>> bool(np.allclose(check_density(a), a.T / a.mean()))   # rows are y
    True
    >>> ramp = check_density(lambda p: 1.0 + p[:, 0])     # rising along x, the columns
    >>> ramp.shape, bool(ramp[0, -1] > ramp[0, 0])
    ((256, 256), True)
    """
    if isinstance(density, str):
        return check_choice(density, name, DENSITIES)
    target = as_density(density, 2, name)
    wide, high = (IMAGE_SIDE, IMAGE_SIDE) if target.image is None else \
        (max(IMAGE_SIDE, target.image.shape[0]), max(IMAGE_SIDE, target.image.shape[1]))
    if target.image is not None and target.image.shape == (wide, high):
        image = np.ascontiguousarray(target.image.T)    # its values at its own centres
    else:
        x, y = np.meshgrid((np.arange(wide) + 0.5) / wide, (np.arange(high) + 0.5) / high)
        image = target(np.stack([x.ravel(), y.ravel()], axis=1)).reshape(high, wide)
    if not image.sum() > 0:
        raise InvalidArgumentError(
            f"'{name}' must be positive somewhere on the {wide} x {high} pixel centres")
    return image


def warp_to_image(points, image):
    """Points of the integer torus warped to an image's density: the row by the inverse
    of the rows' cumulative masses, then the column by the inverse of that row's, each
    inside its pixel linearly (the density is constant over a pixel). Monotone in each
    coordinate, so a stratified set stays stratified (Pharr, Jakob, Humphreys, *Physically
    Based Rendering*, the piecewise-constant 2-D distribution).

    Parameters
    ----------
    points : ndarray (..., 2) of uint32
        Integer torus coordinates of points uniform on the torus.
    image : ndarray (h, w)
        From :func:`check_density`.

    Returns
    -------
    ndarray (..., 2) of uint32
    """
    h, w = image.shape
    u = it.to_unit(points)
    rows = image.sum(axis=1)
    cdf = np.concatenate([[0.0], np.cumsum(rows)]) / rows.sum()
    uy = u[..., 1]
    i = np.clip(np.searchsorted(cdf, uy, side="right") - 1, 0, h - 1)
    mass = np.maximum(cdf[i + 1] - cdf[i], np.finfo(float).tiny)
    y = (i + np.clip((uy - cdf[i]) / mass, 0.0, 1.0)) / h
    # each row's own cumulative masses, row-major
    cols = np.concatenate([np.zeros((h, 1)), np.cumsum(image, axis=1)], axis=1)
    cols /= np.maximum(cols[:, -1:], np.finfo(float).tiny)
    ux = u[..., 0]
    row_cdf = cols[i]                                      # (..., w + 1)
    j = np.clip((row_cdf <= ux[..., None]).sum(axis=-1) - 1, 0, w - 1)
    lo = np.take_along_axis(row_cdf, j[..., None], -1)[..., 0]
    hi = np.take_along_axis(row_cdf, j[..., None] + 1, -1)[..., 0]
    x = (j + np.clip((ux - lo) / np.maximum(hi - lo, np.finfo(float).tiny), 0.0, 1.0)) / w
    return it.to_torus(np.stack([x, y], axis=-1) % 1.0)


@register("bnot")
class BNOTSampler(OptimizerSampler):
    """Blue noise through optimal transport: sites at the centroids of power cells of
    exactly equal capacity.

    Parameters
    ----------
    d : int
        Must be 2 (the unit torus [0, 1)^2; distances wrap).
    seed : int
        Seeds the starting sites and the density points (Philox, ``Stream.INIT``: the
        same as ``ccvt``'s for the same seed; realization k does not depend on how many
        are drawn).
    points_per_site : int
        Capacity of every cell, default 256: M = n * points_per_site density points.
    iterations : int
        Cap on the iterations (default 64).
    tol : float
        Stop once an iteration lowers the transport cost by at most this fraction of it
        (default 1e-5; 0 runs every iteration).
    density : {"jittered", "random"}, image or callable, optional
        With ``cells="points"`` (default ``"jittered"``): the density points, as
        ``ccvt`` draws them (:func:`clsamp.samplers.ccvt.density.
        density_points`): one per cell of an equal-area partition of the torus, shifted
        at random per realization (default), or i.i.d. uniform. A target density as
        ``gbn`` takes one (:func:`clsamp.density.as_density`: a callable on points (m, 2),
        or an array with 2 axes, the first x) gives adaptive sampling: the jittered
        points warped to that density (:func:`check_density`, :func:`warp_to_image`),
        so that every cell holds an equal share of its mass and the sites crowd where it
        is high.
    newton : int
        Cap on the Newton steps of one weight solve (default 16).
    cells : {"points", "exact"}
        How the cells are measured: by CCVT's density points (default; capacities exact
        in whole points, any density), or exactly, as polygons of the uniform density
        (de Goes et al.'s exact areas; ``points_per_site`` and ``density`` do not apply;
        needs a device with fp64). See Notes.
    backend : {"opencl", "numpy"}
    progress : bool
        Show a progress bar over the iterations (after 2 s; default True).

    Notes
    -----
    de Goes et al. minimize the transport cost E(X, T) = sum_i integral over T(i) of
    |y - x_i|^2 over the sites X and the partitions T of the domain into cells of equal
    mass. For fixed sites the optimal partition is a power diagram, whose weights w
    maximize the concave dual F(w) = sum_i integral over Pow_i(w) of (|y - x_i|^2 - w_i)
    + sum_i w_i m_i; for a fixed partition the optimal sites are the cells' centroids.
    BNOT alternates the two. Here the measure is the M density points of CCVT
    (capacities exact, as CCVT's): each iteration

    1. solves for the weights by Newton's method on F (:func:`solve_weights`): the
       gradient is the capacity minus the count of each power cell, the Hessian the
       Laplacian of the cells' adjacency weighted by (boundary length) / (2 |x_i -
       x_j|), measured by the points within a band of the boundaries; a step (its
       weights rounded to integers) is halved until it lowers the total count error
       sum |capacity - count|, which nearly always raises F too (in 214 of 220 steps
       measured at n = 256), from the previous iteration's weights;
    2. makes the cells exact in capacity: the power cells, with the few points over a
       cell's capacity (the counts change in whole points) passed along neighbouring
       cells to the nearest ones with room (CCVT's start,
       :func:`clsamp.samplers.ccvt.relay.relay`); if the previous iteration's cells
       cost less for the current sites they are kept, so the cost never rises;
    3. moves every site to the periodic centroid of its cell (rounded on the 2^22
       integer torus, which never raises a cell's cost).

    The power passes (every density point's two power-nearest sites among the sites of
    the 3 x 3 cells of a grid around it) run on the device; all the rest is exact
    integers or host arithmetic on identical inputs, so every device and the NumPy
    reference give the same bits. ``sample(..., return_info=True)`` also returns a
    :class:`BNOTInfo`: the cost after every iteration, the dual, the Newton steps, the
    capacities, the iterations and whether each realization converged.

    ``cells="exact"`` takes de Goes et al.'s measure itself, the uniform density of the
    torus, with the cells as exact polygons: every site's power cell is clipped from the
    square of its own images by the bisectors of the nearby sites
    (:mod:`clsamp.samplers.bnot_cells`, one work-item a site on the device), which gives
    its area, centroid and second moment and the exact Hessian (|edge| / (2 |x_i - x_j|))
    without sampling. Each iteration solves the weights by the damped Newton method of
    Kitagawa, Merigot and Thibert [3] until every area is within 1e-5 of 1/n (looser, up to
    1e-2, in the iterations before the last while the sites still move far;
    :func:`clsamp.samplers.bnot_cells.solve_exact_weights`), then moves every site to its
    cell's centroid. The kernel and its NumPy twin give the same bits, and the rest is
    host arithmetic on identical inputs, so every fp64 device gives the same sets.

    References
    ----------
    .. [1] F. de Goes, K. Breeden, V. Ostromoukhov, M. Desbrun, "Blue noise through
       optimal transport", ACM Trans. Graph. 31(6) (SIGGRAPH Asia), 2012.
    .. [2] F. Aurenhammer, F. Hoffmann, B. Aronov, "Minkowski-type theorems and
       least-squares clustering", Algorithmica 20, 1998.
    .. [3] J. Kitagawa, Q. Merigot, B. Thibert, "Convergence of a Newton algorithm for
       semi-discrete optimal transport", J. Eur. Math. Soc. 21(9), 2019.

    Examples
    --------
    >>> import clsamp
    >>> s = clsamp.make_sampler("bnot", seed=3, points_per_site=32, iterations=8)
    >>> pts, info = s.sample(64, return_info=True)
    >>> int(info.capacities.min()), int(info.capacities.max())
    (32, 32)
    >>> bool(info.energy_history[0, -1] <= info.energy_history[0, 0])
    True
    >>> pts, info = clsamp.make_sampler("bnot", seed=3, cells="exact").sample(
    ...     256, return_info=True)
    >>> bool(abs(info.capacities - 1).max() < 1e-5)
    True
    """

    info = BNOTInfo
    # the device runs only CCVT's power pass, in integers on the integer torus: the same bits
    # without fp64 (tests/test_devices.py)
    needs_fp64 = False

    def __init__(self, d=2, seed=0, points_per_site=POINTS_PER_SITE, iterations=ITERATIONS,
                 tol=TOL, density=None, newton=NEWTON, cells="points", backend="opencl",
                 progress=True):
        super().__init__(d=d, seed=seed, backend=backend)
        self.progress = check_bool(progress, "progress")
        self.points_per_site = check_positive_int(points_per_site, "points_per_site",
                                                  maximum=MAX_POINTS_PER_SITE)
        self.iterations = check_positive_int(iterations, "iterations", maximum=MAX_ITERATIONS)
        self.tol = check_real(tol, "tol", minimum=0.0, maximum=1.0)
        self.cells = check_choice(cells, "cells", CELLS)
        if self.cells == "exact" and density is not None:
            raise InvalidArgumentError(
                "'density' applies to cells='points'; cells='exact' is the uniform density")
        self.density = check_density("jittered" if density is None else density)
        self.newton = check_int(newton, "newton", minimum=0, maximum=64)

    def _most_sites(self):
        return self.max_n if self.cells == "exact" else (2**32 - 1) // self.points_per_site

    def _check_n(self, n):
        if self.cells == "points":      # its own message first, then the base's
            check_points_per_site(self.points_per_site, n)
        return super()._check_n(n)

    def _work_bytes(self, n):
        # measured: 151 bytes a density point (38745 a site at 256 a site); 3325 bytes a
        # site with exact cells
        return (3325 if self.cells == "exact" else 151 * self.points_per_site) * n

    def _optimize(self, sites, realizations, backend):
        n, p = sites.shape[1], self.points_per_site
        index = np.arange(realizations.start, realizations.stop, dtype=np.int64)
        if self.cells == "exact":
            return self._optimize_exact(it.to_unit(sites), index, backend)
        name = self.density if isinstance(self.density, str) else "jittered"
        if backend == "numpy":
            points = density_points(self.seed, index, n * p, name)
        else:
            points = density_points_device(self.seed, index, n * p, name)
            runtime.wait()
            points = points.get()
        if not isinstance(self.density, str):
            points = warp_to_image(points, self.density)
        out, info = bnot_optimize(sites, points, p, self.iterations, self.tol, backend, index,
                                  self.newton, self.progress)
        return it.to_unit(out), info

    def _optimize_exact(self, sites, index, backend):
        if backend == "opencl":
            runtime.require_fp64()
        out, *lists, areas, converged = exact_optimize(
            sites, self.iterations, self.tol, backend, self.newton, self.progress)
        return out, _info(index, *lists, areas, converged)
