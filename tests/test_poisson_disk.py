"""The poisson_disk sampler: fixed n at a relative radius, maximal sets, the kernels
against the NumPy reference, and bad input."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

import clsamp
from clsamp import runtime
from clsamp.errors import InvalidArgumentError
from clsamp.metrics import max_min_distance, min_distance, relative_radius
from clsamp.samplers import poisson_disk
from clsamp.samplers.poisson_disk import sampler as poisson_sampler


def uncovered(points, radius, probes):
    """The probes r or more from every point (toroidal), exactly: candidates from a
    periodic k-d tree, then the distance recomputed as the sampler computes it."""
    tree = cKDTree(points, boxsize=1.0)
    dist, _ = tree.query(probes, k=1)
    return probes[dist >= radius * (1.0 - 1e-12)]


def probe_grid(k, d):
    axes = [(np.arange(k) + 0.5) / k] * d
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, d)


@pytest.mark.parametrize("d, n, r", [(2, 256, 6), (3, 256, 3), (4, 256, 2)])
def test_fixed_n_reaches_rho_in_every_realization(d, n, r):
    sampler = clsamp.make_sampler("poisson_disk", d=d, rho=0.75, seed=5)
    pts, info = sampler.sample(n, realizations=r, return_info=True)
    assert pts.shape == (r, n, d) and pts.dtype == np.float64
    assert pts.min() >= 0.0 and pts.max() < 1.0
    rho = relative_radius(pts)
    assert np.all(rho >= 0.75), rho
    assert np.all(info.counts == n) and info.realizations.tolist() == list(range(r))
    assert info.radius == pytest.approx(0.75 * max_min_distance(n, d))
    assert np.all(info.rho_bound <= rho) and info.darts > 0 and info.rounds > 0
    for i in range(r):
        for j in range(i):
            assert not np.array_equal(pts[i], pts[j])


def test_default_rho_is_075_and_interfaces_used_elsewhere():
    pts = clsamp.make_sampler("poisson_disk", d=2, seed=1).sample(256, realizations=8)
    assert pts.shape == (8, 256, 2) and np.all(relative_radius(pts) >= 0.75)
    one = clsamp.make_sampler("poisson_disk", d=2, seed=1).sample(256)
    np.testing.assert_array_equal(one, pts[0])


def test_realization_k_does_not_depend_on_how_many_were_asked():
    sampler = clsamp.make_sampler("poisson_disk", seed=3)
    five = sampler.sample(128, realizations=5)
    np.testing.assert_array_equal(sampler.sample(128, realizations=2), five[:2])


def test_same_seed_same_set_other_seed_other_set():
    a = clsamp.make_sampler("poisson_disk", seed=11).sample(200, realizations=2)
    b = clsamp.make_sampler("poisson_disk", seed=11).sample(200, realizations=2)
    np.testing.assert_array_equal(a, b)
    c = clsamp.make_sampler("poisson_disk", seed=12).sample(200, realizations=2)
    assert not np.array_equal(a, c)
    s = clsamp.make_sampler("poisson_disk", radius=0.06, seed=11)
    np.testing.assert_array_equal(s.sample(), s.sample())


@pytest.mark.parametrize("d, n, r, rho", [(1, 40, 3, 0.7), (2, 64, 3, 0.75), (3, 64, 2, 0.75),
                                               (4, 32, 1, 0.75), (5, 64, 2, 0.65),
                                               (6, 48, 2, 0.65), (7, 48, 2, 0.7),
                                               (8, 64, 2, 0.65)])
def test_kernel_equals_numpy_reference_fixed_n(d, n, r, rho):
    kw = dict(d=d, seed=2**40 + 9, rho=rho)
    cl = clsamp.make_sampler("poisson_disk", **kw).sample(n, realizations=r)
    ref = clsamp.make_sampler("poisson_disk", backend="numpy", **kw).sample(n, realizations=r)
    np.testing.assert_array_equal(cl, ref)


def test_coarse_kernels_equal_numpy_reference_through_the_cells():
    # d >= 5 finds neighbours through cells at least r wide: 4 per axis here, so the 3^5
    # stencil wraps around the torus (the sets above have one cell, every pair)
    kw = dict(d=5, radius=0.15, seed=5)
    sampler = clsamp.make_sampler("poisson_disk", **kw)
    assert sampler._geometry(2048).G == 4
    a, info = sampler.sample(2048, return_info=True)
    b, ref_info = clsamp.make_sampler("poisson_disk", backend="numpy", **kw).sample(
        2048, return_info=True)
    np.testing.assert_array_equal(a, b)
    assert (info.rounds, info.darts) == (ref_info.rounds, ref_info.darts)
    assert min_distance(a) >= 0.15


@pytest.mark.parametrize("d, n", [(4, 512), (5, 512), (6, 256), (7, 256), (8, 512)])
def test_a_d_dimensional_poisson_disk_set_keeps_its_radius(d, n):
    sampler = clsamp.make_sampler("poisson_disk", d=d, seed=3)
    assert sampler.rho == (0.75 if d <= 4 else 0.65)
    pts, info = sampler.sample(n, realizations=2, return_info=True)
    assert pts.shape == (2, n, d) and pts.min() >= 0.0 and pts.max() < 1.0
    assert np.all(min_distance(pts) >= info.radius)
    assert np.all(relative_radius(pts) >= sampler.rho)
    assert info.radius == pytest.approx(sampler.rho * max_min_distance(n, d))
    # and not far above it: the points are packed, not merely spread
    assert np.all(relative_radius(pts) < sampler.rho + 0.1)


def test_maximal_sets_beyond_4d_are_refused_naming_d():
    sampler = clsamp.make_sampler("poisson_disk", d=5, radius=0.3, seed=1)
    assert sampler.needs_n
    for call in (sampler.sample, lambda: sampler.sample_sets(2)):
        with pytest.raises(InvalidArgumentError, match="'d'=5: maximal sets .* d <= 4"):
            call()
    pts = sampler.sample(40, realizations=2)
    assert pts.shape == (2, 40, 5) and np.all(min_distance(pts) >= 0.3)


def test_kernel_equals_numpy_reference_with_redraws():
    # At n = 16 a few realizations become maximal below n and are drawn again.
    cl = clsamp.make_sampler("poisson_disk", seed=1)
    ref = clsamp.make_sampler("poisson_disk", seed=1, backend="numpy")
    a, info = cl.sample(16, realizations=64, return_info=True)
    b, ref_info = ref.sample(16, realizations=64, return_info=True)
    assert info.redraws > 0
    assert (info.rounds, info.darts, info.redraws) == (ref_info.rounds, ref_info.darts,
                                                       ref_info.redraws)
    np.testing.assert_array_equal(a, b)
    assert np.all(relative_radius(a) >= 0.75)


@pytest.mark.parametrize("d, radius", [(2, 0.07), (3, 0.2), (4, 0.45)])
def test_kernel_equals_numpy_reference_maximal(d, radius):
    cl = clsamp.make_sampler("poisson_disk", d=d, radius=radius, seed=7)
    ref = clsamp.make_sampler("poisson_disk", d=d, radius=radius, seed=7, backend="numpy")
    a, info = cl.sample(return_info=True)
    b, ref_info = ref.sample(return_info=True)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(info.counts, ref_info.counts)
    assert info.counts.tolist() == [len(a)]


def _bits(points):
    return [np.ascontiguousarray(p).view(np.uint64) for p in points]


@pytest.mark.parametrize("d, n, seed, params", [
    (2, 256, 2**40 + 9, {}), (2, 64, 4, {}), (3, 128, 5, {}), (4, 32, 6, {}),
    (5, 2048, 5, {"radius": 0.15}),        # through 4^5 cells (the coarse kernels' stencil)
    (6, 96, 8, {})])
def test_without_fp64_a_fixed_n_has_the_same_bits(d, n, seed, params):
    """Every double of the dart-throwing kernels by integer arithmetic (kernels/f64bits.h),
    as a device without fp64 computes it: the bits of the fp64 path and of the NumPy twin
    (fine grid in d <= 4, the coarse kernels in d >= 5)."""
    s = clsamp.make_sampler("poisson_disk", d=d, seed=seed, **params)
    assert not s.needs_fp64
    here = s.sample(n, realizations=range(1, 3))
    with runtime.without_fp64():
        there = s.sample(n, realizations=range(1, 3))
    assert np.array_equal(_bits([here]), _bits([there]))
    if n <= 256:
        ref = clsamp.make_sampler("poisson_disk", d=d, seed=seed, backend="numpy",
                                  **params).sample(n, realizations=range(1, 3))
        assert np.array_equal(_bits([ref]), _bits([there]))


@pytest.mark.parametrize("d, radius, seed", [(2, 0.04, 3), (2, 0.1, 11), (3, 0.13, 4),
                                             (4, 0.35, 2)])
def test_without_fp64_a_maximal_set_has_the_same_bits(d, radius, seed):
    """Maximal sets (every refinement level of the voids) by integer arithmetic: the bits
    of the fp64 path, set by set."""
    s = clsamp.make_sampler("poisson_disk", d=d, radius=radius, seed=seed)
    here = s.sample_sets(range(2, 4))
    with runtime.without_fp64():
        there = s.sample_sets(range(2, 4))
    assert [len(p) for p in here] == [len(p) for p in there]
    assert all(np.array_equal(a, b) for a, b in zip(_bits(here), _bits(there), strict=True))


@pytest.mark.parametrize("d, radius, k", [(2, 0.03, 600), (3, 0.11, 64), (4, 0.2, 12)])
def test_maximal_set_leaves_no_void(d, radius, k):
    sampler = clsamp.make_sampler("poisson_disk", d=d, radius=radius, seed=4)
    pts, info = sampler.sample(return_info=True)
    assert pts.shape == (info.counts[0], d) and not sampler.needs_n
    assert min_distance(pts) >= radius
    rng = np.random.default_rng(0)
    probes = np.concatenate([probe_grid(k, d), rng.random((200_000, d))])
    assert uncovered(pts, radius, probes).size == 0
    # the probes do see a void: drop one point and its neighbourhood opens up (in 4-D that
    # void is too small for the probes to hit for sure; its centre is r from the rest)
    if d == 4:
        probes = np.concatenate([probes, pts[:1]])
    assert uncovered(pts[1:], radius, probes).size > 0
    # and maximal dart throwing lands where the literature puts it (rho about 0.7-0.8 in 2-D)
    if d == 2:
        assert 0.68 < relative_radius(pts) < 0.80
    if d == 4:  # random sequential addition saturates at a density of about 0.256 (Torquato
        # et al. 2006), rho = (0.256 / 0.6169)^(1/4) = 0.80 of the D4 lattice's spacing
        assert 0.78 < relative_radius(pts) < 0.83


def test_sample_device_and_sample_sets():
    sampler = clsamp.make_sampler("poisson_disk", rho=0.75, seed=2)
    on_device = sampler.sample_device(256, realizations=3)
    assert on_device.shape == (3, 256, 2)
    np.testing.assert_array_equal(on_device.get(), sampler.sample(256, realizations=3))
    maximal = clsamp.make_sampler("poisson_disk", radius=0.08, seed=2)
    sets = maximal.sample_sets(3)
    assert len(sets) == 3 and len({len(s) for s in sets}) >= 2
    np.testing.assert_array_equal(sets[0], maximal.sample())
    np.testing.assert_array_equal(maximal.sample_device().get(), sets[0])
    assert maximal.sample(realizations=1).shape == (1, len(sets[0]), 2)
    later, info = maximal.sample_sets(range(1, 3), return_info=True)
    assert all(np.array_equal(a, b) for a, b in zip(later, sets[1:], strict=True))
    assert info.counts.tolist() == [len(x) for x in sets[1:]]
    np.testing.assert_array_equal(maximal.sample(realizations=range(2, 3))[0], sets[2])


def test_batches_give_the_same_sets(monkeypatch):
    sampler = clsamp.make_sampler("poisson_disk", seed=6)
    whole = sampler.sample(100, realizations=5)
    monkeypatch.setattr(poisson_sampler, "BATCH_CELLS", 700)   # two realizations per batch
    np.testing.assert_array_equal(sampler.sample(100, realizations=5), whole)


def test_radius_with_n_gives_exactly_n_points_r_apart():
    sampler = clsamp.make_sampler("poisson_disk", radius=0.05, seed=8)
    pts = sampler.sample(150, realizations=2)
    assert pts.shape == (2, 150, 2) and np.all(min_distance(pts) >= 0.05)


@pytest.mark.parametrize("params, name", [
    ({"radius": 0.0}, "radius"), ({"radius": -0.1}, "radius"), ({"radius": 0.51}, "radius"),
    ({"rho": 0.91}, "rho"), ({"rho": 0.0}, "rho"),
    ({"rho": -1.0}, "rho"), ({"rho": 0.7, "radius": 0.1}, "radius"), ({"d": 9}, "d"),
    ({"d": 0}, "d"),
    # in 1-D a disk of radius 1/2 leaves only the antipode, which no dart hits: the run
    # ended in "did not finish ... (a bug: please report it)"
    ({"d": 1, "radius": 0.5}, "radius"),
])
def test_bad_parameters_name_the_argument(params, name):
    with pytest.raises(InvalidArgumentError, match=f"'{name}'"):
        clsamp.make_sampler("poisson_disk", **params)


def test_bad_calls_name_the_argument():
    sampler = clsamp.make_sampler("poisson_disk", seed=1)
    for n in (0, -3):
        with pytest.raises(InvalidArgumentError, match="'n'"):
            sampler.sample(n)
    with pytest.raises(InvalidArgumentError, match="'n'"):
        sampler.sample()
    with pytest.raises(InvalidArgumentError, match="'start'"):
        sampler.sample(16, start=3)
    with pytest.raises(InvalidArgumentError, match="'realizations'"):
        clsamp.make_sampler("poisson_disk", radius=0.1).sample(realizations=3)
    # maximal sets by sample_sets: realization 2^32 + k was realization k
    with pytest.raises(InvalidArgumentError, match=r"'realizations' must lie in \[0, 4294967295\]"):
        clsamp.make_sampler("poisson_disk", radius=0.1).sample_sets(range(2**32, 2**32 + 1))
    # an n too large for the grid names n and rho (it named n alone)
    with pytest.raises(InvalidArgumentError,
                       match=r"'n'=4194304 with 'rho'=0.75 is too much .* 3.6\de\+07 cells"):
        clsamp.make_sampler("poisson_disk", d=3).sample(2**22)
    # from 5-D on the darts are numbered in 26 bits (a plain ValueError before)
    with pytest.raises(InvalidArgumentError, match=r"'n' must be below 2\^26 for d >= 5"):
        clsamp.make_sampler("poisson_disk", d=5).sample(2**26)
    assert clsamp.make_sampler("poisson_disk", d=8, radius=1e-310).sample(20).shape == (20, 8)


@pytest.mark.parametrize("d, radius", [(2, 1e-5), (3, 0.001), (4, 0.02), (3, 1e-310), (1, 5e-324)])
def test_a_radius_too_small_for_a_maximal_set_still_gives_n_points(d, radius):
    # such a radius was refused when the sampler was made, even for a fixed n (4-D below
    # 0.031); a maximal set is refused when asked for, naming the radius
    sampler = clsamp.make_sampler("poisson_disk", d=d, radius=radius, seed=4)
    for call in (sampler.sample, lambda: sampler.sample_sets(2)):
        with pytest.raises(InvalidArgumentError, match=f"'radius'={radius} is too small for a "
                           f"maximal set in d={d}: .* give n"):
            call()
    pts = sampler.sample(20, realizations=3)
    assert pts.shape == (3, 20, d) and np.all(min_distance(pts) >= radius)


@pytest.mark.parametrize("d, radius, n", [(2, 0.01, 16), (3, 0.01, 16), (4, 0.05, 40), (1, 1e-4, 30)])
def test_a_sparse_fixed_n_is_thrown_into_the_whole_torus(d, radius, n):
    # 16 points at 0.01 in 3-D searched a fine grid of 5.2 M cells: 50 s for 8 sets; more
    # than COARSE_SPARSE cells a point now take the coarse kernels, the same bits everywhere
    kw = dict(d=d, radius=radius, seed=6)
    sampler = clsamp.make_sampler("poisson_disk", **kw)
    assert type(sampler._geometry(n)).__name__ == "CoarseGeometry"
    a, info = sampler.sample(n, realizations=8, return_info=True)
    b, ref_info = clsamp.make_sampler("poisson_disk", backend="numpy", **kw).sample(
        n, realizations=8, return_info=True)
    np.testing.assert_array_equal(a, b)
    assert (info.rounds, info.darts) == (ref_info.rounds, ref_info.darts)
    assert np.all(min_distance(a) >= radius)
    # the default rho keeps the fine grid
    assert type(clsamp.make_sampler("poisson_disk", d=d)._geometry(n)).__name__ == "Geometry"


def test_unplaceable_n_says_so_and_suggests_a_smaller_rho():
    with pytest.raises(InvalidArgumentError, match="cannot be placed.*smaller 'rho'"):
        clsamp.make_sampler("poisson_disk", rho=0.85, seed=1).sample(64)
    with pytest.raises(InvalidArgumentError, match="cannot be placed.*64 rounds.*smaller 'rho'"):
        clsamp.make_sampler("poisson_disk", d=6, rho=0.85, seed=1).sample(64)
    with pytest.raises(InvalidArgumentError, match="cannot be placed"):
        clsamp.make_sampler("poisson_disk", radius=0.2, seed=1).sample(40)


def test_acceptance_threshold_keeps_the_promise_to_the_last_ulp():
    import math
    for n in range(1, 3000):
        d_max = max_min_distance(n, 2)
        r2 = poisson_disk.acceptance_threshold(0.75 * d_max, d_max, 0.75)
        assert math.sqrt(r2) / d_max >= 0.75 and math.sqrt(r2) >= 0.75 * d_max
    for radius in (0.1, 0.01215, 1 / 3, 0.5):
        assert math.sqrt(poisson_disk.acceptance_threshold(radius)) >= radius


@pytest.mark.slow
def test_benchmark_sizes_hold_their_promises():
    # the maximal case (about 4.7k points) and the tour's largest fixed-n batch
    sampler = clsamp.make_sampler("poisson_disk", radius=0.01215, seed=1)
    pts = sampler.sample()
    assert 4500 < len(pts) < 5000 and min_distance(pts) >= 0.01215
    rng = np.random.default_rng(1)
    probes = np.concatenate([probe_grid(1024, 2), rng.random((500_000, 2))])
    assert uncovered(pts, 0.01215, probes).size == 0
    fixed = clsamp.make_sampler("poisson_disk", rho=0.75, seed=2).sample(1024, realizations=128)
    assert np.all(relative_radius(fixed) >= 0.75)


def test_a_maximal_set_that_ends_on_a_gap_of_no_measure():
    # at this radius and seed two subcells at the crossing of two circles stay after 30
    # levels: no disk alone covers them, the union does; the set is maximal (it raised
    # "did not finish in 2048 rounds / 30 levels" before)
    from scipy.spatial import cKDTree
    r = 0.0004653110621747719
    pts = clsamp.make_sampler("poisson_disk", radius=r, seed=1).sample_sets(1)[0]
    tree = cKDTree(pts, boxsize=1.0)
    assert tree.query(pts, k=2)[0][:, 1].min() >= r
    probe = clsamp.make_sampler("random", seed=5).sample(200_000)
    assert tree.query(probe, k=1)[0].max() < r


def test_a_fixed_n_at_a_radius_whose_grid_is_too_large_names_both():
    # radius mode with n on the fine grid had no limit once the constructor's check moved to
    # maximal sets: 70 000 points at 3.45e-4 built 16.8 M cells (2.25 GB)
    with pytest.raises(InvalidArgumentError,
                       match=r"'n'=70000 with 'radius'=0.000345 is too much .* 1.68e\+07"):
        clsamp.make_sampler("poisson_disk", radius=3.45e-4).sample(70000)
