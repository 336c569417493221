"""The tour's QMC section: what ``integrate`` costs against its tolerance, by method (and
qmcpy's ``CubQMCNetG`` / ``CubQMCLatticeG`` beside it where qmcpy is installed), and the
rates of higher-order digital nets on a smooth integrand.
"""

import time
import traceback
import warnings

import numpy as np

from . import plots
from .report import img, table

# (label, integrate's keyword arguments) of the methods compared
METHODS = (
    ("replications (Owen-Sobol', 16)", {"method": "replications"}),
    ("digital (Sobol', Walsh bound)", {"method": "digital"}),
    ("lattice (Kuo, Fourier bound)", {"method": "lattice"}),
)
# (label, make_sampler keyword arguments) of the nets in the higher-order panel
ORDERS = (
    ("order 1, Owen scrambling", {"order": 1, "randomize": "owen"}),
    ("order 2, digital shift", {"order": 2, "randomize": "xor"}),
    ("order 3, digital shift", {"order": 3, "randomize": "xor"}),
)


def tour_qmc_plan(quick):
    """The QMC section's sizes: (d of Keister's integrand, tolerances, higher-order N range,
    realizations).

    Parameters
    ----------
    quick : bool

    Returns
    -------
    (int, tuple of float, list of int, int)

    Examples
    --------
    >>> tour_qmc_plan(True)[1]
    (0.01, 0.001)
    """
    if quick:
        return 4, (1e-2, 1e-3), [2**m for m in range(6, 13)], 8
    return 4, (1e-2, 1e-3, 1e-4), [2**m for m in range(6, 15)], 16


def _qmcpy(f, d, tol, method):
    """qmcpy's guaranteed cubature on the same NumPy integrand: (estimate, points)."""
    import qmcpy
    if method == "digital":
        sampler = qmcpy.DigitalNetB2(d, seed=7)
        solver = qmcpy.CubQMCNetG(qmcpy.CustomFun(qmcpy.Uniform(sampler), g=f), abs_tol=tol)
    else:
        sampler = qmcpy.Lattice(d, seed=7)
        solver = qmcpy.CubQMCLatticeG(qmcpy.CustomFun(qmcpy.Uniform(sampler), g=f), abs_tol=tol)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        estimate, data = solver.integrate()
    return float(np.asarray(estimate).reshape(-1)[0]), int(data.n_total)


def _peers():
    """qmcpy's two cubatures as (label, method) where qmcpy imports, else none."""
    try:
        import qmcpy  # noqa: F401
    except ImportError:
        return ()
    return (("qmcpy CubQMCNetG", "digital"), ("qmcpy CubQMCLatticeG", "lattice"))


def _cost_against_tolerance(report, quick):
    """integrate on Keister's integrand at each tolerance by each method (and qmcpy)."""
    from .integrands import keister
    from .integration import integrate
    d, tolerances, _, _ = tour_qmc_plan(quick)
    f = keister(d)
    exact = float(f.integral)
    runs = [(label, lambda tol, kw=kw: _clsamp(integrate, f, d, tol, kw)) for label, kw in METHODS]
    runs += [(label, lambda tol, m=m: _qmcpy(f.__call__, d, tol, m)) for label, m in _peers()]
    rows, curves, data = [], {}, {}
    for label, run in runs:
        try:
            run(tolerances[0])                       # builds kernels / warms qmcpy's imports
            seconds, errors = [], []
            for tol in tolerances:
                t0 = time.perf_counter()
                estimate, n = run(tol)
                seconds.append(time.perf_counter() - t0)
                errors.append(abs(estimate - exact))
                rows.append((label, f"{tol:g}", n, seconds[-1], errors[-1],
                             "yes" if errors[-1] <= tol else "no"))
            curves[label] = (seconds, np.maximum(errors, 1e-17))
            data[label] = {"tolerances": list(tolerances), "seconds": seconds, "errors": errors}
        except Exception as error:  # one method failing leaves the others in the report
            rows.append((label, "-", "-", "-", f"failed: {error}", "-"))
            data[label] = {"error": traceback.format_exc()}
    body = (f"<p><code>clsamp.integrate</code> on Keister's integrand in d = {d} (exact "
            f"{exact:.10g}; a NumPy integrand) at each absolute tolerance, by its three "
            "methods: independent replications with a Student-t interval, and the single-sequence "
            "bounds of Hickernell &amp; Jim&eacute;nez Rugama (2016) from the Walsh coefficients "
            "of a digitally shifted Sobol' sequence and the Fourier coefficients of a shifted "
            "lattice. qmcpy's <code>CubQMCNetG</code> and <code>CubQMCLatticeG</code> run the "
            "same integrand where qmcpy is installed. Points: those each used; error: against "
            "the exact integral.</p>")
    body += table(("method", "abs_tol", "points", "seconds", "error", "met"), rows)
    if curves:
        path, src = report.picture("qmc_cost")
        plots.error_time_figure(path, [{"curves": curves, "ylabel": "error",
                                        "title": f"Keister d = {d}: error against seconds"}])
        body += img(src, "error against seconds", 600)
    return body, data


def _clsamp(integrate, f, d, tol, kw):
    """integrate's (estimate, integrand evaluations) on f's NumPy evaluation."""
    res = integrate(f.__call__, d, abs_tol=tol, seed=7, progress=False, **kw)
    return res.estimate, res.evaluations


def _higher_order(report, quick):
    """MSE against N of Sobol' nets of order 1, 2, 3 on a smooth product, with the verdicts."""
    from . import theory
    from .integrands.qmc import Genz
    from .samplers import make_sampler
    from .sweep import convergence
    _, _, ns, realizations = tour_qmc_plan(quick)
    f = Genz("gaussian", a=[1.0, 1.0], u=[0.5, 0.5])
    results, rows, data = [], [], {}
    for label, kw in ORDERS:
        try:
            sampler = make_sampler("sobol", d=2, seed=3, **kw)
            res = convergence(sampler, f, ns, realizations=realizations, homogenize=False,
                              progress=False)
            res.sampler = label
            verdict = theory.compare(res)
            results.append(res)
            rows.append((label, f"{verdict['slope']:.2f} ± {verdict['stderr']:.2f}",
                         verdict["expected_text"] or "-", verdict["verdict"], float(res.mse[-1])))
            data[label] = {"comparison": verdict, **res.to_dict()}
        except Exception as error:
            rows.append((label, "-", "-", f"failed: {error}", "-"))
            data[label] = {"error": traceback.format_exc()}
    body = (f"<p>Higher-order digital nets (Dick 2008: the digits of 2&alpha; Sobol' "
            "coordinates interlaced into 2) on a smooth non-periodic Gaussian in 2-D, "
            f"N = {ns[0]}..{ns[-1]}, {realizations} randomizations each: the order-1 net with "
            "Owen's nested uniform scrambling converges as Owen (1997) says (N<sup>-3</sup>), the interlaced "
            "nets of order &alpha; as N<sup>-2&alpha;</sup> (a digital shift) until the points' "
            "32 bits floor them.</p>")
    body += table(("net", "fitted slope", "theory", "verdict", "MSE at largest N"), rows)
    if results:
        path, src = report.picture("qmc_higher_order")
        plots.convergence(results, path)
        body += img(src, "MSE against N", 600)
    return body, data


def section_qmc(report, quick):
    """QMC: integrate's cost against tolerance by method (qmcpy beside it where installed),
    and higher-order nets' rates.

    Parameters
    ----------
    report : clsamp.report.Report
    quick : bool

    Returns
    -------
    (str, dict)
        The section's HTML and its numbers.
    """
    cost, cost_data = _cost_against_tolerance(report, quick)
    rates, rate_data = _higher_order(report, quick)
    return cost + rates, {"integrate": cost_data, "higher_order": rate_data}
