"""The stratified family: regular grids, jittering, Latin hypercubes and multi-jittering.

Registered names: ``regular``, ``jittered``, ``uncorrelated_jitter``,
``latin_hypercube`` (alias ``n_rooks``), ``multijittered`` and
``correlated_multijittered``. Each has an OpenCL kernel in ``kernels/stratified.cl``
(all realizations in one launch) and a NumPy reference here (``backend="numpy"``)
that gives the same bits for the same seed.

Every jittered coordinate is placed by :func:`stratum_point`: the point of stratum
``k`` of ``count`` at relative offset ``u`` is ``(k + u) / count`` in exactly rounded
double arithmetic, nudged by an ulp where rounding would carry it across the
stratum's edge, so that ``floor(x * count) == k`` holds exactly and ``x < 1``.

Randomness: jitter of coordinate ``j`` of point ``i`` in realization ``r`` is
``philox.uniform(seed, Stream.POINTS, r, start + i, j)``; shuffles use
``Stream.PERMUTATION`` and depend only on (seed, realization). ``start`` therefore
offsets the jitter counters only (these are sets, not sequences).
"""

import math
import re

import numpy as np

from .. import permutation, philox, runtime
from ..errors import InvalidArgumentError
from ..validation import check_bool, check_int, check_real
from .base import PILLEBOUE, Rate, Sampler, register

# -- small pure functions, shared by the references and the parameter checks ----------
STRATUM_STEPS = 4   # ulp steps of stratum_point each way (CLSAMP_STRATUM_STEPS in the kernel)


def stratum_point(k, u, count):
    """The coordinate at relative offset ``u`` in stratum ``k`` of ``count`` (the kernel's twin).

    Parameters
    ----------
    k : array_like of int
        Stratum indices in [0, count).
    u : array_like of float
        Offsets in [0, 1) (0.5 for the centre).
    count : array_like of int
        Number of strata (broadcasts).

    Returns
    -------
    ndarray of float64
        ``x = (k + u) / count`` rounded to nearest, then moved by whole ulps (at most
        four each way, which the rounding error bound makes enough) until
        ``floor(x * count) == k`` in double arithmetic; hence ``0 <= x < 1``.
    """
    c = np.asarray(count, dtype=np.float64)
    kd = np.asarray(k, dtype=np.float64)
    x = (kd + np.asarray(u, dtype=np.float64)) / c
    x, c, kd = (np.array(a) for a in np.broadcast_arrays(x, c, kd))
    # The quotient is within two ulps (four if the ulp halves) of an admissible double:
    # the kernel's four fixed steps each way, moving one ulp by the integer view.
    for _ in range(STRATUM_STEPS):
        x.view(np.int64)[x * c >= kd + 1.0] -= 1
    for _ in range(STRATUM_STEPS):
        x.view(np.int64)[x * c < kd] += 1
    return x


def integer_root(n, s):
    """The largest integer k with k**s <= n (exact, for any size of n).

    Parameters
    ----------
    n, s : int
        s at least 1.

    Returns
    -------
    int
        0 for n < 1.
    """
    if n < 1:
        return 0
    k = int(round(n ** (1.0 / s)))
    while k ** s > n:
        k -= 1
    while (k + 1) ** s <= n:
        k += 1
    return k


def nearest_power(n, s, maximum):
    """The s-th power k**s (k >= 1, at most ``maximum``) nearest to n; ties go down.

    Parameters
    ----------
    n, s, maximum : int

    Returns
    -------
    int
    """
    k = max(1, integer_root(n, s))
    best = k ** s
    if (k + 1) ** s <= maximum and abs((k + 1) ** s - n) < abs(best - n):
        best = (k + 1) ** s
    return best


def balanced_factors(n):
    """(m, k) with m * k = n, m <= k and m the largest divisor of n not above sqrt(n).

    Parameters
    ----------
    n : int

    Returns
    -------
    (int, int)
    """
    m = math.isqrt(n)
    while n % m:
        m -= 1
    return m, n // m


def _int_tuple(value, name):
    """A tuple given as a sequence or, from the command line, as text like "3x4" or "2,2,1"."""
    if isinstance(value, str):
        parts = [p for p in re.split(r"[x,\s]+", value.strip()) if p]
        try:
            return tuple(int(p) for p in parts)
        except ValueError:
            raise InvalidArgumentError(
                f"'{name}' must be integers like '3x4' or '2,2,1', got {value!r}") from None
    if isinstance(value, int) and not isinstance(value, bool):
        return (value,)
    return value


def _check_strata(strata, d, name="strata"):
    strata = _int_tuple(strata, name)
    if not isinstance(strata, (tuple, list)) or len(strata) != d:
        raise InvalidArgumentError(
            f"'{name}' must be a tuple of {d} positive integers (one per dimension), got {strata!r}")
    return tuple(check_int(s, name, minimum=1) for s in strata)


STEIN = "Stein 1987"
LATIN_RATES = {"best": Rate(-1.0, STEIN), "worst": Rate(-1.0, STEIN)}


def jitter_rate(d, case, source=PILLEBOUE):
    """The published rate of jittered sampling of k^d cells (Pilleboue et al. 2015): in 2-D
    N^-2 for smooth integrands and N^-1.5 for edges (curved, or along the axes, where the
    cells of one column or row are cut); in d-D N^(-1-2/d) and N^(-1-1/d).

    Parameters
    ----------
    d : int
    case : {"best", "worst", "axis"}
    source : str

    Returns
    -------
    Rate or None
    """
    if d == 2:
        return {"best": Rate(-2.0, source), "worst": Rate(-1.5, source),
                "axis": Rate(-1.5, source)}.get(case)
    if case == "best":
        return Rate(-1.0 - 2.0 / d, source)
    if case == "worst":
        return Rate(-1.0 - 1.0 / d, source)
    return None


def _default_groups(d):
    return (2,) * (d // 2) + ((1,) if d % 2 else ())


def _layout_reference(sampler, n, realizations, start, radix, group, perms):
    """NumPy twin of ``stratified_points``: points (len(realizations), n, d)."""
    r = len(realizations)
    d = len(radix)
    reals = np.arange(realizations.start, realizations.stop)
    if sampler.centered:
        u = np.full((r, n, d), 0.5)
    else:
        u = philox.uniform_block(sampler.seed, philox.Stream.POINTS, reals, n, d, start)
    out = np.empty((r, n, d))
    cell = None
    current = None
    for j in range(d):
        if group[j] != current:
            current = group[j]
            cell = (perms[:, current, :].astype(np.int64) if perms is not None
                    else np.broadcast_to(np.arange(n, dtype=np.int64), (r, n)))
        digit = cell % int(radix[j])
        cell = cell // int(radix[j])
        out[:, :, j] = stratum_point(digit, u[:, :, j], int(radix[j]))
    return out


class _Stratified(Sampler):
    """Samplers made by ``stratified_points``: each group of dimensions is a grid of
    cells; point i of a group takes cell i, or cell perm[i] when ``permuted``."""

    permuted = False
    centered = False
    host_output = True

    def _layout(self, n):
        """(radix per dimension, group per dimension, number of groups)."""
        raise NotImplementedError

    progress = True     # the NumPy reference's shuffles show a bar when long

    def _perms_reference(self, n, realizations, groups):
        if not self.permuted:
            return None
        return permutation.random_permutations(self.seed, philox.Stream.PERMUTATION,
                                               realizations, n, groups, progress=self.progress)

    def _reference(self, n, realizations, start):
        radix, group, groups = self._layout(n)
        perms = self._perms_reference(n, realizations, groups)
        return _layout_reference(self, n, realizations, start, radix, group, perms)

    def _device(self, n, realizations, start, out=None):
        queue = runtime.queue()
        radix, group, groups = self._layout(n)
        r = len(realizations)
        target = runtime.Output((r, n, self.d), host=out)
        radix_d = runtime.table(("stratified radix", radix), lambda: radix)
        group_d = runtime.table(("stratified group", group), lambda: group)
        if self.permuted:
            perms = permutation.random_permutations_device(
                self.seed, philox.Stream.PERMUTATION, realizations, n, groups)
        else:
            perms = runtime.table("stratified unused", lambda: [0])   # the kernel reads cell = i
        local = runtime.local_size()
        quads = -(-n // 4)                                     # four points a work-item
        split, grid, group = runtime.dimension_split(self.d, 64, (-(-quads // local) * local, r),
                                                     (local, 1))
        kernel = runtime.kernel("stratified.cl", "stratified_points",
                                defines={"PERMUTED": int(self.permuted),
                                         "CENTERED": int(self.centered), **split})
        kernel(queue, grid, group, target.buffer, np.uint32(n),
               np.uint32(self.d), np.uint32(start), np.uint32(realizations.start),
               *philox.seed_key(self.seed), np.uint32(philox.Stream.POINTS),
               radix_d.data, group_d.data, perms.data, np.uint32(groups))
        return target.finish()


class _Grid(_Stratified):
    """A k1 x ... x kd grid: n = k^d by default, or ``strata=(k1, ..., kd)``."""

    def __init__(self, d=2, seed=0, strata=None, backend="opencl"):
        super().__init__(d=d, seed=seed, backend=backend)
        self.strata = None if strata is None else _check_strata(strata, self.d)
        if self.strata is not None and math.prod(self.strata) > self.max_n:
            raise InvalidArgumentError(
                f"'strata' {self.strata} make {math.prod(self.strata)} points, more than "
                f"the {self.max_n} point indices allow")

    def _default_n(self):
        return None if self.strata is None else math.prod(self.strata)

    def valid_n(self, n):
        """The valid point count nearest to ``n``: the product of ``strata`` where given,
        else the nearest k^d (k strata per axis).

        Parameters
        ----------
        n : int

        Returns
        -------
        int
        """
        if self.strata is not None:
            return math.prod(self.strata)
        return nearest_power(n, self.d, self.max_n)

    def _check_n(self, n):
        valid = self.valid_n(n)
        if valid != n:
            if self.strata is not None:
                need = f"n = {' * '.join(map(str, self.strata))} = {valid} for 'strata'={self.strata}"
            else:
                need = f"n = k^{self.d} points (k strata per axis)"
            raise InvalidArgumentError(
                f"sampler {self.name!r} with d={self.d} needs {need}, got n={n}; "
                f"the nearest valid n is {valid}")
        return n

    def _layout(self, n):
        strata = self.strata or (integer_root(n, self.d),) * self.d
        return strata, (0,) * self.d, 1


@register("regular")
class RegularSampler(_Grid):
    """Cell centres of a regular grid in [0, 1)^d.

    Point i has coordinates ``(c_j + 1/2) / k_j`` where ``(c_0, ..., c_{d-1})`` are the
    mixed-radix digits of i (first dimension fastest): the midpoint rule.

    Parameters
    ----------
    d : int
        Dimension.
    seed : int
        Unused (the grid is deterministic); accepted for a uniform interface.
    strata : tuple of int, optional
        Cells per axis ``(k_1, ..., k_d)``; then n must be their product (and may be
        left out). Default: n must be k^d, k cells per axis.

    Notes
    -----
    For smooth integrands the midpoint rule errs by O(n^{-2/d}); it aliases badly on
    anything periodic with the grid's frequency and its spectrum is a lattice of
    Dirac peaks. ``start`` has no effect.

    Examples
    --------
    >>> import clsamp
    >>> clsamp.make_sampler("regular", d=2).sample(4).tolist()
    [[0.25, 0.25], [0.75, 0.25], [0.25, 0.75], [0.75, 0.75]]
    """

    centered = True
    randomized = False


@register("jittered")
class JitteredSampler(_Grid):
    """Jittered (stratified) sampling: one uniform point in each cell of a k^d grid.

    Point i lies in the cell whose mixed-radix digits (first dimension fastest) are
    those of i: ``x_j = (c_j + u_j) / k_j`` with ``u_j`` uniform in [0, 1).

    Parameters
    ----------
    d : int
        Dimension.
    seed : int
        Seed in [0, 2^64).
    strata : tuple of int, optional
        Cells per axis ``(k_1, ..., k_d)`` (or text such as ``"3x4"``, as the command
        line passes it); then n must be their product (and may be left out). Default:
        n must be k^d, and another n raises naming the nearest k^d.

    Notes
    -----
    Stratification removes the between-cell part of the variance: for a piecewise
    smooth integrand in 2-D the MSE falls as n^{-3/2} (n^{-1-1/d} in d-D) instead of
    n^{-1} (Pilleboue et al. 2015). Proposed for rendering by Cook, Porter and
    Carpenter (1984) and Dippé and Wold (1985).

    References
    ----------
    .. [1] R. L. Cook, "Stochastic sampling in computer graphics", ACM TOG 5(1), 1986.
    .. [2] A. Pilleboue et al., "Variance analysis for Monte Carlo integration", ACM TOG
       34(4), 2015.

    Examples
    --------
    >>> import clsamp, numpy as np
    >>> pts = clsamp.make_sampler("jittered", d=2, seed=3).sample(16)
    >>> np.unique(np.floor(pts * 4) @ [1, 4]).size   # one point per cell of the 4x4 grid
    16
    """

    def convergence_rate(self, case):
        """The published rate of the MSE for ``case`` (:meth:`Sampler.convergence_rate`).

        Parameters
        ----------
        case : {"best", "worst", "axis"}

        Returns
        -------
        Rate or None
            :func:`jitter_rate` for k^d cubic cells; None for unequal strata per axis.
        """
        if self.strata is not None and len(set(self.strata)) > 1:
            return None     # the published rates are for k^d cubic cells
        return jitter_rate(self.d, case)


@register("uncorrelated_jitter")
class UncorrelatedJitterSampler(_Stratified):
    """Uncorrelated jitter (Cook 1984): dimensions jittered in groups, groups shuffled.

    The d dimensions are split into groups of consecutive dimensions (default: pairs,
    then one single dimension if d is odd: pixel 2-D, lens 2-D, time 1-D for d = 5).
    Group g of size s is a jittered k_g^s grid with n = k_g^s cells; point i takes
    cell ``pi_g(i)`` of group g, where the ``pi_g`` are independent uniformly random
    permutations of [0, n) (one per group and realization). Each group alone is
    jittered; across groups the pairing is random, so no group's stratum tells
    anything about another's.

    Parameters
    ----------
    d : int
        Dimension.
    seed : int
        Seed in [0, 2^64).
    groups : tuple of int, optional
        Sizes of the groups, in order; they must add up to d. Every group size s
        requires n to be an s-th power, so n must be k^L with L the lcm of the sizes.
    progress : bool
        Whether the NumPy reference (``backend="numpy"``) shows a progress bar when its
        Python Fisher–Yates loop is long (millions of swaps).

    Notes
    -----
    Jittering all d dimensions at once needs k^d samples; grouping keeps
    stratification where it matters (within the pixel, within the lens) at any
    n that is a square, at the price of no joint stratification across groups.

    References
    ----------
    .. [1] R. L. Cook, T. Porter, L. Carpenter, "Distributed ray tracing", SIGGRAPH 1984.
    .. [2] R. L. Cook, "Stochastic sampling in computer graphics", ACM TOG 5(1), 1986.

    Examples
    --------
    >>> import clsamp
    >>> s = clsamp.make_sampler("uncorrelated_jitter", d=5, seed=1)
    >>> s.groups, s.sample(16).shape
    ((2, 2, 1), (16, 5))
    """

    permuted = True

    def __init__(self, d=2, seed=0, groups=None, backend="opencl", progress=True):
        super().__init__(d=d, seed=seed, backend=backend)
        self.progress = check_bool(progress, "progress")
        groups = _default_groups(self.d) if groups is None else _int_tuple(groups, "groups")
        if not isinstance(groups, (tuple, list)) or not groups:
            raise InvalidArgumentError(
                f"'groups' must be a tuple of positive group sizes adding up to d={self.d}, "
                f"got {groups!r}")
        groups = tuple(check_int(g, "groups", minimum=1) for g in groups)
        if sum(groups) != self.d:
            raise InvalidArgumentError(
                f"'groups' must add up to d={self.d}, got {groups} (sum {sum(groups)})")
        self.groups = groups
        self._power = math.lcm(*groups)

    def convergence_rate(self, case):
        """The published rate of the MSE for ``case`` (:meth:`Sampler.convergence_rate`).

        Parameters
        ----------
        case : {"best", "worst", "axis"}

        Returns
        -------
        Rate or None
            A jittered grid's for one group, a Latin hypercube's for groups (1, 1).
        """
        if self.groups == (self.d,):     # one group: a jittered grid, shuffled
            return jitter_rate(self.d, case, PILLEBOUE + " (jittered)")
        if self.groups == (1, 1):        # two shuffled 1-D strata: a Latin hypercube
            return LATIN_RATES.get(case)
        return None

    def valid_n(self, n):
        """The nearest k^l to ``n``, l the groups' least common multiple (whole strata).

        Parameters
        ----------
        n : int

        Returns
        -------
        int
        """
        return nearest_power(n, self._power, self.max_n)

    def _check_n(self, n):
        valid = self.valid_n(n)
        if valid != n:
            raise InvalidArgumentError(
                f"sampler {self.name!r} with 'groups'={self.groups} needs n = k^{self._power} "
                f"(an s-th power for every group size s), got n={n}; the nearest valid n is {valid}")
        return n

    def _layout(self, n):
        radix, group = [], []
        for g, size in enumerate(self.groups):
            radix += [integer_root(n, size)] * size
            group += [g] * size
        return tuple(radix), tuple(group), len(self.groups)


@register("latin_hypercube", "n_rooks")
class LatinHypercubeSampler(_Stratified):
    """Latin hypercube sampling (N-rooks): every axis split into n slabs, one point each.

    ``x_ij = (pi_j(i) + u_ij) / n`` with independent, exactly uniform random
    permutations ``pi_j`` of [0, n) (Fisher–Yates driven by Philox, see
    :mod:`clsamp.permutation`) and uniform jitter ``u_ij``.

    Parameters
    ----------
    d : int
        Dimension.
    seed : int
        Seed in [0, 2^64).
    progress : bool
        Whether the NumPy reference (``backend="numpy"``) shows a progress bar when its
        Python Fisher–Yates loop is long (millions of swaps).

    Notes
    -----
    Every one-dimensional projection is stratified, so the variance of additive
    (separable) integrands falls like jittering's in 1-D whatever d is; the joint
    distribution is otherwise random (McKay, Beckman, Conover 1979; Shirley 1991 in
    graphics as "N-rooks"). Same distribution as
    ``scipy.stats.qmc.LatinHypercube(d)`` (with ``scramble=True``).

    References
    ----------
    .. [1] M. D. McKay, R. J. Beckman, W. J. Conover, "A comparison of three methods for
       selecting values of input variables...", Technometrics 21(2), 1979.
    .. [2] P. Shirley, "Discrepancy as a quality measure for sample distributions",
       Eurographics 1991.

    Examples
    --------
    >>> import clsamp, numpy as np
    >>> pts = clsamp.make_sampler("n_rooks", d=3, seed=2).sample(10)
    >>> [np.unique(np.floor(pts[:, j] * 10)).size for j in range(3)]
    [10, 10, 10]
    """

    permuted = True
    rates = LATIN_RATES

    def __init__(self, d=2, seed=0, backend="opencl", progress=True):
        super().__init__(d=d, seed=seed, backend=backend)
        self.progress = check_bool(progress, "progress")

    def _layout(self, n):
        return (n,) * self.d, tuple(range(self.d)), self.d


@register("multijittered")
class MultiJitteredSampler(Sampler):
    """Multi-jittered sampling (Chiu, Shirley, Wang 1994): jittered and N-rooks at once.

    With n = mx * my, the unit square is an mx x my grid of cells (mx columns) and
    also n slabs along each axis. Point ``p = row * mx + col`` has
    ``x = (col * my + sigma_col(row) + u) / n`` and ``y = (row * mx + tau_row(col) + v) / n``,
    where the ``sigma_col`` (one per column, of length my) and ``tau_row`` (one per
    row, of length mx) are independent, exactly uniform random permutations: the
    canonical arrangement with its columns' x and rows' y shuffled. Every grid cell
    and every x- and y-slab holds exactly one point.

    Parameters
    ----------
    seed : int
        Seed in [0, 2^64).
    strata : (int, int), optional
        ``(mx, my)``; then n must be mx * my (and may be left out).
    max_aspect : float, optional
        Largest accepted ``my / mx`` (>= 1). By default any n works (a prime n gives a
        1 x n grid); with ``max_aspect`` an n whose most square factorization
        ``mx <= my`` is more elongated raises, naming the nearest valid n.
    progress : bool
        Whether the NumPy reference (``backend="numpy"``) shows a progress bar when its
        Python Fisher–Yates loop is long (millions of swaps).

    Notes
    -----
    By default mx is the largest divisor of n not above sqrt(n), my = n / mx.

    References
    ----------
    .. [1] K. Chiu, P. Shirley, C. Wang, "Multi-jittered sampling", Graphics Gems IV, 1994.

    Examples
    --------
    >>> import clsamp, numpy as np
    >>> pts = clsamp.make_sampler("multijittered", seed=5).sample(12)   # 3 x 4 cells
    >>> np.unique(np.floor(pts * 12), axis=0).shape[0], np.unique(np.floor(pts[:, 0] * 12)).size
    (12, 12)
    """

    dimensions = (2,)
    host_output = True

    def __init__(self, d=2, seed=0, strata=None, max_aspect=None, backend="opencl", progress=True):
        super().__init__(d=d, seed=seed, backend=backend)
        self.progress = check_bool(progress, "progress")
        self.strata = None if strata is None else _check_strata(strata, 2)
        self.max_aspect = (None if max_aspect is None
                           else check_real(max_aspect, "max_aspect", minimum=1.0))
        if self.strata is not None and math.prod(self.strata) > self.max_n:
            raise InvalidArgumentError(
                f"'strata' {self.strata} make {math.prod(self.strata)} points, more than "
                f"the {self.max_n} point indices allow")

    def factors(self, n):
        """The grid (mx, my) used for n points: ``strata`` where given, else
        :func:`balanced_factors` of n.

        Parameters
        ----------
        n : int

        Returns
        -------
        (int, int)
        """
        return self.strata if self.strata is not None else balanced_factors(n)

    def _acceptable(self, n):
        m, k = balanced_factors(n)
        return self.max_aspect is None or k <= self.max_aspect * m

    def valid_n(self, n):
        """The valid point count nearest to ``n``: the product of ``strata`` where given;
        else the nearest count whose balanced grid is within ``max_aspect`` (any count
        without it).

        Parameters
        ----------
        n : int

        Returns
        -------
        int
        """
        if self.strata is not None:
            return math.prod(self.strata)
        for step in range(n + 1):
            for candidate in (n - step, n + step):
                if 1 <= candidate <= self.max_n and self._acceptable(candidate):
                    return candidate
        return 1

    def _check_n(self, n):
        valid = self.valid_n(n)
        if valid != n:
            if self.strata is not None:
                need = f"n = {self.strata[0]} * {self.strata[1]} = {valid} for 'strata'={self.strata}"
            else:
                m, k = balanced_factors(n)
                need = (f"n = m * k with m <= k <= {self.max_aspect:g} * m ('max_aspect'); "
                        f"n={n} factors at best as {m} x {k}")
            raise InvalidArgumentError(
                f"sampler {self.name!r} needs {need}, got n={n}; the nearest valid n is {valid}")
        mx, my = self.factors(n)
        if mx + my > permutation.MAX_PERM:
            raise InvalidArgumentError(
                f"sampler {self.name!r}: the {mx} x {my} grid of n={n} needs mx + my < 2^22 "
                "shuffles; give 'strata' or 'max_aspect' (or an n with a squarer factorization)")
        return n

    def _default_n(self):
        return None if self.strata is None else math.prod(self.strata)

    def _reference(self, n, realizations, start):
        mx, my = self.factors(n)
        reals = np.arange(realizations.start, realizations.stop)
        colperm = permutation.random_permutations(self.seed, philox.Stream.PERMUTATION,
                                                  realizations, my, range(0, mx), self.progress)
        rowperm = permutation.random_permutations(self.seed, philox.Stream.PERMUTATION,
                                                  realizations, mx, range(mx, mx + my), self.progress)
        u = philox.uniform_block(self.seed, philox.Stream.POINTS, reals, n, 2, start)
        i = np.arange(n)
        col, row = i % mx, i // mx
        sx = colperm[:, col, row].astype(np.int64)
        sy = rowperm[:, row, col].astype(np.int64)
        out = np.empty((len(realizations), n, 2))
        out[..., 0] = stratum_point(col * my + sx, u[..., 0], n)
        out[..., 1] = stratum_point(row * mx + sy, u[..., 1], n)
        return out

    def _device(self, n, realizations, start, out=None):
        queue = runtime.queue()
        mx, my = self.factors(n)
        r = len(realizations)
        colperm = permutation.random_permutations_device(
            self.seed, philox.Stream.PERMUTATION, realizations, my, range(0, mx))
        rowperm = permutation.random_permutations_device(
            self.seed, philox.Stream.PERMUTATION, realizations, mx, range(mx, mx + my))
        target = runtime.Output((r, n, 2), host=out)
        local = runtime.local_size()
        quads = -(-n // 4)                                     # four points a work-item
        runtime.kernel("stratified.cl", "multijittered_points")(
            queue, (-(-quads // local) * local, r), (local, 1), target.buffer, np.uint32(mx),
            np.uint32(my), np.uint32(start), np.uint32(realizations.start),
            *philox.seed_key(self.seed), np.uint32(philox.Stream.POINTS), colperm.data,
            rowperm.data)
        return target.finish()


@register("correlated_multijittered")
class CorrelatedMultiJitteredSampler(Sampler):
    """Correlated multi-jittered sampling (Kensler 2013): multi-jittering, any n, point by point.

    With m = floor(sqrt(n)) columns and k = ceil(n / m) rows, point i of pattern p is
    (Kensler's final listing, aspect 1)::

        s  = permute(i, n, p * 0x51633e2d)          # shuffle the order
        sx = permute(s % m, m, p * 0x68bc21eb)      # one column shuffle for all rows
        sy = permute(s / m, k, p * 0x02e5be93)      # one row shuffle for all columns
        x  = (sx * k + sy + u) / (m * k),   y = (s + v) / n

    with :func:`clsamp.permutation.permute` (Kensler's hash permutation, an
    approximation of a random permutation), the pattern ``p`` a Philox word per
    realization and the jitter ``(u, v)`` from Philox (53-bit doubles where Kensler
    uses a 32-bit hash). Because one shuffle serves every column (and one every row)
    the points are correlated, which lowers discrepancy and variance compared with
    multi-jittering; each point is computed alone, with no permutation table.

    Parameters
    ----------
    seed : int
        Seed in [0, 2^64).

    Notes
    -----
    When n = m * k exactly (squares, and products m(m+1), m(m+2) with m = floor(sqrt(n)))
    every cell of the m x k grid and every x- and y-slab of width 1/n holds exactly
    one point. For other n the set is the first n points of an m x k pattern in a
    shuffled order: y stays stratified in n slabs, x in m * k slabs of which n are
    used.

    References
    ----------
    .. [1] A. Kensler, "Correlated Multi-Jittered Sampling", Pixar Technical Memo 13-01, 2013.

    Examples
    --------
    >>> import clsamp, numpy as np
    >>> pts = clsamp.make_sampler("correlated_multijittered", seed=4).sample(16)
    >>> np.unique(np.floor(pts[:, 0] * 16)).size, np.unique(np.floor(pts * 4) @ [1, 4]).size
    (16, 16)
    """

    dimensions = (2,)
    max_n = 2**32 - 2**17       # m * k stays below 2^32
    host_output = True

    @staticmethod
    def factors(n):
        """The grid (m, k) used for n points: m = floor(sqrt(n)), k = ceil(n / m).

        Parameters
        ----------
        n : int

        Returns
        -------
        (int, int)
        """
        m = math.isqrt(n)
        return m, -(-n // m)

    def _pattern(self, realizations):
        return philox.random_words(self.seed, philox.Stream.PERMUTATION,
                                   np.arange(realizations.start, realizations.stop), 0, 0)

    def _reference(self, n, realizations, start):
        m, k = self.factors(n)
        p = self._pattern(realizations).astype(np.uint64)[:, None]
        i = np.arange(n, dtype=np.uint64)[None, :]
        mask = np.uint64(0xFFFFFFFF)
        s = permutation.permute(i, n, (p * np.uint64(0x51633E2D)) & mask).astype(np.int64)
        sx = permutation.permute(s % m, m, (p * np.uint64(0x68BC21EB)) & mask).astype(np.int64)
        sy = permutation.permute(s // m, k, (p * np.uint64(0x02E5BE93)) & mask).astype(np.int64)
        u = philox.uniform_block(self.seed, philox.Stream.POINTS,
                                 np.arange(realizations.start, realizations.stop), n, 2, start)
        out = np.empty((len(realizations), n, 2))
        out[..., 0] = stratum_point(sx * k + sy, u[..., 0], m * k)
        out[..., 1] = stratum_point(s, u[..., 1], n)
        return out

    def _device(self, n, realizations, start, out=None):
        queue = runtime.queue()
        m, k = self.factors(n)
        r = len(realizations)
        target = runtime.Output((r, n, 2), host=out)
        local = runtime.local_size()
        quads = -(-n // 4)                                     # four points a work-item
        runtime.kernel("stratified.cl", "correlated_multijittered_points")(
            queue, (-(-quads // local) * local, r), (local, 1), target.buffer, np.uint32(n),
            np.uint32(m), np.uint32(k), np.uint32(start), np.uint32(realizations.start),
            *philox.seed_key(self.seed), np.uint32(philox.Stream.POINTS),
            np.uint32(philox.Stream.PERMUTATION))
        return target.finish()
