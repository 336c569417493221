"""The tour report's parts in words and pictures: slopes, devices, warnings, timings,
axes, and verdicts that know a published rate's log factor (issue 40)."""

import io
import math
import warnings

import numpy as np
import pytest

from clsamp import plot_axes, plots, report, theory, tour_cost


def test_a_slope_over_too_few_points_says_so_in_words():
    assert report.slope_text(float("nan"), float("nan")) == "too few N to fit"
    text = report.slope_text(-0.67, float("nan"), 2)
    assert "nan" not in text.lower() and "too few N" in text and "-0.67" in text
    assert report.slope_text(-0.5, 0.0312) == "-0.50 ± 0.03"


def test_device_rows_are_in_human_units():
    rows = dict(report.device_rows({"name": "cpu", "global_memory": 23128711168,
                                    "max_allocation": 5782177792, "local_memory": 65536,
                                    "extensions": ("cl_khr_fp64", "cl_khr_int64_base_atomics")}))
    assert rows["global_memory"] == "21.5 GiB" and rows["max_allocation"] == "5.4 GiB"
    assert rows["local_memory"] == "64.0 KiB"
    assert rows["extensions (2)"] == "cl_khr_fp64, cl_khr_int64_base_atomics"
    long = dict(report.device_rows({"extensions": tuple(f"cl_ext_{i}" for i in range(40))}, width=60))
    assert all(len(line) <= 60 for line in long["extensions (40)"].splitlines())


def test_clsamp_warnings_print_as_one_line_only_inside_the_block():
    before = warnings.showwarning
    out = io.StringIO()
    clsamp_file = tour_cost.__file__
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        with report.one_line_warnings(out):
            warnings.warn_explicit("need a power of two", UserWarning, clsamp_file, 12)
            assert warnings.showwarning is not before
        assert warnings.showwarning is before
    assert out.getvalue() == "clsamp: warning: need a power of two\n"


def test_other_warnings_go_to_the_handler_before():
    seen, out = [], io.StringIO()
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        warnings.showwarning = lambda message, category, *rest: seen.append((str(message), category))
        with report.one_line_warnings(out):
            warnings.warn_explicit("not ours", DeprecationWarning, "/elsewhere/mod.py", 3)
    assert seen == [("not ours", DeprecationWarning)] and out.getvalue() == ""


def test_times_are_medians_of_repeats(monkeypatch):
    ticks = iter([0.0, 1.0, 1.0, 1.2, 1.2, 5.2])       # runs of 1.0, 0.2 and 4.0 s
    monkeypatch.setattr(tour_cost.time, "perf_counter", lambda: next(ticks))
    seconds, value = tour_cost.median_seconds(lambda: "x", repeats=3)
    assert seconds == pytest.approx(1.0) and value == "x"


def test_legends_sit_below_the_data_and_log_ticks_do_not_crowd():
    plt = plots.pyplot()
    fig, ax = plt.subplots()
    ax.loglog([0.0031, 0.0052, 0.011], [1e-2, 3e-3, 1e-3], "o-", label="random")
    plots._label(ax, "seconds", "t")
    plot_axes.readable_log_ticks(ax)
    fig.canvas.draw()
    legend = ax.get_legend().get_window_extent()
    assert legend.y1 < ax.get_window_extent().y0          # under the axes, not over the data
    labels = [t.get_text() for t in ax.get_xticklabels() if t.get_text()
              and ax.get_xlim()[0] <= t.get_position()[0] <= ax.get_xlim()[1]]
    assert 1 <= len(labels) <= 5 and all(len(t) <= 6 for t in labels), labels
    assert all(t.get_text() == "" for t in ax.get_xticklabels(minor=True))
    plt.close(fig)


def test_a_series_falling_to_rounding_does_not_stretch_the_axis():
    plt = plots.pyplot()
    fig, ax = plt.subplots()
    ns = np.array([16, 64, 256, 1024])
    series = {"random": 1e-3 / ns, "jittered": 1e-3 / ns**2, "regular": np.array([1e-4, 1e-8, 1e-19, 1e-35])}
    for label, values in series.items():
        ax.loglog(ns, values, label=label)
    assert plot_axes.clip_far_below(ax, series) == ["regular"]
    assert ax.get_ylim()[0] == pytest.approx(1e-3 / 1024**2 / 10)
    assert plot_axes.clip_far_below(ax, {k: series[k] for k in ("random", "jittered")}) == []
    plt.close(fig)


class _Owen:
    """A stand-in sweep of an Owen-scrambled net on a smooth integrand, fitted over ``ns``."""

    def __init__(self, ns, slope, stderr=0.01, ci=None):
        self.kind = self.sampler = "sobol:owen"
        self.ns, self.d, self.integrand = np.asarray(ns), 2, "gaussian"
        self.traits, self.rates = {"smooth": True, "periodic": True}, {"best": (-3.0, "Owen 1997")}
        self._fit, self._ci = (slope, stderr), ci
        if ci is not None:
            self.members = 32
            self.mean = np.asarray(ns, dtype=float) ** slope

    def fit_range(self):
        return np.arange(len(self.ns))

    def rate(self, statistic=None):
        return (self._fit[0], *self._ci) if self._ci else self._fit


def test_log_factor_bend_is_the_slope_of_log_log_n():
    k, bend = theory.log_factor_slope("Owen 1997", "best", [256, 1024])
    assert k == 1
    assert bend == pytest.approx((math.log(math.log(1024)) - math.log(math.log(256))) / math.log(4))
    assert theory.log_factor_slope("Owen 1997", "best", [256, 1024], d=3)[0] == 2
    assert theory.log_factor_slope("He and Wang 2015", "worst", [256, 1024]) == (0, 0.0)


def test_a_rate_with_a_log_factor_reads_pre_asymptotic_not_differs():
    # N^-3 log N, fitted over 256..1024, has slope -2.84: 0.16 off N^-3, more than 3 sigma + 0.15
    ns = [256, 1024]
    slope = -3 + theory.log_factor_slope("Owen 1997", "best", ns)[1]
    cmp = theory.compare(_Owen(ns, slope))
    assert cmp["verdict"].startswith("pre-asymptotic (log N)^1 factor"), cmp["verdict"]
    assert cmp["log_factor"] == 1
    # the factor explains 0.16 of a slope, not 0.6
    assert theory.compare(_Owen(ns, -2.4))["verdict"].split()[0] == "differs"
    # a family: the interval holds N^-3 shifted by the factor's bend
    fam = theory.compare(_Owen(ns, slope, ci=(slope - 0.02, slope + 0.02)))
    assert fam["verdict"] == "pre-asymptotic" and "(log N)^1 factor" in fam["note"]
    far = theory.compare(_Owen(ns, -2.4, ci=(-2.45, -2.35)))
    assert far["verdict"] == "differs" and far["note"].startswith("beyond the (log N)^1 factor's +0.16")


def test_local_slopes_that_approach_the_rate_read_pre_asymptotic():
    # issue 40: Owen-Sobol on random Gaussians (sigma 0.025..0.055) steepens toward N^-3 as N
    # passes 1/sigma^2; the family verdict said "differs"
    from clsamp import convergence
    res = convergence("sobol:owen", "random_gaussians", [16, 64, 256, 1024], realizations=32,
                      members=32, seed=3, progress=False)
    cmp = theory.compare(res)
    assert cmp["verdict"] == "pre-asymptotic" and "approach N^-3" in cmp["note"], cmp
    local = theory.approaching(res.ns, res.mean, -3)
    assert len(local) == 3 and local[0] > local[1] > local[2] > -3
    # a slope steady away from the rate, or one that overshoots it, is no approach
    assert theory.approaching([16, 64, 256, 1024], [1e-2, 1e-3, 1e-4, 1e-5], -3) == ()
    assert theory.approaching([16, 64, 256, 1024], [1, 4.0**-2, 4.0**-4.5, 4.0**-8], -3) == ()
    assert theory.approaching([16, 64, 256], [1, 4.0**-2, 4.0**-4.5], -3) == ()


def test_a_tour_page_written_before_its_last_section_says_it_is_incomplete(tmp_path, monkeypatch):
    # a stopped tour's index.html and tour.json read like a whole one ("mode full", no word)
    import json

    from clsamp import tour
    calls = []

    def fake(key):
        def section(rep, quick, *rest):
            calls.append(key)
            if key == "b":
                raise KeyboardInterrupt          # stopped in the second of three sections
            return "<p>ok</p>", {"key": key}
        return section
    monkeypatch.setattr(tour, "SECTIONS", [(k, k.upper(), fake(k)) for k in "abc"])
    with pytest.raises(KeyboardInterrupt):
        tour.run_tour(tmp_path / "t", progress=False)
    page = (tmp_path / "t" / "index.html").read_text()
    assert "Incomplete: 2 of 3 sections not run" in page
    assert json.loads((tmp_path / "t" / "tour.json").read_text())["meta"]["complete"] is False
