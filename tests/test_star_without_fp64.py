"""The exact star discrepancy without fp64 (the integer path of kernels/star_discrepancy.cl):
the fp64 sweep's double, bit for bit, under ``runtime.without_fp64()`` on PoCL and on a
real device without fp64 where one is installed (Mesa's rusticl on llvmpipe), on random,
jittered, Sobol', lattice and Halton sets, grids whose points share coordinates (many
boxes of equal value: ties), and coordinates at the edges (0, -0.0, subnormal, tiny, near
1); in 2-D and 3-D, n up to a few thousand, and in the short launches a device with a
loop limit runs."""

import numpy as np
import pytest

import clsamp
from clsamp import runtime
from clsamp.metrics import star

DEFAULT = runtime.current_device()
WITHOUT_FP64 = [d for d in runtime.devices()
                if not d.fp64 and not d.simulator and runtime.compiles(d.index)]


def _sampled(name, d, n, **params):
    return lambda: clsamp.make_sampler(name, d=d, seed=11, **params).sample(n)


def _grid(d, n, m, seed):
    """n points on the grid k / m: many shared coordinates, boxes of equal value."""
    return lambda: np.random.default_rng(seed).integers(0, m, (n, d)) / m


def _edges(d):
    def make():
        p = np.random.default_rng(d).random((300, d))
        p[:30] *= 1e-310                      # subnormal
        p[30:60] *= 1e-200                    # volumes below 2^-600
        p[60:70] = 0.0
        p[70, 0] = p[71, 1] = -0.0
        p[80:120] = 1.0 - p[80:120] * 1e-12   # near 1
        p[120:130] = p[130:140]               # repeated points
        return p
    return make


SETS = {
    "random-2d": _sampled("random", 2, 3000),
    "jittered-2d": _sampled("jittered", 2, 2500),
    "sobol-2d": _sampled("sobol", 2, 4096),
    "sobol-owen-2d": _sampled("sobol", 2, 1024, randomize="owen"),
    "lattice-2d": _sampled("lattice", 2, 2048),
    "halton-2d": _sampled("halton", 2, 1000),
    "grid-2d": _grid(2, 1500, 16, 1),
    "edges-2d": _edges(2),
    "random-3d": _sampled("random", 3, 400),
    "jittered-3d": _sampled("jittered", 3, 343),
    "sobol-3d": _sampled("sobol", 3, 512),
    "lattice-3d": _sampled("lattice", 3, 512),
    "grid-3d": _grid(3, 300, 6, 2),
    "edges-3d": _edges(3),
}


def _bits(value):
    return np.asarray(value, dtype=np.float64).view(np.uint64)


@pytest.mark.parametrize("name", list(SETS))
def test_without_fp64_the_value_is_the_fp64_bits(name):
    pts = SETS[name]()
    want = clsamp.star_discrepancy(pts)
    with runtime.without_fp64():
        got = clsamp.star_discrepancy(pts)
    assert _bits(got) == _bits(want), (got, want)
    if pts.shape[1] == 2:                          # and the NumPy twin's
        assert _bits(star.star_discrepancy_reference(pts + 0.0)) == _bits(want)


def test_small_sets_and_batches_without_fp64():
    rng = np.random.default_rng(3)
    for d in (2, 3):
        for n in (1, 2, 3, 5, 8):
            pts = rng.random((n, d))
            with runtime.without_fp64():
                got = clsamp.star_discrepancy(pts)
            assert _bits(got) == _bits(star.star_discrepancy_brute(pts)), (d, n)
        batch = rng.random((3, 70, d))
        want = clsamp.star_discrepancy(batch)
        with runtime.without_fp64():
            assert np.array_equal(_bits(clsamp.star_discrepancy(batch)), _bits(want))
    with runtime.without_fp64():
        assert clsamp.star_discrepancy(np.zeros((5, 3))) == 1.0


def test_near_ties_are_resolved_exactly():
    """Lattice points moved by up to 3e-7 of themselves: many boxes whose values differ by
    less than their float estimates can tell apart, where the exact evaluation of every box
    within the estimates' margin of the best decides (without the margin, 4 of these 200
    sets lose their largest box)."""
    for seed in range(200):
        rng = np.random.default_rng(seed)
        d = 2 + seed % 2
        base = clsamp.make_sampler("lattice", d=d, seed=seed).sample(256 if d == 2 else 64)
        pts = np.minimum(base * (1 + rng.uniform(-3e-7, 3e-7, base.shape)), 1 - 2.0**-53)
        want = clsamp.star_discrepancy(pts)
        with runtime.without_fp64():
            assert _bits(clsamp.star_discrepancy(pts)) == _bits(want), seed


@pytest.mark.parametrize("name", ["sobol-2d", "lattice-3d", "grid-3d", "edges-2d"])
def test_launches_of_few_points_give_the_same_bits(monkeypatch, name):
    """What a device with a loop limit runs (llvmpipe: 65535 iterations a work-item): the
    sweep in launches of a few points, its counts and best values carried between them."""
    pts = SETS[name]()
    want = clsamp.star_discrepancy(pts)
    monkeypatch.setattr(runtime.discovery, "loop_limit", lambda: 1000)
    with runtime.without_fp64():
        assert _bits(clsamp.star_discrepancy(pts)) == _bits(want)


@pytest.mark.skipif(not WITHOUT_FP64, reason="no device without fp64 here")
@pytest.mark.parametrize("name", ["random-2d", "sobol-2d", "lattice-2d", "grid-2d", "edges-2d",
                                  "jittered-3d", "grid-3d", "edges-3d"])
def test_a_device_without_fp64_gives_the_fp64_bits(name):
    pts = SETS[name]()
    want = clsamp.star_discrepancy(pts)
    for device in WITHOUT_FP64:
        runtime.use_device(device.index)
        try:
            got = clsamp.star_discrepancy(pts)
        finally:
            runtime.use_device(DEFAULT.index)
        assert _bits(got) == _bits(want), (str(device), got, want)
