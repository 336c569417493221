"""Blue noise through optimal transport (``bnot``): the device and the NumPy twin give the
same bits; the cells are exact in capacity and the sites their centroids; Newton lowers the
weight solve's count error; the transport cost never rises; quality at n = 1024 in 2-D
against Poisson disk measured in the same test. The contract matrix
(test_sampler_contract.py) covers shapes, seeds, realizations and chunks."""

import math

import numpy as np
import pytest

import clsamp
from clsamp import spectral_stats
from clsamp.errors import InvalidArgumentError
from clsamp.geometry import integer_torus as it
from clsamp.metrics import relative_radius
from clsamp.samplers import bnot
from clsamp.samplers.ccvt.density import density_points
from clsamp.samplers.ccvt.power import PowerPass, start_grid_size
from clsamp.samplers.optimizer import initial_sites


def low_frequency_power(points):
    """Mean periodogram power over the integer frequencies 0 < |w| < sqrt(n) / 2."""
    n = points.shape[-2]
    resolution = 2 * math.ceil(math.sqrt(n) / 2) + 2
    P = clsamp.power_spectrum(points, resolution=resolution, method="direct", progress=False)
    return spectral_stats.low_frequency_power(P, n)


@pytest.mark.parametrize("n, p, density", [(64, 32, "jittered"), (150, 16, "random"),
                                           (3, 10, "jittered")])
def test_the_device_gives_the_twins_bits(n, p, density):
    kw = dict(seed=5, points_per_site=p, iterations=6, density=density)
    a, ia = clsamp.make_sampler("bnot", **kw).sample(n, realizations=2, return_info=True)
    b, ib = clsamp.make_sampler("bnot", backend="numpy", **kw).sample(n, realizations=2,
                                                                       return_info=True)
    assert np.array_equal(a, b)
    for field in ("energy_history", "dual_history", "newton_steps", "capacities",
                  "iterations", "converged"):
        assert np.array_equal(getattr(ia, field), getattr(ib, field)), field


def _cells(n, p, seed=1):
    sites = initial_sites(seed, [0], n)[0].astype(np.int64)
    points = density_points(seed, [0], n * p)[0].astype(np.int64)
    return sites, points


def test_newton_lowers_the_count_error():
    # jittered sites: cells of unequal size, none empty
    n, p = 196, 64
    points = _cells(n, p)[1]
    sites = it.to_torus(clsamp.make_sampler("jittered", seed=2).sample(n)).astype(np.int64)
    power = PowerPass(sites[None].astype(np.uint32), start_grid_size(n), "numpy")
    pts32 = points[None].astype(np.uint32)

    def cells(weights):
        return tuple(a[0] for a in power(pts32, weights[None]))

    def error(w):
        owner = cells(w)[0].astype(np.int64)
        return int(np.abs(np.bincount(owner, minlength=n) - p).sum())

    zero = np.zeros(n, dtype=np.int64)
    w, owner, dual, steps = bnot.solve_weights(points, sites, zero, p, cells)
    assert steps >= 1
    assert error(w) < error(zero) / 4
    counts = np.bincount(owner.astype(np.int64), minlength=n)
    # the dual at w equals sum of power distances plus p sum w, exactly
    d2 = it.distance2(points[:, 0], points[:, 1], sites[owner, 0], sites[owner, 1])
    assert dual == int(d2.sum()) - int(w[owner.astype(np.int64)].sum()) + p * int(w.sum())
    assert counts.sum() == n * p


def test_the_cells_are_exact_in_capacity():
    # the power cells of the Newton weights (counts within a few points of p) made exact:
    # every site gets p points, every point one site, at nearly the power cells' cost
    n, p = 121, 40
    points = _cells(n, p, seed=7)[1]
    sites = it.to_torus(clsamp.make_sampler("jittered", seed=7).sample(n)).astype(np.int64)
    power = PowerPass(sites[None].astype(np.uint32), start_grid_size(n), "numpy")

    def cells(weights):
        return tuple(a[0] for a in power(points[None].astype(np.uint32), weights[None]))

    w, owner, _, _ = bnot.solve_weights(points, sites, np.zeros(n, dtype=np.int64), p, cells)
    counts = np.bincount(owner.astype(np.int64), minlength=n)
    assert np.any(counts != p) and np.abs(counts - p).max() <= 4
    label = bnot._exact_cells(sites, points, owner, p)
    assert np.array_equal(np.bincount(label, minlength=n), np.full(n, p))
    before = bnot._cost_and_centroids(sites, points, owner.astype(np.int64), n)[0]
    exact = bnot._cost_and_centroids(sites, points, label, n)[0]
    assert exact < 1.02 * before
    out, info = bnot.bnot_optimize(sites[None].astype(np.uint32), points[None], p,
                                   iterations=5, backend="numpy")
    assert np.all(info.capacities == p)
    assert np.all(np.diff(info.energy_history[0]) <= 0)


def test_the_centroid_step_is_the_rounded_mean():
    n, p = 30, 20
    sites, points = _cells(n, p, seed=3)
    label = np.repeat(np.arange(n), p)[np.random.default_rng(0).permutation(n * p)]
    before, moved, after = bnot._cost_and_centroids(sites, points, label, n)
    for i in range(n):
        mine = points[label == i]
        for axis in (0, 1):
            d = it.delta(mine[:, axis], sites[i, axis])
            mean = (2 * d.sum() + len(d)) // (2 * len(d))
            assert moved[i, axis] == (sites[i, axis] + mean) & it.MASK
    assert after <= before


def test_the_cost_never_rises():
    _, info = clsamp.make_sampler("bnot", seed=4, points_per_site=64, tol=0,
                                  iterations=20).sample(256, realizations=2, return_info=True)
    assert np.all(np.diff(info.energy_history, axis=1) <= 0)
    assert np.all(info.capacities == 64)
    assert np.all(info.energy_history[:, -1] < info.energy_history[:, 0])


@pytest.mark.slow
@pytest.mark.parametrize("cells", ["points", "exact"])
def test_quality_against_poisson_disk(cells):
    # the figure: rho >= 0.75 and low-frequency power at most a seventh of
    # Poisson disk's, n = 1024, three seeds, Poisson disk measured here too
    n = 1024
    pd = np.mean([low_frequency_power(clsamp.make_sampler("poisson_disk", seed=s).sample(n))
                  for s in (1, 2, 3)])
    for seed in (1, 2, 3):
        pts, info = clsamp.make_sampler("bnot", seed=seed, cells=cells,
                                        progress=False).sample(n, return_info=True)
        if cells == "points":
            assert np.all(info.capacities == bnot.POINTS_PER_SITE)
        assert relative_radius(pts) >= 0.75, seed
        assert low_frequency_power(pts) <= pd / 7, seed


@pytest.mark.parametrize("kw, name", [({"points_per_site": 0}, "points_per_site"),
                                      ({"iterations": 0}, "iterations"),
                                      ({"tol": -1.0}, "tol"),
                                      ({"density": "blue"}, "density"),
                                      ({"newton": -1}, "newton"),
                                      ({"d": 3}, "d")])
def test_bad_arguments_are_refused_by_name(kw, name):
    with pytest.raises(InvalidArgumentError, match=name):
        clsamp.make_sampler("bnot", **kw)


def test_an_image_density_places_the_sites_by_its_mass():
    # a bump four times the background in a disk of radius 0.15: the share of sites in
    # it equals the share of the density's mass (the cells hold equal masses)
    def bump(p):
        return 1.0 + 4.0 * (np.hypot(p[:, 0] - 0.5, p[:, 1] - 0.5) < 0.15)

    n = 400
    kw = dict(seed=1, density=bump, points_per_site=64, iterations=12)
    pts, info = clsamp.make_sampler("bnot", **kw).sample(n, return_info=True)
    assert np.all(info.capacities == 64)
    image = bnot.check_density(bump)
    c = (np.arange(image.shape[0]) + 0.5) / image.shape[0]
    x, y = np.meshgrid(c, c)
    share = (image * (np.hypot(x - 0.5, y - 0.5) < 0.15)).sum() / image.sum()
    inside = (np.hypot(pts[:, 0] - 0.5, pts[:, 1] - 0.5) < 0.15).mean()
    assert abs(inside - share) < 0.03
    assert np.array_equal(pts, clsamp.make_sampler("bnot", backend="numpy", **kw).sample(n))


def test_the_warp_follows_the_image():
    # the warped jittered points fall in each pixel of a 2 x 4 image by its mass
    image = np.array([[1.0, 0.0, 2.0, 1.0], [0.5, 0.5, 3.0, 0.0]])
    pts = it.to_unit(bnot.warp_to_image(density_points(1, [0], 80000)[0], image))
    counts = np.histogram2d(pts[:, 1], pts[:, 0], bins=(2, 4), range=((0, 1), (0, 1)))[0]
    assert np.allclose(counts / counts.sum(), image / image.sum(), atol=2e-3)


@pytest.mark.parametrize("density", [np.zeros((4, 4)), np.full((2, 2), np.nan), -np.ones((3, 3)),
                                     np.ones(5), np.ones((2, 2, 2)), "blue", lambda p: -p[:, 0],
                                     lambda x, y: x, lambda p: np.ones(3), {"a": 1}])
def test_bad_densities_are_refused(density):
    with pytest.raises(InvalidArgumentError, match="density"):
        clsamp.make_sampler("bnot", density=density)


def test_a_density_means_what_it_means_to_gbn():
    # the library's one convention (clsamp.density.as_density): an array's first axis is x,
    # a callable takes points (m, 2); so the same array or callable crowds bnot's sites
    # and gbn's points on the same side
    left = np.array([[4.0], [1.0]])                     # x = 1/4: 4, x = 3/4: 1, along x
    # the multilinear density's mass left of x = 1/2: (1/4 4 + 1/4 3.25) / 2.5
    share = (0.25 * 4.0 + 0.25 * 3.25) / 2.5
    image = bnot.check_density(left)
    assert image.shape == (bnot.IMAGE_SIDE, bnot.IMAGE_SIDE)
    x = (np.arange(image.shape[1]) + 0.5) / image.shape[1]
    assert abs(image[:, x < 0.5].sum() / image.sum() - share) < 1e-3
    assert np.ptp(image, axis=0).max() == 0           # nothing changes along y
    ramp = bnot.check_density(lambda p: 1.0 + 3.0 * (p[:, 0] < 0.5))
    assert np.array_equal(ramp, bnot.check_density(np.where(x < 0.5, 4.0, 1.0)[:, None]
                                                    * np.ones((1, 256))))
    for density in (left, lambda p: 1.0 + 3.0 * (p[:, 0] < 0.5)):
        pts = clsamp.make_sampler("bnot", seed=2, density=density, points_per_site=32,
                                  iterations=4).sample(256)
        gbn = clsamp.make_sampler("gbn", seed=2, density=density, iterations=20).sample(256)
        assert (pts[:, 0] < 0.5).mean() > 0.65 and (gbn[:, 0] < 0.5).mean() > 0.65


def test_a_large_array_is_warped_by_its_own_pixels():
    a = np.random.default_rng(3).random((300, 260)) + 0.1
    image = bnot.check_density(a)
    assert image.shape == (260, 300)
    assert np.array_equal(image, (a / a.mean()).T)
    # the same array, one axis narrower than 256: interpolated along that axis only
    narrow = bnot.check_density(a[:, :100])
    assert narrow.shape == (256, 300)
    assert np.allclose(narrow[[0, -1]], (a[:, [0, 99]] / a[:, :100].mean()).T, rtol=1e-12)


@pytest.mark.parametrize("cells, n", [("points", 64), ("exact", 2)])
def test_tol_zero_runs_every_iteration(cells, n):
    # these sets reach a fixed point (the same cost iteration after iteration) within a
    # few iterations (64 sites of 32 points: 6; 2 exact cells: 17); tol = 0 still runs
    # them all, on both backends, the same bits
    kw = dict(seed=3, tol=0, iterations=24, cells=cells, progress=False,
              **({"points_per_site": 32} if cells == "points" else {}))
    runs = [clsamp.make_sampler("bnot", backend=backend, **kw).sample(n, return_info=True)
            for backend in ("opencl", "numpy")]
    for _, info in runs:
        assert info.iterations.tolist() == [24] and not info.converged.any()
        assert info.energy_history.shape == (1, 24)
        # (exact cells: never rising beyond their tolerance; here the rounding of 1/12)
        assert np.all(np.diff(info.energy_history[0]) <= 1e-15)
    assert np.array_equal(runs[0][0], runs[1][0])
