"""The tour's section on blue noise since 2009: the optimizing samplers side by side at one
n in 2-D (points, expected spectrum, radial mean, PCF, ρ, N·E, low-frequency power and
the seconds each took: quality against time), and one 4-D case, depth of field, rendered.

Samplers not registered in this build are listed as such, so the section grows with the
registry (``sot``, ``sample_elimination``, ``bnot`` where present).
"""

import time
import traceback

import numpy as np

from . import plots
from .report import img, table
from .spectral_stats import low_frequency_power

# (name, parameters) of the optimizers compared, oldest first
BLUE_NOISE = (
    ("poisson_disk", {"rho": 0.75}),
    ("lloyd", {"iterations": 100}),
    ("ccvt", {"points_per_site": 128}),
    ("bnot", {"cells": "exact", "iterations": 32}),
    ("sample_elimination", {}),
    ("sot", {}),
    ("gbn", {}),
)
DOF_SAMPLERS = ("random", "sobol:owen", "gbn")


def quiet_sampler(name, seed, params):
    """``make_sampler(name, d=2, seed=seed, **params)`` with the sampler's own progress bar
    off where it has one (the tour shows its own, or none with ``--no-progress``).

    Parameters
    ----------
    name : str
    seed : int
    params : dict

    Returns
    -------
    Sampler
    """
    from .samplers import make_quiet_sampler
    return make_quiet_sampler(name, d=2, seed=seed, **params)


def section_blue_noise(report, quick):
    """Blue noise since 2009: each optimizer's sets at n = 1024 (256 quick) in 2-D, their
    quality against the seconds they took, and gbn in 4-D for depth of field.

    Parameters
    ----------
    report : clsamp.report.Report
    quick : bool

    Returns
    -------
    (str, dict)
        The section's HTML and its numbers.
    """
    from . import metrics, spectrum
    from .samplers import sampler_names
    n, realizations, resolution = (256, 2, 32) if quick else (1024, 4, 64)
    known = set(sampler_names())
    rows, data, cells, scatter = [], {}, [], []
    for name, params in BLUE_NOISE:
        if name not in known:
            rows.append((name, "-", "-", "-", "-", "-", "not in this build"))
            continue
        try:
            sampler = quiet_sampler(name, 1, dict(params))
            t0 = time.perf_counter()
            points = sampler.sample(n, realizations=realizations)
            seconds = time.perf_counter() - t0
            P = spectrum.power_spectrum(points, resolution=resolution, method="direct", progress=False)
            radii, pcf = metrics.pair_correlation(points)
            rho = float(np.mean(metrics.relative_radius(points)))
            ne = float(np.mean(metrics.normalized_energy(points)))
            low = low_frequency_power(P, n)
            path, src = report.picture(f"blue_{name}")
            plots.sampler_figure(path, points, P, (radii, pcf), n=n, label=sampler.label)
            cells.append((sampler.label, src))
            scatter.append((sampler.label, seconds, low, rho))
            rows.append((sampler.label, n, realizations, seconds, rho, ne, f"{low:.3g}"))
            data[name] = {"seconds": seconds, "rho": rho, "normalized_energy": ne,
                          "low_frequency_power": low, "params": params}
        except Exception as error:  # one sampler failing leaves the others in the report
            rows.append((name, n, realizations, "-", "-", "-", f"failed: {error}"))
            data[name] = {"error": traceback.format_exc()}
    body = (f"<p>The optimizers since Poisson disk, each making {realizations} sets of n = {n} "
            "points in 2-D (seed 1; Poisson disk at &rho; = 0.75, Lloyd 100 iterations, CCVT "
            "128 points a site, BNOT exact cells and 32 iterations, the others at their "
            "defaults): "
            "&rho; the relative radius, N&middot;E the normalized CVT energy (0.1604 for the "
            "hexagonal lattice, 1/&pi; for white noise), and the low-frequency power the mean "
            "periodogram over the integer frequencies 0 &lt; |k| &lt; &radic;N / 2 (white "
            "noise: 1). The figure puts each against the seconds it took: the power "
            "(lower is better) and &rho; (higher is better).</p>")
    body += table(("sampler", "n", "sets", "seconds", "ρ (mean)", "N·E (mean)", "low-freq. power"),
                  rows)
    if scatter:
        path, src = report.picture("blue_quality_time")
        plots.quality_time(path, scatter, title=f"n = {n}, 2-D, {realizations} sets")
        body += img(src, "quality against seconds", 900)
    body += "".join(f"<div>{img(src, name, 1100)}</div>" for name, src in cells)
    dof_body, data["depth_of_field"] = _depth_of_field(quick)
    return body + dof_body, data


def _depth_of_field(quick):
    """4-D: the dof scene (pixel and lens) rendered with 4-D sets against its reference."""
    from . import render as rendering
    from .samplers import sampler_names
    from .scene import Scene
    scene = Scene.from_file("dof")
    resolution, spp = (24, 32) if quick else (48, 64)
    ref, stderr = rendering.reference(scene, resolution=resolution, spp=1024, progress=False,
                                      return_noise=True)
    rows, data = [], {}
    for name in DOF_SAMPLERS:
        if name.split(":")[0] not in sampler_names():
            continue
        try:
            t0 = time.perf_counter()
            image = rendering.render(scene, name, spp=spp, resolution=resolution, seed=4, pad=False,
                                     progress=False)
            seconds = time.perf_counter() - t0
            mse = rendering.compare(image, ref, stderr)["mse"]
            rows.append((name, spp, mse, seconds))
            data[name] = {"spp": spp, "mse": mse, "seconds": seconds}
        except Exception as error:
            rows.append((name, spp, f"failed: {error}", "-"))
            data[name] = {"error": traceback.format_exc()}
    body = (f"<p>Depth of field is a 4-D integral per pixel (the pixel area and the lens): "
            f"the scene <code>{scene.name}</code> at {resolution}&times;{resolution}, "
            f"{spp} samples per pixel, each pixel's samples one 4-D set, MSE against a "
            "1024-spp reference.</p>")
    return body + table(("sampler", "spp", "MSE", "seconds"), rows), data
