"""What the command line checks before it works: every output path (a writable folder, no
file in the way, a suffix it writes) and every name (samplers, randomizations, integrands,
families, metrics), each refused in one line with exit status 2; a write that still fails
is one line and leaves nothing behind; clsamp's warnings are one line; `sample --plot`
draws the points. In-process, through ``main``."""

import errno
import os
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import clsamp
from clsamp import files
from clsamp.cli import FOLDERS, main


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    captured = capsys.readouterr()
    return code, captured.out + captured.err


def listing(folder):
    return sorted(str(p.relative_to(folder)) for p in Path(folder).rglob("*"))


@pytest.fixture
def no_work(monkeypatch):
    """Every entry to the work of a command fails the test: the checks must come first."""
    def forbidden(*args, **kwargs):
        raise AssertionError("the work started before the arguments were checked")
    from clsamp import integration, render, spectrum, sweep, tour
    from clsamp.samplers.base import Sampler
    monkeypatch.setattr(Sampler, "sample", forbidden)
    monkeypatch.setattr(spectrum, "power_spectrum", forbidden)
    monkeypatch.setattr(sweep, "convergence", forbidden)
    monkeypatch.setattr(integration, "integrate", forbidden)
    monkeypatch.setattr(render, "render", forbidden)
    monkeypatch.setattr(tour, "run_tour", forbidden)


# -- sample --plot ------------------------------------------------------------------------
def test_sample_plot_draws_the_points(tmp_path, capsys):
    code, text = run(capsys, "sample", "jittered", "-n", "64", "--realizations", "12",
                     "-o", tmp_path / "p.npy", "--plot", tmp_path / "p.png")
    assert code == 0, text
    assert listing(tmp_path) == ["p.npy", "p.png"]
    assert "p.npy" in text and "p.png" in text
    assert (tmp_path / "p.png").read_bytes()[:4] == b"\x89PNG"
    code, text = run(capsys, "sample", "sobol:owen", "-n", "64", "-d", "3",
                     "--plot", tmp_path / "q.pdf")             # d > 2: two coordinates; no -o
    assert code == 0, text
    assert (tmp_path / "q.pdf").read_bytes()[:4] == b"%PDF"
    code, text = run(capsys, "sample", "pmj02", "-n", "64", "--plot", tmp_path / "t.png", "--tiled",
                     "--projections")
    assert code == 0 and (tmp_path / "t.png").read_bytes()[:4] == b"\x89PNG", text
    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    assert any(line.startswith("clsamp sample ") and " --plot " in line for line in readme.splitlines())


@pytest.mark.parametrize("argv, expected", [
    (("--plot", "{}/p.jpg"), "'--plot'"),
    (("--plot", "{}/p.png", "-d", "1"), "'-d' 1"),
    (("-o", "{}/p.npy", "--plot", "{}/p"), "no suffix"),
    (("-o", "{}/p.npy", "--tiled"), "give '--plot'"),
])
def test_sample_plot_is_checked_first(tmp_path, capsys, no_work, argv, expected):
    code, text = run(capsys, "sample", "random", "-n", "8", *(a.format(tmp_path) for a in argv))
    assert code == 2 and expected in text and "Traceback" not in text
    assert listing(tmp_path) == []


# -- output paths -------------------------------------------------------------------------
COMMANDS = [
    ("sample", "random", "-n", "8", "-o", "{}.npy"),
    ("sample", "random", "-n", "8", "--plot", "{}.png"),
    ("spectrum", "random", "-n", "64", "-o", "{}.png"),
    ("spectrum", "random", "-n", "64", "-o", "{ok}/s.png", "--plots", "{}.pdf"),
    ("metrics", "random", "-n", "64", "-o", "{}.json"),
    ("convergence", "--samplers", "random", "--ns", "16,64", "--realizations", "4", "-o", "{}.png"),
    ("integrate", "gaussian", "-o", "{}.json"),
    ("render", "ao", "--spp", "4", "--resolution", "4", "-o", "{}.exr"),
    ("tour", "--quick", "--out", "{}"),
]


@pytest.mark.parametrize("argv", COMMANDS, ids=lambda a: " ".join(a[:2]))
def test_a_file_in_the_way_is_refused_before_any_work(tmp_path, capsys, no_work, argv):
    (tmp_path / "afile").write_text("")
    target = str(tmp_path / "afile" / "out")
    code, text = run(capsys, *(a.format(target, ok=tmp_path) for a in argv))
    assert code == 2, text
    assert "is a file, not a folder" in text and "Traceback" not in text
    assert len(text.strip().splitlines()) == 1
    assert listing(tmp_path) == ["afile"]


@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="needs Linux's /proc")
@pytest.mark.parametrize("argv", COMMANDS[:1] + COMMANDS[2:3] + COMMANDS[7:8],
                         ids=lambda a: a[0])
def test_a_folder_that_takes_no_file_is_refused_before_any_work(capsys, no_work, argv):
    code, text = run(capsys, *(a.format("/proc/clsamp-out") for a in argv))
    assert code == 2 and "no file can be written in '/proc'" in text and "Traceback" not in text


def test_a_folder_where_the_file_should_be_is_refused(tmp_path, capsys, no_work):
    (tmp_path / "p.npy").mkdir()
    code, text = run(capsys, "sample", "random", "-n", "8", "-o", tmp_path / "p.npy")
    assert code == 2 and "is a folder, not a file" in text
    (tmp_path / "c.json").mkdir()                             # a companion in the way
    code, text = run(capsys, "convergence", "--samplers", "random", "--ns", "16,64",
                     "-o", tmp_path / "c.png")
    assert code == 2 and "c.json" in text and "is a folder, not a file" in text


def test_missing_folders_are_created_as_help_and_readme_say(tmp_path, capsys):
    code, text = run(capsys, "sample", "random", "-n", "8", "-o", tmp_path / "new" / "sub" / "p.txt")
    assert code == 0 and (tmp_path / "new" / "sub" / "p.txt").is_file()
    with pytest.raises(SystemExit):
        main(["sample", "--help"])
    assert FOLDERS in " ".join(capsys.readouterr().out.split())
    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    assert FOLDERS in " ".join(readme.split())


def test_a_write_that_fails_is_one_line_and_leaves_nothing(tmp_path, capsys, monkeypatch):
    def full(fd):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    monkeypatch.setattr(files.os, "fsync", full)
    code, text = run(capsys, "sample", "random", "-n", "8", "-o", tmp_path / "p.npy")
    assert code != 0 and "Traceback" not in text
    assert f"clsamp sample: error: cannot write {str(tmp_path / 'p.npy')!r}: No space left on device" in text
    assert listing(tmp_path) == []
    with pytest.raises(files.WriteError, match="cannot write") as info:
        files.write_text(tmp_path / "t.txt", "x")
    assert isinstance(info.value, OSError) and listing(tmp_path) == []


def test_a_file_where_a_folder_should_be_is_a_write_error(tmp_path):
    (tmp_path / "afile").write_text("")
    with pytest.raises(files.WriteError, match="cannot write"):
        files.write_text(tmp_path / "afile" / "x.txt", "x")


def test_a_reference_cache_that_cannot_be_written_warns_and_keeps_the_result(tmp_path, monkeypatch):
    from clsamp import render
    (tmp_path / "afile").write_text("")
    monkeypatch.setenv("CLSAMP_CACHE", str(tmp_path / "afile" / "cache"))
    with pytest.warns(UserWarning, match="the reference render is not cached: cannot write"):
        ref = render.reference("ao", 4, spp=64, progress=False)
    assert ref.shape == (4, 4) and listing(tmp_path) == ["afile"]


# -- names ---------------------------------------------------------------------------------
@pytest.mark.parametrize("argv, expected", [
    (("convergence", "--samplers", "random,jitterd"),
     "unknown sampler 'jitterd'; did you mean 'jittered'?"),
    (("convergence", "--samplers", "random,sobol:owne"),
     "unknown randomization 'owne' of sampler 'sobol'; did you mean 'sobol:owen'?"),
    (("convergence", "--samplers", "random", "--integrand", "gaussian,gausian"),
     "unknown integrand or family 'gausian'; did you mean 'gaussian'?"),
    (("convergence", "--samplers", "random", "--family", "heavisdes"),
     "Did you mean 'heavisides'?"),
    (("convergence", "--samplers", "random", "--family", "disk"),
     "is an integrand; give it to '--integrand'"),
    (("convergence", "--samplers", "random", "--integrand", "disk,heavisides"), "mixes"),
    (("metrics", "random", "-n", "16", "--metric", "cd,l2star", "-o", "{}/m.json"),
     "did you mean 'l2-star'?"),
    (("render", "ao", "--sampler", "sobl:owen", "-o", "{}/r.exr"),
     "unknown sampler 'sobl'; did you mean 'sobol:owen'?"),
    (("integrate", "gaussian", "--sampler", "sobol:owne"), "did you mean 'sobol:owen'?"),
    (("sample", "jitered", "-n", "4"), "unknown sampler 'jitered'; did you mean 'jittered'?"),
    (("spectrum", "random:owen", "-n", "4", "-o", "{}/s.png"), "takes no randomization"),
])
def test_every_name_is_resolved_before_any_work(tmp_path, capsys, no_work, argv, expected):
    argv = [a.format(tmp_path) for a in argv]
    if argv[0] == "convergence":
        argv += ["--ns", "16,64", "--realizations", "4", "-o", str(tmp_path / "c.png")]
    code, text = run(capsys, *argv)
    assert code == 2 and expected in text and "Traceback" not in text, text
    assert listing(tmp_path) == []


def test_unknown_sampler_message_reads_plainly():
    with pytest.raises(clsamp.InvalidArgumentError) as info:
        clsamp.make_sampler("jitered")
    message = str(info.value)
    assert message.startswith("unknown sampler 'jitered'; did you mean 'jittered'? Known samplers: ")
    assert "'name'=" not in message
    with pytest.raises(clsamp.InvalidArgumentError, match="'sobol:owen'") as info:
        clsamp.make_sampler("sobol:owne")
    assert "'randomize'" not in str(info.value)


# -- warnings ------------------------------------------------------------------------------
def test_clsamp_warnings_are_one_line_and_showwarning_is_restored(capsys):
    before = warnings.showwarning
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        code, text = run(capsys, "sample", "sobol:owen", "-n", "5")
    assert code == 0 and warnings.showwarning is before
    lines = [line for line in text.splitlines() if "warning" in line.lower()]
    assert lines and all(line.startswith("clsamp: warning: the balance properties") for line in lines)
    assert "UserWarning" not in text and "warnings.warn" not in text


def test_other_warnings_keep_their_usual_form(capsys, monkeypatch):
    from clsamp import cli

    def run_devices(args):
        warnings.warn_explicit("not ours", UserWarning, "elsewhere.py", 3)
        return 0
    monkeypatch.setattr(cli, "_run_devices", run_devices)
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        shown = []
        warnings.showwarning = lambda *a, **k: shown.append(a[0])
        assert main(["devices"]) == 0
    assert [str(m) for m in shown] == ["not ours"]
    assert "clsamp: warning" not in capsys.readouterr().err
    assert sys.modules["clsamp.cli"] is cli


def test_sample_list_names_the_randomizations(capsys):
    from clsamp import cli
    assert cli.main(["sample", "--list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "sobol sobol:shift sobol:xor sobol:owen sobol:lms sobol:lms+shift" in lines
    assert "faure faure:shift faure:xor faure:lms faure:lms+shift" in lines and "jittered" in lines


def test_tour_help_describes_the_report(capsys):
    from clsamp import cli
    with pytest.raises(SystemExit):
        cli.main(["tour", "--help"])
    out = capsys.readouterr().out
    assert "index.html" in out and "two minutes" not in out


def test_a_fast_integrate_shows_no_progress_bar(capsys):
    import numpy as np

    import clsamp
    clsamp.integrate(lambda x: np.exp(-np.sum(x * x, axis=1)), 2, abs_tol=1e-4)
    assert "integrate" not in capsys.readouterr().err


@pytest.mark.parametrize("argv, named", [
    (["sample", "gbn", "-n", "abc"], "argument -n: invalid int value: 'abc'"),
    (["sample", "gbn", "--seed", "1.5"], "argument --seed: invalid int value: '1.5'"),
    (["sample", "gbn", "--bogus"], "unrecognized arguments: --bogus"),
    (["sampel"], "invalid choice: 'sampel'"),
])
def test_argparse_errors_are_one_line(capsys, no_work, argv, named):
    # a value argparse itself refuses gets one line naming the argument, as clsamp's own
    # checks give it, not the usage block
    with pytest.raises(SystemExit) as stop:
        main(argv)
    text = capsys.readouterr().err
    assert stop.value.code == 2 and text.count("\n") == 1 and named in text
    assert text.startswith("clsamp") and "usage" not in text


@pytest.mark.parametrize("argv", [
    ["sample", "gbn", "-n", "16", "--param", "seed=3"],
    ["sample", "gbn", "-n", "16", "--param", "d=3"],
    ["sample", "random", "-n", "16", "--param", "backend=numpy"],
    ["spectrum", "gbn", "-n", "16", "--param", "seed=3", "-o", "{}/s.png"],
])
def test_params_that_are_the_commands_own_options_are_one_line(tmp_path, capsys, no_work, argv):
    # make_sampler got them twice ("got multiple values for keyword argument 'seed'")
    code, text = run(capsys, *[a.format(tmp_path) for a in argv])
    assert code == 2 and ", not by --param" in text and "Traceback" not in text, text
    assert listing(tmp_path) == []


def test_a_3d_spectrum_goes_to_npy_only(tmp_path, capsys):
    # it was computed (256^3), then refused as a picture ('P' must be a 2-D spectrum)
    code, text = run(capsys, "spectrum", "random", "-n", "16", "-d", "3", "-o", str(tmp_path / "s.png"))
    assert code == 2 and "a 3-D spectrum goes to -o .npy (--plots: 1-D, 2-D)" in text, text
    assert listing(tmp_path) == []
    code, _ = run(capsys, "spectrum", "random", "-n", "16", "-d", "3", "--resolution", "8",
                  "-o", str(tmp_path / "s.npy"))
    assert code == 0 and np.load(tmp_path / "s.npy").shape == (8, 8, 8)


def test_a_spectrum_that_cannot_go_to_its_outputs_leaves_none(tmp_path, capsys):
    # a 1-D spectrum was refused as a PNG after the work; --plots' refusal (a spectrum too
    # small for its annuli) came after -o was written
    code, text = run(capsys, "spectrum", "random", "-n", "16", "-d", "1", "-o", str(tmp_path / "s.png"))
    assert code == 2 and "a 1-D spectrum goes to -o .npy or .exr" in text, text
    code, text = run(capsys, "spectrum", "random", "-n", "64", "--resolution", "2", "--backend", "numpy",
                     "-o", str(tmp_path / "r.png"), "--plots", str(tmp_path / "p.png"))
    assert code == 2 and "annulus" in text and listing(tmp_path) == [], text


@pytest.mark.parametrize("argv, expected", [
    # each was refused only after the sampler's work (163 s for a 200-iteration lloyd set)
    (["spectrum", "random", "-n", "16", "-d", "3", "-o", "{}/s.png"], "a 3-D spectrum goes to -o .npy"),
    (["spectrum", "random", "-n", "16", "-d", "3", "-o", "{}/s.npy", "--plots", "{}/p.png"],
     "(--plots: 1-D, 2-D)"),
    (["spectrum", "random", "-n", "16", "-d", "4", "-o", "{}/s.npy"], "a spectrum is made in 1-D to 3-D"),
    (["spectrum", "random", "-n", "16", "--resolution", "7", "-o", "{}/s.npy"],
     "'--resolution' must be even and at least 2, got 7"),
    # the last of two values won without a word
    (["sample", "jittered", "-n", "4", "--param", "strata=2x2", "--param", "strata=4x1"],
     "'--param strata=4x1': strata is given twice"),
])
def test_a_spectrum_request_and_its_params_are_checked_before_the_sampler_runs(tmp_path, capsys, no_work,
                                                                                argv, expected):
    code, text = run(capsys, *[a.format(tmp_path) for a in argv])
    assert code == 2 and expected in text and "Traceback" not in text, text
    assert listing(tmp_path) == []


def test_the_analysed_samplers_backend_is_a_param(tmp_path, capsys):
    # spectrum and metrics refused it as "set by --backend", which sets where they compute
    code, text = run(capsys, "spectrum", "random", "-n", "16", "--resolution", "8", "--param",
                     "backend=numpy", "-o", str(tmp_path / "s.npy"))
    assert code == 0, text
    made = clsamp.make_sampler("random", backend="numpy").sample(16)
    assert np.allclose(np.load(tmp_path / "s.npy"), clsamp.power_spectrum(made, resolution=8, progress=False))


@pytest.mark.parametrize("argv, expected", [
    # a traceback (FileExistsError from the report), or a refusal after section 1 had written 70 files
    (["tour", "--out", "{}/t2", "--quick"], "/t2/img' is a file, not a folder"),
    (["tour", "--out", "{}/t4", "--quick"], "'{}/t4/tour.json' is a folder, not a file"),
    (["tour", "--out", ""], "'--out' must name a folder, got ''"),       # ran into the current folder
    # checked after the render was written, naming 'spp'; ignored without --reference
    (["render", "ao", "--reference", "--reference-spp", "100", "-o", "{}/r.exr"],
     "'--reference-spp': 'spp'=100"),
    (["render", "ao", "--reference-spp", "0", "-o", "{}/r.exr"], "give '--reference'"),
    (["render", "nosuch", "-o", "{}/r.exr"], "'scene' 'nosuch' is neither"),            # named 'path'
    # found when its sweep came up, after the earlier ones had run
    (["convergence", "--samplers", "random,jittered", "--ns", "20,50", "-o", "{}/c.png"],
     "sampler 'jittered' with d=2 cannot make n=20"),
    (["convergence", "--samplers", "random,van_der_corput", "--ns", "16,64", "-o", "{}/c.png"],
     "supports 'd' in (1), got 2"),
    (["metrics", "random", "-n", "250", "-d", "4", "--metric", "cd,star", "-o", "{}/m.json"],
     "'--metric' star is exact for d = 1 to 3, got d = 4"),                            # after CD
    (["metrics", "random", "-n", "1", "-o", "{}/m.json"], "'-n' must be at least 2 for pcf and nn"),
    # accepted, and silently ignored or run twice
    (["convergence", "--checkpoint", "", "-o", "{}/c.png"], "'--checkpoint' must name a folder"),
    (["convergence", "--family", "", "-o", "{}/c.png"], "'--family' must each name at least one"),
    (["convergence", "--members", "0", "-o", "{}/c.png"], "'--members' is the families'"),
    (["convergence", "--family", "gaussians", "--members", "0", "-o", "{}/c.png"], "'members' must be"),
    (["convergence", "--family", "gaussians", "--integrand", "disk", "-o", "{}/c.png"],
     "give '--family' or '--integrand', not both"),
    (["convergence", "--samplers", "jittered,jittered", "-o", "{}/c.png"], "'--samplers' names one twice"),
    (["metrics", "jittered", "-n", "64", "--metric", "cd", "--bounds", "-o", "{}/m.json"], "has no star"),
    (["metrics", "jittered", "-n", "64", "--metric", "cd,,cd", "-o", "{}/m.json"], "names one twice"),
    (["integrate", ":sq", "--abs-tol", "1e-4"], "'function' ':sq' cannot be loaded"),   # ValueError
    (["convergence", "--integrand", "", "-o", "{}/c.png"], "'--integrand' must each name at least one"),
    (["metrics", "random", "-d", "3", "-n", "3000", "--metric", "cd,star", "-o", "{}/m.json"],
     "star: the exact value takes n <= 2048 in 3-D"),
])
def test_every_commands_requests_are_checked_before_any_work(tmp_path, capsys, no_work, argv, expected):
    (tmp_path / "t2").mkdir()
    (tmp_path / "t2" / "img").write_text("")
    (tmp_path / "t4" / "tour.json").mkdir(parents=True)
    before = listing(tmp_path)
    code, text = run(capsys, *[a.format(tmp_path) for a in argv])
    assert code == 2 and expected.format(tmp_path) in text and text.count("\n") == 1, text
    assert listing(tmp_path) == before


def test_an_integrand_object_loaded_by_name_keeps_its_kernel_and_checks(tmp_path, capsys, monkeypatch):
    # wrapped as a plain function it took the host path (14.6 s -> 31.9 s) and lost its d check
    (tmp_path / "myk.py").write_text("from clsamp.integrands import keister\nk = keister(3)\n")
    monkeypatch.chdir(tmp_path)
    code, text = run(capsys, "integrate", "myk:k", "--d", "2", "--abs-tol", "1e-3")
    assert code == 2 and "integrand 'keister' is 3-dimensional, 'd' is 2" in text, text


def test_a_user_function_that_raises_is_one_line(tmp_path, capsys, monkeypatch):
    (tmp_path / "myf.py").write_text("def boom(x):\n    raise RuntimeError('boom')\n")
    monkeypatch.chdir(tmp_path)
    code, text = run(capsys, "integrate", "myf:boom", "--abs-tol", "1e-4")
    assert code == 2 and "'function' 'myf:boom' raised RuntimeError: boom" in text and "Traceback" not in text


def test_a_malformed_scheduler_address_is_one_line(capsys, no_work):
    pytest.importorskip("distributed")
    code, text = run(capsys, "convergence", "--scheduler", "nosuch", "-o", "/tmp/unused.png")
    assert code == 2 and "'scheduler'='nosuch'" in text and "Traceback" not in text, text
