"""L2-type discrepancies of point sets, in closed form over pairs of points.

For n points x_i in [0, 1)^d each discrepancy here is

    D^2 = c0 + c1 / n * sum_i prod_k f(x_ik) + c2 / n^2 * sum_i sum_j prod_k g(x_ik, x_jk),

an O(n^2 d) sum computed in OpenCL (``kernels/discrepancy.cl``), with every sum added
without rounding error on the host (``math.fsum`` of compensated partial sums), so that
the cancellation between the three terms costs no more than the terms' own rounding.
The NumPy reference (``backend="numpy"``) evaluates the same formulas in blocks.
"""

import dataclasses
import math
from fractions import Fraction

import numpy as np

from .. import runtime
from ..errors import InvalidArgumentError
from ..float_float import U2, check_precision, split
from ..validation import check_choice, check_int, check_points, check_positive_int, point_sets

METHODS = ("CD", "WD", "MD", "L2-star", "symmetric", "L2")
BACKENDS = ("opencl", "numpy")
ROOTED = {"L2-star", "symmetric", "L2"}      # these are returned as D, the others as D^2
ROW_VECTORS = {"L2-star": 2}                 # RV: row vectors of four per work-item (1 else)
_CODES = {m: k for k, m in enumerate(METHODS)}


def _constants(method, d, n):
    """(c0, c1 / n, c2 / n^2) of the method, exact rationals."""
    n = Fraction(n)
    if method == "CD":
        return Fraction(13, 12) ** d, Fraction(-2) / n, 1 / n**2
    if method == "WD":
        return -Fraction(4, 3) ** d, Fraction(0), 1 / n**2
    if method == "MD":          # f is kept three times larger: 5/3 is not a double
        return Fraction(19, 12) ** d, Fraction(-2) / n / 3**d, 1 / n**2
    if method == "L2-star":
        return Fraction(1, 3) ** d, -Fraction(2) ** (1 - d) / n, 1 / n**2
    if method == "symmetric":
        return Fraction(4, 3) ** d, Fraction(-2) / n, Fraction(2) ** d / n**2
    return Fraction(1, 12) ** d, -Fraction(2) ** (1 - d) / n, 1 / n**2       # L2 (unanchored)


def _terms(method, x, y=None):
    """f(x) per coordinate (y None) or g(x, y) per coordinate pair, broadcast (NumPy), in
    the forms that round least (the kernel's: see the note in kernels/discrepancy.cl)."""
    if y is None:
        a = np.abs(x - 0.5)
        if method == "CD":
            return 1.0 + 0.5 * a - 0.5 * a * a
        if method == "WD":
            return np.ones_like(x)
        if method == "MD":
            return 5.0 - 0.75 * a - 0.75 * a * a           # 3 f
        if method == "L2-star":
            return 1.0 - x * x
        if method == "symmetric":
            return 1.0 + 2.0 * x - 2.0 * x * x
        return x * (1.0 - x)
    if method == "CD":          # 1 + a_i/2 + a_j/2 - |x_i - x_j|/2
        same = (x < 0.5) == (y < 0.5)
        return 1.0 + np.where(same, np.minimum(np.abs(x - 0.5), np.abs(y - 0.5)), 0.0)
    delta = np.abs(x - y)
    if method == "WD":
        return 1.5 - delta + delta * delta
    if method == "MD":
        return (1.875 - 0.25 * np.abs(x - 0.5) - 0.25 * np.abs(y - 0.5) - 0.75 * delta
                + 0.5 * delta * delta)
    if method == "L2-star":
        return 1.0 - np.maximum(x, y)
    if method == "symmetric":
        return 1.0 - delta
    return np.minimum(x, y) * (1.0 - np.maximum(x, y))         # min(x, y) - x y


def _exact_sum(values):
    """The sum of ``values`` as an exact rational of two doubles: fsum's correctly rounded
    sum and the correctly rounded remainder (together within an ulp of the remainder)."""
    values = np.asarray(values, dtype=np.float64).ravel().tolist()
    hi = math.fsum(values)
    lo = math.fsum(values + [-hi])
    return Fraction(hi) + Fraction(lo)


def _combine(method, d, n, single, pairs):
    """The discrepancy from the two sums of the formula (each given as a list of floats
    whose exact sum it is), combined in exact rational arithmetic and rounded once."""
    c0, c1, c2 = _constants(method, d, n)
    value = float(c0 + c1 * _exact_sum(single) + c2 * _exact_sum(pairs))
    if method in ROOTED:
        return math.sqrt(value) if value >= 0.0 else float("nan")
    return value


def discrepancy_reference(points, method="CD"):
    """NumPy twin of :func:`discrepancy` for one set: the same formulas, the pair sum in blocks
    of rows, each row summed by NumPy and the rows added exactly.

    Parameters
    ----------
    points : ndarray (n, d)
        One set.
    method : str
        One of :data:`METHODS`.

    Returns
    -------
    float
        As :func:`discrepancy` gives it for one set.
    """
    check_choice(method, "method", METHODS)
    (points,), _ = check_points(points, "points", allow_batch=False)
    _check_range(method, *points.shape)
    n, d = points.shape
    single = np.prod(_terms(method, points), axis=1)
    pairs = []
    step = max(1, (1 << 22) // max(1, n * d))
    for lo in range(0, n, step):
        block = np.prod(_terms(method, points[lo:lo + step, None, :], points[None, :, :]), axis=2)
        pairs.extend(np.sum(block, axis=1))
    return _combine(method, d, n, single, pairs)


# the largest |g| of a pair term, per method (CD, WD: 3/2; MD: 15/8; symmetric 1 with c2 = 2^d
# / n^2, counted here; L2: 1/4)
_G_MAX = {"CD": 1.5, "WD": 1.5, "MD": 1.875, "L2-star": 1.0, "symmetric": 2.0, "L2": 0.25}
FF_BLOCK = 64                # terms per partial sum in discrepancy_ff.cl


def float_float_bound(method, d):
    """How far the float-float pair sum can move D^2 (``precision="float-float"``).

    Parameters
    ----------
    method : str
        One of :data:`METHODS`.
    d : int

    Returns
    -------
    float
        A bound on |D^2_float-float - D^2|: (17d + 600)·u²·G^d, u = 2^-24, G the largest
        pair factor of the method (3/2 for CD and WD, 15/8 for MD, 1 for L2-star, 2 for
        symmetric, whose c2 is 2^d / n², 1/4 for L2). The rooted methods (L2-star,
        symmetric, L2) return D, off by at most this bound over 2D.

    Notes
    -----
    With the float-float errors of Joldes, Muller & Popescu 2017 (an addition 3u², a
    product 5u², relative): the host's split of each float64 layout number errs by u²;
    each factor g (at most two additions, a product and exact min/max/abs) is then within
    12u² of its value relative to G, and the product of d factors within (17d)u² of
    Π g. A lane of the kernel sums one row's terms (weights 0, 1 or 2, exact) in blocks of
    64 columns, then adds the block sums of its two rows' chunks (at most 2·(4096/64 + 1)
    = 130): each addition errs by at most 3u² times the partial sum, so the sum is within
    3u²·(64 + 130) <= 600u² of the sum of |terms|; the host adds the lanes' sums exactly.
    Σ|Π g| <= n² G^d and c2 = 1/n² give the bound. The double path's own rounding (a few
    ulps of the terms) is below 2^-50 G^d, inside it.
    """
    check_method(method)
    return (17.0 * d + 600.0) * U2 * _G_MAX[method] ** d


def _layouts(batch, method):
    """The rows' and columns' numbers of each point (XR, UR, XC, VC of discrepancy.cl), in
    float64 on the host: (4, r, n, d)."""
    x = batch
    a = np.abs(x - 0.5)
    zero = np.zeros_like(x)
    if method == "CD":          # VC: the factor's floor 1 (discrepancy_ff.cl loads it)
        return np.stack([1.0 + a, np.where(x < 0.5, -0.0, 0.0), np.where(x < 0.5, -(1.0 + a), 1.0 + a),
                         np.ones_like(x)])
    if method == "WD":
        return np.stack([x, zero, x, zero])
    if method == "MD":
        return np.stack([x, 1.875 - 0.25 * a, x, 0.25 * a])
    if method == "L2-star":
        return np.stack([1.0 - x, zero, 1.0 - x, zero])
    return np.stack([x, 1.0 - x, x, (1.0 - x) if method == "L2" else x])   # symmetric, L2


def _device_sums_ff(batch, method):
    """Per realization: the per-point products (r, n) (host, float64) and the pair sum's
    partial sums in float-float from ``discrepancy_ff_pairs``, as float64 values whose exact
    sum it is (r, 2 · chunks · items)."""
    import pyopencl.array as cla
    q = runtime.queue()
    r, n, d = batch.shape
    single = np.prod(_terms(method, batch), axis=2)
    layouts = [cla.to_device(q, np.ascontiguousarray(split(v))) for v in _layouts(batch, method)]
    limit = runtime.loop_limit()
    cols = 4096 if limit is None else max(1, min(4096, limit // (4 * (d + 2))))
    tiles = -(-n // 8)                                     # tiles of 8 rows, two an item
    chunks, items = -(-n // cols), -(-tiles // 2)
    out = cla.empty(q, (r, chunks, items, 8, 2), np.float32)
    defines = {"METHOD": _CODES[method], "D": d, "COLS": cols, "BLOCK": FF_BLOCK}
    runtime.kernel("discrepancy_ff.cl", "discrepancy_ff_pairs", defines)(
        q, (items, chunks, r), None, *(v.data for v in layouts), np.uint32(n), np.uint32(items), out.data)
    return single, out.get().astype(np.float64).reshape(r, -1)


def _device_sums(batch, method):
    """Per realization: (the per-point products (r, n), the row blocks' pair sums as
    (hi, lo) pairs (r, nb, 2)). Each set is sorted by its first coordinate first (the
    kernel's SORT0: the first factor in its cheaper form)."""
    import pyopencl.array as cla
    runtime.require_fp64()
    q = runtime.queue()
    r, n, d = batch.shape
    rv = ROW_VECTORS.get(method, 1)
    npad = -(-n // (4 * rv)) * 4 * rv
    order = np.argsort(batch[:, :, 0], axis=1, kind="stable")
    points = runtime.to_device(np.take_along_axis(batch, order[:, :, None], axis=1))
    defines = {"METHOD": _CODES[method], "D": d, "RV": rv, "SORT0": 1}
    options = ("-cl-mad-enable",)
    xr, ur, xc, vc = (cla.empty(q, (r, d, npad), np.float64) for _ in range(4))
    f = cla.empty(q, (r, npad), np.float64)
    valid = runtime.table(("discrepancy valid", n, npad),
                          lambda: (np.arange(npad) < n).astype(np.float64), np.float64)
    local = runtime.local_size(64)
    runtime.kernel("discrepancy.cl", "discrepancy_prepare", defines, options)(
        q, (-(-npad // local) * local, r), (local, 1), points.data, np.uint32(n),
        np.uint32(npad), xr.data, ur.data, xc.data, vc.data, f.data)
    nb = npad // (4 * rv)
    items = -(-nb // 2)
    out = cla.empty(q, (r, nb, 2), np.float64)
    runtime.kernel("discrepancy.cl", "discrepancy_pairs", defines, options)(
        q, (items, r), None, xr.data, ur.data, xc.data, vc.data, valid.data, np.uint32(n),
        np.uint32(npad), np.uint32(nb), np.uint32(items), out.data)
    return f.get()[:, :n], out.get()


def discrepancy(points, method="CD", backend="opencl", precision=None):
    """The L2-type discrepancy of a point set, as scipy.stats.qmc and UTK define it.

    Parameters
    ----------
    points : ndarray or pyopencl.array.Array, (n, d) or (r, n, d), or a list of (n_k, d)
        Points in [0, 1)^d, n >= 1. A batch (or a list of sets of different sizes) gives
        one value per set, in one launch for a batch.
    method : {"CD", "WD", "MD", "L2-star", "symmetric", "L2"}
        ``"CD"`` centered, ``"WD"`` wrap-around, ``"MD"`` mixture (Hickernell 1998; Zhou
        et al. 2013), ``"L2-star"`` (Warnock 1972), ``"symmetric"`` (Hickernell 1998),
        ``"L2"`` the unanchored (extreme) L2 discrepancy (Morokoff and Caflisch 1994).
    backend : {"opencl", "numpy"}
    precision : {"double", "float-float"}, optional
        What the device computes the pair sum in; default ``"double"`` where the device
        has fp64, ``"float-float"`` where it has not: then |ΔD²| <=
        :func:`float_float_bound` (method, d) = (17d + 600)·2^-48·G^d (G = 3/2 for CD).

    Returns
    -------
    float for one set, ndarray (r,) for r sets.
        As ``scipy.stats.qmc.discrepancy`` returns them: the squared discrepancy for
        ``"CD"``, ``"WD"`` and ``"MD"``, the discrepancy itself (the square root) for
        ``"L2-star"``; ``"symmetric"`` and ``"L2"`` the discrepancy itself, as UTK.

    Raises
    ------
    InvalidArgumentError
        An unknown method, or points that are not a set in [0, 1)^d.

    Notes
    -----
    Each is an integral over a family of boxes of the squared difference between the
    fraction of points in the box and its volume, which the kernel's reproducing property
    turns into the closed form of the module docstring: O(n^2 d) operations, here in
    OpenCL, each pair once (the pair term is symmetric), four rows against one column per
    vector operation. The pair terms are written in the forms that round least (for CD,
    1 + min(|x_i - 1/2|, |x_j - 1/2|) when both coordinates lie on one side of 1/2, else
    1, exactly the textbook term), summed in double with Neumaier compensation every 64
    columns, and the partial sums and the constants (exact rationals) are added on the
    host without rounding. The result is then as accurate as the pair terms allow: a few
    ulps of the terms, divided by D^2 (for 16384 random points in d = 4, against an
    extended-precision evaluation: 4e-15 relative for CD, 2e-15 for WD, 0 for L2-star,
    2e-13 for MD); scipy adds the n^2 terms one by one, which for large n and small D^2
    costs it digits (3e-8 relative for CD there).

    References
    ----------
    .. [1] F. J. Hickernell, "A generalized discrepancy and quadrature error bound",
       Math. Comp. 67(221), 1998.
    .. [2] Y.-D. Zhou, K.-T. Fang, J.-H. Ning, "Mixture discrepancy for quasi-random
       point sets", J. Complexity 29(3-4), 2013.
    .. [3] T. T. Warnock, "Computational investigations of low discrepancy point sets",
       Applications of Number Theory to Numerical Analysis, 1972.
    .. [4] W. J. Morokoff, R. E. Caflisch, "Quasi-random sequences and their
       discrepancies", SIAM J. Sci. Comput. 15(6), 1994.

    Examples
    --------
    >>> import clsamp
    >>> pts = clsamp.make_sampler("sobol", d=2).sample(256)
    >>> rnd = clsamp.make_sampler("random", d=2, seed=1).sample(256)
    >>> bool(clsamp.discrepancy(pts) < clsamp.discrepancy(rnd))
    True
    >>> clsamp.discrepancy(rnd[None].repeat(3, axis=0), method="L2-star").shape
    (3,)
    """
    check_choice(method, "method", METHODS)
    check_choice(backend, "backend", BACKENDS)
    precision = check_precision(precision, backend)
    sets = point_sets(points)
    if sets is not None:
        return np.array([discrepancy(s, method, backend, precision) for s in sets])
    batch, single = check_points(points, "points")
    r, n, d = batch.shape
    _check_range(method, n, d)
    if backend == "numpy":
        values = np.array([discrepancy_reference(batch[k], method) for k in range(r)])
    else:
        values = np.empty(r)
        # per realization: the points, four per-point layouts and the products
        sums = _device_sums_ff if precision == "float-float" else _device_sums
        for lo, hi in runtime.chunk_ranges(r, 8 * (n + 8) * (5 * d + 2)):
            f, pairs = sums(batch[lo:hi], method)
            values[lo:hi] = [_combine(method, d, n, f[k], pairs[k]) for k in range(hi - lo)]
    return float(values[0]) if single else values


_F_MAX = {"CD": 1.125, "WD": 1.0, "MD": 5.0, "L2-star": 1.0, "symmetric": 1.5, "L2": 0.25}


def _check_range(method, n, d):
    """Refuse a d whose largest products (a term's bound to the d) summed n^2 times pass a
    double's range: the sums would be infinite."""
    biggest = max(_F_MAX[method], _G_MAX[method])
    if biggest > 1.0 and d * math.log(biggest) + 2.0 * math.log(n) > 709.0:
        most = int((709.0 - 2.0 * math.log(n)) / math.log(biggest))
        raise InvalidArgumentError(
            f"'points' in d = {d}: the {method} discrepancy's terms reach {biggest:g}^d, past a "
            f"double's range; at most d = {most} for n = {n}")


def check_method(method):
    """Check a discrepancy's name.

    Parameters
    ----------
    method : str

    Returns
    -------
    str
        ``method``.

    Raises
    ------
    InvalidArgumentError
        A name not in :data:`METHODS` (the message lists them).
    """
    if method not in METHODS:
        raise InvalidArgumentError(
            f"'method' must be one of {', '.join(repr(m) for m in METHODS)}; got {method!r}")
    return method


@dataclasses.dataclass
class DiscrepancySweep:
    """A discrepancy against the number of points (:func:`discrepancy_sweep`).

    ``values[k]`` is the root-mean-square over the realizations of the discrepancy D
    (not D^2, for every method) of ``ns[k]`` points; ``stderr`` its standard error.
    """

    sampler: str
    method: str
    ns: np.ndarray
    values: np.ndarray
    stderr: np.ndarray
    realizations: int

    def slope(self):
        """(slope, standard error) of log D against log N over the larger half of the
        sweep (least squares), the rate to hold against N^-1/2 (random) or N^-1 up to
        log factors (low discrepancy)."""
        idx = np.arange(len(self.ns) // 2, len(self.ns))
        idx = idx[self.values[idx] > 0]
        if len(idx) < 2:
            return float("nan"), float("nan")
        x, y = np.log(self.ns[idx].astype(np.float64)), np.log(self.values[idx])
        fit, cov = np.polyfit(x, y, 1, cov=True) if len(idx) > 2 else (np.polyfit(x, y, 1), None)
        return float(fit[0]), float(math.sqrt(cov[0, 0])) if cov is not None else float("nan")

    def to_dict(self):
        """The sweep as JSON-able Python types, with its fitted slope."""
        slope, stderr = self.slope()
        return {"sampler": self.sampler, "method": self.method, "ns": self.ns.tolist(),
                "values": self.values.tolist(), "stderr": self.stderr.tolist(),
                "realizations": int(self.realizations), "slope": slope, "slope_stderr": stderr}


def discrepancy_block(sampler, n, lo, hi, methods):
    """One task of :func:`discrepancy_sweep`: the discrepancies of some realizations of n points.

    Parameters
    ----------
    sampler : Sampler
    n : int
    lo, hi : int
        The realizations lo .. hi - 1.
    methods : sequence of str
        Names in :data:`METHODS`.

    Returns
    -------
    ndarray, shape (len(methods), hi - lo)
    """
    points = sampler.sample(n, realizations=range(lo, hi))
    return np.stack([np.atleast_1d(discrepancy(points, method)) for method in methods])


def discrepancy_sweep(sampler, ns, realizations=8, methods=("CD", "L2-star"), client=None,
                      checkpoint=None, progress=False):
    """Discrepancies of a sampler's sets as N grows.

    Parameters
    ----------
    sampler : Sampler or str
        Any sampler (:func:`clsamp.make_sampler`), or a name made with its defaults; each n
        is moved to its nearest valid count (``sampler.valid_n``), so a grid takes squares.
    ns : sequence of int
    realizations : int
        Sets per n (randomized samplers differ between them, deterministic ones repeat).
    methods : sequence of str
        Any of :data:`METHODS`.
    client : dask.distributed.Client, optional
        Compute the blocks of realizations there (:mod:`clsamp.parallel`): the same values,
        bit for bit.
    checkpoint : str or Path, optional
        A folder keeping every finished block.
    progress : bool

    Returns
    -------
    dict
        ``{method: DiscrepancySweep}``.

    Raises
    ------
    InvalidArgumentError
        A method not in :data:`METHODS`.

    Examples
    --------
    >>> import clsamp
    >>> from clsamp.metrics import discrepancy_sweep
    >>> sweep = discrepancy_sweep(clsamp.make_sampler("random", seed=1), [64, 256, 1024, 4096])
    >>> slope, _ = sweep["L2-star"].slope()
    >>> bool(-0.7 < slope < -0.3)
    True
    """
    from .. import parallel
    from ..samplers import Sampler, make_sampler
    if isinstance(sampler, str):
        sampler = make_sampler(sampler)
    if not isinstance(sampler, Sampler):
        raise InvalidArgumentError(f"'sampler' must be a Sampler or a sampler's name, got {sampler!r}")
    methods = (methods,) if isinstance(methods, str) else tuple(methods)
    if not methods:
        raise InvalidArgumentError("'methods' must name at least one discrepancy")
    for method in methods:
        check_method(method)
    realizations = check_int(realizations, "realizations", minimum=1, maximum=2**32 - 1)
    ns = list(ns) if hasattr(ns, "__iter__") and not isinstance(ns, (str, bytes)) else []
    if not ns:
        raise InvalidArgumentError("'ns' must be a sequence of point counts, at least one")
    ns = [check_positive_int(n, "ns", maximum=sampler.max_n) for n in ns]
    counts = sorted({int(sampler.valid_n(n)) for n in ns})
    values = {m: [] for m in methods}
    errors = {m: [] for m in methods}
    tasks, owners = [], []
    for n in counts:
        owners.append([])
        for lo, hi in parallel.block_ranges(realizations, n * n // 64):
            owners[-1].append(len(tasks))
            tasks.append((sampler, n, lo, hi, methods))
    blocks, _ = parallel.run(discrepancy_block, tasks, client=client, checkpoint=checkpoint,
                             progress=progress, desc=f"discrepancy {sampler.label}")
    for mine in owners:
        found = np.concatenate([blocks[i] for i in mine], axis=1)
        for row, method in enumerate(methods):
            v = found[row]
            squares = v if method not in ROOTED else v * v
            values[method].append(math.sqrt(float(np.mean(squares))))
            spread = float(np.std(squares, ddof=1)) / math.sqrt(len(v)) if len(v) > 1 else 0.0
            # the delta method: sd(sqrt(m)) = sd(m) / (2 sqrt(m))
            errors[method].append(spread / (2.0 * values[method][-1]) if values[method][-1] else 0.0)
    return {m: DiscrepancySweep(sampler.label, m, np.array(counts), np.array(values[m]),
                                np.array(errors[m]), realizations) for m in methods}
