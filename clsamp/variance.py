"""Convergence over an integrand family: the spread of the MSE across members as N grows.

:func:`clsamp.convergence` with a family (``"random_heavisides"``, ...) comes here. For
every n and realization k, one point set (shifted by its own toroidal vector when
``homogenize``, as for one integrand) is used for every member m: e[n][k, m] =
(1/n) sum_i f_m(x_ki) - integral_m. Per n the MSE of member m is mean_k e[n][k, m]^2; the
summaries across members are its mean, median, 90 % quantile and maximum. Each summary's
convergence rate is the least-squares slope of log(summary) against log N over the
larger half of the sweep, with a bootstrap confidence interval that resamples members and
realizations (the same draws at every n).

One realization's points serve every member, as in Pilleboue et al. (2015), so the
members' errors within a realization are correlated; the bootstrap resamples realizations
whole for that reason.
"""

import dataclasses
import math
import time

import numpy as np

from . import runtime
from .errors import InvalidArgumentError
from .families import FamilyKernel, errors_numpy
from .geometry import torus

STATISTICS = ("mean", "median", "q90", "max")
BOOTSTRAP = 200         # resamples behind each confidence interval

__all__ = ["FamilyResult", "family_convergence", "STATISTICS"]


def _summaries(mse):
    """(len(ns), M) -> {statistic: (len(ns),)} over members."""
    return {"mean": mse.mean(axis=1), "median": np.median(mse, axis=1),
            "q90": np.quantile(mse, 0.9, axis=1), "max": mse.max(axis=1)}


def _slope(x, y):
    xm, ym = x.mean(), y.mean()
    return float(np.sum((x - xm) * (y - ym)) / np.sum((x - xm) ** 2))


@dataclasses.dataclass(repr=False)
class FamilyResult:
    """The outcome of :func:`clsamp.convergence` over a family of integrands.

    Attributes
    ----------
    sampler, family : str
        Labels (the family's name, ``"random_heavisides"``).
    ns : ndarray of int
    errors : list of ndarray
        Per n, the (realizations, members) errors estimate - integral.
    seconds : ndarray
        Per n, wall seconds (generation, evaluation of every member, read-back).
    mse : ndarray (len(ns), members)
        Each member's MSE over the realizations.
    mean, median, q90, max : ndarray (len(ns),)
        The summaries of ``mse`` across members.
    integrals : ndarray (members,)
    realizations, members, d, seed, homogenize, backend, device, kind, traits, rates
        How it was measured (as :class:`clsamp.convergence.ConvergenceResult`).
    """

    sampler: str
    family: str
    ns: np.ndarray
    errors: list
    seconds: np.ndarray
    integrals: np.ndarray
    realizations: int
    members: int
    d: int = 2
    seed: int = 0
    homogenize: bool = True
    backend: str = "opencl"
    device: str = ""
    kind: str = ""
    traits: dict = dataclasses.field(default_factory=dict)
    rates: dict = dataclasses.field(default_factory=dict)

    def __post_init__(self):
        self.ns = np.asarray(self.ns, dtype=np.int64)
        self.seconds = np.asarray(self.seconds, dtype=np.float64)
        self.errors = [np.asarray(e, dtype=np.float64) for e in self.errors]
        self.mse = np.stack([np.mean(e * e, axis=0) for e in self.errors])
        for name, values in _summaries(self.mse).items():
            setattr(self, name, values)

    @property
    def integrand(self):
        """The family's name (what reports print where one integrand's name would be)."""
        return self.family

    def __repr__(self):
        slope, lo, hi = self.rate("mean")
        return (f"FamilyResult({self.sampler!r} on {self.family!r}: {self.members} members, "
                f"N = {self.ns[0]}..{self.ns[-1]}, {self.realizations} realizations; mean MSE "
                f"{float(self.mean[-1]):.3g} at the largest N, slope {slope:.2f} [{lo:.2f}, {hi:.2f}])")

    def fit_range(self):
        """Indices the rates fit: the larger half of the sweep (as ConvergenceResult)."""
        return np.arange(len(self.ns) // 2, len(self.ns))

    def rate(self, statistic="mean", confidence=0.95, bootstrap=BOOTSTRAP, seed=0):
        """(slope, lower, upper): the fitted exponent of ``statistic`` ~ N^slope over
        :meth:`fit_range`, and its bootstrap confidence interval.

        The interval resamples members and realizations with replacement (``bootstrap``
        times, NumPy's PCG64 seeded by ``seed``: reproducible), recomputes the members'
        MSEs and the statistic at every n, and refits; it is the central ``confidence``
        range of the refitted slopes. nan where a statistic is 0 at some n.
        """
        if statistic not in STATISTICS:
            raise InvalidArgumentError(
                f"'statistic' must be one of {', '.join(STATISTICS)}, got {statistic!r}")
        if not 0 < confidence < 1:
            raise InvalidArgumentError(f"'confidence' must be in (0, 1), got {confidence!r}")
        idx = self.fit_range()
        if len(idx) < 2:
            return float("nan"), float("nan"), float("nan")
        x = np.log(self.ns[idx].astype(np.float64))
        values = getattr(self, statistic)[idx]
        if np.any(values <= 0):
            return float("nan"), float("nan"), float("nan")
        slope = _slope(x, np.log(values))
        rng = np.random.default_rng(seed)
        squares = [self.errors[k] ** 2 for k in idx]
        slopes = []
        for _ in range(bootstrap):
            # drawn realizations as weights (a product, not a gather of the whole matrix)
            weights = np.bincount(rng.integers(0, self.realizations, self.realizations),
                                  minlength=self.realizations) / self.realizations
            cols = rng.integers(0, self.members, self.members)
            mse = np.stack([(weights @ s)[cols] for s in squares])
            stat = _summaries(mse)[statistic]
            if np.all(stat > 0):
                slopes.append(_slope(x, np.log(stat)))
        if not slopes:
            return slope, float("nan"), float("nan")
        tail = (1 - confidence) / 2
        lo, hi = np.quantile(slopes, [tail, 1 - tail])
        return slope, float(lo), float(hi)

    def to_dict(self, errors=False):
        """The numbers as JSON-able Python types."""
        out = {"sampler": self.sampler, "kind": self.kind, "family": self.family, "d": self.d,
               "members": int(self.members), "realizations": int(self.realizations),
               "homogenize": bool(self.homogenize), "seed": int(self.seed), "backend": self.backend,
               "device": self.device, "traits": dict(self.traits), "ns": self.ns.tolist(),
               "seconds": self.seconds.tolist(), "integrals": self.integrals.tolist(),
               "mse": self.mse.tolist()}
        for name in STATISTICS:
            slope, lo, hi = self.rate(name)
            out[name] = getattr(self, name).tolist()
            out[f"rate_{name}"] = {"slope": slope, "ci": [lo, hi]}
        if errors:
            out["errors"] = [e.tolist() for e in self.errors]
        return out


def _errors(kernel, sampler, fam, n, lo, hi, homogenize, seed):
    """The (hi - lo, members) errors of realizations lo .. hi - 1 at n (kernel None: NumPy)."""
    out = np.empty((hi - lo, fam.members))
    # a chunk's points and its (realizations x members) sums stay modest
    per_realization = 8 * max(n * fam.d, 4 * fam.members)
    for a, b in runtime.chunk_ranges(hi - lo, per_realization, 2**24):
        run = range(lo + a, lo + b)
        if kernel is not None:
            out[a:b] = kernel.errors(sampler.sample_device(n, realizations=run), n, lo + a)
        else:
            x = sampler.sample(n, realizations=run)
            if homogenize:
                u = torus.homogenization_shifts(seed, np.arange(run.start, run.stop), fam.d)
                x = torus.shift(x, u[:, None, :])
            out[a:b] = errors_numpy(fam, x)
    return out


def family_errors_block(sampler, fam, n, lo, hi, homogenize, seed, backend):
    """One task of a family sweep (:mod:`clsamp.parallel`): the errors of every member for
    realizations lo .. hi - 1 at n; a realization's errors do not depend on the block."""
    kernel = FamilyKernel(fam, homogenize, seed) if backend == "opencl" else None
    return _errors(kernel, sampler, fam, n, lo, hi, homogenize, seed)


def family_convergence(sampler, fam, ns, realizations, homogenize, seed, progress, backend, label,
                       rates):
    """The sweep behind :func:`clsamp.convergence` for a family, in-process: ``sampler`` a
    Sampler of ``fam.d`` dimensions, ``ns`` checked sample counts (see there)."""
    from tqdm import tqdm
    r = realizations
    kernel = None
    if backend == "opencl":
        kernel = FamilyKernel(fam, homogenize, seed)
        kernel.errors(sampler.sample_device(ns[0], realizations=1), ns[0], 0)   # builds before timing
    errors, seconds = [], []
    bar = tqdm(ns, desc=f"convergence {label} / {fam.name}", unit="n", disable=not progress, delay=2)
    for n in bar:
        t0 = time.perf_counter()
        errors.append(_errors(kernel, sampler, fam, n, 0, r, homogenize, seed))
        seconds.append(time.perf_counter() - t0)
    bar.close()
    return family_result(sampler, fam, ns, errors, seconds, r, homogenize, seed, backend, label, rates)


def family_result(sampler, fam, ns, errors, seconds, r, homogenize, seed, backend, label, rates):
    """The :class:`FamilyResult` of a finished sweep."""
    edges = fam.edges_when_shifted() if homogenize else fam.edges
    traits = {"smooth": bool(fam.smooth and (fam.periodic or not homogenize)), "periodic": fam.periodic,
              "edges": edges}
    device = str(runtime.current_device()) if backend == "opencl" else "numpy"
    return FamilyResult(sampler=label, family=fam.name, ns=ns, errors=errors, seconds=seconds,
                        integrals=fam.integrals, realizations=r, members=fam.members, d=fam.d,
                        seed=seed, homogenize=bool(homogenize), backend=backend, device=device,
                        kind=sampler.label, traits=traits, rates=rates)


def expected(result):
    """(exponent, source) the sampler publishes for the family's case, or (None, None)."""
    from .theory import case_of
    rate = result.rates.get(case_of(result.traits))
    return (None, None) if rate is None else (rate[0], rate[1])


def compare(result, statistic="mean", allowance=None):
    """The fitted rate of ``statistic`` held against the published one.

    Returns a dict: ``slope``, ``ci`` (lower, upper), ``expected`` (exponent or None),
    ``source`` and ``verdict``: "matches" when the expected exponent lies in the
    confidence interval, "pre-asymptotic" when within ``allowance`` (default
    ``theory.CURVATURE_ALLOWANCE``) of it, "differs" beyond, "unknown" without a rate.
    """
    from .theory import CURVATURE_ALLOWANCE
    allowance = CURVATURE_ALLOWANCE if allowance is None else allowance
    slope, lo, hi = result.rate(statistic)
    exponent, source = expected(result)
    if exponent is None or not math.isfinite(lo):
        verdict = "unknown"
    elif lo <= exponent <= hi:
        verdict = "matches"
    elif lo - allowance <= exponent <= hi + allowance:
        verdict = "pre-asymptotic"
    else:
        verdict = "differs"
    return {"statistic": statistic, "slope": slope, "ci": (lo, hi), "expected": exponent,
            "source": source, "verdict": verdict}
