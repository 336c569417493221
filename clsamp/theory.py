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

Exponents of MSE against N in d = 2 (the table below cites each):

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
==========================  ======  ======  ======================================

Random sampling is -1 in the ``"axis"`` case too and jittered -1.5 (the cells of one
column or row are cut). Anything else, and every case of a deterministic sampler that
is not shifted, has no published rate here: the verdict is ``"unknown"``. That includes
samplers whose rate we measured but found no theorem for: in 2-D, N = 1024..16384, 512
realizations, seed 3, this library measured multijittered -1.99 (Gaussian) and -1.47
(disk), correlated_multijittered -2.98 and -1.54, and Owen-scrambled Halton (bases 2
and 3, not a base-2 net; N powers of 4) -2.01 and -1.53.

A measured slope **matches** when |slope - expected| <= 3 stderr + 0.15: three standard
errors for the noise of the fit, plus 0.15 for pre-asymptotic curvature (and the
(log N)^(d-1) factor of scrambled nets, whose local slope over N = 2^10..2^16 is about
0.1 shallower than -3).

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

PILLEBOUE = "Pilleboue et al. 2015"

# (sampler kind, case) -> (exponent, source), for d = 2.
RATES = {
    ("random", "best"): (-1.0, PILLEBOUE),
    ("random", "worst"): (-1.0, PILLEBOUE),
    ("random", "axis"): (-1.0, PILLEBOUE),
    ("jittered", "best"): (-2.0, PILLEBOUE),
    ("jittered", "worst"): (-1.5, PILLEBOUE),
    ("jittered", "axis"): (-1.5, PILLEBOUE),
    ("uncorrelated_jitter", "best"): (-2.0, PILLEBOUE + " (jittered)"),
    ("uncorrelated_jitter", "worst"): (-1.5, PILLEBOUE + " (jittered)"),
    ("latin_hypercube", "best"): (-1.0, "Stein 1987"),
    ("latin_hypercube", "worst"): (-1.0, "Stein 1987"),
    ("poisson_disk", "best"): (-1.0, PILLEBOUE),
    ("poisson_disk", "worst"): (-1.0, PILLEBOUE),
    ("ccvt", "best"): (-3.0, PILLEBOUE),
    ("ccvt", "worst"): (-1.5, PILLEBOUE),
    ("sobol:owen", "best"): (-3.0, "Owen 1997"),
    ("sobol:owen", "worst"): (-1.5, "He and Wang 2015"),
}


def case_of(traits):
    """``"best"``, ``"worst"`` or ``"axis"`` from an integrand's traits (see the module)."""
    if traits.get("smooth") and traits.get("edges", "none") == "none":
        return "best"
    if traits.get("edges") in ("curved", "straight"):
        return "worst"
    if traits.get("edges") == "axis":
        return "axis"
    return "unknown"


def expected_rate(kind, case, d=2):
    """(exponent, source) of MSE ~ N^exponent, or (None, None) when none is published."""
    kind = str(kind)
    if kind == "random" and case in ("best", "worst", "axis"):
        return -1.0, PILLEBOUE
    if kind == "jittered" and d != 2 and case in ("best", "worst"):
        return (-1.0 - 2.0 / d if case == "best" else -1.0 - 1.0 / d), PILLEBOUE
    if d != 2:
        return None, None
    return RATES.get((kind, case), (None, None))


def _kind(result):
    kind = getattr(result, "kind", "") or str(result.sampler)
    base, _, variant = kind.partition(":")
    aliases = {"n_rooks": "latin_hypercube"}
    base = aliases.get(base, base)
    return f"{base}:{variant}" if variant else base


def _text(exponent):
    return f"N^{exponent:g}"


def compare(result):
    """Hold a measured rate against the published one.

    Parameters
    ----------
    result : ConvergenceResult

    Returns
    -------
    dict
        ``case`` (``"best"``, ``"worst"``, ``"axis"`` or ``"unknown"``), ``slope`` and
        ``stderr`` (from ``result.rate()``), ``expected`` (the exponent, or None),
        ``expected_text`` (``"N^-1.5"``, or None), ``source`` (the paper), and
        ``verdict``, whose first word is ``matches``, ``differs`` or ``unknown``.
    """
    slope, stderr = result.rate()
    case = case_of(getattr(result, "traits", {}) or {})
    kind = _kind(result)
    expected, source = expected_rate(kind, case, getattr(result, "d", 2))
    if not getattr(result, "homogenize", True) and not getattr(result, "randomized", True):
        expected, source = None, None      # a fixed point set: no variance to speak of
    out = {"case": case, "slope": slope, "stderr": stderr, "expected": expected,
           "expected_text": None if expected is None else _text(expected), "source": source,
           "kind": kind}
    if expected is None:
        out["verdict"] = f"unknown (no published rate for {kind} in the {case} case)"
    elif not (math.isfinite(slope) and math.isfinite(stderr)):
        out["verdict"] = "unknown (too few positive MSEs to fit a slope)"
    else:
        gap = abs(slope - expected)
        allowed = TOLERANCE_SIGMAS * stderr + CURVATURE_ALLOWANCE
        word = "matches" if gap <= allowed else "differs"
        out["verdict"] = (f"{word} ({_text(expected)}, {source}: |{slope:.2f} - ({expected:g})| = "
                          f"{gap:.2f} {'<=' if gap <= allowed else '>'} 3 x {stderr:.2f} + 0.15)")
    return out
