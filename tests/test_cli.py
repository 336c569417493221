"""The `clsamp` command line, run as a subprocess the way a user runs it."""

import os
import subprocess
import sys

import numpy as np

from clsamp import io

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def clsamp_cli(*args):
    env = dict(os.environ, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    return subprocess.run([sys.executable, "-m", "clsamp", *args], capture_output=True, text=True,
                          env=env, cwd=ROOT, timeout=300)


def test_devices_lists_the_default_device():
    out = clsamp_cli("devices")
    assert out.returncode == 0, out.stderr
    listing = out.stdout.lower()
    assert "*" in listing and ("cpu" in listing or "gpu" in listing)


def test_sample_writes_text_and_npy(tmp_path):
    out = clsamp_cli("sample", "random", "-n", "64", "-d", "3", "--seed", "5", "-o", str(tmp_path / "p.txt"))
    assert out.returncode == 0, out.stderr
    points = io.load_points(tmp_path / "p.txt")
    assert points.shape == (64, 3)
    import clsamp
    np.testing.assert_array_equal(points, clsamp.make_sampler("random", d=3, seed=5).sample(64))
    out = clsamp_cli("sample", "random", "-n", "8", "--realizations", "4", "-o", str(tmp_path / "p.npy"))
    assert out.returncode == 0, out.stderr
    assert np.load(tmp_path / "p.npy").shape == (4, 8, 2)


def test_sample_to_stdout_and_list():
    out = clsamp_cli("sample", "random", "-n", "3")
    assert out.returncode == 0 and len(out.stdout.splitlines()) == 3
    listed = clsamp_cli("sample", "--list")
    assert "random" in listed.stdout.split()


def test_bad_input_is_a_clear_error_not_a_traceback():
    out = clsamp_cli("sample", "nosuch", "-n", "4")
    assert out.returncode == 2
    assert "unknown sampler" in out.stderr and "Traceback" not in out.stderr
    out = clsamp_cli("sample", "random", "-n", "0")
    assert out.returncode == 2 and "'n'" in out.stderr
    out = clsamp_cli("sample", "random", "-n", "4", "--param", "oops")
    assert out.returncode == 2 and "key=value" in out.stderr


def test_metrics_writes_json_and_the_pcf_figure(tmp_path):
    import json

    import clsamp
    out = clsamp_cli("metrics", "jittered", "-n", "256", "--realizations", "4", "--seed", "2",
                     "--metric", "cd,l2-star,star,pcf,nn", "-o", str(tmp_path / "m.json"))
    assert out.returncode == 0, out.stderr
    document = json.loads((tmp_path / "m.json").read_text())
    assert (tmp_path / "m_pcf.png").stat().st_size > 0
    points = clsamp.make_sampler("jittered", d=2, seed=2).sample(256, realizations=4)
    m = document["metrics"]
    assert m["CD"]["values"] == clsamp.discrepancy(points, "CD").tolist()
    assert m["star"]["values"] == clsamp.star_discrepancy(points).tolist()
    assert len(m["pcf"]["radii"]) == 100 and m["nn"]["min"] > 0
    # a point file, and bounds beyond the exact dimensions
    io.save_points(tmp_path / "p.npy", clsamp.make_sampler("sobol", d=5).sample(128))
    out = clsamp_cli("metrics", str(tmp_path / "p.npy"), "--metric", "star", "--bounds",
                     "-o", str(tmp_path / "b.json"))
    assert out.returncode == 0, out.stderr
    star = json.loads((tmp_path / "b.json").read_text())["metrics"]["star"]
    assert star["bounds"] and star["lower"]["mean"] <= star["upper"]["mean"]


def test_metrics_bad_input_is_a_clear_error(tmp_path):
    out = clsamp_cli("metrics", "jittered", "-n", "64", "--metric", "cd,foo", "-o", str(tmp_path / "m.json"))
    assert out.returncode == 2 and "'--metric'" in out.stderr and "'foo'" in out.stderr
    out = clsamp_cli("metrics", "jittered", "-n", "64", "-o", str(tmp_path / "m.png"))
    assert out.returncode == 2 and ".json" in out.stderr
    out = clsamp_cli("metrics", "sobol", "-n", "64", "-d", "5", "--metric", "star",
                     "-o", str(tmp_path / "m.json"))
    assert out.returncode == 2 and "--bounds" in out.stderr and "Traceback" not in out.stderr
    assert not (tmp_path / "m.json").exists()
