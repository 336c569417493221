"""Ctrl-C (SIGINT) or SIGTERM in the middle of a command loses nothing: every output is
whole (or absent), no temporary file stays behind, and the tour's page never links to a
picture that is not there."""

import json
import os
import re
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from clsamp import files

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _interrupted(args, cwd, after, sig):
    """Run ``clsamp args`` in ``cwd``, send ``sig`` ``after`` seconds in; the exit code."""
    env = dict(os.environ, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    # a child of a background job would inherit SIGINT ignored: give it the default
    proc = subprocess.Popen([sys.executable, "-m", "clsamp", *args], cwd=cwd, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    time.sleep(after)
    sent = proc.poll() is None
    if sent:
        proc.send_signal(sig)
    out, err = proc.communicate(timeout=300)
    # 130 / 143: stopped in the middle; -2 / -15: the signal came after the command was done,
    # as the interpreter shut down
    assert proc.returncode in (0, 130, 143, -signal.SIGINT, -signal.SIGTERM), (proc.returncode, err[-2000:])
    if proc.returncode > 0:
        assert "every file written so far is whole" in err, err[-2000:]
    return sent


def _no_temporaries(folder):
    left = [p for p in folder.rglob("*") if p.name.startswith(".") and ".tmp" in p.name]
    assert not left, left


def _whole_png(path):
    from matplotlib import image
    assert image.imread(path).size > 0


CASES = [
    (["sample", "random", "-n", "16777216", "--realizations", "2", "-o", "p.npy"],
     {"p.npy": lambda p: np.load(p, mmap_mode="r").shape == (2, 16777216, 2)}),
    (["convergence", "--samplers", "random,jittered", "--integrand", "disk", "--ns", "16..4096",
      "--realizations", "12000", "--no-progress", "-o", "c.png"],
     {"c.png": _whole_png, "c_time.png": _whole_png,
      "c.json": lambda p: len(json.loads(p.read_text())["results"]) == 2}),
    (["render", "ao", "--sampler", "jittered", "--spp", "256", "--resolution", "384", "-o", "r.exr"],
     {"r.exr": lambda p: files.read_exr(p).shape[:2] == (384, 384), "r.png": _whole_png}),
]


@pytest.mark.parametrize("case", range(len(CASES)))
@pytest.mark.parametrize("after,sig", [(1.2, signal.SIGINT), (2.2, signal.SIGTERM), (3.2, signal.SIGINT)])
def test_an_interrupted_command_leaves_whole_files(tmp_path, case, after, sig):
    args, outputs = CASES[case]
    sent = _interrupted(args, tmp_path, after, sig)
    assert sent or after > 2, "the command ended before the first signal: the case needs more work"
    _no_temporaries(tmp_path)
    for name, check in outputs.items():
        path = tmp_path / name
        if path.exists():
            assert check(path) is not False, name


@pytest.mark.parametrize("after", [4.0, 9.0])
def test_an_interrupted_tour_links_only_pictures_that_exist(tmp_path, after):
    _interrupted(["tour", "--quick", "--no-progress", "--out", "t"], tmp_path, after, signal.SIGINT)
    folder = tmp_path / "t"
    _no_temporaries(tmp_path)
    page = folder / "index.html"
    if page.exists():
        links = re.findall(r"(?:src|href)=['\"]([^'\"#]+)['\"]", page.read_text())
        missing = [link for link in links if not link.startswith("http") and not (folder / link).exists()]
        assert not missing, missing
        json.loads((folder / "tour.json").read_text())


@pytest.mark.parametrize("work", ["spectrum", "ccvt", "ccvt_batch"])
def test_long_work_stops_within_two_seconds_of_ctrl_c(work):
    import threading

    import clsamp
    if work == "spectrum":
        pts = clsamp.make_sampler("random", seed=1).sample(4096, realizations=64)

        def call():
            clsamp.power_spectrum(pts, resolution=1024, method="direct", progress=False)
    elif work == "ccvt":
        def call():
            clsamp.make_sampler("ccvt", points_per_site=16, seed=1, progress=False).sample(131072)
    else:       # a convergence sweep's CCVT batch: long power passes and solve chunks
        def call():
            clsamp.make_sampler("ccvt", seed=1, progress=False).sample(4096, realizations=64)
    fired = []

    def ctrl_c():
        time.sleep(1.0)
        fired.append(time.perf_counter())
        os.kill(os.getpid(), signal.SIGINT)

    # Python's own SIGINT handler, also where the run was started with SIGINT ignored (a
    # shell's background job, nohup): there the signal would be dropped
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        threading.Thread(target=ctrl_c, daemon=True).start()
        with pytest.raises(KeyboardInterrupt):
            call()
    finally:
        signal.signal(signal.SIGINT, previous)
    assert fired and time.perf_counter() - fired[0] < 2.0


@pytest.mark.parametrize("sig, status", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_whose_exception_an_extension_replaced_still_ends_as_stopped(monkeypatch, capsys,
                                                                              sig, status):
    # matplotlib's renderer turns a KeyboardInterrupt raised inside a draw into a ValueError
    # ("Invalid affine transformation matrix"): the command still ends as interrupted
    from clsamp import cli

    def run(args):
        try:
            os.kill(os.getpid(), sig)
            time.sleep(5)
        except BaseException:
            raise ValueError("Invalid affine transformation matrix") from None

    monkeypatch.setattr(cli, "_run_devices", run)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        assert cli.main(["devices"]) == status
    finally:
        signal.signal(signal.SIGINT, previous)
    assert "every file written so far is whole" in capsys.readouterr().err


def test_an_image_and_its_preview_land_together_or_not_at_all(tmp_path, monkeypatch, capsys):
    # Ctrl-C while the PNG preview is drawn: before, the EXR stayed without its PNG
    from clsamp import cli

    def interrupted(path, image, **kwargs):
        raise KeyboardInterrupt()
    monkeypatch.setattr(files, "write_png", interrupted)
    code = cli.main(["render", "ao", "--sampler", "jittered", "--spp", "4", "--resolution", "8",
                     "--no-progress", "-o", str(tmp_path / "comb.exr")])
    assert code == 130 and "every file written so far is whole" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == []
    monkeypatch.undo()
    code = cli.main(["render", "ao", "--sampler", "jittered", "--spp", "4", "--resolution", "8",
                     "--no-progress", "-o", str(tmp_path / "comb.exr")])
    assert code == 0 and sorted(p.name for p in tmp_path.iterdir()) == ["comb.exr", "comb.png"]


def test_a_sweep_on_a_local_cluster_stops_within_two_seconds_of_ctrl_c(tmp_path):
    # the local cluster of --scheduler local:N is closed at once, not at the interpreter's exit
    pytest.importorskip("distributed")
    env = dict(os.environ, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen([sys.executable, "-m", "clsamp", "convergence", "--samplers", "jittered",
                             "--integrand", "disk", "--realizations", "100000", "--no-progress",
                             "--scheduler", "local:2", "-o", "c.png"], cwd=tmp_path, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    time.sleep(4.0)
    assert proc.poll() is None, "the sweep ended before the signal: the case needs more work"
    sent = time.perf_counter()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    stopped = time.perf_counter() - sent
    assert proc.returncode == 130, err[-2000:]
    assert stopped < 2.0, stopped


@pytest.mark.parametrize("status", [130, 143])
def test_a_stopped_command_ends_the_process_without_the_teardown(monkeypatch, status):
    # the console script and python -m clsamp: 130 / 143 flush and end at once (os._exit)
    import clsamp.__main__ as script
    ended = []
    monkeypatch.setattr(script, "main", lambda argv=None: status)
    monkeypatch.setattr(os, "_exit", lambda code: ended.append(code))
    script.entry([])
    assert ended == [status]


@pytest.mark.parametrize("status", [0, 2])
def test_a_finished_command_ends_through_sys_exit(monkeypatch, status):
    import clsamp.__main__ as script
    monkeypatch.setattr(script, "main", lambda argv=None: status)
    monkeypatch.setattr(os, "_exit", lambda code: pytest.fail("os._exit for a finished command"))
    with pytest.raises(SystemExit) as ended:
        script.entry([])
    assert ended.value.code == status
