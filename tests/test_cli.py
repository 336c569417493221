"""The `clsamp` command line, run as a subprocess the way a user runs it."""

import os
import subprocess
import sys

import numpy as np

from clsamp import files

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
    points = files.load_points(tmp_path / "p.txt")
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
    assert {"sobol:lms", "sobol:lms+shift"} <= set(listed.stdout.split())


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
    files.save_points(tmp_path / "p.npy", clsamp.make_sampler("sobol", d=5).sample(128))
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


def test_convergence_over_a_family_writes_the_plot_and_json(tmp_path):
    import json
    out = clsamp_cli("convergence", "--samplers", "jittered,regular", "--family", "heavisides",
                     "--members", "8", "--ns", "16..1024", "--realizations", "8", "--no-progress",
                     "-o", str(tmp_path / "fam.png"))
    assert out.returncode == 0, out.stderr
    assert "random_heavisides" in out.stdout and "mean slope" in out.stdout
    document = json.loads((tmp_path / "fam.json").read_text())
    assert document["members"] == 8 and len(document["results"]) == 2
    assert np.array(document["results"][0]["mse"]).shape == (4, 8)
    assert (tmp_path / "fam.png").stat().st_size > 0
    # a family name in --integrand runs the same sweep; mixing refuses
    same = clsamp_cli("convergence", "--samplers", "jittered", "--integrand", "random_disks",
                      "--members", "4", "--ns", "16,64", "--realizations", "4", "--no-progress",
                      "-o", str(tmp_path / "d.png"))
    assert same.returncode == 0, same.stderr
    mixed = clsamp_cli("convergence", "--integrand", "disk,random_disks", "-o", str(tmp_path / "m.png"))
    assert mixed.returncode == 2 and "mixes" in mixed.stderr
    unknown = clsamp_cli("convergence", "--family", "random_planes", "-o", str(tmp_path / "u.png"))
    assert unknown.returncode == 2 and "unknown 'family'" in unknown.stderr


def test_integrate_a_named_integrand_and_a_python_function(tmp_path):
    import json
    out = clsamp_cli("integrate", "gaussian", "--d", "2", "--abs-tol", "1e-6", "-o", str(tmp_path / "i.json"))
    assert out.returncode == 0, out.stderr
    assert "converged" in out.stdout
    result = json.loads((tmp_path / "i.json").read_text())
    assert result["converged"] and result["half_width"] <= 1e-6
    (tmp_path / "userf.py").write_text("import numpy as np\n\ndef f(x):\n    return x[:, 0] * x[:, 1]\n")
    env_dir = str(tmp_path)
    user = subprocess.run([sys.executable, "-m", "clsamp", "integrate", "userf:f", "--d", "2",
                           "--abs-tol", "1e-5"], capture_output=True, text=True, cwd=env_dir,
                          env=dict(os.environ, PYTHONPATH=ROOT), timeout=300)
    assert user.returncode == 0, user.stderr
    assert abs(float(user.stdout.split()[0]) - 0.25) < 1e-4
    missing = clsamp_cli("integrate", "gaussian", "--d", "2")
    assert missing.returncode == 2 and "abs_tol" in missing.stderr
    stuck = clsamp_cli("integrate", "disk", "--d", "2", "--abs-tol", "1e-12", "--max-n", "1024")
    assert stuck.returncode == 1 and "max_n" in stuck.stderr and "NOT converged" in stuck.stdout


def test_convergence_on_a_local_cluster_from_the_command_line(tmp_path):
    import json

    import pytest
    pytest.importorskip("distributed")
    args = ["convergence", "--samplers", "jittered", "--integrand", "disk", "--ns", "16,64",
            "--realizations", "16", "--no-progress"]
    here = clsamp_cli(*args, "-o", str(tmp_path / "a.png"))
    there = clsamp_cli(*args, "--scheduler", "local:1", "--checkpoint", str(tmp_path / "ck"),
                       "-o", str(tmp_path / "b.png"))
    assert here.returncode == 0 and there.returncode == 0, there.stderr
    a = json.loads((tmp_path / "a.json").read_text())["results"][0]["mse"]
    b = json.loads((tmp_path / "b.json").read_text())["results"][0]["mse"]
    assert a == b
    assert any((tmp_path / "ck").iterdir())
    bad = clsamp_cli(*args, "--scheduler", "tcp://127.0.0.1:9", "-o", str(tmp_path / "c.png"))
    assert bad.returncode == 2 and "cannot reach a Dask scheduler" in bad.stderr
