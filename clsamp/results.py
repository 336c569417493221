"""What a convergence sweep gives: per n the errors of every realization, their
statistics and the fitted rate, for one integrand (:class:`ConvergenceResult`) or a family
(:class:`FamilyResult`); and what accuracy costs in time across results
(:func:`pareto_front`, :func:`time_to_mse`). :func:`clsamp.theory.compare` holds a result's
rate against the published one.

Statistics of one integrand (fp64, from the r errors e_k = estimate_k - integral):

* ``mean`` = integral + fsum(e) / r, ``bias2`` = (fsum(e) / r)^2;
* ``variance`` = fsum((e - mean error)^2) / r (dividing by r, not r - 1, so that
  ``mse = bias2 + variance`` holds to rounding; the unbiased sample variance is
  variance * r / (r - 1));
* ``mse`` = fsum(e^2) / r, correctly rounded sums (``math.fsum``), so the MSE has no
  rounding floor however small the errors are;
* ``mse_stderr``: the standard error of ``mse`` as a mean of r squared errors.

Over a family, per n the MSE of member m is mean_k e[n][k, m]^2; the summaries across
members are its mean, median, 90 % quantile and maximum. Each summary's rate is the
least-squares slope of log(summary) against log N over the larger half of the sweep, with
a bootstrap confidence interval that resamples members and realizations (the same draws
at every n). One realization's points serve every member, as in Pilleboue et al. (2015),
so the members' errors within a realization are correlated; the bootstrap resamples
realizations whole for that reason.
"""

import dataclasses
import math

import numpy as np

from .errors import InvalidArgumentError

STATISTICS = ("mean", "median", "q90", "max")
BOOTSTRAP = 200         # resamples behind each confidence interval

__all__ = ["ConvergenceResult", "FamilyResult", "STATISTICS", "pareto_front", "time_to_mse"]


@dataclasses.dataclass(repr=False)
class ConvergenceResult:
    """The outcome of :func:`clsamp.convergence` for one integrand: per n, the errors and
    their statistics.

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
        """Indices of the sweep that :meth:`rate` fits.

        Parameters
        ----------
        n_min : int, optional
            Fit the ns >= n_min; by default the larger half of the sweep (from index
            len(ns) // 2 on: the last 4 of 7, the last 2 of 4).

        Returns
        -------
        ndarray of int
        """
        if n_min is None:
            return np.arange(len(self.ns) // 2, len(self.ns))
        return np.flatnonzero(self.ns >= n_min)

    def rate(self, n_min=None):
        """The convergence rate: the slope of log MSE against log N.

        A weighted least-squares line over the asymptotic range (:meth:`fit_range`). Point k has
        weight 1 / s_k^2 with s_k = mse_stderr_k / mse_k, the delta-method standard deviation of
        log mse_k. The slope's standard error is sqrt(1 / sum w (x - x_w)^2), scaled up by
        sqrt(chi^2 / dof) when the residuals scatter more than the weights say (curvature).

        Parameters
        ----------
        n_min : int, optional
            As :meth:`fit_range` takes it.

        Returns
        -------
        slope, stderr : float
            nan with fewer than two positive MSEs in the range.
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
        """The numbers as JSON-able Python types, with the fitted rate.

        Parameters
        ----------
        errors : bool, optional
            Add every error of every realization.

        Returns
        -------
        dict
        """
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
        How it was measured (as :class:`ConvergenceResult`).
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
        """The fitted exponent of a summary across members, ``statistic`` ~ N^slope over
        :meth:`fit_range`, and its bootstrap confidence interval.

        The interval resamples members and realizations with replacement, recomputes the
        members' MSEs and the statistic at every n, and refits; it is the central ``confidence``
        range of the refitted slopes.

        Parameters
        ----------
        statistic : {"mean", "median", "q90", "max"}
        confidence : float, optional
            In (0, 1).
        bootstrap : int, optional
            Resamples.
        seed : int, optional
            Seed of NumPy's PCG64 for the resamples: the interval is reproducible.

        Returns
        -------
        slope, lower, upper : float
            nan where the statistic is 0 at some n of the range.

        Raises
        ------
        InvalidArgumentError
            An unknown ``statistic`` or a ``confidence`` outside (0, 1).
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
        """The numbers with each statistic's rate; see :meth:`ConvergenceResult.to_dict`."""
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

    Parameters
    ----------
    result : ConvergenceResult
    target : float
        A positive MSE.

    Returns
    -------
    dict or None
        ``{'n', 'seconds', 'mse'}`` of the smallest measured n whose MSE is <= target
        (seconds per estimate there), plus ``'n_interpolated'`` and
        ``'seconds_interpolated'``: where the log-log line between that n and the one
        before it crosses the target (equal to the measured values at the first n).
        None when no n in the sweep reaches the target.

    Raises
    ------
    InvalidArgumentError
        A ``target`` that is not positive.
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
