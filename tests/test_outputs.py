"""Outputs a user can trust: the command line refuses suffixes it does not write (before any
work), derives every companion file from one stem and lists what it wrote, tells a missing
file from a sampler name, and files get the mode the umask gives; variable-size point sets
have a spectrum and metrics; results and verdicts read as numbers."""

import os
import stat

import numpy as np
import pytest

import clsamp
from clsamp import files, metrics
from clsamp.cli import main


def run(capsys, *argv):
    code = main(list(argv))
    captured = capsys.readouterr()
    return code, captured.out + captured.err


def listing(folder):
    return sorted(p.name for p in folder.iterdir())


# -- suffixes ------------------------------------------------------------------------------
@pytest.mark.parametrize("suffix", [".npy", ".txt", ".dat", ".pts"])
def test_sample_writes_each_accepted_suffix(tmp_path, capsys, suffix):
    code, text = run(capsys, "sample", "jittered", "-n", "16", "-o", str(tmp_path / f"p{suffix}"))
    assert code == 0 and f"p{suffix}" in text
    assert files.load_points(tmp_path / f"p{suffix}").shape == (16, 2)


@pytest.mark.parametrize("argv, option", [
    (("sample", "random", "-n", "8", "-o", "{}/p.csv"), "'-o'"),
    (("sample", "random", "-n", "8", "-o", "{}/p"), "no suffix"),
    (("spectrum", "random", "-n", "64", "-o", "{}/s.jpg"), ".png, .exr, .npy"),
    (("spectrum", "random", "-n", "64", "-o", "{}/s.png", "--plots", "{}/p.gif"), "'--plots'"),
    (("convergence", "--samplers", "random", "--ns", "16,64", "--realizations", "4",
      "-o", "{}/c.jpg"), ".png, .pdf, .svg"),
    (("render", "ao", "--spp", "4", "--resolution", "4", "-o", "{}/r.jpg"), ".exr, .png"),
])
def test_a_wrong_suffix_is_refused_and_nothing_is_written(tmp_path, capsys, argv, option):
    code, text = run(capsys, *(a.format(tmp_path) for a in argv))
    assert code == 2 and option in text and "Traceback" not in text
    assert listing(tmp_path) == []


def test_spectrum_outputs_and_a_collision(tmp_path, capsys):
    for suffix in (".png", ".exr", ".npy"):
        code, text = run(capsys, "spectrum", "jittered", "-n", "64", "--resolution", "16",
                         "-o", str(tmp_path / f"s{suffix}"))
        assert code == 0 and f"s{suffix}" in text
    assert np.load(tmp_path / "s.npy").shape == (16, 16)
    code, text = run(capsys, "spectrum", "jittered", "-n", "64", "--resolution", "16", "-o",
                     str(tmp_path / "t.png"), "--plots", str(tmp_path / "t.png"))
    assert code == 2 and "overwrite" in text and not (tmp_path / "t.png").exists()
    code, text = run(capsys, "spectrum", "jittered", "-n", "64", "--resolution", "16", "-o",
                     str(tmp_path / "u.exr"), "--plots", str(tmp_path / "u.pdf"))
    assert code == 0 and "u.exr" in text and "u.pdf" in text
    assert (tmp_path / "u.pdf").read_bytes()[:4] == b"%PDF"


@pytest.mark.parametrize("suffix", [".exr", ".png"])
def test_render_writes_one_stem_twice_never_over_itself(tmp_path, capsys, suffix):
    code, text = run(capsys, "render", "ao", "--sampler", "jittered", "--spp", "16",
                     "--resolution", "8", "--no-progress", "-o", str(tmp_path / f"x{suffix}"))
    assert code == 0
    assert listing(tmp_path) == ["x.exr", "x.png"]
    assert "x.exr" in text and "x.png" in text
    image, header = files.read_exr(tmp_path / "x.exr", with_header=True)
    assert image.shape == (8, 8) and str(header["sampler"]) == "jittered"
    assert (tmp_path / "x.png").read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize("suffix", [".png", ".pdf", ".svg"])
def test_convergence_companions_follow_the_plot(tmp_path, capsys, suffix):
    code, text = run(capsys, "convergence", "--samplers", "random", "--ns", "16,64",
                     "--realizations", "8", "--no-progress", "-o", str(tmp_path / f"c{suffix}"))
    assert code == 0
    assert listing(tmp_path) == sorted([f"c{suffix}", f"c_time{suffix}", "c.json"])
    for name in listing(tmp_path):
        assert name in text


# -- sources -------------------------------------------------------------------------------
def test_a_missing_file_is_not_a_bad_sampler_name(tmp_path, capsys):
    code, text = run(capsys, "spectrum", str(tmp_path / "missing.npy"), "-o", str(tmp_path / "x.png"))
    assert code == 2 and "no such file" in text and "unknown sampler" not in text
    code, text = run(capsys, "spectrum", "data/missing", "-n", "64", "-o", str(tmp_path / "x.png"))
    assert code == 2 and "no such file" in text
    code, text = run(capsys, "spectrum", "nosuch", "-n", "64", "-o", str(tmp_path / "x.png"))
    assert code == 2 and "unknown sampler" in text


@pytest.mark.parametrize("flag", [("-n", "64"), ("--realizations", "3"), ("--seed", "4"),
                                  ("-d", "2"), ("--param", "randomize=owen")])
def test_a_flag_that_does_not_apply_to_a_file_is_refused(tmp_path, capsys, flag):
    source = tmp_path / "pts.npy"
    files.save_points(source, clsamp.make_sampler("random", seed=1).sample(64))
    code, text = run(capsys, "spectrum", str(source), *flag, "-o", str(tmp_path / "x.png"))
    assert code == 2 and repr(flag[0]) in text and "applies to a sampler" in text
    assert not (tmp_path / "x.png").exists()
    code, _ = run(capsys, "spectrum", str(source), "--resolution", "16", "-o", str(tmp_path / "x.png"))
    assert code == 0 and (tmp_path / "x.png").is_file()


# -- modes ---------------------------------------------------------------------------------
@pytest.mark.parametrize("mask, mode", [(0o022, 0o644), (0o077, 0o600), (0o002, 0o664)])
def test_files_get_the_mode_the_umask_gives(tmp_path, mask, mode):
    old = os.umask(mask)
    try:
        paths = [files.write_text(tmp_path / "a.txt", "x") or tmp_path / "a.txt",
                 files.save_points(tmp_path / "p.npy", np.full((2, 2), 0.5)),
                 files.write_png(tmp_path / "i.png", np.zeros((4, 4))),
                 files.write_exr(tmp_path / "i.exr", np.zeros((4, 4), dtype=np.float32))]
    finally:
        os.umask(old)
    for path in paths:
        assert stat.S_IMODE(os.stat(path).st_mode) == mode, path
    os.chmod(paths[0], 0o640)                      # an existing file keeps its own mode
    files.write_text(paths[0], "y")
    assert stat.S_IMODE(os.stat(paths[0]).st_mode) == 0o640


# -- variable-size sets --------------------------------------------------------------------
def test_maximal_sets_have_a_spectrum_and_metrics():
    sets = clsamp.make_sampler("poisson_disk", radius=0.06, seed=2).sample_sets(4)
    assert len({len(s) for s in sets}) > 1
    for method in ("direct", "fast"):
        P = clsamp.power_spectrum(sets, 32, method=method, progress=False)
        one_by_one = np.mean([clsamp.power_spectrum(s, 32, method=method, progress=False)
                              for s in sets], axis=0)
        assert np.allclose(P, one_by_one, rtol=1e-13, atol=1e-12)
        assert P[16, 16] == pytest.approx(np.mean([len(s) for s in sets]))
    for metric in (metrics.min_distance, metrics.relative_radius,
                   metrics.normalized_energy):
        got = metric(sets)
        assert got.shape == (4,)
        assert np.array_equal(got, [metric(s) for s in sets])
    assert np.all(metrics.min_distance(sets) >= 0.06)
    with pytest.raises(clsamp.InvalidArgumentError, match=r"'points\[1\]'"):
        clsamp.power_spectrum([sets[0], np.full((3, 2), 1.5)], 16)


def test_a_list_of_lists_is_still_one_set():
    pts = [[0.1, 0.2], [0.6, 0.7]]
    assert metrics.min_distance(pts) == metrics.min_distance(np.array(pts))


# -- numbers as people read them -----------------------------------------------------------
def test_messages_show_plain_numbers():
    with pytest.raises(clsamp.InvalidArgumentError) as info:
        clsamp.make_sampler("random").sample(np.float64(2.5))
    assert "np.float64" not in str(info.value) and "2.5" in str(info.value)
    with pytest.raises(clsamp.InvalidArgumentError) as info:
        clsamp.power_spectrum(np.array([[0.25, 1.0]]), 16)
    assert "np.float64" not in str(info.value) and "[0.25, 1.0]" in str(info.value)


def test_spectrum_pictures_have_plus_y_up():
    # one frequency (0, +3): the bright pixel of the picture lies above the centre
    x = np.arange(64) / 64
    pts = np.stack([np.zeros(64), x], axis=-1)        # points along y: power at fx = 0 only
    P = clsamp.power_spectrum(pts, 16, progress=False)
    from clsamp import plots
    image = plots.spectrum_image(P)
    assert np.array_equal(image, np.clip(P.T[::-1] / 4, 0, 1))
    Q = np.zeros((16, 16))
    Q[8, 8 + 3] = 4.0                                 # fx = 0, fy = +3
    row, col = np.unravel_index(np.argmax(plots.spectrum_image(Q)), (16, 16))
    assert col == 8 and row == 16 - 1 - (8 + 3)       # above the centre row (7)
