"""The pictures of clsamp.plots that the tour draws: point sets, a sampler at a glance,
radial means by family, discrepancy against N, error against time."""

import numpy as np
import pytest

import clsamp
from clsamp import plots
from clsamp.metrics import discrepancy_sweep

PNG = b"\x89PNG\r\n\x1a\n"


def _is_png(path):
    return path.is_file() and path.read_bytes()[:8] == PNG


@pytest.fixture(scope="module")
def sets():
    return clsamp.make_sampler("jittered", seed=1).sample(64, realizations=3)


def test_points_draws_the_first_set_on_the_unit_square(sets):
    fig, ax = plots.pyplot().subplots()
    dots = plots.points(ax, sets, title="jittered")
    np.testing.assert_array_equal(dots.get_offsets(), sets[0])
    assert ax.get_xlim() == (0, 1) and ax.get_ylim() == (0, 1)
    assert ax.get_aspect() == 1.0 and ax.get_title() == "jittered"
    # a list of sets of different sizes: its first
    maximal = [sets[0][:40], sets[1]]
    np.testing.assert_array_equal(plots.points(ax, maximal).get_offsets(), sets[0][:40])
    plots.pyplot().close(fig)


def test_points_tiled_shows_the_torus_2x2_and_projections_the_coordinates(sets):
    fig, ax = plots.pyplot().subplots()
    dots = plots.points(ax, sets, tiled=True, projections=True)
    shown = dots.get_offsets()
    assert len(shown) == 4 * len(sets[0]) and ax.get_xlim() == (0, 2) and ax.get_ylim() == (0, 2)
    for shift in ((0, 0), (0, 1), (1, 0), (1, 1)):      # every copy of the set, shifted whole
        assert any(np.array_equal(shown[k * 64:(k + 1) * 64], sets[0] + shift) for k in range(4))
    strips = ax.child_axes                               # the x ticks below, the y ticks left
    assert len(strips) == 2
    xs = np.sort([seg[0][0] for seg in strips[0].collections[0].get_segments()])
    ys = np.sort([seg[0][1] for seg in strips[1].collections[0].get_segments()])
    np.testing.assert_allclose(xs, np.sort(sets[0][:, 0]))
    np.testing.assert_allclose(ys, np.sort(sets[0][:, 1]))
    plots.pyplot().close(fig)


@pytest.mark.parametrize("shape", ["one", "batch", "list"])
def test_points_figure_writes_a_png(tmp_path, sets, shape):
    points = {"one": sets[0], "batch": sets, "list": [sets[0][:40], sets[1], sets[2][:10]]}[shape]
    out = plots.points_figure(tmp_path / f"{shape}.png", points, title=shape, columns=2)
    assert out == tmp_path / f"{shape}.png"
    assert _is_png(out)
    assert _is_png(plots.points_figure(tmp_path / "t.png", points, tiled=True, projections=True))


@pytest.mark.parametrize("bad, match", [
    (np.full((8, 3), 0.5), "'points' must have 2 dimensions"),
    (np.full((8, 2), 1.5), "'points'"),
    (np.zeros((2, 2, 2, 2)), "'points' must have shape"),
    ("points", "'points' must be a NumPy array"),
])
def test_points_refuses_what_is_not_a_2d_point_set(tmp_path, bad, match):
    fig, ax = plots.pyplot().subplots()
    with pytest.raises(ValueError, match=match):
        plots.points(ax, bad)
    plots.pyplot().close(fig)
    with pytest.raises(ValueError, match=match):
        plots.points_figure(tmp_path / "bad.png", bad)
    assert not (tmp_path / "bad.png").exists()


def test_points_refuses_bad_options(tmp_path, sets):
    fig, ax = plots.pyplot().subplots()
    with pytest.raises(ValueError, match="'size'"):
        plots.points(ax, sets, size=-1.0)
    plots.pyplot().close(fig)
    with pytest.raises(ValueError, match="'columns'"):
        plots.points_figure(tmp_path / "p.png", sets, columns=0)


def test_the_tour_figures_write_pngs(tmp_path, sets):
    P = clsamp.power_spectrum(sets, resolution=32, method="direct", progress=False)
    assert _is_png(plots.sampler_figure(tmp_path / "s.png", sets, P, clsamp.pair_correlation(sets),
                                        n=64, label="jittered"))
    curves = {"random": clsamp.radial_mean(P), "jittered": clsamp.radial_mean(P)}
    assert _is_png(plots.radial_mean_families(tmp_path / "r.png", curves,
                                              [("stratified", ("jittered",)), ("other", ())], n=64))
    sweeps = [discrepancy_sweep(clsamp.make_sampler(s, seed=3), [16, 64, 256], realizations=2,
                                progress=False) for s in ("random", "halton")]
    assert _is_png(plots.discrepancy_figure(tmp_path / "d.png", sweeps))
    panels = [{"curves": {"a": ([1e-3, 2e-3], [1e-2, 1e-4])}, "exact": ("exact", 3e-3)}, None]
    assert _is_png(plots.error_time_figure(tmp_path / "t.png", panels))


def test_the_tour_figures_refuse_nothing_to_draw(tmp_path):
    with pytest.raises(ValueError, match="'sweeps'"):
        plots.discrepancy_figure(tmp_path / "d.png", [])
    with pytest.raises(ValueError, match="'panels'"):
        plots.error_time_figure(tmp_path / "t.png", [])


def test_spectrum_titles_say_n_and_sets_and_family_legends_say_what_band_and_lines_are(tmp_path,
                                                                                     monkeypatch):
    # issue 40 (8): titles without n and the number of sets; a legend that did not explain the
    # shaded band, the dotted and the dashed lines
    titles, legends = [], []
    save = plots._save

    def keep(fig, path):
        titles.extend(ax.get_title() for ax in fig.axes)
        legends.extend(t.get_text() for ax in fig.axes if ax.get_legend()
                       for t in ax.get_legend().get_texts())
        return save(fig, path)
    monkeypatch.setattr(plots, "_save", keep)
    P = np.ones((16, 16))
    plots.spectrum_figure(tmp_path / "s.png", P, n=256, realizations=8, label="jittered")
    assert "jittered, n = 256, 8 sets" in titles
    fam = clsamp.convergence("jittered", "random_gaussians", [16, 64], realizations=4, members=4,
                             seed=1, progress=False)
    plots.family_convergence([fam], tmp_path / "f.png")
    assert {"shaded: 10-90 % of the members", "dotted: the worst member",
            "dashed: the published rate"} <= set(legends), legends


@pytest.mark.parametrize("call, match", [
    (lambda d: plots.points_figure(d / "p.xyz", np.full((4, 2), 0.5)), r"must end in .png, .pdf, .svg"),
    (lambda d: plots.points_figure(None, np.full((4, 2), 0.5)), "'path' must be a file path"),
    (lambda d: plots.points_figure(d / "afile" / "p.png", np.full((4, 2), 0.5)), "is a file, not a folder"),
    (lambda d: plots.save_spectrum_png(d / "s.jpg", np.ones((4, 4))), "must end in .png"),
    (lambda d: plots.save_spectrum_exr(d / "s.png", np.ones((4, 4))), "must end in .exr"),
    (lambda d: plots.save_spectrum_exr(d / "s.exr", np.ones((4, 4, 4))), "'P' must be a 1-D or 2-D"),
])
def test_a_figures_path_is_checked_before_drawing(tmp_path, call, match):
    # an unknown suffix was matplotlib's ValueError after drawing, /proc or a file in the way
    # a WriteError after it; a spectrum's writers took any suffix (PNG bytes in s.jpg)
    (tmp_path / "afile").write_text("")
    with pytest.raises(clsamp.InvalidArgumentError, match=match):
        call(tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]


def test_a_figure_that_fails_is_closed():
    before = set(plots.pyplot().get_fignums())
    with pytest.raises(ValueError):
        plots.quality_time("/tmp/unused.png", [("a", 1, 2)])       # rows of 4, one of 3
    assert set(plots.pyplot().get_fignums()) == before


@pytest.mark.parametrize("rows", [[("a", 1, 2)], [], [("a", float("nan"), 0.1, 0.7)], [("a", 1.0, "x", 0.7)]])
def test_quality_time_refuses_rows_it_cannot_draw(tmp_path, rows):
    # a row of 3 failed to unpack, NaN seconds inside matplotlib's log scale, [] drew nothing
    with pytest.raises(clsamp.InvalidArgumentError, match="'rows' must be"):
        plots.quality_time(tmp_path / "q.png", rows)
    assert list(tmp_path.iterdir()) == []


_R = np.linspace(0.0, 0.1, 20)
_P = np.ones((8, 8))


@pytest.mark.parametrize("call, match", [
    (lambda d, s: plots.pcf_figure(d / "g.png", _R, np.ones(19)), "'radii' and 'pcf' must have the same"),
    (lambda d, s: plots.pcf_figure(d / "g.png", _R, _R, n=64, d=0), "'d' must be an integer >= 1"),
    (lambda d, s: plots.pcf_figure(d / "g.png", _R, _R, n=-1), "'n' must be > 0"),
    (lambda d, s: plots.pcf_figure(d / "g.png", _R, ["a"] * 20), "'pcf' must be a non-empty 1-D array"),
    (lambda d, s: plots.pcf_figure(d / "g.png", _R, np.ones((2, 20))), "'pcf' must be a non-empty 1-D"),
    (lambda d, s: plots.sampler_figure(d / "s.png", s, _P, _R), "'pcf' must be .radii, g."),
    (lambda d, s: plots.sampler_figure(d / "s.png", s, _P, (_R, np.ones(3))), "'pcf' radii and"),
    (lambda d, s: plots.spectrum_figure(d / "s.png", _P, realizations="x"), "'realizations' must be"),
    (lambda d, s: plots.spectrum_figure(d / "s.png", _P, realizations=-2), "'realizations' must be"),
    (lambda d, s: plots.spectrum_figure(d / "s.png", _P, convention="x"), "'convention' must be one"),
    (lambda d, s: plots.radial_mean_families(d / "r.png", {"a": (_R, _R[:-1])}, [("f", ["a"])]),
     r"'curves'\['a'\]'s frequencies and"),
    (lambda d, s: plots.radial_mean_families(d / "r.png", {"a": (_R, _R)}, []), "'families' must be one"),
    (lambda d, s: plots.radial_mean_families(d / "r.png", {"a": (_R, _R)}, [("f", "a")]), "'families' must"),
    (lambda d, s: plots.discrepancy_figure(d / "d.png", [1, 2]), "'sweeps' must be discrepancy_sweep"),
    (lambda d, s: plots.error_time_figure(d / "t.png", [{"curves": 1}]), "'curves' must be a dict"),
    (lambda d, s: plots.error_time_figure(d / "t.png", [3]), "'panels' must hold"),
    (lambda d, s: plots.error_spectra(d / "e.png", {"a": (_R, _R[:3])}), r"'curves'\['a'\]'s frequencies"),
    (lambda d, s: plots.render_comparison(d / "c.png", np.zeros((4, 4)), {"a": np.zeros((5, 4))}),
     "'images' 'a' has shape"),
    (lambda d, s: plots.render_comparison(d / "c.png", np.zeros((4, 4)), {"a": np.zeros((4, 4))}, columns=0),
     "'columns' must be an integer >= 1"),
])
def test_a_figures_curves_and_counts_are_checked_by_name(tmp_path, sets, call, match):
    # each failed inside matplotlib or numpy (shapes, unpacking, d=0 a ZeroDivisionError),
    # took strings as categories, or took columns=0 and a bad convention silently
    before = set(plots.pyplot().get_fignums())
    with pytest.raises(clsamp.InvalidArgumentError, match=match):
        call(tmp_path, sets)
    assert list(tmp_path.iterdir()) == []
    assert set(plots.pyplot().get_fignums()) == before
