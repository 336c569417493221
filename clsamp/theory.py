"""Published convergence rates of sampler MSE, and the verdict on a measured one.

The MSE of a homogenized estimator falls as N^a, with a fixed by the sampler's power
spectrum near zero frequency and by the integrand's smoothness (Pilleboue et al. 2015).
Cases, from the integrand as the estimator sees it (``ConvergenceResult.traits``):

* ``"best"``: smooth (a smooth periodic integrand, or a smooth one on the square when
  not shifted);
* ``"worst"``: discontinuous along a curve or a straight edge not parallel to the axes;
* ``"axis"``: discontinuous only along lines parallel to the axes (a shifted
  non-periodic smooth integrand, a step in x): a separate case, since stratification
  along the axes helps there; few rates are published.

Each sampler reports its own published rate for its parameters and dimension
(:meth:`clsamp.Sampler.convergence_rate`); the exponents of MSE against N in d = 2 for the
default parameters are (a test holds this table to what the samplers say):

==========================  ======  ======  ======================================
sampler                     best    worst   source
==========================  ======  ======  ======================================
random                      -1      -1      Pilleboue et al. 2015 (any integrand)
jittered                    -2      -1.5    Pilleboue et al. 2015 (d-D: -1-2/d, -1-1/d)
uncorrelated_jitter         -2      -1.5    as jittered in 2-D (one group of two
                                            dimensions is a jittered set)
latin_hypercube             -1      -1      Stein 1987 (non-additive integrands)
poisson_disk                -1      -1      Pilleboue et al. 2015
ccvt                        -3      -1.5    Pilleboue et al. 2015
sobol:owen                  -3      -1.5    Owen 1997 (smooth, up to log N); He and
                                            Wang 2015 (indicators)
zsobol                      -3      -1.5    as sobol:owen: each pixel's set is an
                                            Owen-scrambled (0, m, 2)-net
pmj02                       -3      -1.5    as sobol:owen: equivalent to an
                                            Owen-scrambled (0, 2)-sequence (Helmer
                                            et al. 2021)
pmj02bn                     -3      -1.5    as pmj02: its prefixes 2^k are the same
                                            nets, the jitter chosen otherwise
==========================  ======  ======  ======================================

Random sampling is -1 in the ``"axis"`` case too and jittered -1.5 (the cells of one
column or row are cut); jittered in d-D is N^(-1-2/d) and N^(-1-1/d). Parameters change
the answer: ``uncorrelated_jitter(groups=(1, 1))`` is a Latin hypercube (-1),
``jittered(strata=(4096, 1))`` is not a grid of square cells (unknown), and
``ccvt(density="random")`` has an N^-1 floor (unknown). Anything else, and every case of
a deterministic sampler that is not shifted, has no published rate here: the verdict is
``"unknown"``. That includes samplers with no theorem for their rate, such as
multijittered, correlated_multijittered and Owen-scrambled Halton (bases 2 and 3, not a
base-2 net), whatever slope a measurement shows (docs/performance.md lists measured ones).
Higher-order nets (``sobol`` and ``digital_net`` with ``order=2 | 3``) declare N^(-2 alpha) with
the digital shift (Dick 2008) and N^(-2 alpha - 1) with ``"lms+shift"`` (Dick 2011) for smooth
integrands in any d (:mod:`clsamp.samplers.higher_order`).
Shifted rank-1 lattices (``lattice``) reach O(N^(-2α+ε)) for periodic integrands of
smoothness α in a Korobov space (Sloan and Joe 1994), which the integrands here do not
have as a finite α; ``kronecker`` has no published MSE rate: both say unknown.

The verdict holds the fitted slope s (standard error sigma) against the published exponent
a, at the distance s - a, in slope units and in standard errors:

* **matches** when |s - a| <= 3 sigma: the gap is within the fit's own noise;
* **pre-asymptotic** when 3 sigma < |s - a| <= 3 sigma + 0.15: beyond the noise, but within
  the curvature that the finite N of a sweep leaves; a longer sweep should close it;
* **differs** beyond that.

The verdict's text says which, how far (for example "0.15 steeper than N^-1, 3.8
standard errors") and the rule.

Some published rates carry a log factor, MSE ~ N^a (log N)^k: Owen's for scrambled nets
in the smooth case is N^-3 (log N)^(d-1) (:data:`LOG_FACTORS`, by source). Over a finite
sweep such a factor makes the fitted slope shallower than a by the slope of k log log N
against log N over the fitted N (:func:`log_factor_slope`: 0.16 over N = 256..1024, 0.12
over 1024..16384 in 2-D). A slope that misses a but lies, by the rules above, at a plus
that bend is **pre-asymptotic** and the verdict names the factor ("pre-asymptotic
(log N)^1 factor"); a slope that matches a itself still matches.

A family's statistic can also be **pre-asymptotic** when the sweep has not reached the
rate's regime at all: Owen's N^-3 shows for a Gaussian of width sigma only once N is well
above 1/sigma^d. Where the local slopes between consecutive N (at least three) each lie
nearer a than the one before (:func:`approaching`), the verdict says so and lists them.

References
----------
.. [1] A. Pilleboue, G. Singh, D. Coeurjolly, M. Kazhdan, V. Ostromoukhov, "Variance
   analysis for Monte Carlo integration", ACM TOG 34(4), 2015.
.. [2] A. B. Owen, "Scrambled net variance for integrals of smooth functions", Annals
   of Statistics 25(4), 1997.
.. [3] Z. He, X. Wang, "On the convergence rate of randomized quasi-Monte Carlo for
   discontinuous functions", SIAM J. Numer. Anal. 53(5), 2015.
.. [4] M. Stein, "Large sample properties of simulations using Latin hypercube
   sampling", Technometrics 29(2), 1987.
"""

import math

TOLERANCE_SIGMAS = 3.0
CURVATURE_ALLOWANCE = 0.15
# Published rates whose proof carries a (log N)^k factor in a case, by source: the power k
# as a function of the dimension d. Owen 1997: N^-3 (log N)^(d-1) for smooth integrands.
LOG_FACTORS = {("Owen 1997", "best"): lambda d: d - 1}


def log_factor_slope(source, case, ns, d=2):
    """(k, bend): the power k of the log factor of a published rate, and the slope that
    (log N)^k adds to a log-log fit over ``ns``.

    Parameters
    ----------
    source : str or None
        The rate's publication (:data:`LOG_FACTORS`).
    case : str
        As :func:`case_of` gives it.
    ns : sequence of int
        The fitted N.
    d : int
        The dimension.

    Returns
    -------
    k : int
        0 where the rate has no log factor.
    bend : float
        The least-squares slope of k log log N against log N over ``ns`` (0 with k = 0 or
        fewer than two N); positive: the fit reads shallower than N^a.

    Examples
    --------
    >>> k, bend = log_factor_slope("Owen 1997", "best", [256, 1024])
    >>> k, round(bend, 2)
    (1, 0.16)
    """
    power = LOG_FACTORS.get((source, case))
    k = 0 if power is None else int(power(d))
    x = [math.log(n) for n in ns if n > 1]
    if k == 0 or len(set(x)) < 2:
        return k, 0.0
    y = [k * math.log(v) for v in x]
    xm, ym = sum(x) / len(x), sum(y) / len(y)
    bend = sum((a - xm) * (b - ym) for a, b in zip(x, y, strict=True)) / sum((a - xm) ** 2 for a in x)
    return k, float(bend)


def _fitted_ns(result):
    """The N a result's rate is fitted over (all of them for a stand-in without a range)."""
    ns = getattr(result, "ns", None)
    if ns is None:
        return []
    fit_range = getattr(result, "fit_range", None)
    return [int(n) for n in (ns[fit_range()] if fit_range else ns)]


def case_of(traits):
    """``"best"``, ``"worst"`` or ``"axis"`` from an integrand's traits (see the module).

    Parameters
    ----------
    traits : dict
        ``smooth`` (bool) and ``edges`` (``"none"``, ``"curved"``, ``"straight"`` or
        ``"axis"``), as an integrand's attributes give them.

    Returns
    -------
    str
        The case, or ``"unknown"`` for a discontinuous integrand without edges named.

    Examples
    --------
    >>> case_of({"smooth": True}), case_of({"edges": "curved"}), case_of({"edges": "axis"})
    ('best', 'worst', 'axis')
    """
    if traits.get("smooth") and traits.get("edges", "none") == "none":
        return "best"
    if traits.get("edges") in ("curved", "straight"):
        return "worst"
    if traits.get("edges") == "axis":
        return "axis"
    return "unknown"


def expected_rate(sampler, case, d=2):
    """(exponent, source) of MSE ~ N^exponent, or (None, None) when none is published.

    Parameters
    ----------
    sampler : Sampler or str
        A sampler (its own parameters and dimension count), or a name such as
        ``"sobol:owen"``, made with default parameters in ``d`` dimensions.
    case : {"best", "worst", "axis"}
    d : int
        The dimension, for a sampler given by name.

    Returns
    -------
    exponent : float or None
    source : str or None
        The publication the rate comes from.

    Examples
    --------
    >>> expected_rate("jittered", "worst")
    (-1.5, 'Pilleboue et al. 2015')
    """
    from .errors import InvalidArgumentError
    from .samplers import Sampler, make_sampler
    if not isinstance(sampler, Sampler):
        try:
            sampler = make_sampler(str(sampler), d=d)
        except InvalidArgumentError:
            return None, None          # an unknown name, or one that does not exist in d-D
    rate = sampler.convergence_rate(case)
    return (None, None) if rate is None else (rate.exponent, rate.source)


def _text(exponent):
    return f"N^{exponent:g}"


def compare(result, statistic="mean", allowance=None):
    """Hold a measured rate against the published one.

    Parameters
    ----------
    result : ConvergenceResult or FamilyResult
        Its ``rates`` (the sampler's own answer, recorded by :func:`clsamp.convergence`)
        give the published rate; a result without them asks a sampler made from its
        ``kind``. A :class:`~clsamp.results.FamilyResult` (a sweep over a family) is
        compared by :func:`compare_family`, with ``statistic`` and ``allowance``.

    Returns
    -------
    dict
        ``case`` (``"best"``, ``"worst"``, ``"axis"`` or ``"unknown"``), ``slope`` and
        ``stderr`` (from ``result.rate()``), ``expected`` (the exponent, or None),
        ``expected_text`` (``"N^-1.5"``, or None), ``source`` (the paper), ``kind``,
        ``distance`` (slope - expected) and ``sigmas`` (|distance| / stderr), None without
        an expected rate, and ``verdict``, whose first word is ``matches``,
        ``pre-asymptotic``, ``differs`` or ``unknown`` (see the module).
    """
    if hasattr(result, "members"):
        return compare_family(result, statistic, allowance)
    slope, stderr = result.rate()
    case = case_of(getattr(result, "traits", {}) or {})
    kind = getattr(result, "kind", "") or str(result.sampler)
    rates = getattr(result, "rates", None)
    if rates:
        expected, source = rates.get(case) or (None, None)
    else:
        expected, source = expected_rate(kind, case, getattr(result, "d", 2))
    if not getattr(result, "homogenize", True) and not getattr(result, "randomized", True):
        expected, source = None, None      # a fixed point set: no variance to speak of
    out = {"case": case, "slope": slope, "stderr": stderr, "expected": expected,
           "expected_text": None if expected is None else _text(expected), "source": source,
           "kind": kind, "distance": None, "sigmas": None}
    if expected is None:
        out["verdict"] = f"unknown (no published rate for {kind} in the {case} case)"
    elif not (math.isfinite(slope) and math.isfinite(stderr)):
        out["verdict"] = "unknown (too few positive MSEs to fit a slope)"
    else:
        gap = slope - expected
        sigmas = abs(gap) / stderr if stderr > 0 else (0.0 if gap == 0 else math.inf)
        out["distance"], out["sigmas"] = float(gap), float(sigmas)
        noise = TOLERANCE_SIGMAS * stderr
        k, bend = log_factor_slope(source, case, _fitted_ns(result), getattr(result, "d", 2))
        out["log_factor"], out["log_slope"] = k, bend
        factor = ""
        if abs(gap) <= noise:
            word = "matches"
        elif k and abs(gap - bend) <= noise + CURVATURE_ALLOWANCE:
            word = f"pre-asymptotic (log N)^{k} factor"
            factor = f"; the (log N)^{k} factor's slope over the fitted N: {bend:+.2f}"
        elif abs(gap) <= noise + CURVATURE_ALLOWANCE:
            word = "pre-asymptotic"
        else:
            word = "differs"
        side = "steeper" if gap < 0 else "shallower"
        out["verdict"] = (f"{word} ({abs(gap):.2f} {side} than {_text(expected)}, {sigmas:.1f} "
                          f"standard errors{factor}; {source}; matches within 3 standard errors, "
                          f"pre-asymptotic within 3 standard errors + {CURVATURE_ALLOWANCE})")
    return out


# The known rates of L2-type discrepancies D (not D^2) against N in d = 2, for section 1
# of the tour: (exponent, text). Independent uniform points and a Latin hypercube have
# E[D^2] = O(1/N); the centred grid D ~ 1/sqrt(N) (Warnock 1972); one point per cell of a
# square grid (jittered) E[D^2] = O(N^(-1 - 1/d)), only the cells a box's boundary cuts
# adding variance (Beck and Chen, Irregularities of Distribution, 1987); the
# low-discrepancy sets D = O(N^-1 log N), above Roth's lower bound sqrt(log N) / N
# (Roth 1954), so a fitted slope near -1 up to the log factor. Others: none published.
DISCREPANCY_RATES = {
    "random": (-0.5, "N^-1/2"),
    "latin_hypercube": (-0.5, "N^-1/2"),
    "regular": (-0.5, "N^-1/2"),
    "jittered": (-0.75, "N^-3/4"),
    "uncorrelated_jitter": (-0.75, "N^-3/4"),
    "halton": (-1.0, "N^-1 log N"),
    "hammersley": (-1.0, "N^-1 log N"),
    "sobol": (-1.0, "N^-1 log N"),
}


def family_expected(result):
    """The rate a family result's sampler publishes for the family's case
    (:func:`case_of` its traits).

    Parameters
    ----------
    result : FamilyResult

    Returns
    -------
    exponent : float or None
    source : str or None
        Both None where no rate is published.
    """
    rate = result.rates.get(case_of(result.traits))
    return (None, None) if rate is None else (rate[0], rate[1])


def approaching(ns, values, exponent, allowance=CURVATURE_ALLOWANCE):
    """The local slopes of ``values`` against ``ns`` where they move toward ``exponent``.

    A sweep that has not reached its asymptotic regime (a narrow Gaussian needs N well
    above 1/sigma^d before a scrambled net's N^-3 shows) has local slopes, between
    consecutive N, that bend toward the published exponent as N grows. This names that
    case: at least three local slopes, each strictly nearer ``exponent`` than the one
    before, none past it by more than ``allowance``.

    Parameters
    ----------
    ns : sequence of int
        The sweep's N, increasing.
    values : sequence of float
        The statistic at each N (positive).
    exponent : float
        The published exponent.
    allowance : float, optional
        How far past ``exponent`` a local slope may lie.

    Returns
    -------
    tuple of float
        The local slopes, or () where they do not approach ``exponent`` so.

    Examples
    --------
    >>> [round(v, 2) for v in approaching([16, 64, 256, 1024], [1e-3, 1e-4, 3e-6, 5e-8], -3)]
    [-1.66, -2.53, -2.95]
    >>> approaching([16, 64, 256, 1024], [1e-3, 1e-4, 1e-5, 1e-6], -3)
    ()
    """
    x = [math.log(n) for n in ns]
    y = [math.log(v) if v > 0 else math.nan for v in values]
    local = tuple((y[i + 1] - y[i]) / (x[i + 1] - x[i]) for i in range(len(x) - 1))
    if len(local) < 3 or not all(math.isfinite(v) for v in local):
        return ()
    gaps = [abs(v - exponent) for v in local]
    past = [(v - exponent) * (local[0] - exponent) < 0 and abs(v - exponent) > allowance
            for v in local]
    if any(past) or any(b >= a for a, b in zip(gaps[:-1], gaps[1:], strict=True)):
        return ()
    return local


def compare_family(result, statistic="mean", allowance=None):
    """The fitted rate of a family sweep's statistic held against the published one.

    Parameters
    ----------
    result : FamilyResult
    statistic : {"mean", "median", "q90", "max"}
        The summary across members whose rate is fitted (:meth:`FamilyResult.rate`).
    allowance : float, optional
        How far outside the confidence interval the exponent may lie and still count as
        "pre-asymptotic"; :data:`CURVATURE_ALLOWANCE` by default.

    Returns
    -------
    dict
        ``statistic``, ``slope``, ``ci`` (lower, upper), ``expected`` (exponent or None),
        ``source`` and ``verdict``: "matches" when the expected exponent lies in the
        confidence interval, "pre-asymptotic" when within ``allowance`` of it (or the
        exponent plus its log factor's bend is, :func:`log_factor_slope`, or the local
        slopes approach it, :func:`approaching`), "differs" beyond, "unknown" without a
        rate; ``log_factor`` (k), ``log_slope`` (the bend) and ``note`` (what explains a
        pre-asymptotic verdict or a missed log factor, or "").

    Raises
    ------
    InvalidArgumentError
        A statistic :meth:`FamilyResult.rate` refuses.
    """
    allowance = CURVATURE_ALLOWANCE if allowance is None else allowance
    slope, lo, hi = result.rate(statistic)
    exponent, source = family_expected(result)
    k, bend = log_factor_slope(source, case_of(result.traits), _fitted_ns(result), result.d)
    note = ""
    if exponent is None or not math.isfinite(lo):
        verdict = "unknown"
        note = "no published rate" if exponent is None else "too few positive N to fit"
    elif lo <= exponent <= hi:
        verdict = "matches"
    elif k and lo - allowance <= exponent + bend <= hi + allowance:
        verdict = "pre-asymptotic"
        note = f"(log N)^{k} factor: {bend:+.2f} over the fitted N"
    elif lo - allowance <= exponent <= hi + allowance:
        verdict = "pre-asymptotic"
    elif (local := approaching(result.ns, getattr(result, statistic), exponent, allowance)):
        verdict = "pre-asymptotic"
        note = (f"local slopes {', '.join(f'{v:+.2f}' for v in local)} approach "
                f"{_text(exponent)} as N grows")
    else:
        verdict = "differs"
        note = f"beyond the (log N)^{k} factor's {bend:+.2f} over the fitted N" if k else ""
    return {"statistic": statistic, "slope": slope, "ci": (lo, hi), "expected": exponent,
            "source": source, "verdict": verdict, "log_factor": k, "log_slope": bend,
            "note": note}


def discrepancy_rate(label):
    """(exponent, text) of the known rate of a sampler's L2 discrepancy in 2-D, or None.

    Parameters
    ----------
    label : str
        The sampler's name, with or without its randomization (``"sobol:owen"``).

    Returns
    -------
    tuple of (float, str) or None
        The exponent of N and the rate as text, where one is known.
    """
    return DISCREPANCY_RATES.get(label.split(":")[0])
