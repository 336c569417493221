"""``clsamp tour``: the whole lecture story in one command, as an HTML report.

The tour runs on the current device and writes ``DIR/index.html`` with its pictures
(relative links, readable without a server) and the raw data beside it: point sets as
.npy, images as OpenEXR, every number as JSON (``tour.json``). Each section (:data:`SECTIONS`,
a ``section_*`` function) is independent: a failure in one is reported in its place on the
page, and the others still run and keep their results.
"""

import dataclasses
import html
import platform
import time
import traceback
from pathlib import Path

import numpy as np

from . import files, plots, runtime
from .errors import InvalidArgumentError
from .report import (
    Report,
    Section,
    device_rows,
    fmt,
    img,
    one_line_warnings,
    slope_text,
    table,
    versions,
    write_html,
)
from .tour_blue import quiet_sampler, section_blue_noise
from .tour_cost import section_cost
from .tour_qmc import section_qmc
from .validation import check_bool

# Samplers shown in section 1, with the parameters that make each one its textbook self.
TOUR_SAMPLERS = (
    ("random", {}), ("regular", {}), ("jittered", {}), ("uncorrelated_jitter", {}),
    ("latin_hypercube", {}), ("multijittered", {}), ("correlated_multijittered", {}),
    ("halton", {}), ("hammersley", {}), ("sobol", {"randomize": "owen"}), ("lattice", {}),
    ("kronecker", {}), ("pmj02", {}), ("pmj02bn", {}), ("poisson_disk", {}), ("lloyd", {}),
    ("ccvt", {}),
)
# Section 1 shows Poisson disk as the lecture plots it: maximal sets (each of its own size)
# at the radius 0.75 d_max(n), so about n points each.
MAXIMAL_RHO = 0.75
# The tour's budgets for the samplers whose points cost most (Sampler.expensive): the
# parameters of section 1, full and --quick, and of the convergence sweeps, with their
# (sample counts, realizations) where they stop earlier than the others.
TOUR_BUDGETS = {
    "ccvt": {"full": {"points_per_site": 128}, "quick": {"points_per_site": 64},
             "convergence": {"points_per_site": 64}},
    "lloyd": {"quick": {"iterations": 20}},
}
TOUR_SWEEPS = {
    "poisson_disk": ([16, 64, 256, 1024, 4096], 512),
    "ccvt": ([16, 64, 256, 1024], 64),
}


def tour_sampler_params(name, quick):
    """A sampler's parameters in section 1: its textbook ones (:data:`TOUR_SAMPLERS`) and its
    budget in :data:`TOUR_BUDGETS`, if any.

    Parameters
    ----------
    name : str
    quick : bool

    Returns
    -------
    dict
    """
    params = dict(dict(TOUR_SAMPLERS).get(name, {}))
    params.update(TOUR_BUDGETS.get(name, {}).get("quick" if quick else "full", {}))
    return params


def section_samplers(report, quick):
    """Section 1, samplers: each one's points, expected spectrum, radial mean and PCF; radial
    means by family; CD and L2-star discrepancy against N, fitted slopes beside the known.

    Parameters
    ----------
    report : clsamp.report.Report
        Where pictures and data go.
    quick : bool
        ``clsamp tour --quick``: smaller sizes (here 8 sets of 256 points, not 32 of 1024).

    Returns
    -------
    (str, dict)
        The section's HTML, and its numbers for ``tour.json``.
    """
    from . import metrics, spectrum
    from .samplers import sampler_names
    n, realizations, resolution = (256, 8, 64) if quick else (1024, 32, 128)
    known = set(sampler_names())
    rows, data, cells, curves = [], {}, [], {}
    for name, _ in TOUR_SAMPLERS:
        if name not in known:
            rows.append((name, "-", "-", "-", "-", "-", "-", "not registered"))
            continue
        try:
            params = tour_sampler_params(name, quick)
            if name == "poisson_disk":        # maximal sets: a list of different sizes
                params["radius"] = MAXIMAL_RHO * metrics.max_min_distance(n)
            sampler = quiet_sampler(name, 1, params)
            label = sampler.label
            t0 = time.perf_counter()
            if sampler.needs_n:
                points = sampler.sample(n, realizations=realizations)
            else:
                points = sampler.sample_sets(realizations)
            seconds = time.perf_counter() - t0
            size = n if sampler.needs_n else float(np.mean([len(p) for p in points]))
            P = spectrum.power_spectrum(points, resolution=resolution, method="direct", progress=False)
            freqs, mean = spectrum.radial_mean(P)
            _, aniso = spectrum.anisotropy(P)
            radii, pcf = metrics.pair_correlation(points)
            rho = np.asarray(metrics.relative_radius(points))
            report.points(f"points_{name}", points)
            report.array(f"spectrum_{name}", P)
            plots.save_spectrum_exr(report.out / "data" / f"spectrum_{name}.exr", P,
                                    header={"sampler": name, "n": size, "realizations": realizations})
            path, src = report.picture(f"sampler_{name}")
            plots.sampler_figure(path, points, P, (radii, pcf), n=n, label=label)
            cells.append((label, src))
            curves[label] = (freqs, mean)
            low = float(np.nanmean(mean[freqs <= 0.5 * np.sqrt(n)]))
            peak = float(radii[np.argmax(pcf)] * size ** 0.5)
            rows.append((label, n if sampler.needs_n else f"{size:.0f} (maximal)", realizations,
                         seconds, float(rho.mean()), float(np.nanmean(aniso[len(aniso) // 4:])),
                         f"{low:.3g}", f"{float(np.max(pcf)):.3g} at {peak:.2f}"))
            data[name] = {"label": label, "n": size, "realizations": realizations, "seconds": seconds,
                          "params": params, "rho": rho, "radial_mean": mean, "frequencies": freqs,
                          "anisotropy_db": aniso, "pcf": pcf, "pcf_radii": radii}
        except Exception as error:  # one sampler failing leaves the others in the report
            rows.append((name, n, realizations, "-", "-", "-", "-", f"failed: {error}"))
            data[name] = {"error": traceback.format_exc()}
    path, overlay = report.picture("radial_means")
    plots.radial_mean_families(path, curves, FAMILIES, n=n, note=f"n = {n}, {realizations} sets")
    body = (f"<p>Each sampler makes {realizations} sets of n = {n} points (seed 1); the spectrum is the mean "
            "periodogram over the sets (exact, <code>method='direct'</code>), DC at the centre; "
            "the pair correlation function (PCF) is the mean over the sets of the Gaussian-smoothed "
            "pair-distance density on the torus (&sigma; = 0.05 mean spacings), 1 for white noise. "
            "&rho; is the relative radius (minimum toroidal distance over the hexagonal packing's, "
            "Lagae &amp; Dutr&eacute; 2008); the low-frequency power is the radial mean below "
            "2&nu;/&radic;N = 1 (white noise: 1; blue noise: near 0); the PCF peak is its largest "
            "value and where (in mean spacings). Poisson disk makes "
            f"maximal sets at radius {MAXIMAL_RHO} d<sub>max</sub>(n), each of its own size; "
            "their spectrum and PCF are means over the sets.</p>")
    body += table(("sampler", "n", "sets", "seconds", "ρ (mean)", "anisotropy dB (mean)",
                    "low-freq. power", "PCF peak"), rows)
    body += img(overlay, "radial means of all samplers, by family", 1000)
    body += "".join(f"<div>{img(src, name, 1100)}</div>" for name, src in cells)
    disc_body, data["discrepancy_against_n"] = _discrepancy_against_n(report, quick)
    body += disc_body
    return body, data


# Section 1's families, one panel each in the overlay of radial means (white noise, the
# reference, in every panel).
FAMILIES = (
    ("stratified", ("regular", "jittered", "uncorrelated_jitter", "latin_hypercube",
                    "multijittered", "correlated_multijittered")),
    ("low discrepancy", ("halton", "hammersley", "sobol:owen", "lattice", "kronecker", "pmj02",
                         "pmj02bn")),
    ("blue noise", ("poisson_disk", "lloyd", "ccvt")),
)
# Discrepancy against N: the sweep, and where the optimizers stop (full, quick).
DISCREPANCY_NS = ((16, 64, 256, 1024, 4096, 16384), (16, 64, 256, 1024))
DISCREPANCY_REALIZATIONS = (8, 4)
DISCREPANCY_CAPS = {"lloyd": (4096, 256), "ccvt": (1024, 256)}


def _discrepancy_against_n(report, quick):
    """CD and L2-star discrepancy of every sampler's sets against N, slopes against the
    known rates (theory.DISCREPANCY_RATES)."""
    from . import theory
    from .metrics import discrepancy_sweep
    from .samplers import sampler_names
    ns_all = DISCREPANCY_NS[1 if quick else 0]
    realizations = DISCREPANCY_REALIZATIONS[1 if quick else 0]
    methods = ("CD", "L2-star")
    rows, data, drawn = [], {}, []
    known = set(sampler_names())
    for name, _ in TOUR_SAMPLERS:
        if name not in known:
            continue
        try:
            params = tour_sampler_params(name, quick)
            cap = DISCREPANCY_CAPS.get(name, (None, None))[1 if quick else 0]
            ns = [m for m in ns_all if cap is None or m <= cap]
            sampler = quiet_sampler(name, 3, params)
            t0 = time.perf_counter()
            sweeps = discrepancy_sweep(sampler, ns, realizations=realizations, methods=methods)
            seconds = time.perf_counter() - t0
            expected = theory.discrepancy_rate(sampler.label)
            drawn.append(sweeps)
            slopes = {m: sweeps[m].slope() for m in methods}
            rows.append((sampler.label, f"{sweeps['CD'].ns[0]}..{sweeps['CD'].ns[-1]}",
                         *(slope_text(*slopes[m], len(sweeps[m].ns) - len(sweeps[m].ns) // 2)
                           for m in methods),
                         expected[1] if expected else "-", seconds))
            data[sampler.label] = {m: sweeps[m].to_dict() for m in methods}
        except Exception as error:  # one sampler failing leaves the others in the report
            rows.append((name, "-", "-", "-", "-", f"failed: {error}"))
            data[name] = {"error": traceback.format_exc()}
    body = ("<h3>Discrepancy against N</h3><p>The centred (CD) and L2-star discrepancies D "
            "(<code>clsamp.discrepancy</code>; the root of scipy's CD), root-mean-square over "
            f"{realizations} sets per N (seed 3), with the slope of log D against log N fitted "
            "over the larger half of each sweep. Known in 2-D: N<sup>-1/2</sup> for independent "
            "points, a Latin hypercube and the grid, N<sup>-3/4</sup> for one point per square "
            "cell (jittered), N<sup>-1</sup> up to a log factor for low-discrepancy sets. The "
            "optimizers' sweeps stop earlier (their points cost most).</p>")
    body += table(("sampler", "N", "CD slope", "L2-star slope", "known", "seconds"), rows)
    if drawn:
        path, src = report.picture("discrepancy_against_n")
        plots.discrepancy_figure(path, drawn)
        body += img(src, "discrepancy against N", 1100)
    return body, data


# -- 2. convergence ---------------------------------------------------------------------------
def tour_convergence_plan(quick):
    """Section 2's sweeps; the optimizers' stop earlier, with fewer realizations (their points
    cost most).

    Parameters
    ----------
    quick : bool

    Returns
    -------
    samplers, integrands : tuple of str
    sweeps : dict
        ``{sampler: (ns, realizations)}``.
    """
    if quick:
        samplers = ("random", "jittered", "sobol:owen", "poisson_disk")
        ns, realizations = [16, 64, 256, 1024], 128
        sweeps = {name: (ns, realizations) for name in samplers}
    else:
        samplers = ("random", "jittered", "latin_hypercube", "sobol:owen", "halton:owen",
                    "pmj02", "poisson_disk", "ccvt")
        ns, realizations = [16, 64, 256, 1024, 4096, 16384], 512
        sweeps = {name: TOUR_SWEEPS.get(name, (ns, realizations)) for name in samplers}
    return samplers, ("gaussian", "disk"), sweeps


def _sampler_for_convergence(name, quick):
    """The sampler of a sweep; expensive ones at the tour's budget (named in the report)."""
    base, _, variant = name.partition(":")
    params = {"randomize": variant} if variant else {}
    params.update(TOUR_BUDGETS.get(base, {}).get("convergence", {}))
    return quiet_sampler(base, 2, params), params


def section_convergence(report, quick):
    """Section 2, convergence: MSE against N for a smooth and a discontinuous integrand, then over
    families of random integrands; fitted rates against theory (Pilleboue et al. 2015).

    Parameters
    ----------
    report, quick
        As :func:`section_samplers`; the sweeps are :func:`tour_convergence_plan`'s.

    Returns
    -------
    (str, dict)
    """
    from . import theory
    from .sweep import convergence
    samplers, integrands, sweeps = tour_convergence_plan(quick)
    results, rows, data = [], [], {}
    for integrand in integrands:
        for name in samplers:
            label = f"{name} / {integrand}"
            try:
                sampler, params = _sampler_for_convergence(name, quick)
                report.results.setdefault("convergence_samplers", {})[name] = sampler
                sweep, realizations = sweeps[name]
                result = convergence(sampler, integrand, sweep, realizations=realizations, seed=3,
                                     progress=False, client=report.client)
                result.sampler = name
                results.append(result)
                verdict = theory.compare(result)
                rows.append((name, integrand, f"{sweep[0]}..{sweep[-1]}, {realizations}",
                             verdict["case"], slope_text(verdict["slope"], verdict["stderr"]),
                             verdict["expected_text"] or "-",
                             verdict["verdict"], float(result.mse[-1]), float(np.sum(result.seconds))))
                data[label] = {"params": params, "comparison": verdict, **result.to_dict()}
            except Exception as error:
                rows.append((name, integrand, "-", "-", "-", "-", f"failed: {error}", "-", "-"))
                data[label] = {"error": traceback.format_exc()}
    report.results["convergence"] = results
    path, picture = report.picture("convergence")
    plots.convergence(results, path)
    body = ("<p>Each point: the given number of realizations (sets), each shifted by its own "
            "random toroidal vector (homogenization: the estimator is unbiased); MSE of the "
            "estimate of the integral of a wrapped Gaussian (smooth: the best case) and of a disk "
            "(discontinuous: the worst case). The optimizers (CCVT at 64 density points per site) "
            "run shorter sweeps. The slope is a weighted log-log fit over the larger half of the "
            "sweep, &plusmn; its standard error; it <span class='matches'>matches</span> the "
            "published rate (Pilleboue et al. 2015; Owen 1997 for scrambled nets) within three "
            "standard errors, is <span class='pre-asymptotic'>pre-asymptotic</span> within "
            "three standard errors plus 0.15 (the curvature a finite sweep leaves), and "
            "<span class='differs'>differs</span> beyond; the verdict says how far.</p>")
    headers = ("sampler", "integrand", "N range, sets", "case", "fitted slope", "theory", "verdict",
               "MSE at largest N", "seconds")
    verdict_column = headers.index("verdict")

    def cell(i, value):
        css = f" class='{html.escape(str(value).split()[0])}'" if i == verdict_column else ""
        return f"<td{css}>{html.escape(fmt(value))}</td>"

    verdicts = "".join("<tr>" + "".join(cell(i, v) for i, v in enumerate(r)) + "</tr>" for r in rows)
    body += ("<table><thead><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in headers)
             + f"</tr></thead><tbody>{verdicts}</tbody></table>")
    body += img(picture, "MSE against N", 1000)
    family_body, data["families"] = _family_sweeps(report, quick)
    return body + family_body, data


TOUR_FAMILIES = ("random_heavisides", "random_gaussians", "random_disks")
TOUR_FAMILY_SAMPLERS = ("random", "regular", "jittered", "sobol:owen")


def _family_sweeps(report, quick):
    """Section 2's second part: MSE over families of random integrands, the spread across
    members shaded, the worst member dotted."""
    from . import theory
    from .sweep import convergence
    ns, realizations, members = (([16, 64, 256, 1024], 32, 32) if quick
                                  else ([16, 64, 256, 1024, 4096, 16384], 64, 256))
    results, rows, data = [], [], {}
    for family in TOUR_FAMILIES:
        for name in TOUR_FAMILY_SAMPLERS:
            try:
                res = convergence(name, family, ns, realizations=realizations, members=members,
                                  seed=3, progress=False, client=report.client)
                results.append(res)
                cmp = theory.compare(res)
                worst = res.rate("max")
                fitted = (f"{cmp['slope']:.2f} [{cmp['ci'][0]:.2f}, {cmp['ci'][1]:.2f}]"
                          if np.isfinite(cmp["ci"][0]) else "too few positive MSEs to fit")
                rows.append((name, family, fitted,
                             "-" if cmp["expected"] is None else f"N^{cmp['expected']:g}",
                             f"{cmp['verdict']} ({cmp['note']})" if cmp["note"] else cmp["verdict"],
                             f"{worst[0]:.2f}" if np.isfinite(worst[0]) else "-", float(res.mean[-1]),
                             float(res.max[-1]), float(np.sum(res.seconds))))
                data[f"{name} / {family}"] = {"comparison": cmp, **res.to_dict()}
            except Exception as error:
                rows.append((name, family, f"failed: {error}", "-", "-", "-", "-", "-", "-"))
                data[f"{name} / {family}"] = {"error": traceback.format_exc()}
    body = (f"<h3>Over families of random integrands</h3><p>One integrand hides a sampler's weak "
            f"directions, so each family draws {members} random members (half-planes with a "
            "quarter of them along or near an axis; anisotropic Gaussians; disks) and every "
            f"realization ({realizations} per N) estimates all of them. The line is the mean MSE "
            "over members, the band the members' 10&ndash;90 % range, the dotted line the worst "
            "member; the slope's interval is a bootstrap over members and realizations. The "
            "verdict holds the mean's slope against the published rate: it matches when the "
            "rate lies in the interval. A regular grid's worst half-planes fall as N^-1, no "
            "faster than random points; on the smooth periodic Gaussians the grid is the "
            "trapezoid rule and converges faster than any power.</p>")
    body += table(("sampler", "family", "mean MSE slope [95 % CI]", "theory", "verdict",
                   "worst member's slope", "mean MSE at largest N", "worst MSE", "seconds"), rows)
    if results:
        path, picture = report.picture("families")
        plots.family_convergence(results, path)
        body += img(picture, "MSE over integrand families", 1100)
    return body, data


# -- 3. rendering ------------------------------------------------------------------------------
TOUR_RENDER_SAMPLERS = (
    ("random", {}), ("jittered", {"strata": (16, 8)}), ("poisson_disk", {}),
    ("ccvt", {"points_per_site": 256}), ("sobol:owen", {}), ("pmj02", {}),
)


def section_render(report, quick):
    """Section 3, rendering: ambient occlusion at 128 rays per pixel with several samplers, MSE
    against a reference render.

    Parameters
    ----------
    report, quick
        As :func:`section_samplers`; ``quick`` renders 48² pixels, not 192².

    Returns
    -------
    (str, dict)
    """
    from . import render as rendering
    from .scene import Scene
    resolution = 48 if quick else 192
    scene = Scene.from_file("ao")
    spp = scene.default_spp
    ref, stderr = rendering.reference(scene, resolution=resolution, spp=2048 if quick else 8192,
                                      progress=False, return_noise=True)
    floor = rendering.noise_floor(stderr)
    report.exr("render_reference", ref, {"scene": scene.name, "sampler": "sobol:owen (reference)",
                                         "mse_floor": floor})
    rows, data, cells, timings, images = [], {}, [], [], {}
    cells.append(("reference", report.png("render_reference", ref)))
    for name, params in TOUR_RENDER_SAMPLERS:
        try:
            t0 = time.perf_counter()
            if quick and "points_per_site" in params:
                params = {**params, "points_per_site": 64}
            image = rendering.render(scene, name, spp=spp, resolution=resolution, seed=4,
                                     sampler_params=params or None, progress=False)
            seconds = time.perf_counter() - t0
            metrics = rendering.compare(image, ref, stderr)
            safe = name.replace(":", "_")
            report.exr(f"render_{safe}", image, {"scene": scene.name, "sampler": name, "spp": spp,
                                                 "seed": 4})
            cells.append((f"{name}: MSE {metrics['mse']:.3g}", report.png(f"render_{safe}", image)))
            images[name] = image
            rows.append((name, spp, metrics["mse"], metrics["mse_excess"], metrics["psnr"],
                         metrics["ssim"], seconds))
            data[name] = {"spp": spp, "seconds": seconds, "params": params, **metrics}
            timings.append((name, seconds, metrics["mse"]))
        except Exception as error:
            rows.append((name, spp, f"failed: {error}", "-", "-", "-", "-"))
            data[name] = {"error": traceback.format_exc()}
    report.results["render"] = {"scene": scene, "resolution": resolution, "reference": ref,
                                "timings": timings}
    data["reference"] = {"sampler": rendering.REFERENCE_SAMPLER, "passes": rendering.REFERENCE_PASSES,
                         "mse_floor": floor, "max_stderr": float(stderr.max())}
    body = (f"<p>The scene <code>{html.escape(scene.name)}</code> ({html.escape(scene.description)}) "
            f"at {resolution}&times;{resolution}, {spp} samples per pixel, seed 4, against a "
            f"reference of {rendering.REFERENCE_PASSES} independent Owen-scrambled Sobol' passes. "
            "The spread of the passes measures the reference's own noise: its MSE floor is "
            f"{floor:.3g} (largest per-pixel standard error {float(stderr.max()):.3g}), which every "
            "MSE below includes; <i>MSE - floor</i> estimates the error against the true image. "
            "2-D samplers are padded pairwise with random permutations, as pbrt pads; expensive "
            "samplers reuse a pool of realizations with a per-pixel random toroidal shift.</p>")
    body += table(("sampler", "spp", "MSE", "MSE - floor", "PSNR dB", "SSIM", "seconds"), rows)
    if images:
        path, side = report.picture("render_comparison")
        plots.render_comparison(path, ref, images, columns=len(images) + 1)
        body += img(side, "renders beside the reference", 1100)
    body += "<div class='grid'>" + "".join(
        f"<div class='cell'>{img(src, label, 220)}<br>{html.escape(label)}</div>" for label, src in cells)
    body += "</div>"
    blue_body, data["error_spectra"] = _error_spectra(report, scene, ref, resolution, quick)
    return body + blue_body, data


def _error_spectra(report, scene, ref, resolution, quick):
    """Where in screen space the error sits: zsobol against independent pixels."""
    from . import render as rendering
    spp = 16
    curves, rows, data = {}, [], {}
    for name in ("random", "sobol:owen", "zsobol"):
        image = rendering.render(scene, name, spp, resolution, seed=4, progress=False)
        curves[name] = rendering.error_spectrum(image, ref)
        low = rendering.low_frequency_power(image, ref)
        error = rendering.mse(image, ref)
        rows.append((name, spp, error, low))
        data[name] = {"spp": spp, "mse": error, "low_frequency_share": low}
    path, picture = report.picture("render_error_spectra")
    plots.error_spectra(path, curves, title=f"error spectra, {scene.name}, {spp} spp")
    body = ("<h3>Error in screen space</h3><p>The power spectrum of each render's error image, "
            "radially averaged (<code>clsamp.render.error_spectrum</code>). Independent "
            "per-pixel sampling (random, sobol:owen) leaves white error, flat across "
            "frequencies; zsobol hands neighbouring pixels complementary parts of one "
            "Owen-scrambled Sobol' sequence along a Morton curve (Ahmed and Wonka 2020, pbrt-v4's "
            "ZSobolSampler), so their errors cancel at low frequencies and the error turns blue. "
            "<i>Low-frequency share</i>: mean error power below 1/8 cycle per pixel over the "
            "mean at all frequencies (1 for white error).</p>")
    body += table(("sampler", "spp", "MSE", "low-frequency share"), rows)
    body += img(picture, "error spectra", 700)
    return body, data


# -- 5. stability --------------------------------------------------------------------------------
def _stability_cases(quick):
    """Each hard case: (name, what is measured, value reached, bound, passed)."""
    from fractions import Fraction

    from . import philox, spectrum
    from .samplers import make_sampler
    cases = []

    def case(name, measure, fn, bound):
        try:
            value = float(fn())
            cases.append((name, measure, value, bound, bool(value <= bound)))
        except Exception as error:
            cases.append((name, measure, f"failed: {error}", bound, False))

    def grid_spectrum():
        k = 64 if quick else 256
        g = (np.stack(np.meshgrid(np.arange(k), np.arange(k), indexing="ij"), -1).reshape(-1, 2) + 0.5) / k
        P = spectrum.power_spectrum(g, resolution=k, method="direct", progress=False)
        f = np.arange(-(k // 2), k // 2)
        aliased = (f[:, None] % k == 0) & (f[None, :] % k == 0)
        return np.max(P[~aliased]) / len(g)
    case("regular grid spectrum", "max power off the aliases / N", grid_spectrum, 1e-12)

    def edge_points():
        x = np.array([[1 - 2.0**-53, 1 - 2.0**-53], [0.0, 0.0], [0.5, 0.5], [0.5, 0.5]])
        P = spectrum.power_spectrum(x, resolution=32, method="direct", progress=False)
        Q = spectrum.direct_reference(x[None], 32)
        return np.max(np.abs(P - Q)) / len(x)
    case("points at 1 - 2^-53 and duplicates", "kernel vs reference, max |ΔP| / N", edge_points, 1e-12)

    def vdc_end():
        s = make_sampler("van_der_corput", d=1)
        got = s.sample(2, start=2**32 - 2)[:, 0]
        exact = [Fraction(int(f"{i:032b}"[::-1], 2), 2**32) for i in (2**32 - 2, 2**32 - 1)]
        return max(abs(Fraction(g) - e) for g, e in zip(got, exact, strict=True))
    case("Van der Corput at 2^32 - 1", "|error| against exact rationals", vdc_end, 0.0)

    def halton_power():
        s = make_sampler("halton", d=2)
        i = 3**20
        got = s.sample(1, start=i)[0, 1]
        digits, value, scale = i, Fraction(0), Fraction(1, 3)
        while digits:
            digits, digit = divmod(digits, 3)
            value += digit * scale
            scale /= 3
        return abs(Fraction(got) - value) / Fraction(float(np.spacing(got)))
    case("Halton base 3 at 3^20", "|error| in ulps of the result", halton_power, 0.5)

    def philox_identity():
        n = 200_000
        a = make_sampler("random", d=4, seed=2**63 + 5).sample(n)
        r = philox.uniform_block(2**63 + 5, philox.Stream.POINTS, np.arange(1), n, 4)[0]
        return np.count_nonzero(a != r)
    case("Philox kernel vs NumPy (800k doubles)", "mismatching values", philox_identity, 0.0)

    def owen_mse():
        from .sweep import convergence
        n = 2**12 if quick else 2**16
        res = convergence("sobol:owen", "gaussian", [n], realizations=64, seed=7, progress=False)
        from math import fsum
        exact = fsum(Fraction(e) ** 2 for e in res.errors[0]) / len(res.errors[0])
        return abs(Fraction(float(res.mse[0])) - exact) / exact
    case("Owen-Sobol MSE, Gaussian (tiny MSE)", "relative error of the MSE vs exact rationals",
         owen_mse, 1e-12)

    def ccvt_capacities():
        _, info = make_sampler("ccvt", seed=3, points_per_site=32).sample(64, return_info=True)
        caps = info.capacities[0]
        energy = info.energy_history[0]
        rises = np.max(np.diff(energy)) if len(energy) > 1 else 0.0
        return max(float(caps.max() - caps.min()), max(0.0, rises))
    case("CCVT capacities and energy", "capacity spread + largest energy rise", ccvt_capacities, 0.0)

    def poisson_radius():
        from .metrics import relative_radius
        pts = make_sampler("poisson_disk", rho=0.75, seed=2).sample(512, realizations=4)
        return 0.75 - float(np.min(relative_radius(pts)))
    case("Poisson disk ρ >= 0.75", "0.75 - smallest ρ", poisson_radius, 0.0)
    return cases


def section_stability(report, quick):
    """Section 5, stability: the hard cases, each with the error it reached and its bound.

    Parameters
    ----------
    report, quick
        As :func:`section_samplers`; ``quick`` makes some cases smaller.

    Returns
    -------
    (str, dict)
    """
    cases = _stability_cases(quick)
    rows = [(name, measure, value, bound, "ok" if passed else "FAILED")
            for name, measure, value, bound, passed in cases]
    body = ("<p>Cases where a careless implementation loses precision or breaks an invariant, "
            "each with the error this run reached and the bound the tests hold it to.</p>")
    body += table(("case", "measure", "reached", "bound", ""), rows)
    data = {name: {"measure": m, "value": v, "bound": b, "passed": p} for name, m, v, b, p in cases}
    return body, data


def section_device(report, quick, timings):
    """Section 6: the device, the versions, every device found and what runs on it, timings.

    Parameters
    ----------
    report, quick
        As :func:`section_samplers` (``quick`` changes nothing here).
    timings : dict
        ``{section: seconds}`` of the sections before.

    Returns
    -------
    (str, dict)
    """
    device = runtime.current_device()
    rows = device_rows(dataclasses.asdict(device))
    rows += [(f"version: {k}", v) for k, v in versions().items()]
    rows.append(("platform", platform.platform()))
    timing_rows = [(k, f"{v:.2f}") for k, v in timings.items()]
    found = []
    for other in runtime.devices():
        runs = runtime.capabilities(other.index)
        found.append((str(other), other.implementation or "unknown",
                      ", ".join(k if why is None else f"{k} (no: {why})" for k, why in runs.items())))
    body = (table(("property", "value"), rows)
            + "<h3>Every device found</h3>" + table(("device", "implementation", "runs"), found)
            + "<h3>Seconds per section</h3>" + table(("section", "seconds"), timing_rows))
    return body, {"device": dataclasses.asdict(device), "versions": versions(), "timings": timings,
                  "devices": [dict(dataclasses.asdict(d), runs=runtime.capabilities(d.index))
                              for d in runtime.devices()]}


SECTIONS = (
    ("samplers", "1. Samplers: spectra, radial means, pair correlation, discrepancy",
     section_samplers),
    ("convergence", "2. Convergence against theory", section_convergence),
    ("render", "3. Ambient occlusion at 128 rays: samplers in images", section_render),
    ("cost", "4. What accuracy costs in time", section_cost),
    ("stability", "5. Stability: the hard cases", section_stability),
    ("blue_noise", "6. Blue noise since 2009: quality against seconds, and in 4-D", section_blue_noise),
    ("qmc", "7. QMC: integrate's cost against tolerance, and higher-order nets", section_qmc),
    ("device", "8. Device, versions and timings", section_device),
)


def check_out(out, name="'out'"):
    """Refuse, before any work, a tour folder whose outputs cannot be written: an empty name,
    or ``index.html``, ``tour.json``, ``img/`` or ``data/`` blocked
    (:func:`clsamp.files.check_output`).

    Parameters
    ----------
    out : str or Path
    name : str
        The argument that named it, for the message.

    Raises
    ------
    InvalidArgumentError
        What blocks it.
    """
    if not str(out).strip():
        raise InvalidArgumentError(f"{name} must name a folder, got {str(out)!r}")
    for inside in ("index.html", "tour.json", "img/x.png", "data/x.npy"):
        files.check_output(Path(out) / inside, name)


def run_tour(out, quick=False, progress=True, client=None):
    """Run every section into the folder ``out``.

    Parameters
    ----------
    out : str or Path
        Output folder (created).
    quick : bool
        Smaller sizes, for CI (about 30 s on 2 cores).
    progress : bool
        Show a progress bar over the sections.
    client : dask.distributed.Client, optional
        Run section 2's sweeps there (:mod:`clsamp.parallel`: the same numbers).

    Returns
    -------
    Path
        The report's ``index.html``.

    Raises
    ------
    InvalidArgumentError
        ``out`` cannot hold the report (:func:`check_out`).
    """
    check_bool(progress, "progress")
    check_out(out)
    from tqdm import tqdm

    report = Report(out)
    report.client = client
    timings = {}
    meta = {"device": str(runtime.current_device()), "quick": bool(quick),
            "date": time.strftime("%Y-%m-%d %H:%M:%S %Z"), "sections": len(SECTIONS)}
    results = {}
    with one_line_warnings():
        for key, title, fn in tqdm(SECTIONS, desc="clsamp tour", disable=not progress, unit="section"):
            _run_section(report, quick, key, title, fn, timings, results, meta)
    return report.out / "index.html"


def _run_section(report, quick, key, title, fn, timings, results, meta):
    """Run one section into the report, its failure reported in its place; rewrite the page."""
    section = Section(key, title)
    t0 = time.perf_counter()
    try:
        if key == "device":
            section.body, section.data = fn(report, quick, timings)
        else:
            section.body, section.data = fn(report, quick)
    except Exception:  # a failed section is reported in the page; the rest go on
        section.error = traceback.format_exc()
    section.seconds = time.perf_counter() - t0
    timings[key] = section.seconds
    report.sections.append(section)
    results[key] = {"title": title, "seconds": section.seconds, "error": section.error,
                    "data": section.data}
    document = {"meta": {**meta, "complete": len(results) == meta["sections"]}, "sections": results}
    files.write_json(report.out / "tour.json", document)
    write_html(report, meta)
