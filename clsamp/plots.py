"""Pictures of what clsamp measures: spectra, radial means, anisotropy, pair correlation,
discrepancy against N, and MSE against N or against time, as matplotlib figures or
PNG/OpenEXR files (written whole, through :mod:`clsamp.files`).

matplotlib is imported when a picture is made (the Agg backend: no screen needed).
"""

import math

import numpy as np

from . import files, theory
from . import spectrum as spectra
from .errors import InvalidArgumentError
from .plot_axes import clip_far_below, legend_below, readable_log_ticks
from .plot_points import point_sets_2d, points, points_figure, pyplot, scatter, writes  # noqa: F401 (public here)
from .results import pareto_front
from .validation import check_choice, check_curve, check_curves, check_positive_int, check_real

__all__ = ["points", "points_figure", "spectrum", "radial_mean", "anisotropy", "spectrum_figure",
           "sampler_figure", "radial_mean_families", "pair_correlation", "pcf_figure",
           "discrepancy", "discrepancy_figure", "convergence", "family_spread",
           "family_convergence", "accuracy_time", "error_time", "error_time_figure", "quality_time",
           "render_comparison", "error_spectra", "spectrum_image", "save_spectrum_png",
           "save_spectrum_exr", "pyplot"]


def _save(fig, path):
    """Lay ``fig`` out and save it whole (:func:`clsamp.files.save_figure`)."""
    fig.tight_layout()
    return files.save_figure(path, fig)


# -- spectra --------------------------------------------------------------------------------
def spectrum_image(P, scale="linear", vmin=None, vmax=None):
    """A 2-D spectrum as a grey image in [0, 1], DC at the centre, +y up and +x right.

    ``image[R - 1 - j, i] = P[i, j]``, ``P[i, j]`` being at (x, y) frequency (i - R/2, j - R/2):
    the picture as people read one (``plt.imshow(P)`` would show it transposed).

    Parameters
    ----------
    P : ndarray (R, R)
    scale : {"linear", "log"}
        ``"linear"``: P / vmax clipped to [0, 1] (vmax default 4, so white noise is a
        mid grey after the PNG's gamma, the look of PSA and UTK pictures). ``"log"``:
        10·log10 P mapped from [vmin, vmax] dB (default [-20, 10]).
    vmin, vmax : float, optional

    Returns
    -------
    ndarray (R, R) of float64 in [0, 1]
    """
    P = spectra.check_spectrum(P)
    if P.ndim != 2:
        raise InvalidArgumentError(f"'P' must be a 2-D spectrum to make an image, got shape {P.shape}")
    check_choice(scale, "scale", ("linear", "log"))
    if scale == "linear":
        top = 4.0 if vmax is None else check_real(vmax, "vmax", minimum=0.0, open_minimum=True)
        image = P / top
    else:
        low = -20.0 if vmin is None else check_real(vmin, "vmin")
        high = 10.0 if vmax is None else check_real(vmax, "vmax")
        if high <= low:
            raise InvalidArgumentError(f"'vmax' must be > 'vmin', got {high} <= {low}")
        with np.errstate(divide="ignore"):
            image = (10.0 * np.log10(P) - low) / (high - low)
    return np.clip(image.T[::-1], 0.0, 1.0)


@writes((".png",))
def save_spectrum_png(path, P, scale="linear", vmin=None, vmax=None):
    """Write a 2-D spectrum as a grey PNG (gamma 2.2 for ``"linear"``).

    Parameters
    ----------
    path : str or Path
    P, scale, vmin, vmax
        As :func:`spectrum_image` takes them.

    Returns
    -------
    Path
    """
    image = spectrum_image(P, scale, vmin, vmax)
    return files.write_png(path, image, gamma=2.2 if scale == "linear" else 1.0)


@writes((".exr",))
def save_spectrum_exr(path, P, header=None):
    """Write a spectrum's values as a float32 OpenEXR oriented as :func:`spectrum_image`.

    Parameters
    ----------
    path : str or Path
    P : ndarray (R,) or (R, R)
    header : dict, optional
        More attributes for the file's header.

    Returns
    -------
    Path
    """
    P = spectra.check_spectrum(P, dims=(1, 2))     # an image: a 3-D spectrum goes to .npy
    image = P[None, :] if P.ndim == 1 else P.T[::-1]
    info = {"clsamp": "power spectrum",
            "layout": "row j: fy = R/2 - 1 - j (+y up); column i: fx = i - R/2"}
    info.update(header or {})
    return files.write_exr(path, np.ascontiguousarray(image), header=info)


def spectrum(ax, P, scale="linear", vmin=None, vmax=None, title=None):
    """Show a 2-D spectrum on a matplotlib Axes: +y up, +x right, axes in integer frequencies.

    Parameters
    ----------
    ax : matplotlib Axes
    P, scale, vmin, vmax
        As :func:`spectrum_image` takes them.
    title : str, optional

    Returns
    -------
    matplotlib AxesImage
    """
    R = P.shape[0]
    image = spectrum_image(P, scale, vmin, vmax)
    shown = ax.imshow(image ** (1 / 2.2) if scale == "linear" else image, cmap="gray", vmin=0, vmax=1,
                      extent=(-R / 2 - 0.5, R / 2 - 0.5, -R / 2 - 0.5, R / 2 - 0.5),
                      interpolation="nearest")
    ax.set_xlabel("frequency x")
    ax.set_ylabel("frequency y")
    if title:
        ax.set_title(title)
    return shown


def _frequency_axis(ax, freqs, n, convention):
    check_choice(convention, "convention", ("psa", "utk"))
    if n is None:
        ax.set_xlabel("frequency |ω|")
        return np.asarray(freqs, dtype=np.float64)
    label = "2ν/√N" if convention == "psa" else "ν/√N"
    ax.set_xlabel(f"frequency {label}")
    return spectra.normalized_frequency(freqs, n, convention)


def radial_mean(ax, freqs, values, label=None, n=None, convention="psa", **line_args):
    """Plot a radial mean (:func:`clsamp.radial_mean`), a dotted line at 1 (white noise).

    Parameters
    ----------
    ax : matplotlib Axes
    freqs, values : ndarray
    label : str, optional
    n : int, optional
        Points per set: frequencies are then normalized as PSA (2ν/√N,
        ``convention="psa"``) or UTK (ν/√N) do, so sets of different N line up.
    convention : {"psa", "utk"}
    **line_args
        For ``ax.plot``.

    Returns
    -------
    matplotlib Line2D
    """
    freqs, values = check_curve(freqs, values, ("'freqs'", "'values'"))
    x = _frequency_axis(ax, freqs, n, convention)
    (line,) = ax.plot(x, values, label=label, **line_args)
    ax.axhline(1.0, color="0.6", linewidth=0.8, linestyle=":")
    ax.set_ylabel("radial mean power")
    if label:
        ax.legend()
    return line


def anisotropy(ax, freqs, values, label=None, n=None, convention="psa", realizations=None,
                    **line_args):
    """Plot an anisotropy curve (dB, :func:`clsamp.anisotropy`) on a matplotlib Axes.

    Parameters
    ----------
    ax, freqs, values, label, n, convention, **line_args
        As :func:`radial_mean` takes them.
    realizations : int, optional
        Sets averaged: a dotted line marks -10·log10(r) dB, white noise's level.

    Returns
    -------
    matplotlib Line2D
    """
    freqs, values = check_curve(freqs, values, ("'freqs'", "'values'"))
    x = _frequency_axis(ax, freqs, n, convention)
    (line,) = ax.plot(x, values, label=label, **line_args)
    if realizations is not None:
        realizations = check_positive_int(realizations, "realizations")
        ax.axhline(-10.0 * math.log10(realizations), color="0.6", linewidth=0.8, linestyle=":")
    ax.set_ylabel("anisotropy (dB)")
    if label:
        ax.legend()
    return line


@writes()
def spectrum_figure(path, P, n=None, realizations=None, label=None, bin_width=1.0,
                    convention="psa", scale="linear"):
    """A spectrum, its radial mean and (2-D) its anisotropy, saved as one figure.

    Parameters
    ----------
    path : str or Path
    P : ndarray (R,) or (R, R)
    n, realizations, label, convention
        As :func:`anisotropy` takes them; the title is ``label``, n and the number of sets.
    bin_width, scale
        As :func:`clsamp.radial_mean` and :func:`spectrum_image` take them.

    Returns
    -------
    Path
    """
    plt = pyplot()
    P = spectra.check_spectrum(P)
    if realizations is not None:
        realizations = check_positive_int(realizations, "realizations")
    sets = realizations and f"{realizations} set{'s' if realizations > 1 else ''}"
    label = ", ".join(str(part) for part in (label, n and f"n = {n}", sets) if part) or None
    panels = 3 if P.ndim == 2 else 1
    figure, axes = plt.subplots(1, panels, figsize=(4.2 * panels, 3.8), squeeze=False)
    axes = axes[0]
    freqs, mean = spectra.radial_mean(P, bin_width)
    if P.ndim == 2:
        spectrum(axes[0], P, scale=scale, title=label)
        radial_mean(axes[1], freqs, mean, n=n, convention=convention)
        f, a = spectra.anisotropy(P, bin_width)
        anisotropy(axes[2], f, a, n=n, convention=convention, realizations=realizations)
    else:
        radial_mean(axes[0], freqs, mean, n=n, convention=convention)
        if label:
            axes[0].set_title(label)
    return _save(figure, path)


@writes()
def sampler_figure(path, points, P, pcf, n=None, label=None):
    """A sampler at a glance: its first point set, spectrum, radial mean and PCF.

    Parameters
    ----------
    path : str or Path
    points : ndarray (n, 2) or (r, n, 2), or list of (n_k, 2) arrays
    P : ndarray (R, R)
        Their :func:`clsamp.power_spectrum`.
    pcf : (radii, g)
        Their :func:`clsamp.pair_correlation`.
    n : int, optional
        Points per set for the radial mean's axis (2ν/√N); the sets' mean size by default.
    label : str, optional

    Returns
    -------
    Path

    Examples
    --------
    >>> import clsamp, tempfile, pathlib
    >>> from clsamp import plots
    >>> sets = clsamp.make_sampler("jittered", seed=1).sample(256, realizations=4)
    >>> P = clsamp.power_spectrum(sets, resolution=64, progress=False)
    >>> out = plots.sampler_figure(pathlib.Path(tempfile.mkdtemp()) / "j.png", sets, P,
    ...                            clsamp.pair_correlation(sets), label="jittered")
    """
    sets = point_sets_2d(points)
    size = float(np.mean([len(s) for s in sets]))
    P = spectra.check_spectrum(P)
    if not isinstance(pcf, (tuple, list)) or len(pcf) != 2:
        raise InvalidArgumentError("'pcf' must be (radii, g), as clsamp.pair_correlation returns it")
    radii, g = check_curve(*pcf, names=("'pcf' radii", "'pcf' g"))
    several = f", {len(sets)} sets" if len(sets) > 1 else ""
    fig, axes = pyplot().subplots(1, 4, figsize=(14, 3.3))
    first = f"n = {len(sets[0])}"
    scatter(axes[0], sets[0], f"{label}, {first}" if label else first)
    spectrum(axes[1], P, title=f"expected spectrum{several}" if several else "spectrum")
    radial_mean(axes[2], *spectra.radial_mean(P), n=round(size) if n is None else n)
    axes[2].set_ylim(0, 2.5)
    pair_correlation(axes[3], radii, g, n=size)
    axes[3].set_ylim(0, max(2.5, float(np.max(g)) * 1.05))
    axes[3].set_title(f"expected PCF{several}" if several else "PCF", fontsize=10)
    return _save(fig, path)


@writes()
def radial_mean_families(path, curves, families, n=None, reference="random", note=None):
    """Radial means of many samplers, one panel per family, a reference curve in grey in each.

    Parameters
    ----------
    path : str or Path
    curves : dict
        ``{sampler: (frequencies, radial mean)}`` (:func:`clsamp.radial_mean`).
    families : sequence of (name, samplers)
        The panels, each with the samplers it shows (those in ``curves``, in this order).
    n : int, optional
        Points per set, to draw frequencies as 2ν/√N.
    reference, note : str, optional
        The entry of ``curves`` drawn in every panel; a note for each title.

    Returns
    -------
    Path

    Examples
    --------
    >>> import clsamp, tempfile, pathlib
    >>> from clsamp import plots
    >>> curves = {s: clsamp.radial_mean(clsamp.power_spectrum(clsamp.make_sampler(s, seed=1).sample(
    ...     256, realizations=4), resolution=64, progress=False)) for s in ("random", "jittered", "halton")}
    >>> out = plots.radial_mean_families(pathlib.Path(tempfile.mkdtemp()) / "r.png", curves,
    ...     [("stratified", ["jittered"]), ("low discrepancy", ["halton"])], n=256)
    """
    curves = check_curves(curves, "curves", ("frequencies", "radial mean"))
    families = list(families)
    if not families or not all(isinstance(f, (tuple, list)) and len(f) == 2
                               and not isinstance(f[1], str) for f in families):
        raise InvalidArgumentError("'families' must be one or more (name, [samplers]) pairs")
    fig, axes = pyplot().subplots(1, len(families), figsize=(5.2 * len(families), 5.0), sharey=True,
                                  squeeze=False)
    for ax, (family, members) in zip(axes[0], families, strict=True):
        if reference in curves:
            radial_mean(ax, *curves[reference], n=n, color="0.55", linewidth=1.0, label=reference)
        for k, name in enumerate(m for m in members if m in curves):
            radial_mean(ax, *curves[name], n=n, color=f"C{k}", label=name)
        ax.set_ylim(0, 2.5)
        ax.set_title(f"{family} ({note})" if note else family, fontsize=10)
        legend_below(ax, fontsize=8, columns=2)
    return _save(fig, path)


# -- metrics ------------------------------------------------------------------------------
def pair_correlation(ax, radii, pcf, n=None, d=2, label=None, **line_args):
    """Plot a pair correlation function (:func:`clsamp.pair_correlation`), a dotted line at 1.

    Parameters
    ----------
    ax : matplotlib Axes
    radii, pcf : ndarray
    n, d : int, optional
        Points per set and dimension: radii are then drawn in mean spacings, r n^(1/d),
        so sets of different N line up.
    label : str, optional
    **line_args
        For ``ax.plot``.

    Returns
    -------
    matplotlib Line2D
    """
    radii, pcf = check_curve(radii, pcf, ("'radii'", "'pcf'"))
    if n is not None:
        n = check_real(n, "n", minimum=0.0, open_minimum=True)
    x = radii * n ** (1.0 / check_positive_int(d, "d")) if n else radii
    (line,) = ax.plot(x, pcf, label=label, **line_args)
    ax.axhline(1.0, color="0.6", linewidth=0.8, linestyle=":")
    ax.set_xlabel("r (mean spacings)" if n else "r")
    ax.set_ylabel("pair correlation g(r)")
    if label:
        ax.legend()
    return line


@writes()
def pcf_figure(path, radii, pcf, n=None, d=2, label=None):
    """One pair correlation function, saved as a figure.

    Parameters
    ----------
    path : str or Path
    radii, pcf, n, d, label
        As :func:`pair_correlation` takes them (``label`` is the title).

    Returns
    -------
    Path
    """
    fig, ax = pyplot().subplots(figsize=(5.5, 3.8))
    pair_correlation(ax, radii, pcf, n=n, d=d)
    if label:
        ax.set_title(label)
    return _save(fig, path)


def discrepancy(ax, sweep, expected=None, **line_args):
    """Plot a discrepancy against N, log-log, its fitted slope in the label.

    Parameters
    ----------
    ax : matplotlib Axes
    sweep : clsamp.metrics.DiscrepancySweep
    expected : (float, str), optional
        A known exponent and its text: a dashed line through the largest N.
    **line_args
        For ``ax.errorbar``.

    Returns
    -------
    matplotlib ErrorbarContainer
    """
    slope, _ = sweep.slope()
    label = f"{sweep.sampler}: {slope:.2f}" if math.isfinite(slope) else f"{sweep.sampler}: too few N"
    label += f" ({expected[1]})" if expected else ""
    line_args = {"marker": "o", "markersize": 3, "capsize": 2, **line_args}
    line = ax.errorbar(sweep.ns, sweep.values, yerr=sweep.stderr, label=label, **line_args)
    if expected:
        n = sweep.ns.astype(np.float64)
        ax.plot(n, sweep.values[-1] * (n / n[-1]) ** expected[0], "--",
                color=line[0].get_color(), linewidth=0.9, alpha=0.7)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("N (points)")
    ax.set_ylabel(f"{sweep.method} discrepancy")
    return line


@writes()
def discrepancy_figure(path, sweeps):
    """Discrepancies of many samplers against N, a log-log panel per method, each with its fitted
    slope and a dashed line of the rate :func:`clsamp.theory.discrepancy_rate` knows.

    Parameters
    ----------
    path : str or Path
    sweeps : sequence of dict
        One :func:`clsamp.metrics.discrepancy_sweep` result (``{method: DiscrepancySweep}``)
        per sampler (at least one), all with the methods of the first.

    Returns
    -------
    Path

    Examples
    --------
    >>> import clsamp, tempfile, pathlib
    >>> from clsamp import plots, metrics
    >>> sweeps = [metrics.discrepancy_sweep(clsamp.make_sampler(s, seed=3), [16, 64, 256, 1024],
    ...                                     progress=False) for s in ("random", "halton")]
    >>> out = plots.discrepancy_figure(pathlib.Path(tempfile.mkdtemp()) / "d.png", sweeps)
    """
    sweeps = list(sweeps)
    if not sweeps:
        raise InvalidArgumentError("'sweeps' must hold at least one sampler's sweeps")
    methods = list(sweeps[0]) if isinstance(sweeps[0], dict) else []
    if not methods or not all(isinstance(s, dict) and set(methods) <= set(s) for s in sweeps):
        raise InvalidArgumentError("'sweeps' must be discrepancy_sweep results ({method: "
                                   "DiscrepancySweep}), each with the methods of the first")
    plt = pyplot()
    fig, axes = plt.subplots(1, len(methods), figsize=(6.5 * len(methods), 5.2), squeeze=False)
    colours = plt.get_cmap("tab20").colors      # up to twenty samplers, no colour twice
    for index, by_method in enumerate(sweeps):
        for ax, method in zip(axes[0], methods, strict=True):
            sweep = by_method[method]
            discrepancy(ax, sweep, theory.discrepancy_rate(sweep.sampler),
                        color=colours[index % 20], marker="os^vD<>"[index % 7])
    for ax, method in zip(axes[0], methods, strict=True):
        sets = sweeps[0][method].realizations
        ax.set_title(f"{method} discrepancy (RMS of D over {sets} sets; dashed: known)")
        ax.grid(True, which="both", alpha=0.2)
        legend_below(ax, columns=3)
    return _save(fig, path)


# -- convergence --------------------------------------------------------------------------
def _panels(results):
    """One matplotlib panel per integrand: (figure, [(axes, integrand name, its results)])."""
    groups = {}
    for res in results:
        groups.setdefault(res.integrand, []).append(res)
    if not groups:
        raise InvalidArgumentError("'results' must hold at least one ConvergenceResult")
    fig, axes = pyplot().subplots(1, len(groups), figsize=(5.5 * len(groups), 5.8), squeeze=False)
    return fig, list(zip(axes[0], groups, groups.values(), strict=True))


def _label(ax, xlabel, title):
    """The labels, grid and legend every panel has (MSE up the side)."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel("MSE")
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.2)
    legend_below(ax, columns=1)


@writes()
def convergence(results, path):
    """MSE against N (log-log) of one or more results, one panel per integrand.

    Each result is a line with error bars (one standard error) and, where
    :func:`clsamp.theory.compare` knows it, a dashed line of the published rate.

    Parameters
    ----------
    results : sequence of ConvergenceResult
    path : str or Path

    Returns
    -------
    Path
    """
    fig, panels = _panels(results)
    for ax, name, group in panels:
        for res in group:
            ok = res.mse > 0
            cmp = theory.compare(res)
            label = res.sampler
            if np.isfinite(cmp["slope"]):
                label += f": {cmp['slope']:.2f} (theory {cmp['expected_text'] or '?'})"
            line = ax.errorbar(res.ns[ok], res.mse[ok], yerr=res.mse_stderr[ok], marker="o",
                               markersize=3, capsize=2, label=label)
            if cmp["expected"] is not None and ok.any():
                n = res.ns[ok].astype(np.float64)
                ax.loglog(n, res.mse[ok][-1] * (n / n[-1]) ** cmp["expected"], "--",
                          color=line[0].get_color(), linewidth=0.9, alpha=0.7)
        ax.set_xscale("log")
        ax.set_yscale("log")
        _label(ax, "N (samples)", f"{name}: MSE against N (dashed: theory)")
    return _save(fig, path)


def family_spread(ax, res, color=None, label=None):
    """Plot one family result: the mean MSE over members (a line), the members' 10-90 %
    quantile band (shaded), the worst member (dotted) and the published rate (dashed).

    Parameters
    ----------
    ax : matplotlib Axes
    res : clsamp.results.FamilyResult
    color : matplotlib colour, optional
    label : str, optional

    Returns
    -------
    matplotlib Line2D
        The mean's.
    """
    n = res.ns.astype(np.float64)
    lo, hi = np.quantile(res.mse, [0.1, 0.9], axis=1)
    cmp = theory.compare(res)
    text = label or res.sampler
    if np.isfinite(cmp["slope"]):
        text += f": {cmp['slope']:.2f} [{cmp['ci'][0]:.2f}, {cmp['ci'][1]:.2f}]"
        text += "" if cmp["expected"] is None else f" (theory {cmp['expected']:g})"
    (line,) = ax.loglog(n, res.mean, "o-", markersize=3, color=color, label=text)
    color = line.get_color()
    ax.fill_between(n, np.maximum(lo, np.finfo(float).tiny), hi, color=color, alpha=0.2, linewidth=0)
    ax.loglog(n, res.max, ":", color=color, linewidth=0.9)
    if cmp["expected"] is not None and res.mean[-1] > 0:
        ax.loglog(n, res.mean[-1] * (n / n[-1]) ** cmp["expected"], "--", color=color,
                  linewidth=0.9, alpha=0.7)
    return line


@writes()
def family_convergence(results, path):
    """MSE against N over integrand families, a panel per family, :func:`family_spread` each.

    Parameters
    ----------
    results, path
        As :func:`convergence` takes them, with FamilyResult here.

    Returns
    -------
    Path
    """
    fig, panels = _panels(results)
    for ax, name, group in panels:
        lines = {res.sampler: family_spread(ax, res) for res in group}
        ax.fill_between([], [], color="0.5", alpha=0.3, label="shaded: 10-90 % of the members")
        ax.plot([], [], ":", color="0.3", label="dotted: the worst member")
        ax.plot([], [], "--", color="0.3", label="dashed: the published rate")
        for cut in clip_far_below(ax, {res.sampler: res.mean for res in group}):
            lines[cut].set_label(f"{lines[cut].get_label()} (below the axis: falls to rounding)")
        _label(ax, "N (samples)", f"{name} ({group[0].members} members): MSE against N")
    return _save(fig, path)


@writes()
def accuracy_time(results, path):
    """MSE against seconds per estimate (generation included) per integrand, with its
    :func:`clsamp.results.pareto_front` in black.

    Parameters
    ----------
    results, path
        As :func:`convergence` takes them.

    Returns
    -------
    Path
    """
    fig, panels = _panels(results)
    for ax, name, group in panels:
        for res in group:
            ok = (res.mse > 0) & (res.seconds_per_estimate > 0)
            ax.loglog(res.seconds_per_estimate[ok], res.mse[ok], "o-", markersize=3, label=res.sampler)
        front = [p for p in pareto_front(group) if p["mse"] > 0 and p["seconds"] > 0]
        if front:
            ax.step([p["seconds"] for p in front], [p["mse"] for p in front], "k-", where="post",
                    linewidth=1.5, alpha=0.6, label="front")
        _label(ax, "seconds per estimate (generation included)", f"{name}: accuracy against time")
    return _save(fig, path)


def error_time(ax, curves, xlabel="seconds", ylabel="MSE", title=None, exact=None,
               markersize=3, fontsize=7):
    """Error against time on a matplotlib Axes, log-log, a line with markers per curve.

    Parameters
    ----------
    ax : matplotlib Axes
    curves : dict
        ``{label: (seconds, error)}``, positive values.
    xlabel, ylabel, title : str
    exact : (label, seconds), optional
        A method without error (the direct spectrum), drawn as a dashed vertical line.
    markersize, fontsize : float or None
        Marker size and the legend's font size (None: matplotlib's defaults).

    Returns
    -------
    list of Line2D
    """
    curves = check_curves(curves, "curves", ("seconds", "error"))
    lines = [ax.loglog(x, y, "o-", label=label, markersize=markersize)[0]
             for label, (x, y) in curves.items()]
    if exact:
        lines.append(ax.axvline(exact[1], color="k", linestyle="--", label=exact[0]))
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title)
    ax.legend(fontsize=fontsize, loc="best")
    readable_log_ticks(ax, "x")
    return lines


@writes()
def error_time_figure(path, panels):
    """Panels of error against time (:func:`error_time`) side by side.

    Parameters
    ----------
    path : str or Path
    panels : sequence of dict or None
        At least one: the keyword arguments of :func:`error_time` for each panel, or None for a
        panel left empty (a measurement that failed).

    Returns
    -------
    Path

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from clsamp import plots
    >>> out = plots.error_time_figure(pathlib.Path(tempfile.mkdtemp()) / "t.png",
    ...     [{"curves": {"a": ([1, 2], [1e-2, 1e-3])}, "title": "a"}, None])
    """
    panels = list(panels)
    if not panels or not all(panel is None or isinstance(panel, dict) for panel in panels):
        raise InvalidArgumentError("'panels' must hold at least one panel: dicts of error_time's "
                                   "arguments, or None")
    fig, axes = pyplot().subplots(1, len(panels), figsize=(5.0 * len(panels), 4.2), squeeze=False)
    for ax, panel in zip(axes[0], panels, strict=True):
        if panel is not None:
            error_time(ax, **panel)
    return _save(fig, path)


# -- renders ---------------------------------------------------------------------------
@writes()
def quality_time(path, rows, title=None):
    """Samplers' quality against the seconds they took: low-frequency power (down is better)
    and ρ (up is better), one labelled dot a sampler, seconds on a log axis.

    Parameters
    ----------
    path : str or Path
    rows : sequence of (label, seconds, low-frequency power, rho)
    title : str, optional

    Returns
    -------
    Path

    Raises
    ------
    InvalidArgumentError
        No rows, a row not of four, seconds not positive (a log axis), or a power or rho
        negative or not finite.
    """
    rows = list(rows)
    try:
        values = np.array([row[1:] for row in rows], dtype=np.float64)
    except (TypeError, ValueError):
        values = None
    if not rows or values is None or values.shape != (len(rows), 3) or not (
            np.all(values[:, 0] > 0) and np.all(values >= 0) and np.all(np.isfinite(values))):
        raise InvalidArgumentError("'rows' must be (label, seconds, low-frequency power, rho) rows: "
                                   "seconds positive, power and rho not negative, all finite")
    fig, (low, rho) = pyplot().subplots(1, 2, figsize=(10, 3.8))
    for label, seconds, power, radius in rows:
        for ax, value in ((low, power), (rho, radius)):
            ax.scatter([seconds], [value], s=18)
            ax.annotate(label, (seconds, value), fontsize=7, xytext=(3, 3), textcoords="offset points")
    low.set(xscale="log", yscale="log", xlabel="seconds", ylabel="low-frequency power (white noise 1)")
    rho.set(xscale="log", xlabel="seconds", ylabel="ρ (relative radius)")
    for ax in (low, rho):
        ax.grid(True, which="both", alpha=0.2)
    if title:
        fig.suptitle(title, fontsize=10)
    return _save(fig, path)


@writes()
def render_comparison(path, reference, images, columns=4):
    """Rendered images beside their reference, each titled with its MSE against it.

    Parameters
    ----------
    path : str or Path
    reference : ndarray (H, W)
        The reference image (:func:`clsamp.render.reference`).
    images : dict or sequence of (label, image)
    columns : int
        Panels per row.

    Returns
    -------
    Path

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from clsamp import plots, render
    >>> ref = render.render("ao", "random", 64, 16, seed=1, progress=False)
    >>> images = {s: render.render("ao", s, 16, 16, seed=2, progress=False)
    ...           for s in ("random", "sobol:owen")}
    >>> out = plots.render_comparison(pathlib.Path(tempfile.mkdtemp()) / "c.png", ref, images)
    """
    from . import render
    items = list(images.items()) if isinstance(images, dict) else list(images)
    for label, image in items:
        if np.shape(image) != np.shape(reference):
            raise InvalidArgumentError(f"'images' {label!r} has shape {np.shape(image)}, the "
                                       f"reference {np.shape(reference)}")
    panels = [("reference", reference, None)] + [(label, image, render.mse(image, reference))
                                                 for label, image in items]
    columns = min(check_positive_int(columns, "columns"), len(panels))
    rows = -(-len(panels) // columns)
    fig, axes = pyplot().subplots(rows, columns, figsize=(3.0 * columns, 3.2 * rows), squeeze=False)
    for ax in axes.ravel():
        ax.axis("off")
    for ax, (label, image, error) in zip(axes.ravel(), panels, strict=False):
        ax.imshow(files.tone_map(image), cmap="gray", vmin=0, vmax=255, interpolation="nearest")
        ax.set_title(label if error is None else f"{label}\nMSE {error:.3g}", fontsize=9)
    return _save(fig, path)


@writes()
def error_spectra(path, curves, title=None):
    """Radially averaged error spectra of renders (:func:`clsamp.render.error_spectrum`).

    Parameters
    ----------
    path : str or Path
    curves : dict
        ``{label: (frequencies, power)}``, drawn on log power against frequency (cycles
        per pixel); a flat curve is white error, one rising with frequency blue.
    title : str, optional

    Returns
    -------
    Path
    """
    curves = check_curves(curves, "curves", ("frequencies", "power"))
    fig, ax = pyplot().subplots(figsize=(6.0, 4.0))
    for label, (f, p) in curves.items():
        ax.semilogy(f, p, label=label, lw=1.4)
    ax.set_xlabel("frequency (cycles per pixel)")
    ax.set_ylabel("error power")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    if title:
        ax.set_title(title, fontsize=10)
    return _save(fig, path)
