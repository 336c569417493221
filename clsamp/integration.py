"""Integration to a tolerance with an error bar: replicated randomized quasi-Monte Carlo.

:func:`integrate` estimates the integral of f over [0, 1)^d with ``replications``
independent randomizations of a sampler (an Owen-scrambled Sobol' sequence by default),
and doubles the points per replication until the Student-t confidence interval of the
replications' mean is as narrow as asked. The replications are independent and each is an
unbiased estimate, so the interval is honest whatever the integrand (the t interval
assumes the replication means are close to normal, which a few dozen points per
replication already give for bounded f; L'Ecuyer et al. 2023 measure its coverage).

References
----------
.. [1] A. B. Owen, "Practical Quasi-Monte Carlo Integration", 2023, ch. 17 (replicated
   RQMC and its t intervals).
.. [2] P. L'Ecuyer, M. K. Nakayama, A. B. Owen, B. Tuffin, "Confidence intervals for
   randomized quasi-Monte Carlo estimators", Winter Simulation Conference, 2023.
"""

import dataclasses
import math
import time
import warnings

import numpy as np

from . import runtime
from .cubature import M_MIN, Cubature, check_periodization, combine
from .errors import InvalidArgumentError
from .experiments_ff import IntegrandKernelFF
from .float_float import check_precision
from .fused import FusedRule, fused_randomization
from .integrand_kernel import IntegrandKernel, combine_sums, offset
from .integrands import Integrand, make_integrand
from .samplers import Sampler, make_sampler
from .validation import check_bool, check_choice, check_int, check_real, check_seed

BLOCK = 2**20           # points one call of a Python integrand gets at most
METHODS = ("replications", "digital", "lattice")

__all__ = ["IntegrationResult", "integrate"]


@dataclasses.dataclass
class IntegrationResult:
    """What :func:`integrate` reached.

    Attributes
    ----------
    estimate : float
        The mean of the replications' estimates.
    half_width : float
        Half the width of the ``confidence`` interval: the integral lies in
        estimate +- half_width with that confidence.
    n : int
        Points per replication at the end.
    evaluations : int
        Integrand evaluations in all (every replication, every doubling).
    seconds : float
        Wall time of the call.
    converged : bool
        Whether the half-width met the tolerance before ``max_n``.
    replications, confidence, sampler, tolerance
        How it was asked (``tolerance``: the half-width that was the target). The
        guaranteed methods report one replication and confidence 1 (their bound holds for
        every integrand in the cone, not with a probability).
    method : str
        ``"replications"``, ``"digital"`` or ``"lattice"``.
    history : list of (n, estimate, half_width)
        One row per doubling.
    """

    estimate: float
    half_width: float
    n: int
    evaluations: int
    seconds: float
    converged: bool
    replications: int
    confidence: float
    sampler: str
    tolerance: float
    method: str = "replications"
    history: list = dataclasses.field(default_factory=list)


# -- the integrand ---------------------------------------------------------------------
def _python_values(f, x):
    """f at the (m, d) points x, checked: one finite value a point."""
    raw = np.asarray(f(x))
    if raw.dtype.kind not in "biuf":        # a complex value would lose its imaginary part
        raise InvalidArgumentError(
            f"'f' must return real numbers, one a point; it returned dtype {raw.dtype}")
    v = raw.astype(np.float64, copy=False)
    if v.shape != (len(x),):
        raise InvalidArgumentError(
            f"'f' must return one value per point, shape ({len(x)},) for points "
            f"({len(x)}, {x.shape[1]}); it returned shape {v.shape}")
    if not np.all(np.isfinite(v)):
        bad = int(np.count_nonzero(~np.isfinite(v)))
        raise InvalidArgumentError(
            f"'f' returned {bad} NaN or infinite values (of {len(x)}); the first at "
            f"x = {x[np.flatnonzero(~np.isfinite(v))[0]].tolist()}")
    return v


def _blocked_values(f, x):
    """f at the points x, BLOCK points a call."""
    x = np.ascontiguousarray(x)
    return np.concatenate([_python_values(f, x[a:a + BLOCK]) for a in range(0, max(len(x), 1), BLOCK)])


def _python_sums(f, points, count):
    """Per replication, the sum of f over its ``count`` points (points: (R, count, d))."""
    r, _, d = points.shape
    flat = np.ascontiguousarray(points.reshape(-1, d))
    total = np.empty(r)
    per_call = max(1, BLOCK // count) if count <= BLOCK else 1
    for lo in range(0, r, per_call):
        hi = min(r, lo + per_call)
        values = _blocked_values(f, flat[lo * count:hi * count])
        total[lo:hi] = np.sum(values.reshape(hi - lo, count), axis=1)
    return total


def _check_tolerance(value, name):
    if value is None:
        return 0.0
    return check_real(value, name, minimum=0.0, open_minimum=True)


def _guaranteed(f, d, method, periodization, abs_tol, rel_tol, max_n, seed, progress, t0):
    """integrate's single-sequence methods: double n until the cone bound meets the tolerance."""
    if isinstance(f, (str, Integrand)):
        integrand = make_integrand(f, d=d)
        if integrand.d != d:
            raise InvalidArgumentError(
                f"integrand {integrand.name!r} is {integrand.d}-dimensional, 'd' is {d}")
        f = integrand
    elif not callable(f):
        raise InvalidArgumentError(
            f"'f' must be a callable, an Integrand or an integrand name, got {f!r}")
    if max_n < 2**M_MIN:
        raise InvalidArgumentError(f"'max_n' must be at least {2**M_MIN} for method={method!r}, got {max_n}")
    fused = FusedRule(f, method, seed, periodization=periodization) if isinstance(f, Integrand) else None
    rule = Cubature(lambda x: _blocked_values(f, x), d, method, seed, periodization,
                    None if fused is None else fused.values, max_n=max_n,
                    fill=None if fused is None else fused.fill)
    from tqdm import tqdm
    bar = tqdm(desc=f"integrate ({method})", unit="round", disable=not progress, delay=2)
    history = []
    while True:
        mean, bound = rule.step()
        estimate, half, converged = combine(mean, bound, abs_tol, rel_tol)
        tolerance = max(abs_tol, rel_tol * abs(estimate))
        history.append((rule.n, estimate, half))
        bar.set_postfix_str(f"n={rule.n}, {estimate:.8g} +- {half:.2g} (target {tolerance:.2g})",
                            refresh=False)
        bar.update(1)
        if converged:
            break
        if 2 * rule.n > max_n:
            warnings.warn(
                f"integrate stopped at max_n = {max_n} points (n = {rule.n}) with error bound "
                f"{half:.3g}, above the tolerance {tolerance:.3g}: the estimate {estimate:.10g} "
                "is not as accurate as asked", UserWarning, stacklevel=3)
            break
    bar.close()
    return IntegrationResult(estimate=estimate, half_width=half, n=rule.n, evaluations=rule.n,
                             seconds=time.perf_counter() - t0, converged=converged, replications=1,
                             confidence=1.0, sampler=rule.label, tolerance=tolerance, method=method,
                             history=history)


def integrate(f, d, sampler="sobol:owen", abs_tol=None, rel_tol=None, max_n=2**24, replications=16,
              confidence=0.95, seed=0, n_start=1024, progress=True, method="replications",
              periodization=None, precision=None):
    """The integral of ``f`` over [0, 1)^d, with a confidence interval, to a tolerance.

    Parameters
    ----------
    f : callable, Integrand or str
        A vectorised function taking an (m, d) float64 array and returning m values
        (float64 of shape (m,)); or a :mod:`clsamp.integrands` integrand (or its name, or
        one written in OpenCL C: ``clsamp.Integrand.from_opencl``), evaluated on the
        device in the kernel that makes the points (:mod:`clsamp.fused`: no point is
        stored) for ``method="digital" | "lattice"`` and for ``sampler`` given as
        ``"sobol:owen"``, ``"sobol:xor"`` or ``"sobol:shift"``; at a sampler's points on
        the device otherwise.
    d : int
        The dimension.
    sampler : str or Sampler
        A randomized sampler (each replication is one of its realizations); default
        Owen-scrambled Sobol', whose points extend when n doubles (the replications keep
        their first n points and add n more).
    abs_tol, rel_tol : float, optional
        Stop when the half-width is at most max(abs_tol, rel_tol |estimate|); at least
        one is needed.
    max_n : int
        Points per replication at most; reaching it without meeting the tolerance warns
        (``UserWarning``) and returns ``converged=False``.
    replications : int
        Independent randomizations, at least 2 (the interval has replications - 1
        degrees of freedom).
    confidence : float
        Of the two-sided Student-t interval, in (0, 1).
    seed : int
        The sampler's seed when it is given by name.
    n_start : int
        Points per replication of the first round (rounded to a count the sampler makes).
    progress : bool
        A progress bar (one step per doubling, with the estimate and its half-width) once
        the call has run 2 s.
    method : {"replications", "digital", "lattice"}
        ``"replications"`` (the default): the replicated Student-t interval above.
        ``"digital"`` and ``"lattice"``: one randomized sequence (Sobol' with LMS and a
        digital shift, as qmcpy's default; a shifted rank-1 lattice), n = 2^10, 2^11, ..., stopping when the
        cone-based bound of Hickernell and Jiménez Rugama (:mod:`clsamp.cubature`) meets
        the tolerance; the bound is guaranteed for integrands in the cone, whose Walsh
        (Fourier) coefficients decay steadily, and may fail for others: discontinuities,
        spikes the first points miss, and smooth integrands whose error stalls over a
        range of n (a Genz oscillatory in 6-D on the lattice: an error of 1.2e-3 from 2^11
        to 2^14 points, reported converged at half-width 5e-4; GAIL's cubLattice_g gives
        the same bound). These ignore ``sampler``, ``replications``,
        ``confidence`` and ``n_start``; ``max_n`` is the number of points.
    periodization : {"none", "baker", "sidi"}, optional
        ``method="lattice"`` only: integrate f(ψ(x)) prod ψ'(x_j) with Baker's tent
        (the default) or Sidi's sin^2 transform, or f itself (``"none"``).
    precision : {"double", "float-float"}, optional
        What the device evaluates and sums an :mod:`clsamp.integrands` integrand in;
        default ``"double"`` where the device has fp64, ``"float-float"`` where it has not.
        Float-float (``method="replications"`` only) evaluates it at the sampler's points,
        never in the fused kernel, each replication's mean within
        :func:`clsamp.experiments_ff.error_bound` of the fp64 one. A Python callable is
        evaluated in float64 on the host either way.

    Returns
    -------
    IntegrationResult

    Raises
    ------
    InvalidArgumentError
        No tolerance or a non-positive one; a deterministic sampler; an unknown method,
        periodization or precision; ``f`` returning the wrong shape, NaN or infinities
        (the message says which and where); float-float with an integrand and ``method=
        "digital" | "lattice"``, or with an integrand written in OpenCL C.
    NoDeviceError
        ``precision="double"`` on a device without fp64.

    Notes
    -----
    With ``rel_tol`` the guaranteed methods return Hickernell, Jiménez Rugama and Li's
    estimate, which meets max(abs_tol, rel_tol |I|) for every I inside the bound, and
    ``half_width`` its distance to the bound's far end.

    Examples
    --------
    >>> import numpy as np, clsamp
    >>> res = clsamp.integrate(lambda x: np.prod(x, axis=1), 3, abs_tol=1e-6, progress=False)
    >>> bool(abs(res.estimate - 0.125) < 1e-5), res.converged
    (True, True)
    >>> net = clsamp.integrate(clsamp.integrands.keister(3), 3, abs_tol=1e-4, method="digital")
    >>> bool(abs(net.estimate - 2.168309102165) < 1e-4), net.method, net.n
    (True, 'digital', 131072)
    """
    check_bool(progress, "progress")
    t0 = time.perf_counter()
    method = check_choice(method, "method", METHODS)
    periodization = check_periodization(periodization, method)
    d = check_int(d, "d", minimum=1)
    abs_tol = _check_tolerance(abs_tol, "abs_tol")
    rel_tol = _check_tolerance(rel_tol, "rel_tol")
    if abs_tol == 0.0 and rel_tol == 0.0:
        raise InvalidArgumentError("give 'abs_tol' or 'rel_tol' (or both): the half-width to reach")
    max_n = check_int(max_n, "max_n", minimum=2)
    precision = check_precision(precision)
    if method != "replications" and precision == "float-float" and isinstance(f, (str, Integrand)):
        raise InvalidArgumentError(
            f"'method' {method!r} evaluates an integrand in double (its fused kernel); in "
            "float-float (the default on a device without fp64) use method='replications'")
    if method != "replications":
        return _guaranteed(f, d, method, periodization, abs_tol, rel_tol, max_n, check_seed(seed),
                           progress, t0)
    r = check_int(replications, "replications", minimum=2, maximum=2**16)
    confidence = check_real(confidence, "confidence", minimum=0.0, maximum=1.0,
                            open_minimum=True, open_maximum=True)
    seed = check_seed(seed)
    n_start = check_int(n_start, "n_start", minimum=1)
    if isinstance(sampler, str):
        s = make_sampler(sampler, d=d, seed=seed)
    elif isinstance(sampler, Sampler):
        s = sampler
    else:
        raise InvalidArgumentError(f"'sampler' must be a Sampler or a sampler name, got {sampler!r}")
    if s.d != d:
        raise InvalidArgumentError(f"'sampler' makes {s.d}-dimensional points but 'd' is {d}")
    if not s.randomized:
        raise InvalidArgumentError(
            f"'sampler' {s.label!r} is deterministic: its replications would all be equal and "
            "the interval would be 0 wide. Use a randomized one, e.g. 'sobol:owen' or "
            "'halton:owen'")
    kernel = None
    if isinstance(f, str) or isinstance(f, Integrand):
        integrand = make_integrand(f, d=d)
        if integrand.d != d:
            raise InvalidArgumentError(
                f"integrand {integrand.name!r} is {integrand.d}-dimensional, 'd' is {d}")
        fused = fused_randomization(sampler) if isinstance(sampler, str) else None
        if precision == "float-float":
            kernel = IntegrandKernelFF(integrand, False, seed)
        elif fused is not None:         # its points made in the kernel that evaluates f
            kernel = FusedRule(integrand, "sobol", seed, fused)
        else:
            kernel = IntegrandKernel(integrand, False, seed)
    elif not callable(f):
        raise InvalidArgumentError(
            f"'f' must be a callable, an Integrand or an integrand name, got {f!r}")
    extends = s.splits_along_n         # sample(n, start=k) continues sample(k)
    # imported here, not at the top, so that `import clsamp` does not pay for scipy.stats
    from scipy.stats import t as student_t
    t_value = float(student_t.ppf(0.5 + confidence / 2.0, r - 1))

    def sums(count, start):
        """Per replication, the sum of f over points start .. start + count - 1."""
        if isinstance(kernel, FusedRule):
            return kernel.sums(count, start, range(r)) + count * offset(kernel.f)
        if kernel is not None:
            out = np.zeros(r)
            for lo, hi in runtime.chunk_ranges(r, 8 * count * d, 2**27):
                pts = s.sample_device(count, realizations=range(lo, hi), start=start)
                out[lo:hi] = combine_sums(kernel.error_sums(pts, count, lo)) + count * offset(kernel.f)
            return out
        return _python_sums(f, s.sample(count, realizations=r, start=start), count)

    from tqdm import tqdm
    bar = tqdm(desc=f"integrate ({s.label})", unit="round", disable=not progress, delay=2)
    n = s.valid_n(min(n_start, max_n))
    total = sums(n, 0)
    evaluations = r * n
    history = []
    while True:
        estimates = total / n
        mean = math.fsum(estimates) / r
        spread = math.sqrt(math.fsum((estimates - mean) ** 2) / (r - 1))
        half = t_value * spread / math.sqrt(r)
        tolerance = max(abs_tol, rel_tol * abs(mean))
        history.append((n, mean, half))
        # refresh=False: the bar shows only after its delay, as every clsamp bar does
        bar.set_postfix_str(f"n={n}, {mean:.8g} +- {half:.2g} (target {tolerance:.2g})", refresh=False)
        bar.update(1)
        if half <= tolerance:
            converged = True
            break
        bigger = s.valid_n(2 * n)
        if bigger <= n:
            bigger = s.valid_n(4 * n)
        if bigger > max_n or bigger <= n:
            converged = False
            warnings.warn(
                f"integrate stopped at max_n = {max_n} points per replication (n = {n}) with "
                f"half-width {half:.3g}, above the tolerance {tolerance:.3g}: the estimate "
                f"{mean:.10g} is not as accurate as asked", UserWarning, stacklevel=2)
            break
        if extends:
            total = total + sums(bigger - n, n)
            evaluations += r * (bigger - n)
        else:
            total = sums(bigger, 0)
            evaluations += r * bigger
        n = bigger
    bar.close()
    return IntegrationResult(estimate=mean, half_width=half, n=n, evaluations=evaluations,
                             seconds=time.perf_counter() - t0, converged=converged, replications=r,
                             confidence=confidence, sampler=s.label, tolerance=tolerance,
                             history=history)
