"""benchmarks/bench_utk.py without UTK (as CI runs it) and its reading of a UTK binary's
output, through a stand-in binary that writes the driver's format."""

import stat
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

import bench_utk  # noqa: E402


def test_skips_without_utk(monkeypatch, capsys):
    monkeypatch.delenv(bench_utk.ENV, raising=False)
    assert bench_utk.utk_binaries() is None
    assert bench_utk.run([], quick=True) == []
    assert "skipped" in capsys.readouterr().err


def test_reads_the_drivers_output(tmp_path, monkeypatch):
    # a stand-in for utk_faure: the header (seconds, n, d) and n x d points, as utk_peer.cpp
    script = tmp_path / "utk_faure"
    script.write_text(
        f"#!{sys.executable}\n"
        "import sys, numpy as np\n"
        "n, d, out = int(sys.argv[1]), int(sys.argv[2]), sys.argv[4]\n"
        "pts = (np.arange(n * d, dtype=np.float64) / (n * d)).reshape(n, d)\n"
        "np.concatenate([[0.25, n, d], pts.ravel()]).tofile(out)\n")
    script.chmod(script.stat().st_mode | stat.S_IEXEC)
    monkeypatch.setenv(bench_utk.ENV, str(tmp_path))
    found = bench_utk.utk_binaries()
    assert found == {"Faure": str(script)}
    seconds, pts = bench_utk.utk_sample(found["Faure"], 5, 3)
    assert seconds == 0.25
    np.testing.assert_array_equal(pts, (np.arange(15) / 15).reshape(5, 3))


def test_same_points_set_or_differs():
    a = np.array([[0.0, 0.5], [0.5, 0.25], [0.25, 0.75]])
    assert bench_utk._same(a, a.copy()) == "same points as UTK"
    assert bench_utk._same(a, a[::-1].copy()).startswith("same set as UTK")
    assert bench_utk._same(a, a + 0.125).startswith("differs from UTK by up to 0.125")
    # Niederreiter: UTK's first n - 1 points are clsamp's 1..n - 1, in another order
    ours = np.vstack([[0.0, 0.0], a])
    theirs = np.vstack([a[::-1], [0.875, 0.875]])
    assert bench_utk._compare("niederreiter", ours, theirs).startswith("the same net")
    assert bench_utk._compare("faure", ours, theirs).startswith("differs")


def test_utk_points_clamped_into_the_cube():
    pts = np.array([[0.5, 1.0000001], [-1e-9, 0.25], [0.1, 0.2]])
    assert bench_utk.outside(pts) == 2
    inside = bench_utk.into_cube(pts)
    assert inside.min() >= 0 and inside.max() < 1
