"""Convergence experiments: MSE, bias and variance of a sampler's integral estimates
against the number of samples, what each costs in time, and the accuracy-time front.

For every n the estimate of realization k is (1/n) sum_i f(x_ki), where x_k is the
sampler's k-th point set shifted, when ``homogenize``, by its own random toroidal vector
u_k (Pilleboue et al. 2015: the shift makes every point uniform, so the estimator is
unbiased, and its variance depends only on the sampler's power spectrum). The OpenCL
path generates all realizations on the device (the sampler's kernel, or its NumPy
reference copied there), shifts, evaluates and sums per realization in one kernel
(``kernels/integrands.cl``) and reads back only the r errors; the NumPy reference
(``backend="numpy"``) does the same in NumPy. u_k is ``philox.uniform(seed,
Stream.EXPERIMENT, k, 0, j)`` on both paths and every device.

Statistics (fp64, from the r errors e_k = estimate_k - integral):

* ``mean`` = integral + fsum(e) / r, ``bias2`` = (fsum(e) / r)^2;
* ``variance`` = fsum((e - mean error)^2) / r (dividing by r, not r - 1, so that
  ``mse = bias2 + variance`` holds to rounding; the unbiased sample variance is
  variance * r / (r - 1));
* ``mse`` = fsum(e^2) / r, correctly rounded sums (``math.fsum``), so the MSE has no
  rounding floor however small the errors are;
* ``mse_stderr``: the standard error of ``mse`` as a mean of r squared errors.

The kernel computes each e_k as (1/n) sum_i (f(x_ki) - integral) in double-double, which
keeps e_k's relative accuracy even when it is 1e-8 of the integral.

References
----------
.. [1] A. Pilleboue et al., "Variance analysis for Monte Carlo integration", ACM TOG
   34(4), 2015.
"""

import dataclasses
import math
import time

import numpy as np

from . import families, parallel, philox, runtime, variance
from .errors import InvalidArgumentError
from .geometry import torus
from .integrands import Integrand, make_integrand
from .samplers import Sampler, make_sampler
from .samplers.base import CASES
from .validation import MAX_UINT32, check_choice, check_int, check_seed

SLICE = 4096            # points one work-group sums (fixed: the summation order depends on n only)
HOST_CHUNK = 2**22      # doubles per chunk of the NumPy path (32 MB)
# Doubles of points generated per launch: on a CPU 16 MB, so the points the sampler just
# wrote are still in the caches when the integrand kernel reads them (which matters most
# when the integrand is cheap; docs/performance.md); on a GPU larger launches keep more
# items in flight.
DEVICE_CHUNK = {"cpu": 2**21, "gpu": 2**25, "other": 2**23}

__all__ = ["ConvergenceResult", "convergence", "pareto_front", "time_to_mse", "parse_ns",
           "IntegrandKernel", "combine_sums"]


# -- the result ------------------------------------------------------------------------
@dataclasses.dataclass(repr=False)
class ConvergenceResult:
    """The outcome of :func:`convergence`: per n, the errors and their statistics.

    Attributes
    ----------
    sampler : str
        Label (assignable; reports rename it).
    integrand : str
        The integrand's name.
    ns : ndarray of int
        Sample counts, increasing.
    errors : list of ndarray
        Per n, the r errors estimate - integral (float64).
    seconds : ndarray
        Per n, wall seconds of the whole experiment at that n, generation included.
    realizations, integral, homogenize, seed, backend, device
        How it was measured.
    kind : str
        The sampler's registry name and randomization (``"sobol:owen"``); not changed by
        relabelling.
    randomized : bool
        Whether the sampler itself is random (else only the shift randomizes).
    d : int
        Dimension.
    traits : dict
        ``smooth``, ``periodic`` and ``edges`` of the integrand as the estimator sees it
        (a shifted non-periodic integrand has the square's sides as edges).
    rates : dict
        The sampler's published rates (``Sampler.convergence_rate``) by case, as
        ``{case: (exponent, source)}`` (None where none is published), asked of the
        sampler with its parameters; :func:`clsamp.theory.compare` holds the fit
        against them. Empty: theory asks a sampler made from ``kind``.
    """

    sampler: str
    integrand: str
    ns: np.ndarray
    errors: list
    seconds: np.ndarray
    realizations: int
    integral: float
    homogenize: bool = True
    seed: int = 0
    backend: str = "opencl"
    device: str = ""
    kind: str = ""
    randomized: bool = True
    d: int = 2
    traits: dict = dataclasses.field(default_factory=dict)
    rates: dict = dataclasses.field(default_factory=dict)

    def __post_init__(self):
        self.ns = np.asarray(self.ns, dtype=np.int64)
        self.seconds = np.asarray(self.seconds, dtype=np.float64)
        self.errors = [np.asarray(e, dtype=np.float64) for e in self.errors]
        stats = np.array([_statistics(e) for e in self.errors], dtype=np.float64).reshape(-1, 5)
        mean_error, self.bias2, self.variance, self.mse, self.mse_stderr = stats.T
        self.mean = self.integral + mean_error

    def __repr__(self):
        from . import theory
        verdict = theory.compare(self)
        slope, stderr = verdict["slope"], verdict["stderr"]
        fit = "no fit" if not np.isfinite(slope) else f"slope {slope:.2f} +- {stderr:.2f}"
        theory_text = verdict["expected_text"] or "no published rate"
        return (f"ConvergenceResult({self.sampler!r} on {self.integrand!r}: N = {self.ns[0]}.."
                f"{self.ns[-1]} ({len(self.ns)} values), {self.realizations} realizations,\n"
                f"    MSE {float(self.mse[-1]):.3g} at the largest N, {fit}, theory {theory_text}: "
                f"{verdict['verdict'].split(' (')[0]})")

    @property
    def seconds_per_estimate(self):
        """Seconds per n divided by the realizations: the cost of one estimate."""
        return self.seconds / self.realizations

    def fit_range(self, n_min=None):
        """Indices of the sweep :meth:`rate` fits: ns >= n_min, by default the larger half
        (from index len(ns) // 2 on: the last 4 of 7, the last 2 of 4)."""
        if n_min is None:
            return np.arange(len(self.ns) // 2, len(self.ns))
        return np.flatnonzero(self.ns >= n_min)

    def rate(self, n_min=None):
        """The convergence rate: (slope, standard error) of log MSE against log N.

        A weighted least-squares line over the asymptotic range (:meth:`fit_range`: the
        larger half of the sweep unless ``n_min`` is given). Point k has weight
        1 / s_k^2 with s_k = mse_stderr_k / mse_k, the delta-method standard deviation
        of log mse_k. The slope's standard error is sqrt(1 / sum w (x - x_w)^2),
        scaled up by sqrt(chi^2 / dof) when the residuals scatter more than the
        weights say (curvature). (nan, nan) with fewer than two positive MSEs.
        """
        idx = self.fit_range(n_min)
        idx = idx[self.mse[idx] > 0]
        if len(idx) < 2:
            return float("nan"), float("nan")
        x = np.log(self.ns[idx].astype(np.float64))
        y = np.log(self.mse[idx])
        s = self.mse_stderr[idx] / self.mse[idx]
        weighted = bool(np.all(s > 0))
        w = 1.0 / s**2 if weighted else np.ones_like(x)
        xm = np.sum(w * x) / np.sum(w)
        ym = np.sum(w * y) / np.sum(w)
        sxx = np.sum(w * (x - xm) ** 2)
        slope = float(np.sum(w * (x - xm) * (y - ym)) / sxx)
        dof = len(x) - 2
        chi2 = float(np.sum(w * (y - ym - slope * (x - xm)) ** 2))
        if weighted:
            stderr = math.sqrt(1.0 / sxx) * (max(1.0, math.sqrt(chi2 / dof)) if dof > 0 else 1.0)
        else:
            stderr = math.sqrt(chi2 / dof / sxx) if dof > 0 else float("nan")
        return slope, float(stderr)

    def to_dict(self, errors=False):
        """The numbers as JSON-able Python types (``errors=True`` adds every error)."""
        slope, stderr = self.rate()
        out = {"sampler": self.sampler, "kind": self.kind, "integrand": self.integrand,
               "integral": self.integral, "d": self.d, "realizations": int(self.realizations),
               "homogenize": bool(self.homogenize), "seed": int(self.seed), "backend": self.backend,
               "device": self.device, "traits": dict(self.traits),
               "rates": {k: (list(v) if v else None) for k, v in self.rates.items()},
               "ns": self.ns.tolist(),
               "mean": self.mean.tolist(), "bias2": self.bias2.tolist(),
               "variance": self.variance.tolist(), "mse": self.mse.tolist(),
               "mse_stderr": self.mse_stderr.tolist(), "seconds": self.seconds.tolist(),
               "seconds_per_estimate": self.seconds_per_estimate.tolist(),
               "rate": {"slope": _finite(slope), "stderr": _finite(stderr),
                        "ns": self.ns[self.fit_range()].tolist()}}
        if errors:
            out["errors"] = [e.tolist() for e in self.errors]
        return out


def _finite(x):
    return float(x) if np.isfinite(x) else None


def _statistics(e):
    """(mean error, bias^2, variance, MSE, stderr of the MSE) with correctly rounded sums."""
    r = len(e)
    m = math.fsum(e) / r
    sq = e * e
    mse = math.fsum(sq) / r
    variance = math.fsum((e - m) ** 2) / r
    spread = math.fsum((sq - mse) ** 2) / (r - 1) if r > 1 else 0.0
    return m, m * m, variance, mse, math.sqrt(spread / r)


# -- arguments -------------------------------------------------------------------------
def _resolve(sampler, integrand, seed, backend):
    if isinstance(sampler, str):
        if isinstance(integrand, Integrand):
            f = integrand
        else:
            f = make_integrand(integrand)
        s = make_sampler(sampler, d=f.d, seed=seed, backend=backend)
        label = sampler
    elif isinstance(sampler, Sampler):
        s = sampler
        f = make_integrand(integrand, d=s.d) if not isinstance(integrand, Integrand) else integrand
        label = s.label
    else:
        raise InvalidArgumentError(
            f"'sampler' must be a Sampler or a sampler name such as 'jittered' or 'sobol:owen', "
            f"got {sampler!r}")
    if f.d != s.d:
        raise InvalidArgumentError(
            f"'integrand' {f.name!r} is {f.d}-dimensional but 'sampler' {label!r} makes "
            f"{s.d}-dimensional points")
    return s, f, label


def sampler_rates(sampler):
    """The published rates of ``sampler`` by case: ``{case: (exponent, source) or None}``."""
    out = {}
    for case in CASES:
        rate = sampler.convergence_rate(case)
        out[case] = None if rate is None else (rate.exponent, rate.source)
    return out


def _check_ns(ns, sampler, label):
    if isinstance(ns, (str, bytes)) or not hasattr(ns, "__iter__"):
        raise InvalidArgumentError(f"'ns' must be a sequence of sample counts, got {ns!r}")
    values = [check_int(n, "ns", minimum=1, maximum=sampler.max_n) for n in ns]
    if not values:
        raise InvalidArgumentError("'ns' must hold at least one sample count, got an empty sequence")
    values = sorted(values)
    if len(set(values)) != len(values):
        raise InvalidArgumentError(f"'ns' must not repeat a sample count, got {list(ns)!r}")
    for n in values:
        valid = sampler.valid_n(n)
        if valid != n:
            raise InvalidArgumentError(
                f"sampler {label!r} with d={sampler.d} cannot make n={n} points (in 'ns'); "
                f"the nearest valid n is {valid}")
    return values


# -- points ----------------------------------------------------------------------------
homogenization_shifts = torus.homogenization_shifts


def _errors_numpy(sampler, f, n, r, homogenize, seed, r0=0):
    """The NumPy reference of one n: the errors (1/n) sum_i (f(x_ki) - integral) of
    realizations r0 .. r0 + r - 1."""
    step = max(1, HOST_CHUNK // (n * f.d))
    out = np.empty(r)
    for lo in range(r0, r0 + r, step):
        hi = min(r0 + r, lo + step)
        x = sampler.sample(n, realizations=range(lo, hi))
        if homogenize:
            x = torus.shift(x, homogenization_shifts(seed, np.arange(lo, hi), f.d)[:, None, :])
        # numpy sums a contiguous row pairwise: error ~ eps log2(n) of sum |f - I|
        out[lo - r0:hi - r0] = np.sum(f._evaluate(x) - f.integral, axis=1) / n
    return out


class IntegrandKernel:
    """The integrand's program and parameters on the current device, built once
    (``kernels/integrands.cl``; ``homogenize`` shifts realization k by its own vector)."""

    def __init__(self, f, homogenize, seed):
        import pyopencl.array as cla
        runtime.require_fp64()
        self.f = f
        self.seed = seed
        self.kernel = runtime.kernel("integrands.cl", "integrand_error_sums",
                                     defines={"DIM": f.d, "INTEGRAND": f.kernel_code,
                                              "HOMOGENIZE": int(bool(homogenize))})
        self.params = cla.to_device(runtime.queue(), np.ascontiguousarray(f.kernel_params(),
                                                                          dtype=np.float64))

    def error_sums(self, points, n, realization0):
        """(r, groups, 2) double-double partial sums of f - integral, on the host."""
        import pyopencl as cl
        import pyopencl.array as cla
        queue = runtime.queue()
        r = points.shape[0]
        if points.shape != (r, n, self.f.d) or not points.flags.c_contiguous:
            points = cla.to_device(queue, np.ascontiguousarray(points.get()).reshape(r, n, self.f.d))
        groups = -(-n // SLICE)
        # a quad of points per work-item step: no more work-items than quads in a slice
        quads = -(-min(n, SLICE) // 4)
        local = min(runtime.local_size(64), 1 << max(0, (quads - 1).bit_length()))
        out = cla.empty(queue, (r, groups, 2), np.float64)
        self.kernel(queue, (groups * local, r), (local, 1), points.data, np.uint32(n),
                    np.uint32(SLICE), np.uint32(realization0), *runtime.key_args(self.seed),
                    np.uint32(philox.Stream.EXPERIMENT), self.params.data,
                    np.float64(self.f.integral), out.data, cl.LocalMemory(16 * local))
        return out.get()


def _two_sum(a, b):
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


def combine_sums(parts):
    """Double-double partial sums (..., groups, 2) added in order to one double per row."""
    hi = np.zeros(parts.shape[:-2])
    lo = np.zeros(parts.shape[:-2])
    for g in range(parts.shape[-2]):
        hi, e = _two_sum(hi, parts[..., g, 0])
        lo = lo + e + parts[..., g, 1]
    return hi + lo


def _errors_opencl(kernel, sampler, n, r, r0=0):
    limit = 8 * DEVICE_CHUNK[runtime.current_device().type]
    out = np.empty(r)
    for lo, hi in runtime.chunk_ranges(r, 8 * n * sampler.d, limit):
        points = sampler.sample_device(n, realizations=range(r0 + lo, r0 + hi))
        out[lo:hi] = combine_sums(kernel.error_sums(points, n, r0 + lo)) / n
    return out


def errors_block(sampler, f, n, lo, hi, homogenize, seed, backend):
    """The errors of realizations lo .. hi - 1 at n: one task of a sweep (see
    :mod:`clsamp.parallel`); each realization's error does not depend on the block."""
    if backend == "opencl":
        return _errors_opencl(IntegrandKernel(f, homogenize, seed), sampler, n, hi - lo, lo)
    return _errors_numpy(sampler, f, n, hi - lo, homogenize, seed, lo)


def sweep_tasks(sampler, f, ns, r, homogenize, seed, backend, cost=1):
    """The tasks of a sweep (one block of realizations of one n each), and per n the
    indices of its tasks in order."""
    tasks, owners = [], []
    for n in ns:
        mine = []
        for lo, hi in parallel.block_ranges(r, n * cost):
            mine.append(len(tasks))
            tasks.append((sampler, f, n, lo, hi, homogenize, seed, backend))
        owners.append(mine)
    return tasks, owners


# -- the experiment --------------------------------------------------------------------
def convergence(sampler, integrand, ns, realizations=1000, homogenize=True, seed=0, progress=True,
                backend="opencl", members=None, client=None, checkpoint=None):
    """MSE, bias^2 and variance of a sampler's integral estimates for every n in ``ns``;
    over a family of integrands, the spread of the MSE across its members.

    Parameters
    ----------
    sampler : Sampler or str
        A sampler object (any registered sampler, its own seed and parameters), or a
        name such as ``"jittered"`` or ``"sobol:owen"``, made with
        ``make_sampler(name, d=integrand.d, seed=seed, backend=backend)``.
    integrand : Integrand, Family or str
        An :mod:`clsamp.integrands` object or a name: ``"gaussian"``, ``"disk"``,
        ``"heaviside"``, ``"pmj_disk"``, ``"pmj_gaussian"``, ``"pmj_bilinear"``,
        ``"pmj_step"``, ``"pmj_triangle"`` (default parameters); or a family of random
        integrands (:mod:`clsamp.families`): ``"random_gaussians"``,
        ``"random_heavisides"``, ``"random_disks"``, ``"random_boxes"``,
        ``"random_clipped_gaussians"`` (drawn from ``seed``, in the sampler's dimension),
        or a :class:`~clsamp.families.Family`.
    ns : sequence of int
        Sample counts (sorted; each must be one the sampler can make).
    realizations : int
        Independent estimates per n, at least 2.
    homogenize : bool
        Shift each realization by its own uniform toroidal vector (Stream.EXPERIMENT of
        ``seed``): unbiased estimates for any sampler.
    seed : int
        Seed of the shifts (and of the sampler when given by name).
    progress : bool
        Show a progress bar over ``ns`` when the sweep takes more than 2 s.
    backend : {"opencl", "numpy"}
        ``"numpy"``: the NumPy reference (points from ``sampler.sample``, evaluation and
        sums in NumPy; a sampler given by name uses its NumPy reference too).
    members : int, optional
        For a family given by name: how many members to draw (default 256).
    client : dask.distributed.Client, optional
        Run the sweep on a Dask cluster, in tasks of whole realization blocks
        (:mod:`clsamp.parallel`): the same errors, bit for bit, as in-process. ``seconds``
        are then the tasks' compute seconds per n, summed over workers.
    checkpoint : str or Path, optional
        A folder that keeps every finished block; calling again with the same sweep
        resumes from it (with or without a client).

    Returns
    -------
    ConvergenceResult, or FamilyResult for a family
        A :class:`~clsamp.variance.FamilyResult` has ``.mse`` of shape (len(ns),
        members), the summaries ``mean``, ``median``, ``q90`` and ``max`` per n, and
        ``rate(statistic)`` with a bootstrap confidence interval.

    Raises
    ------
    InvalidArgumentError
        Empty or repeated ``ns``; an n the sampler cannot make (naming the sampler and
        the nearest valid n); ``realizations`` < 2; an unknown integrand (listing the
        known ones); dimensions that do not match.

    Notes
    -----
    ``seconds[k]`` is the wall time of the k-th n: generating every realization,
    shifting, evaluating, summing, and reading back the r errors. The kernels are
    built before the clock starts (a one-realization warm-up at the smallest n).

    Examples
    --------
    >>> import clsamp
    >>> res = clsamp.convergence("jittered", "gaussian", [16, 64, 256], realizations=100,
    ...                          progress=False)
    >>> bool(res.mse[-1] < res.mse[0])
    True
    """
    from tqdm import tqdm
    backend = check_choice(backend, "backend", ("opencl", "numpy"))
    seed = check_seed(seed)
    r = check_int(realizations, "realizations", minimum=2, maximum=MAX_UINT32)
    if not isinstance(homogenize, (bool, np.bool_)):
        raise InvalidArgumentError(f"'homogenize' must be True or False, got {homogenize!r}")
    if families.is_family(integrand):
        return _family_sweep(sampler, integrand, ns, r, homogenize, seed, progress, backend, members,
                             client, checkpoint)
    if members is not None:
        raise InvalidArgumentError(
            f"'members' is for integrand families ({', '.join(families.family_names())}); "
            f"integrand {integrand!r} is one function")
    s, f, label = _resolve(sampler, integrand, seed, backend)
    values = _check_ns(ns, s, label)
    runtime.check_host_bytes(8 * r * len(values), f"the errors of {r} realizations x {len(values)} n")
    if client is not None or checkpoint is not None:
        tasks, owners = sweep_tasks(s, f, values, r, homogenize, seed, backend)
        blocks, spent = parallel.run(errors_block, tasks, client=client, checkpoint=checkpoint,
                                     progress=progress, desc=f"convergence {label} / {f.name}")
        errors = [np.concatenate([blocks[i] for i in mine]) for mine in owners]
        seconds = [float(np.sum(spent[mine])) for mine in owners]
        return _result(s, f, label, values, errors, seconds, r, homogenize, seed, backend)
    kernel = None
    if backend == "opencl":
        kernel = IntegrandKernel(f, homogenize, seed)
        # builds the sampler's and the integrand's programs before any timing
        _errors_opencl(kernel, s, values[0], 1)

    errors, seconds = [], []
    bar = tqdm(values, desc=f"convergence {label} / {f.name}", unit="n", disable=not progress, delay=2)
    for n in bar:
        t0 = time.perf_counter()
        if backend == "opencl":
            e = _errors_opencl(kernel, s, n, r)
        else:
            e = _errors_numpy(s, f, n, r, homogenize, seed)
        seconds.append(time.perf_counter() - t0)
        errors.append(e)
    bar.close()
    return _result(s, f, label, values, errors, seconds, r, homogenize, seed, backend)


def _result(s, f, label, values, errors, seconds, r, homogenize, seed, backend):
    edges = f.edges_when_shifted() if homogenize else f.edges
    traits = {"smooth": bool(f.smooth and (f.periodic or not homogenize)), "periodic": f.periodic,
              "edges": edges}
    device = str(runtime.current_device()) if backend == "opencl" else "numpy"
    return ConvergenceResult(sampler=label, integrand=f.name, ns=values, errors=errors,
                             seconds=seconds, realizations=r, integral=f.integral,
                             homogenize=bool(homogenize), seed=seed, backend=backend, device=device,
                             kind=s.label, randomized=bool(s.randomized), d=f.d, traits=traits,
                             rates=sampler_rates(s))


def _family_sweep(sampler, integrand, ns, r, homogenize, seed, progress, backend, members, client,
                  checkpoint):
    if isinstance(sampler, str):
        d = integrand.d if isinstance(integrand, families.Family) else 2
        s, label = make_sampler(sampler, d=d, seed=seed, backend=backend), sampler
    elif isinstance(sampler, Sampler):
        s, label = sampler, sampler.label
    else:
        raise InvalidArgumentError(
            f"'sampler' must be a Sampler or a sampler name such as 'jittered' or 'sobol:owen', "
            f"got {sampler!r}")
    if isinstance(integrand, families.Family):
        if members is not None and members != integrand.members:
            raise InvalidArgumentError(
                f"'members'={members!r} differs from the family's own {integrand.members} members")
        fam = integrand
    else:
        fam = families.make_family(integrand, d=s.d, members=256 if members is None else members,
                                   seed=seed)
    if fam.d != s.d:
        raise InvalidArgumentError(
            f"'integrand' family {fam.name!r} is {fam.d}-dimensional but 'sampler' {label!r} makes "
            f"{s.d}-dimensional points")
    values = _check_ns(ns, s, label)
    runtime.check_host_bytes(8 * r * fam.members * len(values),
                             f"the errors of {r} realizations x {fam.members} members x {len(values)} n")
    if client is not None or checkpoint is not None:
        # a point costs about as much to make as 100 member evaluations (docs/performance.md)
        tasks, owners = sweep_tasks(s, fam, values, r, homogenize, seed, backend,
                                    cost=1 + fam.members / 100)
        blocks, spent = parallel.run(variance.family_errors_block, tasks, client=client,
                                     checkpoint=checkpoint, progress=progress,
                                     desc=f"convergence {label} / {fam.name}")
        errors = [np.concatenate([blocks[i] for i in mine]) for mine in owners]
        seconds = [float(np.sum(spent[mine])) for mine in owners]
        return variance.family_result(s, fam, values, errors, seconds, r, homogenize, seed, backend,
                                      label, sampler_rates(s))
    return variance.family_convergence(s, fam, values, r, homogenize, seed, progress, backend, label,
                                       sampler_rates(s))


# -- accuracy against time -------------------------------------------------------------
def pareto_front(results):
    """The (sampler, n) points no other point beats in both seconds and MSE.

    Parameters
    ----------
    results : sequence of ConvergenceResult
        Usually one integrand, several samplers.

    Returns
    -------
    list of dict
        ``{'sampler', 'n', 'seconds', 'mse'}`` sorted by seconds (seconds per estimate,
        generation included); a point is kept unless another has seconds <= and
        MSE <= with one of them strictly smaller.
    """
    points = [(float(t), float(m), res.sampler, int(n))
              for res in results
              for n, t, m in zip(res.ns, res.seconds_per_estimate, res.mse, strict=True)]
    points.sort(key=lambda p: (p[0], p[1]))
    front, best = [], math.inf
    for t, m, name, n in points:
        if m < best:
            front.append({"sampler": name, "n": n, "seconds": t, "mse": m})
            best = m
    return front


def time_to_mse(result, target):
    """What reaching an MSE of ``target`` costs with this sampler.

    Returns
    -------
    dict or None
        ``{'n', 'seconds', 'mse'}`` of the smallest measured n whose MSE is <= target
        (seconds per estimate there), plus ``'n_interpolated'`` and
        ``'seconds_interpolated'``: where the log-log line between that n and the one
        before it crosses the target (equal to the measured values at the first n).
        None when no n in the sweep reaches the target.
    """
    target = float(target)
    if not target > 0:
        raise InvalidArgumentError(f"'target' must be a positive MSE, got {target!r}")
    hits = np.flatnonzero(result.mse <= target)
    if hits.size == 0:
        return None
    k = int(hits[0])
    t = result.seconds_per_estimate
    out = {"n": int(result.ns[k]), "seconds": float(t[k]), "mse": float(result.mse[k]),
           "n_interpolated": float(result.ns[k]), "seconds_interpolated": float(t[k])}
    if k > 0 and result.mse[k - 1] > 0 and result.mse[k] > 0 and result.mse[k] < result.mse[k - 1]:
        a = (math.log(target) - math.log(result.mse[k - 1])) / (
            math.log(result.mse[k]) - math.log(result.mse[k - 1]))
        out["n_interpolated"] = float(math.exp(
            (1 - a) * math.log(result.ns[k - 1]) + a * math.log(result.ns[k])))
        if t[k - 1] > 0 and t[k] > 0:
            out["seconds_interpolated"] = float(math.exp(
                (1 - a) * math.log(t[k - 1]) + a * math.log(t[k])))
    return out


# -- the command line's sample counts --------------------------------------------------
def parse_ns(text):
    """Sample counts from text: ``"16,64,256"``, or ``"a..b"`` for a, 4a, 16a, ... <= b
    (powers of 4 from a: squares stay squares, as jittered needs), or ``"a..b:q"`` for
    ratio q (``"16..4096:2"``: powers of 2)."""
    text = str(text).strip()
    if ".." in text:
        span, _, ratio = text.partition(":")
        a, _, b = span.partition("..")
        try:
            a, b, q = int(a), int(b), int(ratio) if ratio else 4
        except ValueError:
            raise InvalidArgumentError(f"'ns' must look like 'a..b' or 'a..b:q', got {text!r}") from None
        if a < 1 or b < a or q < 2:
            raise InvalidArgumentError(
                f"'ns' range needs 1 <= a <= b and ratio q >= 2, got {text!r}")
        values = []
        while a <= b:
            values.append(a)
            a *= q
        return values
    try:
        return [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise InvalidArgumentError(f"'ns' must be integers like '16,64,256', got {text!r}") from None
