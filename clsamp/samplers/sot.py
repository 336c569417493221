"""The ``sot`` sampler: sliced optimal transport sampling (Paulin et al. 2020), points moved
toward the uniform measure on [0, 1)^d by 1-D optimal transports along random directions,
with the projective variant that optimizes chosen coordinate projections as well.

One batch is four passes -- the 1-D targets of each direction (the quantiles of the cube's
projection), the projections of the points, their displacements to the targets of their
ranks, the move -- in ``kernels/sot.cl`` on the device (:mod:`clsamp.samplers.sot_device`)
and in :func:`quantiles_reference`, :func:`project_reference`, a stable sort with
:func:`displacements_reference`, and :func:`move_reference` here (:func:`batch_reference`),
the same bits; both order ties by index. The directions and their CDFs (:class:`Slice`)
are host code both backends share, drawn for blocks of batches at once
(:func:`sot_optimize`).
"""

import dataclasses
import itertools
import math
import numbers
import re

import numpy as np

from .. import philox, runtime
from ..errors import InvalidArgumentError
from ..validation import MAX_ITERATIONS, check_positive_int, check_real
from . import sot_device
from .base import SampleInfo, Sampler, info_field, make_sampler, register
from .sot_device import CHUNK, QMAX, QTOL

DIRECTIONS = 32      # directions a batch (full space), as the authors' code
ITERATIONS = 256
STEP = None         # the dimension: the full step (see SOTSampler's Notes)
MAX_STEP = 2        # times the dimension
TOL = 0.0
WINDOW = 16          # the cost is compared over windows of this many batches
SETTLE = 8           # a resident run reads its batches' costs this many at a time
MAX_D = 8
CANCEL = 1e-8        # the most relative error the CDF's alternating sum may carry
EPS = 2.0 ** -52
TOP = 1.0 - 2.0 ** -53
BLOCK_BYTES = 1 << 23   # the most memory a block of batches' slices takes


@dataclasses.dataclass(frozen=True)
class Slice:
    """The distribution of <theta, U>, U uniform in [0, 1)^d, as the quantile pass reads it.

    <theta, U> = base + sum_j a_j U_j over the kept components a_1 >= ... >= a_m > 0 of
    |theta| (U_j uniform in [0, 1)), whose CDF is the alternating sum over the 2^m vertices
    of the box, F(t) = norm sum_v sign_v (t - c_v)_+^m. Components small enough that the sum
    would cancel to more than ``CANCEL`` relative error (bounded by
    2^-52 2^m total^m norm) are replaced by their mean a_j / 2, which moves a quantile by
    at most a_j / 2 (and by O(a_j^2) where the density is smooth).

    Attributes
    ----------
    c, sign : ndarray (K, 2^d)
        Vertex sums and signs (the first 2^m of each row used, in vertex order v = 0, 1, ...,
        bit j of v choosing a_(j+1)).
    m : ndarray of int32 (K,)
    norm, total, base : ndarray (K,)
        1 / (m! prod a_j), sum a_j, and sum of the negative theta_j plus the dropped a_j / 2.
    """

    c: np.ndarray
    sign: np.ndarray
    m: np.ndarray
    norm: np.ndarray
    total: np.ndarray
    base: np.ndarray

    @classmethod
    def of(cls, theta):
        """The slices of directions theta (K, d), unit vectors.

        Parameters
        ----------
        theta : ndarray (K, d)

        Returns
        -------
        Slice

        Notes
        -----
        Every sum and product runs over the components in the same order, one array
        operation a component, so each row's values are those of the scalar recurrences
        the class docstring states.
        """
        K, d = theta.shape
        a = np.sort(np.abs(theta), axis=1)[:, ::-1]
        low = np.zeros(K)
        for j in range(d):
            low = low + np.minimum(theta[:, j], 0.0)
        m = np.full(K, d, dtype=np.int32)
        for top in range(d, 1, -1):           # drop the smallest kept component while it cancels
            drop = (m == top) & _cancels(a, top)
            low = np.where(drop, low + a[:, top - 1] * 0.5, low)
            m = np.where(drop, top - 1, m).astype(np.int32)
        c = np.zeros((K, 2 ** d))
        sign = np.zeros((K, 2 ** d))
        for v in range(2 ** d):
            s, odd = np.zeros(K), 0
            for j in range(d):
                if v >> j & 1:
                    s, odd = s + a[:, j], odd ^ 1
            used = v < (1 << m)
            c[:, v] = np.where(used, s, 0.0)
            sign[:, v] = np.where(used, -1.0 if odd else 1.0, 0.0)
        prod, total = np.ones(K), np.zeros(K)
        for j in range(d):
            prod = np.where(j < m, prod * a[:, j], prod)
            total = np.where(j < m, total + a[:, j], total)
        factorial = np.array([math.factorial(k) for k in range(d + 1)], dtype=np.float64)
        return cls(c, sign, m, 1.0 / (factorial[m] * prod), total, low)

    def take(self, rows):
        """The slices of directions ``rows`` (an index array), in that order.

        Parameters
        ----------
        rows : ndarray of int

        Returns
        -------
        Slice
        """
        return Slice(*(getattr(self, f.name)[rows] for f in dataclasses.fields(self)))


def _cancels(a, m):
    """Per row of ``a`` (components sorted decreasing), whether keeping the first ``m``
    lets the alternating vertex sum cancel to more than ``CANCEL`` (:func:`_cancellation`).

    The bound is computed for all rows at once; a row within a relative 1e-9 of ``CANCEL``
    is decided by :func:`_cancellation` itself, so the decision does not depend on how
    the array power rounds.
    """
    kept = a[:, :m]
    s = np.zeros(a.shape[0])
    prod = np.ones(a.shape[0])
    for j in range(m):
        s, prod = s + kept[:, j], prod * kept[:, j]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        bound = EPS * 2.0 ** m * np.power(s, float(m)) / (math.factorial(m) * prod)
    bound = np.where(kept[:, -1] <= 0.0, math.inf, bound)
    close = np.flatnonzero(np.abs(bound - CANCEL) <= 1e-9 * CANCEL)
    out = bound > CANCEL
    out[close] = [_cancellation([float(v) for v in kept[k]]) > CANCEL for k in close]
    return out


def _cancellation(a):
    """A bound of the alternating vertex sum's relative error for components a (> 0)."""
    if a[-1] <= 0.0:
        return math.inf
    m, s = len(a), sum(a)
    return EPS * 2 ** m * s ** m / (math.factorial(m) * math.prod(a))


def quantiles_reference(sl, n):
    """NumPy twin of ``sot_quantiles``: the n targets of each slice.

    Parameters
    ----------
    sl : Slice
    n : int

    Returns
    -------
    ndarray (K, n)
        Row k: F_k^-1((i + 1/2) / n), i = 0..n-1, increasing.

    Notes
    -----
    The lower half is solved in chunks of ``CHUNK`` consecutive quantiles, position c of
    every chunk at once (:func:`_solve`), each from the last roots of its chunk
    extrapolated (the kernel's rule); the upper half mirrors it.
    """
    K = sl.m.shape[0]
    half = (n + 1) // 2
    t = np.zeros((K, half))
    solved = np.flatnonzero(sl.m > 2)
    for c in range(min(CHUNK, half)):
        j = np.arange(c, half, CHUNK)
        j = j[2 * j + 1 != n]                       # an odd n's middle: total / 2
        rows, cols = np.repeat(solved, j.size), np.tile(j, solved.size)
        p = (cols + 0.5) / float(n)
        if c == 0:
            start = sl.total[rows] * 0.5 * 0.5
        else:
            t1 = t[rows, cols - 1]
            start = t1 if c == 1 else (
                2.0 * t1 - t[rows, cols - 2] if c == 2
                else 3.0 * t1 - 3.0 * t[rows, cols - 2] + t[rows, cols - 3])
            start = np.where(start < t1, t1, start)
        start = np.where(start > sl.total[rows] * 0.5, sl.total[rows] * 0.5, start)
        t[rows, cols] = _solve(sl, rows, p, start)
    closed = np.flatnonzero(sl.m <= 2)
    a1 = sl.c[closed, 1][:, None]
    a2 = np.where(sl.m[closed] == 2, sl.c[closed, 2], 0.0)[:, None]
    p = (np.arange(half) + 0.5) / float(n)
    t[closed] = np.where(2.0 * a1 * p <= a2, np.sqrt(2.0 * a1 * a2 * p), a1 * p + 0.5 * a2)
    total = sl.total[:, None]
    q = np.empty((K, n))
    q[:, :half] = sl.base[:, None] + t
    q[:, n - half:] = (sl.base[:, None] + (total - t))[:, ::-1]
    if n % 2:
        q[:, half - 1] = sl.base + sl.total * 0.5
    return q


def _solve(sl, row, p, t):
    """Safeguarded Newton (rtsafe) on F_row(t) = p from the starts ``t``, bracket
    [0, total / 2], every quantile in vector form: the kernel's steps and stopping rule."""
    total, norm, m = sl.total[row], sl.norm[row], sl.m[row]
    t = t.copy()
    lo = np.zeros(row.size)
    hi = total * 0.5
    dx_old = hi.copy()
    live = np.arange(row.size)          # the quantiles still being solved
    for _ in range(QMAX):
        if live.size == 0:
            break
        r, x, mm, tol = row[live], t[live], m[live], QTOL * total[live]
        F = np.zeros(live.size)
        dF = np.zeros(live.size)
        for v in range(1 << int(mm.max())):
            u = x - sl.c[r, v]
            on = (v < (1 << mm)) & (u > 0.0)
            w = np.ones(live.size)
            for j in range(1, int(mm.max())):
                w = np.where(j < mm, w * u, w)
            F = np.where(on, F + sl.sign[r, v] * (w * u), F)
            dF = np.where(on, dF + sl.sign[r, v] * w, dF)
        with np.errstate(divide="ignore", invalid="ignore"):
            f = F * norm[live] - p[live]
            df = dF * norm[live] * mm.astype(np.float64)
            below = f < 0.0
            lo_l = np.where(below, x, lo[live])
            hi_l = np.where(below, hi[live], x)
            tn = x - f / df
            done = (df > 0.0) & (np.abs(tn - x) <= tol)
            newton = (df > 0.0) & (tn > lo_l) & (tn < hi_l) & (np.abs(tn - x) < 0.5 * np.abs(dx_old[live]))
        nxt = np.where(newton, tn, lo_l + (hi_l - lo_l) * 0.5)
        dx = nxt - x
        t[live] = np.where(done, tn, nxt)
        lo[live], hi[live], dx_old[live] = lo_l, hi_l, dx
        live = live[~(done | (np.abs(dx) <= tol))]
    return t


def project_reference(x, theta):
    """NumPy twin of ``sot_project``: <theta_k, x_i> summed over the coordinates in order.

    Parameters
    ----------
    x : ndarray (sets, n, d)
    theta : ndarray (sets, K, d)

    Returns
    -------
    ndarray (sets, K, n)
    """
    p = theta[:, :, None, 0] * x[:, None, :, 0]
    for j in range(1, x.shape[-1]):
        p = p + theta[:, :, None, j] * x[:, None, :, j]
    return p


def displacements_reference(q, rank, proj):
    """NumPy twin of ``sot_displace`` and ``sot_project_displace``: each projection's 1-D
    displacement to the target of its rank.

    Parameters
    ----------
    q : ndarray (sets, K, n)
        The targets, sorted.
    rank : ndarray of uint32 (sets, K, n)
        The rank of each point's projection (:func:`_ranks`).
    proj : ndarray (sets, K, n)

    Returns
    -------
    ndarray (sets, K, n)
    """
    return np.take_along_axis(q, rank.astype(np.intp), axis=2) - proj


def move_reference(x, theta, disp, scale):
    """NumPy twin of ``sot_move``: each point moved by ``scale`` times the sum over the
    batch of its 1-D displacements along their directions.

    Parameters
    ----------
    x : ndarray (sets, n, d)
    theta : ndarray (sets, K, d)
    disp : ndarray (sets, K, n)
        :func:`displacements_reference`.
    scale : float

    Returns
    -------
    points : ndarray (sets, n, d)
    cost : ndarray (sets, n)
        Per point, the sum over the batch of its squared displacement.
    """
    sets, n, d = x.shape
    shift = np.zeros((sets, n, d))
    cost = np.zeros((sets, n))
    for k in range(theta.shape[1]):
        cost = cost + disp[:, k] * disp[:, k]
        shift = shift + disp[:, k, :, None] * theta[:, k, None, :]
    y = x + shift * scale
    y = np.where(y < 0.0, 0.0, y)
    return np.where(y > TOP, TOP, y), cost


def cost_sums(cost):
    """NumPy twin of ``sot_cost``: each set's point costs summed in index order.

    Parameters
    ----------
    cost : ndarray (sets, n)

    Returns
    -------
    ndarray (sets,)
    """
    return np.cumsum(cost, axis=1)[:, -1]


def batch_reference(x, theta, sl, scale):
    """One batch in NumPy: the targets, projections, displacements and move
    (:func:`move_reference`'s result).

    Parameters
    ----------
    x : ndarray (sets, n, d)
    theta : ndarray (sets, K, d)
    sl : Slice
        Of ``theta`` reshaped to (sets K, d).
    scale : float

    Returns
    -------
    points, cost
        As :func:`move_reference` returns them.
    """
    sets, n, _ = x.shape
    q = quantiles_reference(sl, n).reshape(sets, theta.shape[1], n)
    proj = project_reference(x, theta)
    return move_reference(x, theta, displacements_reference(q, _ranks(proj), proj), scale)


def subspaces(projections, d):
    """The coordinate subspaces a projective run also optimizes.

    Parameters
    ----------
    projections : None, "pairs", sequence of sequences of int, or str
        None: none; ``"pairs"``: every 2-D coordinate projection; else the listed axes,
        also as text (``"0,1;2,3"``: subspaces apart by ";", their axes by ",", as the
        command line's ``--param projections=0,1;2,3`` gives them).
    d : int

    Returns
    -------
    tuple of tuple of int
    """
    if projections is None:
        return ()
    if isinstance(projections, str):
        if projections == "pairs":
            return tuple(itertools.combinations(range(d), 2))
        if not re.fullmatch(r"\s*\d+(\s*,\s*\d+)*(\s*;\s*\d+(\s*,\s*\d+)*)*\s*", projections):
            raise InvalidArgumentError(
                f"'projections' must be None, 'pairs', a list of tuples of axes or that list as "
                f"text ('0,1;2,3'), got {projections!r}")
        projections = [[int(a) for a in part.split(",")] for part in projections.split(";")]
    try:
        spaces = tuple(tuple(axes) for axes in projections)
    except TypeError:
        spaces = None
    if spaces is None or not all(isinstance(a, numbers.Integral) and not isinstance(a, (bool, np.bool_))
                                 for axes in spaces for a in axes):
        raise InvalidArgumentError(
            f"'projections' must be None, 'pairs', a list of tuples of axes or that list as "
            f"text ('0,1;2,3'), got {projections!r}")
    spaces = tuple(tuple(int(a) for a in axes) for axes in spaces)
    seen = set()
    for axes in spaces:
        if not axes or len(set(axes)) != len(axes) or min(axes) < 0 or max(axes) >= d:
            raise InvalidArgumentError(
                f"'projections' must list distinct axes in 0..{d - 1} per projection, got {axes!r}")
        if frozenset(axes) in seen:
            raise InvalidArgumentError(f"'projections' lists the subspace of axes {axes!r} twice")
        seen.add(frozenset(axes))
    return spaces


def directions(seed, realizations, batch, K, d, spaces=(), count=None):
    """The unit directions of one batch: K in the full space, then K // 2 (at least 1) in
    each subspace, each a normalized Gaussian vector (Box-Muller on Philox (seed,
    ``Stream.DIRECTIONS``, realization, batch-local index)) restricted to its axes.

    Parameters
    ----------
    seed : int
    realizations : ndarray of int (sets,)
    batch : int
        The iteration.
    K : int
    d : int
    spaces : tuple of tuple of int
    count : int, optional
        Give the directions of ``count`` batches from ``batch`` on, in one call.

    Returns
    -------
    ndarray (sets, K + len(spaces) max(K // 2, 1), d)
        Or (sets, count, K + ..., d) with ``count``; each batch's the same bits either way.
    """
    per = max(K // 2, 1)
    total = K + per * len(spaces)
    mask = np.ones((total, d))
    for s, axes in enumerate(spaces):
        mask[K + s * per:K + (s + 1) * per] = 0.0
        mask[K + s * per:K + (s + 1) * per, list(axes)] = 1.0
    r = np.asarray(realizations, dtype=np.uint32)[:, None, None, None]
    batches = np.uint64(batch) + np.arange(1 if count is None else count, dtype=np.uint64)
    index = batches[:, None] * np.uint64(total) + np.arange(total, dtype=np.uint64)
    index = index.astype(np.uint32)[None, :, :, None]
    dim = np.arange(d, dtype=np.uint32)
    u1, u2 = philox.uniform_pair(seed, philox.Stream.DIRECTIONS, r, index, dim)
    g = np.sqrt(-2.0 * np.log1p(-u1)) * np.cos(2.0 * math.pi * u2) * mask
    norm = np.sqrt((g * g).sum(axis=-1, keepdims=True))
    # a vector of zeros (every u1 of it 0) becomes the first axis of its subspace
    first = np.zeros((total, d))
    first[np.arange(total), np.argmax(mask, axis=1)] = 1.0
    theta = np.where(norm > 0.0, g / np.where(norm > 0.0, norm, 1.0), first)
    return theta[:, 0] if count is None else theta


@dataclasses.dataclass(frozen=True)
class SOTInfo(SampleInfo):
    """What a sliced-optimal-transport run did, per realization (first axis).

    Attributes
    ----------
    realizations : ndarray (r,)
    cost_history : ndarray (r, T)
        Entry t: the sliced transport cost of batch t before its move, the mean over its
        directions of the mean squared 1-D displacement. A set that stopped early holds
        its last value.
    iterations : ndarray (r,)
        The batches each set ran.
    converged : ndarray of bool (r,)
        Whether the set stopped because the mean cost over the last ``WINDOW`` batches fell
        by at most ``tol`` of the previous window's, before ``iterations``.
    """

    cost_history: np.ndarray = info_field("pad")
    iterations: np.ndarray = info_field()
    converged: np.ndarray = info_field()


def _order(proj):
    """Each row's argsort, ties by index: the order of a stable sort.

    NumPy's default sort (introsort, in SIMD where the CPU has it) is several times faster
    than its stable one on doubles; where a row's sorted values hold no two equal
    neighbours its order is the only one, hence the stable sort's, and only the rows with a
    tie are sorted again stably.

    Parameters
    ----------
    proj : ndarray (..., n)

    Returns
    -------
    ndarray of intp (..., n)
    """
    order = np.argsort(proj, axis=-1)
    key = np.take_along_axis(proj, order, axis=-1)
    tied = np.any(key[..., 1:] == key[..., :-1], axis=-1)
    if tied.any():
        order[tied] = np.argsort(proj[tied], axis=-1, kind="stable")
    return order


def _ranks(proj):
    """The rank of each projection in its row, ties by index (a stable sort)."""
    rank = np.empty(proj.shape, dtype=np.uint32)
    np.put_along_axis(rank, _order(proj), np.arange(proj.shape[-1], dtype=np.uint32)[None, None, :]
                      * np.ones(proj.shape[:-1] + (1,), dtype=np.uint32), axis=-1)
    return rank


def sot_optimize(start_points, seed, directions_per_batch=DIRECTIONS, iterations=ITERATIONS,
                 step=STEP, tol=TOL, spaces=(), backend="opencl", realizations=None):
    """Sliced optimal transport from given starting sets.

    Parameters
    ----------
    start_points : ndarray (r, n, d)
    seed : int
        Seeds the directions.
    directions_per_batch : int
        K, the full-space directions of a batch.
    iterations : int
    step : float, optional
        Multiplies the batch's mean displacement (default d, the full step).
    tol : float
        Stop when a window's mean cost is not below (1 - tol) times the previous one's
        (0: run every batch).
    spaces : tuple of tuple of int
        Subspaces also optimized (:func:`subspaces`).
    backend : {"opencl", "numpy"}
    realizations : array_like of int, optional
        The indices of the sets (their directions; default 0..r-1).

    Returns
    -------
    points : ndarray (r, n, d)
    info : SOTInfo
    """
    resident = False
    if backend == "numpy":
        batch = batch_reference
    else:
        runtime.require_fp64()
        batch, resident = sot_device.batch_device, runtime.shape().host_sort
    x = np.array(start_points, dtype=np.float64)
    r, n, d = x.shape
    step = float(d) if step is None else step
    index = np.arange(r) if realizations is None else np.asarray(realizations)
    active = np.ones(r, dtype=bool)
    converged = np.zeros(r, dtype=bool)
    ran = np.zeros(r, dtype=np.int64)
    history = []
    cost = np.zeros(r)
    K = directions_per_batch + max(directions_per_batch // 2, 1) * len(spaces)
    # the directions and slices of a block of batches come from one call each; the first
    # block is short, so that the device starts while the host makes the next
    chunk = int(np.clip(BLOCK_BYTES // (r * K * (16 << d) + 1), 1, 64))
    runner, held = None, None           # resident: the batches of the sets ``held``
    pending = []                        # (sets, per-point costs or None) not yet summed
    # resident: each group's costs are read without a wait (ResidentBatches.costs), and
    # without a tolerance collected one group later, while the device runs the next group
    behind = []
    first, end = 0, 0                   # the block's first batch and the one after it

    def settle(entries, sums):
        for (sets, _), total in zip(entries, sums, strict=True):
            cost[sets] = total / (n * K)
            history.append(cost.copy())

    for it in range(iterations):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        fresh = it == end
        if fresh:
            count = min(chunk if it else min(chunk, SETTLE), iterations - it)
            first, end = it, it + count
            block = directions(seed, index, it, directions_per_batch, d, spaces, count)
            slices = Slice.of(block.reshape(-1, d))
        b = it - first
        if resident:
            if held is None or not np.array_equal(held, idx):
                if held is not None:
                    x[held] = runner.result()
                runner = sot_device.ResidentBatches(x[idx], K, step / K, SETTLE)
                held, fresh = idx, True
            if fresh:                   # the block's rows of the held sets, batch-major
                rows = (idx[None, :, None] * count + np.arange(count)[:, None, None]) * K
                runner.block(block[idx].transpose(1, 0, 2, 3),
                             slices.take((rows + np.arange(K)).ravel()))
            runner.batch(b)
            pending.append((idx, None))
        else:
            theta = np.ascontiguousarray(block[idx, b])
            rows = ((idx[:, None] * count + b) * K + np.arange(K)).ravel()
            y, per_point = batch(np.ascontiguousarray(x[idx]), theta, slices.take(rows), step / K)
            x[idx] = y
            pending.append((idx, per_point))
        ran[idx] += 1
        if tol > 0.0 or len(pending) == SETTLE or it + 1 == iterations:
            if resident:
                behind.append((pending, runner.costs(wait=False)))
            else:
                settle(pending, [cost_sums(p) for _, p in pending])
            pending = []
            # one group stays in flight, unless the stop needs its costs or the run ends
            in_flight = int(tol == 0.0 and it + 1 < iterations)
            while len(behind) > in_flight:
                entries, ticket = behind.pop(0)
                settle(entries, runner.collect(ticket))
        if tol > 0.0 and it + 1 >= 2 * WINDOW:
            h = np.stack(history[-2 * WINDOW:], axis=1)[idx]
            done = h[:, WINDOW:].mean(axis=1) >= (1.0 - tol) * h[:, :WINDOW].mean(axis=1)
            converged[idx[done]] = True
            active[idx[done]] = False
    if held is not None:
        x[held] = runner.result()
    history = np.stack(history, axis=1) if history else np.empty((r, 0))
    info = SOTInfo(realizations=index.astype(np.int64), cost_history=history, iterations=ran,
                   converged=converged)
    return x, info


@register("sot")
class SOTSampler(Sampler):
    """Sliced optimal transport sampling: points moved toward the uniform measure on the
    unit cube by 1-D optimal transports along random directions.

    Parameters
    ----------
    d : int
        Dimension, 2 to 8.
    seed : int
        Seeds the starting points (the ``random`` sampler's) and the directions.
    directions : int
        Full-space directions a batch (default 32).
    iterations : int
        Batches (default 256).
    step : float, optional
        Multiplies the batch's mean displacement (default d, the full step; at most 2d).
    tol : float
        Stop once the mean transport cost over 16 batches is not below (1 - tol) times that
        of the 16 before (default 0: run every batch).
    projections : None, "pairs", list of tuples of int, or str
        The projective variant: also optimize these coordinate projections (``"pairs"``:
        every 2-D one; text such as ``"0,1;2,3"`` for [(0, 1), (2, 3)]), each with
        ``directions // 2`` directions a batch drawn in its subspace.
    backend : {"opencl", "numpy"}

    Notes
    -----
    A batch draws K random unit directions theta_k, projects the points on each, sorts the
    projections and matches the i-th smallest to the quantile F_k^-1((i + 1/2) / n) of
    <theta_k, U>, U uniform in [0, 1)^d: the 1-D optimal transport between the projected
    points and the projected measure. Each point then moves by ``step`` times the mean over
    the batch of its 1-D displacements along their directions, a step of stochastic
    gradient descent on the sliced Wasserstein distance between the points and the uniform
    measure (Paulin et al. 2020, Algorithm 1); ``cost_history`` is that distance as the
    batches see it, which falls on average. The projected measure is the distribution of a
    sum of scaled uniforms, whose CDF is a piecewise polynomial of degree d (the
    alternating sum over the cube's vertices); its quantiles are found in closed form
    where at most two components count (every 2-D direction: a trapezoid) and by
    safeguarded Newton steps to 1e-14 of their range otherwise. The projective variant
    ("projective blue noise") also draws directions within chosen coordinate subspaces, so
    that those projections of the set are optimized too, as the authors' multi-projection
    code does.

    The step: a random unit direction has E[theta theta^T] = I / d, so the batch's mean
    moves a point by about 1/d of its transport displacement. The default step d is the
    full step; it reaches a given quality in a half (2-D) to a quarter (4-D) of the
    batches that step 1, the authors' code's scaling, needs. Longer steps overshoot: near
    2d the low-frequency power rises and falls from batch to batch, and beyond 2d (refused)
    the points pile up on the cube's faces.

    Points stay in the cube [0, 1)^d (a move outside is clamped; the target measure is the
    cube's, not the torus's). Directions and each direction's vertex sums are host code;
    the quantiles (in vector lanes on CPUs), the projections, the sort, the moves and the
    costs run on the device (``kernels/sot.cl``): the sort by a bitonic network on GPUs,
    by buckets one direction a work-item on CPUs, where the points stay on the device for
    the whole run. The NumPy twin gives the same bits.

    References
    ----------
    .. [1] L. Paulin, N. Bonneel, D. Coeurjolly, J.-C. Iehl, A. Webanck, M. Desbrun,
       V. Ostromoukhov, "Sliced Optimal Transport Sampling", ACM Trans. Graph. 39(4),
       2020 (SIGGRAPH).

    Examples
    --------
    >>> import clsamp
    >>> s = clsamp.make_sampler("sot", d=2, seed=1, iterations=64)
    >>> pts, info = s.sample(256, return_info=True)
    >>> pts.shape, bool(info.cost_history[0, -8:].mean() < info.cost_history[0, :8].mean())
    ((256, 2), True)
    """

    dimensions = tuple(range(2, MAX_D + 1))
    max_d = MAX_D
    max_d_source = "the projected cube's CDF sums 2^d vertex terms"
    expensive = True
    accepts_start = False
    needs_fp64 = True
    info = SOTInfo

    def __init__(self, d=2, seed=0, directions=DIRECTIONS, iterations=ITERATIONS, step=STEP,
                 tol=TOL, projections=None, backend="opencl"):
        super().__init__(d=d, seed=seed, backend=backend)
        self.directions = check_positive_int(directions, "directions", maximum=4096)
        self.iterations = check_positive_int(iterations, "iterations", maximum=MAX_ITERATIONS)
        self.step = float(self.d) if step is None else check_real(
            step, "step", minimum=0.0, open_minimum=True, maximum=MAX_STEP * self.d)
        self.tol = check_real(tol, "tol", minimum=0.0, maximum=1.0)
        self.projections = subspaces(projections, self.d)

    def _run(self, n, realizations, backend):
        start = make_sampler("random", d=self.d, seed=self.seed,
                             backend=self.backend).sample(n, realizations=realizations)
        return sot_optimize(start, self.seed, self.directions, self.iterations, self.step,
                            self.tol, self.projections, backend,
                            np.arange(realizations.start, realizations.stop))

    def _work_bytes(self, n):
        # measured: 1318, 1400 and 1480 bytes a point in 2-D, 4-D and 8-D
        return (1270 + 27 * self.d) * n

    def _reference(self, n, realizations, start):
        return self._run(n, realizations, "numpy")

    def _device(self, n, realizations, start, out=None):
        return self._run(n, realizations, "opencl")
