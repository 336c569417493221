"""Launch shapes per device (clsamp.runtime.shapes): every shape gives the same bits, and
the table is measured once, kept on disk, and read back."""

import dataclasses
import json
import os
import subprocess
import sys

import numpy as np
import pytest

import clsamp
from clsamp import runtime
from clsamp.runtime import shapes

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _shapes():
    """The GPU's shape, the host's, and odd ones (a partial last item or group everywhere)."""
    device = runtime.current_device()
    gpu, host = shapes.gpu_shape(device), shapes.host_shape(device)
    odd = dataclasses.replace(host, points_per_item=4, block=16, local=16, host_output=False)
    wide = dataclasses.replace(gpu, points_per_item=32, block=64, local=256, host_output=True)
    return {"gpu": gpu, "host": host, "odd": odd, "wide": wide}


CASES = [("random", {}, 1000), ("random", {"d": 5}, 333),
         ("sobol", {}, 1000), ("sobol", {"randomize": "owen", "d": 7}, 777),
         ("sobol", {"randomize": "lms+shift", "d": 3}, 500),
         ("halton", {"randomize": "permute", "d": 5}, 999), ("hammersley", {"d": 3}, 300),
         ("van_der_corput", {"d": 1, "randomize": "xor"}, 257),
         ("faure", {"d": 3, "randomize": "lms"}, 81), ("niederreiter", {"d": 4}, 512),
         ("jittered", {}, 1024), ("correlated_multijittered", {}, 1000),
         ("multijittered", {}, 100), ("latin_hypercube", {"d": 3}, 1000),
         ("lattice", {}, 1024), ("zsobol", {}, 256), ("pmj02", {}, 1000)]


@pytest.mark.parametrize("name, params, n", CASES, ids=[f"{c[0]}-{i}" for i, c in enumerate(CASES)])
def test_every_shape_gives_the_same_bits(name, params, n):
    sampler = clsamp.make_sampler(name, seed=7, **params)
    want = clsamp.make_sampler(name, seed=7, backend="numpy", **params).sample(n, realizations=3)
    for label, shape in _shapes().items():
        with runtime.forced_shape(shape):
            got = sampler.sample(n, realizations=3)
        assert np.array_equal(got, want), f"{name} {params} at the {label} shape"


@pytest.mark.parametrize("name, params", [("random", {"d": 3}), ("sobol", {"randomize": "owen"})])
def test_the_gpu_shape_gives_the_same_bits_without_fp64(name, params):
    want = clsamp.make_sampler(name, seed=3, backend="numpy", **params).sample(301, realizations=2)
    with runtime.without_fp64(), runtime.forced_shape(_shapes()["gpu"]):
        got = clsamp.make_sampler(name, seed=3, **params).sample(301, realizations=2)
    assert np.array_equal(got, want)


def test_a_forced_shape_reaches_the_launches(monkeypatch):
    # the random sampler's points per work-item is a build option: each shape builds its own
    seen = []
    original = runtime.programs.kernel

    def kernel(file, name, defines=None, *args, **kwargs):
        if name == "random_points":
            seen.append(defines["POINTS_PER_ITEM"])
        return original(file, name, defines, *args, **kwargs)

    monkeypatch.setattr(runtime.programs, "kernel", kernel)
    for shape in _shapes().values():
        with runtime.forced_shape(shape):
            clsamp.make_sampler("random").sample(64)
            assert runtime.local_size() == min(shape.local, runtime.current_device().max_work_group_size)
    assert seen == [1, 16, 4, 32]


def test_sot_sorts_on_either_side_with_the_same_bits():
    kw = dict(d=3, seed=4, iterations=6, projections="pairs")
    runs = []
    for host_sort in (True, False):
        shape = dataclasses.replace(runtime.shape(), host_sort=host_sort)
        with runtime.forced_shape(shape):
            runs.append(clsamp.make_sampler("sot", **kw).sample(40, realizations=2))
    assert np.array_equal(*runs)


def test_spectrum_product_on_either_side_agrees():
    pts = clsamp.make_sampler("random", seed=13).sample(700, realizations=2)
    host = dataclasses.replace(runtime.shape(), host_gemm=True, tile_group=1)
    device = dataclasses.replace(runtime.shape(), host_gemm=False, tile_group=16)
    with runtime.forced_shape(host):
        a = clsamp.power_spectrum(pts, 48, method="direct")
    with runtime.forced_shape(device):
        b = clsamp.power_spectrum(pts, 48, method="direct")
    assert np.abs(a - b).max() <= 1e-13 * 700


def test_render_widths_of_the_shapes_agree():
    from clsamp import render as rendering
    from clsamp.scene import Scene
    scene = Scene.from_file("ao")
    images = []
    for width in (1, 8):
        with runtime.forced_shape(dataclasses.replace(runtime.shape(), vector_width=width)):
            images.append(rendering.render(scene, "random", 11, 6, seed=8, progress=False))
    np.testing.assert_allclose(images[0], images[1], rtol=0, atol=2e-6)


# -- the table ---------------------------------------------------------------------------
@pytest.fixture
def table(tmp_path, monkeypatch):
    path = tmp_path / "shapes" / "launch-shapes.json"
    monkeypatch.setenv("CLSAMP_SHAPES_FILE", str(path))
    monkeypatch.delenv("CLSAMP_SHAPES", raising=False)
    monkeypatch.setattr(shapes, "_table", {})
    return path


def test_a_device_is_measured_once_and_the_row_is_kept(table):
    device = runtime.current_device()
    first = runtime.shape()
    assert first.source == "measured" and table.exists()
    rows = json.loads(table.read_text())
    row = rows[shapes._key(device)]
    assert device.driver in shapes._key(device) and row["version"] == shapes.VERSION
    assert set(row["relative"]) == set(row["least"]) == {"points_per_item", "local", "block"}
    assert row["points_per_item"] in (1, 4, 16) and row["block"] in (1, 16, 256)
    # a new process reads it instead of measuring
    code = ("import clsamp.runtime.shapes as s, clsamp.runtime as r; s.measure = None; "
            "print(r.shape().source, r.shape().points_per_item)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         env={**os.environ, "PYTHONPATH": ROOT}).stdout.split()
    assert out == ["measured", str(row["points_per_item"])]


def test_a_corrupt_table_is_ignored_with_a_warning_and_rewritten(table):
    table.parent.mkdir(parents=True)
    table.write_text("{not json")
    with pytest.warns(RuntimeWarning, match="ignoring the launch-shape cache"):
        shape = runtime.shape()
    assert shape.source == "measured"
    assert shapes._key(runtime.current_device()) in json.loads(table.read_text())


def test_without_measuring_the_defaults_apply(table, monkeypatch):
    monkeypatch.setenv("CLSAMP_SHAPES", "default")
    monkeypatch.setattr(shapes, "measure", None)          # measuring would fail the test
    device = runtime.current_device()
    assert runtime.shape() == shapes.host_shape(device) and not table.exists()


def test_a_gpu_gets_gpu_shaped_launches_without_measuring(table, monkeypatch):
    monkeypatch.setattr(shapes, "measure", None)
    gpu = dataclasses.replace(runtime.current_device(), type="gpu", name="a GPU",
                              host_memory=False, max_work_group_size=1024)
    shape = runtime.shape(gpu)
    assert shape == shapes.gpu_shape(gpu) and shape.source == "gpu"
    assert shape.points_per_item == 1 and shape.block == 1 and 64 <= shape.local <= 256
    assert shape.vector_width == 1 and not (shape.host_output or shape.host_sort or shape.host_gemm)
    assert not table.exists()


def test_a_row_of_another_measurement_version_is_measured_again(table):
    device = runtime.current_device()
    table.parent.mkdir(parents=True)
    table.write_text(json.dumps({shapes._key(device): {"version": -1, "points_per_item": 4,
                                                       "block": 1, "local": 16}}))
    assert runtime.shape().source == "measured"
    assert json.loads(table.read_text())[shapes._key(device)]["version"] == shapes.VERSION


def test_the_cli_shows_and_measures_the_shapes(table, monkeypatch, capsys):
    from clsamp import cli
    measured = []

    def calibrate(index):           # the measurement itself is tested above; this, the wiring
        measured.append(index)
        return dataclasses.replace(shapes.host_shape(runtime.devices()[index]), source="measured")

    monkeypatch.setattr(shapes, "calibrate", calibrate)
    assert cli.main(["devices"]) == 0 and not measured
    assert "launch shape: not measured yet" in capsys.readouterr().out
    assert cli.main(["devices", "--calibrate"]) == 0
    assert runtime.current_device().index in measured
    assert "launch shape: measured: 16 points a work-item" in capsys.readouterr().out
