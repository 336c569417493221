"""The L-infinity star discrepancy: exact in 2-D and 3-D, certified bounds beyond.

D*_n = sup over anchored boxes [0, q) of |A([0, q)) / n - vol([0, q))|, A counting points.
The supremum is attained (as a limit) at the critical boxes, whose corner coordinates are
the points' coordinates or 1: the largest of A([0, q]) / n - vol(q) over closed boxes and
of vol(q) - A([0, q)) / n over open boxes, q on that grid (Niederreiter 1972).
"""

import itertools
import numbers
from typing import NamedTuple

import numpy as np

from .. import runtime
from ..errors import InvalidArgumentError
from ..validation import check_bool, check_points, point_sets

EXACT_DIMENSIONS = (1, 2, 3)
MAX_EXACT_3D = 2048             # n beyond which 3-D exact (O(n^3)) asks for bounds=True
MAX_TWIN = {1: 2**32, 2: 8192, 3: 128}   # the exact NumPy twin's n: 2-D 48 (n + 1)^2 bytes
                                         # (3.2 GB at 8192), 3-D O(n^4) (4.2 s at 64, x9 a doubling)
MAX_LEAVES = 1 << 22            # boxes of a bounds partition at most (memory)
STAR_WORK = 1 << 33             # corner-point tests of a bounds call at most (seconds)
ESTIMATE_ERROR = 2.0**-19      # bound of a box's float estimate (kernels/star_discrepancy.cl)
SNAPPED = 64                    # best corners of each kind snapped to critical boxes
DELTAS = tuple(2.0 ** (-k / 2) for k in range(0, 17))      # 1, 0.71, 0.5, ... 0.004


def _critical_grids(points):
    """Per dimension the sorted distinct coordinates with 1 appended."""
    return [np.append(np.unique(points[:, k]), 1.0) for k in range(points.shape[1])]


def star_discrepancy_brute(points):
    """The star discrepancy by its definition: every critical box counted directly, O(n^(d+1)),
    for tests.

    Parameters
    ----------
    points : ndarray (n, d)
        A small checked set: the work grows as n^(d+1).

    Returns
    -------
    float
    """
    n, d = points.shape
    best = 0.0
    for q in itertools.product(*_critical_grids(points)):
        q = np.asarray(q)
        volume = float(np.prod(q))
        closed = np.count_nonzero(np.all(points <= q, axis=1))
        open_ = np.count_nonzero(np.all(points < q, axis=1))
        best = max(best, closed / n - volume, volume - open_ / n)
    return best


def _star_1d(x):
    """1-D, over the critical points t (the coordinates and 1): O(n log n)."""
    n = len(x)
    x = np.sort(x)
    t = np.append(np.unique(x), 1.0)
    closed = np.searchsorted(x, t, side="right")
    open_ = np.searchsorted(x, t, side="left")
    return float(max(np.max(closed / n - t), np.max(t - open_ / n)))


def exact_limit(d, backend):
    """The most points a set may have for the exact star discrepancy in ``d`` dimensions on
    ``backend`` (:func:`star_discrepancy` refuses more without ``bounds=True``).

    Parameters
    ----------
    d : int
    backend : {"opencl", "numpy"}

    Returns
    -------
    int
        0 where d has no exact method (d > 3).
    """
    if d not in EXACT_DIMENSIONS:
        return 0
    most = MAX_EXACT_3D if d == 3 else MAX_TWIN[1]
    return min(most, MAX_TWIN[d]) if backend == "numpy" else most


def star_discrepancy_reference(points):
    """NumPy twin of the 2-D kernel, with the same arithmetic: the counts of all critical boxes
    at once from a 2-D prefix sum, in (n + 1)^2 memory.

    Parameters
    ----------
    points : ndarray (n, 2)
        One set.

    Returns
    -------
    float
        D*.
    """
    (points,), _ = check_points(points, "points", d=2, allow_batch=False)
    n, d = points.shape
    xs, ys = _critical_grids(points)[:2]
    ix = np.searchsorted(xs, points[:, 0])
    iy = np.searchsorted(ys, points[:, 1])
    hist = np.zeros((len(xs), len(ys)), dtype=np.int64)
    np.add.at(hist, (ix, iy), 1)
    closed = hist.cumsum(0).cumsum(1)                   # #{x <= xs[a], y <= ys[b]}
    open_ = np.zeros_like(closed)
    open_[1:, 1:] = closed[:-1, :-1]                    # #{x < xs[a], y < ys[b]}
    area = xs[:, None] * ys[None, :]
    return float(max(np.max(closed / n - area), np.max(area - open_ / n)))


def _sweep_device(points):
    """The exact sweep of ``kernels/star_discrepancy.cl`` (2-D or 3-D) for one set: in
    double, or without fp64 the same bits in integer arithmetic (the kernel's notes)."""
    import pyopencl.array as cla
    q = runtime.queue()
    n, d = points.shape
    order = np.lexsort((points[:, 0],))                 # by x (stable)
    # + 0.0: a -0.0 as +0.0 (the same value; its bit pattern would compare as the largest)
    p = np.ascontiguousarray(points[order]) + 0.0
    x = p[:, 0]
    flags = np.zeros(n, dtype=np.uint8)
    flags[np.concatenate(([True], x[1:] != x[:-1]))] |= 1
    flags[np.concatenate((x[1:] != x[:-1], [True]))] |= 2
    grids = _critical_grids(p)

    def padded(values):
        return np.concatenate([values, np.ones((-len(values)) % 4)])

    if d == 2:
        sy, sz, ny = padded(grids[1]), np.ones(4), 1
        items = len(sy) // 4
        zs = np.zeros(1)
    else:
        sy, sz = grids[1], padded(grids[2])
        ny = len(sy)
        items = ny * (len(sz) // 4)
        zs = p[:, 2]
    nz4 = (len(sz) // 4) if d == 3 else items
    dev = [runtime.to_device(np.ascontiguousarray(a)) for a in (x, p[:, 1], zs, flags, sy, sz)]
    head = [a.data for a in dev[:4]] + [np.uint32(n), dev[4].data, dev[5].data]
    if runtime.current_device().fp64:
        out = cla.empty(q, max(items, 1), np.float64)
        runtime.kernel("star_discrepancy.cl", "star_sweep", {"DIM": d})(
            q, (items,), None, *head, np.uint32(ny), np.uint32(nz4), out.data)
        return float(out.get().max())
    # without fp64: every box's float estimate, then the exact values of the boxes that
    # could be the largest, in the work-items that hold them (the kernel's notes); in
    # launches of a few points each where the device limits a work-item's loops (llvmpipe:
    # the state carries the counts between them)
    inverse_n = np.float32(1.0 / n)
    limit = runtime.loop_limit()
    estimates = cla.empty(q, items, np.float32)
    state = np.zeros((items, 12), np.uint32)
    state[:, 8:] = np.float32(-1.0).view(np.uint32)
    state = runtime.to_device(state)
    kernel = runtime.kernel("star_discrepancy.cl", "star_estimate", {"DIM": d})
    for k0, k1 in _chunks(n, limit and limit // 2):
        kernel(q, (items,), None, *head, np.uint32(items), np.uint32(nz4), inverse_n,
               np.uint32(k0), np.uint32(k1), state.data, estimates.data)
    estimates = estimates.get()
    top = estimates.max()
    picked = np.flatnonzero(estimates >= float(top) - 2 * ESTIMATE_ERROR).astype(np.uint32)
    out = cla.empty(q, len(picked), np.float64)          # the bits of doubles
    ratios = runtime.to_device(np.arange(n + 1) / n)     # fl(c / n), c = 0..n
    state = np.zeros((len(picked), 12), np.uint32)
    state[:, 10] = top.view(np.uint32)
    state = runtime.to_device(state)
    kernel = runtime.kernel("star_discrepancy.cl", "star_sweep", {"DIM": d})
    picked_device = runtime.to_device(picked)
    for k0, k1 in _chunks(n, limit and limit // 16):    # 9 iterations a point at most
        kernel(q, (len(picked),), None, *head, picked_device.data,
               np.uint32(len(picked)), np.uint32(nz4), ratios.data, inverse_n, np.uint32(k0),
               np.uint32(k1), state.data, out.data)
    return float(out.get().max())


def _chunks(n, size):
    """[k0, k1) ranges of at most ``size`` points (all n at once for None)."""
    size = size or n
    return [(k, min(n, k + size)) for k in range(0, n, size)]


class StarBounds(NamedTuple):
    """Certified bounds of the star discrepancy: ``lower <= D* <= upper``."""
    lower: float
    upper: float


def delta_partition(d, delta, budget=MAX_LEAVES):
    """A delta-partition of [0, 1]^d: boxes [a, b] covering the cube, each with
    vol(b) - vol(a) <= delta.

    Built level by level: a box that is not yet small enough gives the corner box [g, b] with
    g = max(a, t b), t = (1 - delta / vol(b))^(1/d) (so vol(b) - vol(g) <= delta), and the d
    boxes of the rest, {x_j >= g_j for j < k, x_k < g_k} for k = 1..d, each split again (the
    decomposition of Thiemard 2001).

    Parameters
    ----------
    d : int
    delta : float
        In (0, 1].
    budget : int, optional
        The most boxes.

    Returns
    -------
    (ndarray, ndarray) or None
        The lower and upper corners a and b, each (L, d); None where the partition needs more
        than ``budget`` boxes.
    """
    lo, hi = np.zeros((1, d)), np.ones((1, d))
    leaves_lo, leaves_hi, total = [], [], 0
    while len(lo):
        vol_hi = np.prod(hi, axis=1)
        leaf = vol_hi - np.prod(lo, axis=1) <= delta
        leaves_lo.append(lo[leaf])
        leaves_hi.append(hi[leaf])
        lo, hi, vol_hi = lo[~leaf], hi[~leaf], vol_hi[~leaf]
        g = np.maximum(lo, ((1.0 - delta / vol_hi) ** (1.0 / d))[:, None] * hi)
        leaves_lo.append(g)
        leaves_hi.append(hi)
        total += int(np.count_nonzero(leaf)) + len(g)
        if total > budget:
            return None
        next_lo, next_hi = [], []
        for k in range(d):
            keep = g[:, k] > lo[:, k]
            box_lo = np.concatenate([g[keep, :k], lo[keep, k:]], axis=1)
            box_hi = hi[keep].copy()
            box_hi[:, k] = g[keep, k]
            next_lo.append(box_lo)
            next_hi.append(box_hi)
        lo, hi = np.concatenate(next_lo), np.concatenate(next_hi)
    return np.concatenate(leaves_lo), np.concatenate(leaves_hi)


def anchored_counts_reference(points, corners, strict=True):
    """NumPy twin of the anchored_counts kernel (:func:`anchored_counts`).

    Parameters
    ----------
    points, corners, strict
        As :func:`anchored_counts` takes them.

    Returns
    -------
    ndarray of int64, shape (m,)
    """
    out = np.empty(len(corners), dtype=np.int64)
    step = max(1, (1 << 24) // max(1, points.size))
    for lo in range(0, len(corners), step):
        c = corners[lo:lo + step, None, :]
        inside = points[None] < c if strict else points[None] <= c
        out[lo:lo + step] = np.count_nonzero(np.all(inside, axis=2), axis=1)
    return out


def anchored_counts(points, corners, strict=True, backend="opencl"):
    """For each corner c, the number of points in the anchored box [0, c) or [0, c], in OpenCL
    (``kernels/anchored_counts.cl``).

    Parameters
    ----------
    points : ndarray (n, d)
    corners : ndarray (m, d)
    strict : bool
        Count p < c in every coordinate (the open box); else p <= c.
    backend : {"opencl", "numpy"}
        ``"numpy"``: :func:`anchored_counts_reference`.

    Returns
    -------
    ndarray of int64, shape (m,)

    Notes
    -----
    Comparisons only, so the counts are exact on every device; without fp64 the kernel
    compares the float64 bit patterns as unsigned integers (for non-negative doubles the
    same order), so :func:`star_bounds` runs there too, with the same results.
    """
    if backend == "numpy":
        return anchored_counts_reference(points, corners, strict)
    q = runtime.queue()
    n, d = points.shape
    kernel = runtime.kernel("anchored_counts.cl", "anchored_counts",
                            {"D": d, "STRICT": int(bool(strict))})
    device_points = runtime.to_device(np.ascontiguousarray(points))
    out = np.empty(len(corners), dtype=np.int64)
    for lo, hi in runtime.chunk_ranges(len(corners), 8 * (d + 1)):
        m4 = -(-(hi - lo) // 4) * 4
        block = np.zeros((d, m4))
        block[:, :hi - lo] = corners[lo:hi].T
        counts = runtime.Output((m4,), np.uint32, host=np.empty(m4, dtype=np.uint32))
        kernel(q, (m4 // 4,), None, device_points.data, np.uint32(n),
               runtime.to_device(block).data, np.uint32(m4), counts.buffer)
        out[lo:hi] = counts.finish()[:hi - lo]
    return out


def _snapped(points, corner, excess):
    """A critical box near ``corner`` with a larger local discrepancy. Excess (a closed box
    with many points): each coordinate shrunk to the largest coordinate of the points in
    [0, corner], the same points in less volume. Deficit (an open box with few): each
    coordinate in turn grown to the nearest coordinate above of a point that would enter,
    the same points in more volume. Returns the box's local discrepancy (exact counts)."""
    n, d = points.shape
    q = corner.copy()
    if excess:
        inside = np.all(points <= q, axis=1)
        if not inside.any():
            return 0.0
        q = points[inside].max(axis=0)
        return np.count_nonzero(np.all(points <= q, axis=1)) / n - float(np.prod(q))
    for k in range(d):
        others = np.all(np.delete(points < q, k, axis=1), axis=1)
        above = points[others & (points[:, k] >= q[k]), k]
        q[k] = above.min() if len(above) else 1.0
    return float(np.prod(q)) - np.count_nonzero(np.all(points < q, axis=1)) / n


def star_bounds(points, delta=None, backend="opencl"):
    """Certified bounds of the star discrepancy, any d.

    A delta-partition of the cube into boxes [a, b] (:func:`delta_partition`) bounds every
    anchored box [0, q) with a <= q <= b: its count lies between A([0, a)) and A([0, b)) and
    its volume between vol(a) and vol(b), so D* <= the largest
    max(A([0, b)) / n - vol(a), vol(b) - A([0, a)) / n) over the boxes, and D* >= the largest
    local discrepancy of the real boxes at the corners; the gap is at most delta. The lower
    bound is raised further by snapping the best corners to critical boxes. Both bounds
    include the floating-point rounding of the volumes. Certified upper bounds are hard in
    high d (the partition grows like (d / delta)^d / d!): expect a wide gap beyond d = 6.

    Parameters
    ----------
    points : ndarray (n, d)
        One checked set.
    delta : float, optional
        The partition's delta; None takes the smallest of a ladder (1, 0.71, 0.5, ...) whose
        partition fits the work budget (corners times points).
    backend : {"opencl", "numpy"}
        Where the corners are counted (:func:`anchored_counts`).

    Returns
    -------
    StarBounds
        ``lower <= D* <= upper``.

    Raises
    ------
    InvalidArgumentError
        A ``delta`` whose partition has too many boxes.
    """
    n, d = points.shape
    leaves = max(1, min(MAX_LEAVES, STAR_WORK // (2 * n)))
    if delta is None:
        parts = None
        for rung in DELTAS:
            # each rung has about 2^(d/2) times the boxes of the one before: skip the try
            # that is sure to overflow
            if parts is not None and len(parts[0]) * 2.0 ** (d / 2) > 2 * leaves:
                break
            found = delta_partition(d, rung, leaves)
            if found is None:
                break
            parts = found
    else:
        parts = delta_partition(d, float(delta), max(leaves, MAX_LEAVES))
        if parts is None:
            raise InvalidArgumentError(
                f"'delta' = {delta} needs a partition of more than {max(leaves, MAX_LEAVES)} "
                f"boxes in d = {d}; choose a larger delta (or None)")
    lo, hi = parts
    counts = anchored_counts(points, np.concatenate([lo, hi]), True, backend)
    count_lo, count_hi = counts[:len(lo)] / n, counts[len(lo):] / n
    vol_lo, vol_hi = np.prod(lo, axis=1), np.prod(hi, axis=1)
    rounding = (d + 2) * 2.0**-52
    upper = float(np.max(np.maximum(count_hi - vol_lo, vol_hi - count_lo))) + rounding
    local = np.concatenate([count_lo - vol_lo, count_hi - vol_hi])
    corners = np.concatenate([lo, hi])
    lower = float(np.max(np.abs(local)))
    for excess in (True, False):
        score = local if excess else -local
        best = np.argpartition(score, -min(SNAPPED, len(score)))[-SNAPPED:]
        for c in best:
            lower = max(lower, _snapped(points, corners[c], excess))
    lower = max(0.0, float(lower) - rounding)
    return StarBounds(lower, min(1.0, max(upper, lower)))


def star_discrepancy(points, bounds=False, backend="opencl", delta=None):
    """The L-infinity star discrepancy D*_n of a point set.

    Parameters
    ----------
    points : ndarray (n, d) or (r, n, d), or a list of (n_k, d) arrays
        Points in [0, 1)^d.
    bounds : bool
        False: the exact value, d = 1, 2 or 3 (3-D up to n = 2048; on NumPy 2-D up to
        8192 and 3-D up to 128). True:
        ``StarBounds(lower, upper)``, certified bounds for any d (:func:`star_bounds`),
        for when d > 3 or n is too large for the exact value.
    backend : {"opencl", "numpy"}
        Where the exact sweep and the bounds' counts run (the NumPy twins: 2-D prefix
        counts, 3-D the brute force).
    delta : float, optional
        With ``bounds=True`` only: the largest gap between the bounds the partition may
        leave; None picks the smallest that fits the work budget.

    Returns
    -------
    float, or StarBounds(lower, upper) (a tuple); an ndarray (r,) or (r, 2) for r sets.

    Raises
    ------
    InvalidArgumentError
        d > 3, or n past the limits above, without ``bounds=True``; ``delta`` without it.

    Notes
    -----
    The supremum over anchored boxes is attained at the critical boxes, whose corner
    coordinates are the points' coordinates or 1 (closed boxes for the excess of points,
    open ones for the deficit). The exact algorithm sorts the points by x and sweeps
    them once per threshold of the other axes, keeping the counts of the closed and open
    boxes as it goes: O(n^2) in 2-D, O(n^3) in 3-D, both in OpenCL, four thresholds per
    work-item (de Clerck 1986 computes the 2-D case the same way; Dobkin, Eppstein and
    Mitchell 1996 bound the general case). In 1-D the known closed form is
    1/(2n) + max_i |x_(i) - (2i - 1)/(2n)|, which this gives too.

    On a device without fp64 the exact value is the same double, bit for bit: each box's
    value fl(fl(c/n) - fl(fl(t s) u)) is computed as its correctly rounded IEEE-754 bits in
    integer arithmetic (``kernels/f64bits.h``), and since rounding is monotone the largest
    is the double sweep's. A first pass estimates every box in float, within 2^-19 of its
    value, and only boxes whose estimates come within twice that of the best are evaluated
    so, which keeps the cost near the double sweep's (``kernels/star_discrepancy.cl``).

    References
    ----------
    .. [1] H. Niederreiter, "Discrepancy and convex programming", Ann. Mat. Pura Appl. 93,
       1972.
    .. [2] L. de Clerck, "A method for exact calculation of the star-discrepancy of plane
       sets applied to the sequences of Hammersley", Monatsh. Math. 101, 1986.
    .. [3] D. P. Dobkin, D. Eppstein, D. P. Mitchell, "Computing the discrepancy with
       applications to supersampling patterns", ACM TOG 15(4), 1996.

    Examples
    --------
    >>> import numpy as np, clsamp
    >>> x = (2 * np.arange(1, 9) - 1)[:, None] / 16          # the midpoints: D* = 1/(2n)
    >>> clsamp.star_discrepancy(x)
    0.0625
    >>> lo, hi = clsamp.star_discrepancy(clsamp.make_sampler("sobol", d=5).sample(1024),
    ...                                  bounds=True)
    >>> bool(0 < lo <= hi)
    True
    """
    sets = point_sets(points)
    if sets is not None:
        return np.array([star_discrepancy(s, bounds, backend, delta) for s in sets])
    if backend not in ("opencl", "numpy"):
        raise InvalidArgumentError(f"'backend' must be 'opencl' or 'numpy', got {backend!r}")
    batch, single = check_points(points, "points")
    r, n, d = batch.shape
    bounds = check_bool(bounds, "bounds")
    if delta is not None and not bounds:
        raise InvalidArgumentError("'delta' is the bounds' gap; give bounds=True with it")
    if not bounds:
        if d not in EXACT_DIMENSIONS:
            raise InvalidArgumentError(
                f"the exact star discrepancy is implemented for d = 1, 2, 3, got d = {d}; "
                "star_discrepancy(points, bounds=True) (clsamp metrics --bounds) gives certified "
                "(lower, upper) bounds")
        if d == 3 and n > MAX_EXACT_3D:
            raise InvalidArgumentError(
                f"the exact 3-D star discrepancy costs O(n^3): n = {n} is more than "
                f"{MAX_EXACT_3D}; use bounds=True")
        if n > exact_limit(d, backend):                # the NumPy twin's own limits
            raise InvalidArgumentError(
                f"the NumPy twin's exact {d}-D star discrepancy takes n <= {MAX_TWIN[d]}, got "
                f"n = {n}; use backend='opencl' or bounds=True")
        values = []
        for k in range(r):
            p = batch[k]
            if d == 1:
                values.append(_star_1d(p[:, 0]))
            elif backend == "numpy" and d == 2:
                values.append(star_discrepancy_reference(p))
            elif backend == "numpy":
                values.append(star_discrepancy_brute(p))
            else:
                values.append(_sweep_device(p))
        out = np.array(values)
        return float(out[0]) if single else out
    if delta is not None and (isinstance(delta, bool) or not isinstance(delta, numbers.Real)
                              or not 0.0 < delta <= 1.0):
        raise InvalidArgumentError(f"'delta' must be a number in (0, 1], got {delta!r}")
    out = [star_bounds(batch[k], delta, backend) for k in range(r)]
    return out[0] if single else np.array(out)
