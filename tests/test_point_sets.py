"""Minimum distance and relative radius: exact against brute force, known lattices, wrap;
N*E of known sets."""

import math

import numpy as np
import pytest

import clsamp
from clsamp.errors import InvalidArgumentError
from clsamp.geometry.torus import distance2 as toroidal_distance2
from clsamp.metrics import (
    max_min_distance,
    min_distance,
    normalized_energy,
    relative_radius,
)


def brute(points):
    diff = np.abs(points[:, None, :] - points[None, :, :])
    diff = np.minimum(diff, 1.0 - diff)
    d2 = (diff ** 2).sum(-1)
    np.fill_diagonal(d2, np.inf)
    return min(math.sqrt(d2.min()), 1.0)


@pytest.mark.parametrize("d", [1, 2, 3])
@pytest.mark.parametrize("n", [2, 50, 700])
def test_min_distance_equals_brute_force(n, d):
    rng = np.random.default_rng(n * 10 + d)
    pts = rng.random((3, n, d))
    got = min_distance(pts)
    assert got.shape == (3,)
    for k in range(3):
        assert got[k] == pytest.approx(brute(pts[k]), rel=1e-15)


def test_min_distance_of_clustered_set_widens_grid():
    # Points far apart except none: a sparse set on a coarse lattice, wider than d_max cells.
    rng = np.random.default_rng(1)
    pts = np.concatenate([rng.random((200, 2)) * 0.01, rng.random((1, 2)) * 0.01 + 0.5])
    assert min_distance(pts) == pytest.approx(brute(pts), rel=1e-15)
    # Two clusters only: the closest pair is inside one cluster.
    pts = np.array([[0.1, 0.1], [0.1, 0.3]] + [[0.6 + 0.001 * i, 0.6] for i in range(100)])
    assert min_distance(pts) == pytest.approx(0.001, rel=1e-9)


def test_min_distance_wraps_around_the_torus():
    pts = np.array([[0.01, 0.5], [0.98, 0.5], [0.5, 0.2]])
    assert min_distance(pts) == pytest.approx(0.03)
    pts = np.array([[0.01, 0.995], [0.5, 0.5], [0.995, 0.01]])
    assert min_distance(pts) == pytest.approx(math.hypot(0.015, 0.015))


def test_single_point_is_one_period_from_its_image():
    assert min_distance(np.array([[0.3, 0.4]])) == 1.0


def test_relative_radius_of_lattices():
    k = 16
    g = (np.stack(np.meshgrid(np.arange(k), np.arange(k)), -1).reshape(-1, 2) + 0.5) / k
    assert relative_radius(g) == pytest.approx(math.sqrt(math.sqrt(3.0) / 2.0), rel=1e-12)
    # A hexagonal lattice fits the torus only approximately: 30 rows 1/30 apart with
    # 26 points each (ideal spacing sqrt(3)/52 = 0.03331) come close to rho = 1.
    rows, cols = 30, 26
    pts = np.array([[(c + 0.5 * (r % 2)) / cols, r / rows] for r in range(rows) for c in range(cols)])
    rho = relative_radius(pts)
    dmin = min(1 / cols, math.hypot(0.5 / cols, 1 / rows))
    assert rho == pytest.approx(dmin / max_min_distance(rows * cols), rel=1e-12)
    assert rho > 0.99


def test_max_min_distance_closed_forms():
    assert max_min_distance(100, 1) == pytest.approx(0.01)
    assert max_min_distance(100, 2) == pytest.approx(math.sqrt(2 / (math.sqrt(3) * 100)))
    assert max_min_distance(100, 3) == pytest.approx((math.sqrt(2) / 100) ** (1 / 3))
    # E8 has kissing radius 1/sqrt(2) at density 1: n points of that lattice scaled to volume 1/n.
    assert max_min_distance(1, 8) == pytest.approx(2 * (math.pi ** 4 / 384 * 24 / math.pi ** 4) ** 0.125)


def test_batch_and_single_shapes_agree():
    rng = np.random.default_rng(3)
    pts = rng.random((4, 300, 2))
    batch = relative_radius(pts)
    assert batch.shape == (4,)
    assert [relative_radius(p) for p in pts] == list(batch)


def test_distance_formula_is_symmetric_and_wraps():
    a = np.array([0.0, 0.9])
    b = np.array([0.9, 0.0])
    assert toroidal_distance2(a, b) == pytest.approx(0.02)
    assert toroidal_distance2(a, b) == toroidal_distance2(b, a)


@pytest.mark.parametrize("bad", [np.array([[0.5, 1.0]]), np.array([[np.nan, 0.1]]),
                                 np.zeros((2, 2), dtype=np.int64), np.zeros(3)])
def test_bad_points_are_refused(bad):
    with pytest.raises(InvalidArgumentError, match="points"):
        min_distance(bad)


def test_relative_radius_refuses_unknown_packing_dimension():
    with pytest.raises(InvalidArgumentError, match="dimensions"):
        relative_radius(np.full((3, 9), 0.5))


def test_normalized_energy_of_known_sets():
    # a square grid: each cell a square of area 1/n, mean squared distance to its centre
    # 1/(6n), less the discreteness of the 64 x 64 density cells inside each square
    g = (np.stack(np.meshgrid(np.arange(16), np.arange(16)), -1).reshape(-1, 2) + 0.5) / 16
    assert normalized_energy(g) == pytest.approx((1 - 1 / 4096) / 6, rel=1e-12)
    shifted = (g + np.array([0.3, 0.7])) % 1.0          # the torus has no preferred origin
    assert normalized_energy(shifted) == pytest.approx(1 / 6, rel=1e-3)
    # white noise: the expectation is 1/pi (Poisson process, nearest-point distance)
    w = np.random.default_rng(3).random((16, 256, 2))
    ne = normalized_energy(w, density=1024)
    assert ne.shape == (16,)
    assert abs(ne.mean() - 1 / np.pi) < 4 * ne.std() / np.sqrt(len(ne))
    small = w[:2, :64]
    assert np.array_equal(normalized_energy(small, density=256),
                          normalized_energy(small, density=256, backend="numpy"))


def test_normalized_energy_refuses_other_dimensions():
    with pytest.raises(InvalidArgumentError, match="'points'"):
        normalized_energy(np.random.default_rng(0).random((10, 3)))
    with pytest.raises(InvalidArgumentError, match="'density'"):
        normalized_energy(np.random.default_rng(0).random((10, 2)), density=0)


def test_device_arrays_are_accepted():
    sampler = clsamp.make_sampler("poisson_disk", seed=2)
    host = sampler.sample(200, realizations=3)
    device = sampler.sample_device(200, realizations=3)
    assert np.array_equal(min_distance(device), min_distance(host))
    assert np.array_equal(relative_radius(device), relative_radius(host))
    assert np.array_equal(normalized_energy(device), normalized_energy(host))
    assert normalized_energy(sampler.sample_device(200)) == normalized_energy(host[0])


def test_to_torus_on_the_device_equals_numpy():
    import pyopencl.array as cla

    from clsamp import runtime
    from clsamp.geometry import integer_torus
    x = np.concatenate([np.random.default_rng(4).random((999, 2)),
                        [[0.0, 1 - 2.0**-53], [0.5, 2.0**-22], [2.0**-22 - 2.0**-60, 0.75]]])
    on_device = integer_torus.to_torus(cla.to_device(runtime.queue(), x))
    assert on_device.dtype == np.uint32 and np.array_equal(on_device.get(), integer_torus.to_torus(x))
