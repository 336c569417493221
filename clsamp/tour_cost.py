"""Section 4 of ``clsamp tour``: what accuracy costs in time.

Spectrum error against seconds (the NUFFT path against the exact sum), sampler MSE against
seconds per estimate (generation included) and render MSE against seconds per image. Each
time is the median of :data:`REPEATS` runs, so that one slow run does not bend a curve.
"""

import dataclasses
import html
import time
import traceback

import numpy as np

from . import plots
from .report import fmt, img, table

# Each time in this section is the median of this many runs (after one that builds kernels).
REPEATS = 3
# A sweep timed again runs as many realizations as fit in this many seconds, at least
# MIN_REALIZATIONS (fewer make the time per estimate mostly the launch's).
TIMING_SECONDS = 2.0
MIN_REALIZATIONS = 16


def median_seconds(fn, repeats=REPEATS):
    """The median wall time of ``repeats`` calls of ``fn()``, and the last call's value.

    Parameters
    ----------
    fn : callable
    repeats : int

    Returns
    -------
    (float, object)

    Examples
    --------
    >>> seconds, value = median_seconds(lambda: 42)
    >>> value, seconds >= 0
    (42, True)
    """
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        value = fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), value


def _retimed(result, sampler, client):
    """A section-2 result whose seconds per N are the median of its own run and
    :data:`REPEATS` - 1 more of the same sweep, each with as many of its realizations as
    fit in :data:`TIMING_SECONDS` by section 2's times (at least :data:`MIN_REALIZATIONS`)."""
    from .sweep import convergence
    fit = int(TIMING_SECONDS / max(float(np.sum(result.seconds_per_estimate)), 1e-12))
    r = int(np.clip(fit, MIN_REALIZATIONS, result.realizations))
    runs = [result.seconds_per_estimate] + [
        convergence(sampler, result.integrand, list(result.ns), realizations=r, seed=3,
                    progress=False, client=client).seconds_per_estimate for _ in range(REPEATS - 1)]
    per_estimate = np.median(np.asarray(runs, dtype=np.float64), axis=0)
    return dataclasses.replace(result, seconds=per_estimate * result.realizations)


def _spectrum_cost(report, quick):
    """Fast (NUFFT) against direct spectra: max error relative to N, and seconds."""
    from . import spectrum
    from .samplers import make_sampler
    r, n, resolution = (8, 1024, 128) if quick else (64, 4096, 256)
    points = make_sampler("random", seed=5).sample(n, realizations=r)
    spectrum.power_spectrum(points[:1], resolution=resolution, method="direct", progress=False)
    direct_seconds, exact = median_seconds(lambda: spectrum.power_spectrum(
        points, resolution=resolution, method="direct", progress=False))
    rows = [("direct", "-", direct_seconds, "exact (fp64)")]
    curve = []
    for tol in (1e-2, 1e-3, 1e-6, 1e-10, 1e-12):
        spectrum.power_spectrum(points[:1], resolution=resolution, method="fast", tol=tol, progress=False)
        seconds, fast = median_seconds(lambda tol=tol: spectrum.power_spectrum(
            points, resolution=resolution, method="fast", tol=tol, progress=False))
        error = float(np.max(np.abs(fast - exact)) / n)
        rows.append(("fast", tol, seconds, error))
        curve.append((tol, seconds, error))
    return {"realizations": r, "n": n, "resolution": resolution, "direct_seconds": direct_seconds,
            "fast": [{"tol": t, "seconds": s, "max_error_over_n": e} for t, s, e in curve]}, rows


def section_cost(report, quick):
    """Section 4, what accuracy costs in time: spectrum error against seconds (fast against
    direct), sampler MSE against seconds including generation, render MSE against seconds.

    Parameters
    ----------
    report, quick
        As :func:`clsamp.tour.section_samplers`; ``quick`` measures smaller spectra and fewer spp.

    Returns
    -------
    (str, dict)
    """
    data, body, failures = {}, "", []
    panels = [None, None, None]   # spectra, samplers, renders: error against time
    # spectra
    try:
        spec, rows = _spectrum_cost(report, quick)
        data["spectrum"] = spec
        body += (f"<h3>Spectra</h3><p>Expected spectrum of {spec['realizations']} &times; "
                 f"{spec['n']} random points at {spec['resolution']}&sup2; frequencies: the NUFFT "
                 "path at each tolerance against the exact sum (error = max |P<sub>fast</sub> &minus; "
                 f"P<sub>direct</sub>| / N); seconds: the median of {REPEATS} runs.</p>")
        body += table(("method", "tol", "seconds", "max error / N"), rows)
        fast = ([c["seconds"] for c in spec["fast"]], [max(c["max_error_over_n"], 1e-17)
                                                         for c in spec["fast"]])
        panels[0] = {"curves": {"fast (NUFFT)": fast}, "exact": ("direct (exact)", spec["direct_seconds"]),
                     "ylabel": "max error / N", "title": "spectrum: error against time",
                     "markersize": None, "fontsize": None}
    except Exception:
        failures.append(("spectra", traceback.format_exc()))
    # samplers
    try:
        from .results import pareto_front, time_to_mse
        results = report.results.get("convergence")
        if not results:
            raise RuntimeError("section 2 produced no convergence results")
        samplers = report.results["convergence_samplers"]
        results = [_retimed(r, samplers[r.sampler], report.client) for r in results]
        target_rows, sampler_data, curves = [], {}, {}
        for integrand in sorted({r.integrand for r in results}):
            group = [r for r in results if r.integrand == integrand]
            target = float(np.median([r.mse[len(r.mse) // 2] for r in group]))
            for r in group:
                reach = time_to_mse(r, target)
                target_rows.append((r.sampler, integrand, target,
                                    "not reached" if reach is None else reach["n"],
                                    "not reached" if reach is None else reach["seconds"]))
                if integrand == "disk":    # in N order: a line through the sweep
                    curves[r.sampler] = (r.seconds_per_estimate, r.mse)
            sampler_data[integrand] = {"target_mse": target, "pareto_front": pareto_front(group),
                                       "seconds_per_estimate": {r.sampler: r.seconds_per_estimate
                                                                for r in group}}
        panels[1] = {"curves": curves, "xlabel": "seconds per estimate (generation included)",
                     "title": "samplers (disk integrand): MSE against time"}
        data["samplers"] = sampler_data
        body += ("<h3>Samplers</h3><p>From section 2: the seconds one estimate takes, point "
                 "generation included, to reach a target MSE (the median MSE at the middle of the "
                 "sweep), and the N that reaches it. Section 2's MSEs; each N's time per estimate "
                 f"is the median of section 2's run and {REPEATS - 1} more of the same sweep "
                 f"(with the realizations that fit in {TIMING_SECONDS:g} s). A sampler "
                 "that converges faster per point can still lose on time when its points are "
                 "expensive.</p>")
        body += table(("sampler", "integrand", "target MSE", "N needed", "seconds per estimate"),
                       target_rows)
        front = sampler_data.get("disk", {}).get("pareto_front", [])
        front_text = ", ".join(f"{p['sampler']} N={p['n']} ({fmt(p['seconds'])} s, MSE {fmt(p['mse'])})"
                               for p in front)
        body += f"<p>Pareto front (disk): {front_text}</p>"
    except Exception:
        failures.append(("samplers", traceback.format_exc()))
    # renders
    try:
        from . import render as rendering
        state = report.results.get("render")
        if not state:
            raise RuntimeError("section 3 produced no renders")
        scene, resolution, ref = state["scene"], state["resolution"], state["reference"]
        spps = (4, 16, 64) if quick else (4, 16, 64, 256)
        render_rows, render_data, curves = [], {}, {}
        for name, params in (("random", {}), ("jittered", None), ("sobol:owen", {})):
            seconds, errors = [], []
            for spp in spps:
                extra = params
                if params is None:
                    k = int(round(np.sqrt(spp)))
                    extra = {"strata": (k, k)}
                rendering.render(scene, name, spp=spp, resolution=8, seed=6, sampler_params=extra or None,
                                 progress=False)  # builds the kernels before timing
                spent, image = median_seconds(lambda spp=spp, extra=extra, name=name: rendering.render(
                    scene, name, spp=spp, resolution=resolution, seed=6,
                    sampler_params=extra or None, progress=False))
                seconds.append(spent)
                errors.append(rendering.mse(image, ref))
                render_rows.append((name, spp, seconds[-1], errors[-1]))
            curves[name] = (seconds, errors)
            render_data[name] = {"spp": list(spps), "seconds": seconds, "mse": errors}
        panels[2] = {"curves": curves, "xlabel": "seconds per image", "ylabel": "MSE against reference",
                     "title": f"AO renders {resolution}² : MSE against time"}
        data["render"] = render_data
        body += ("<h3>Rendered images</h3><p>The AO scene rendered at increasing samples per pixel: "
                 f"MSE against seconds (the median of {REPEATS} renders), sampling and rendering "
                 "included.</p>")
        body += table(("sampler", "spp", "seconds", "MSE"), render_rows)
    except Exception:
        failures.append(("renders", traceback.format_exc()))
    path, src = report.picture("accuracy_time")
    plots.error_time_figure(path, panels)
    body = img(src, "accuracy against time", 1100) + body
    for part, trace in failures:
        body += f"<div class='error'>The {part} part failed:\n{html.escape(trace)}</div>"
        data[f"{part}_error"] = trace
    if failures and len(failures) == 3:
        raise RuntimeError("every part of the accuracy-against-time section failed")
    return body, data


