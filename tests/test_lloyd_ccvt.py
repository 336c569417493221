"""Lloyd relaxation and CCVT: kernels against their NumPy references, the energy never
rising, exact capacities, degenerate starts, quality, bad input. Sizes are small: the
references are exact twins, so a small case checks every branch."""

import math

import numpy as np
import pytest
from scipy.spatial import cKDTree

import clsamp
from clsamp import metrics, philox, runtime
from clsamp.errors import InvalidArgumentError
from clsamp.geometry import integer_torus as it
from clsamp.geometry import voronoi
from clsamp.samplers import lloyd
from clsamp.samplers.ccvt import density, device, pairs, power, reference, relay, start
from clsamp.samplers.ccvt.sampler import ccvt_optimize
from clsamp.samplers.optimizer import initial_sites


def _degenerate_starts(n):
    duplicates = np.full((n, 2), 0.3)                       # every site at one point
    rng = np.random.default_rng(5)
    cluster = 0.5 + 1e-4 * rng.random((n, 2))               # all in one tiny cell
    half = np.concatenate([np.full((n // 2, 2), 0.7), rng.random((n - n // 2, 2))])
    return np.stack([duplicates, cluster, half])


# -- the integer torus -----------------------------------------------------------------
def test_round_mean_is_the_nearest_integer():
    s = np.array([-7, -6, -5, -1, 0, 1, 5, 6, 7])
    assert it.round_mean(s, 4).tolist() == [-2, -1, -1, 0, 0, 0, 1, 2, 2]


def test_delta_wraps():
    assert it.delta(0, it.SIZE - 1) == 1
    assert it.delta(it.SIZE - 1, 0) == -1
    assert it.delta(it.HALF, 0) == -it.HALF


# -- Lloyd -------------------------------------------------------------------------------
def test_lloyd_kernel_equals_reference():
    sites = initial_sites(4, np.arange(3), 37)
    g = voronoi.density_side(37, 20)
    a = lloyd.lloyd_device(sites, g, 6)
    b = lloyd.lloyd_reference(sites, g, 6)
    assert np.array_equal(a[0], b[0])
    assert a[1] == b[1]                      # exact integer energies, every pass
    assert np.array_equal(a[2], b[2])        # cell sizes of the final assignment


def test_lloyd_sampler_backends_agree_and_energy_never_rises():
    kw = dict(d=2, seed=9, iterations=12, density=32)
    s = clsamp.make_sampler("lloyd", **kw)
    pts, info = s.sample(50, realizations=3, return_info=True)
    ref, ref_info = clsamp.make_sampler("lloyd", backend="numpy", **kw).sample(
        50, realizations=3, return_info=True)
    assert np.array_equal(pts, ref)
    assert np.array_equal(info.energy_history, ref_info.energy_history)
    assert info.energy_history.shape == (3, 12)
    assert np.all(np.diff(info.energy_history, axis=1) <= 0)
    assert np.all(info.energy_history[:, -1] < info.energy_history[:, 0])
    # one set: still a history per realization; realization k does not depend on the others
    one, one_info = s.sample(50, return_info=True)
    assert one_info.energy_history.shape == (1, 12) and one_info.realizations.tolist() == [0]
    assert np.array_equal(one, pts[0])
    assert np.array_equal(s.sample(50, realizations=5)[:3], pts)
    tail, tail_info = s.sample(50, realizations=range(1, 3), return_info=True)
    assert np.array_equal(tail, pts[1:]) and tail_info.realizations.tolist() == [1, 2]
    assert np.array_equal(tail_info.energy_history, info.energy_history[1:])


def test_lloyd_quality():
    s = clsamp.make_sampler("lloyd", seed=2, iterations=40, density=128)
    pts, info = s.sample(128, realizations=2, return_info=True)
    ne = 128 * info.energy_history[:, -1]               # N*E on the sampler's density grid
    assert np.all(ne < 0.168)                           # white noise: 1/pi
    assert np.all(ne > metrics.HEXAGONAL_NE)
    assert np.all(metrics.normalized_energy(pts, density=128) == ne)
    assert np.all(metrics.relative_radius(pts) > 0.6)


def test_lloyd_degenerate_starts_recover():
    starts = _degenerate_starts(20)
    points, a = lloyd.lloyd_relax(starts, density=16, iterations=15)
    ref, b = lloyd.lloyd_relax(starts, density=16, iterations=15, backend="numpy")
    assert np.array_equal(points, ref)
    assert np.array_equal(a.energy_history, b.energy_history)
    assert np.all(a.counts > 0)                            # no site left with an empty cell
    assert np.all(np.diff(a.energy_history, axis=1) <= 0)
    assert np.all(a.energy_history[:, 0] <= a.initial_energy)
    assert np.all(metrics.min_distance(points) > 0)


# -- Lloyd in 1, 3 and 4 dimensions (issue 37) ---------------------------------------------
@pytest.mark.parametrize("d, n, density", [(1, 30, 12), (3, 40, 16), (4, 24, 12)])
def test_lloyd_kernel_equals_reference_in_other_dimensions(d, n, density):
    sites = initial_sites(6, np.arange(2), n, d=d)
    g = voronoi.density_side(n, density, d)
    assert g**d >= n * density > (g - 1) ** d
    a = lloyd.lloyd_device(sites, g, 5)
    b = lloyd.lloyd_reference(sites, g, 5)
    assert a[0].shape == (2, n, d)
    assert np.array_equal(a[0], b[0])
    assert a[1] == b[1]                      # exact integer energies, every pass
    assert np.array_equal(a[2], b[2])
    assert all(e[-1] < e[0] and np.all(np.diff(e) <= 0) for e in a[1])
    assert np.all(a[2].sum(axis=1) == g**d)  # every density point in one cell


@pytest.mark.parametrize("d", [3, 4])
def test_lloyd_sampler_in_3d_and_4d(d):
    kw = dict(d=d, seed=4, iterations=6, density=16)
    pts, info = clsamp.make_sampler("lloyd", **kw).sample(32, realizations=2, return_info=True)
    ref, ref_info = clsamp.make_sampler("lloyd", backend="numpy", **kw).sample(
        32, realizations=2, return_info=True)
    assert pts.shape == (2, 32, d) and np.array_equal(pts, ref)
    assert np.array_equal(info.energy_history, ref_info.energy_history)
    assert np.all(np.diff(info.energy_history, axis=1) <= 0)
    assert np.all(info.energy_history[:, 0] <= info.initial_energy)
    # the energy is what it says: the mean squared toroidal distance of the g^d grid of
    # cell centres to the nearest returned site, here in floating point by brute force
    g = voronoi.density_side(32, 16, d)
    centres = voronoi.density_point(np.arange(g**d), g, d) * it.UNIT
    diff = np.abs(centres[:, None, :] - pts[0][None, :, :])
    diff = np.minimum(diff, 1 - diff)
    E = (diff**2).sum(axis=-1).min(axis=1).mean()
    assert abs(E - info.energy_history[0, -1]) <= 1e-9 * E


def test_lloyd_spreads_points_in_3d():
    # relaxed sites are farther apart than their random start: the mean nearest-neighbour
    # distance grows, the smallest one far more
    start = initial_sites(2, np.arange(1), 64, d=3)[0]
    s = clsamp.make_sampler("lloyd", d=3, seed=2, iterations=20, density=64)
    pts = s.sample(64)
    before = cKDTree(it.to_unit(start), boxsize=1.0).query(it.to_unit(start), k=2)[0][:, 1]
    after = cKDTree(pts, boxsize=1.0).query(pts, k=2)[0][:, 1]
    assert after.mean() > 1.3 * before.mean() and after.min() > 2 * before.min()


@pytest.mark.parametrize("d", [3, 4])
def test_lloyd_degenerate_starts_recover_in_3d_and_4d(d):
    rng = np.random.default_rng(7)
    n = 16
    starts = np.stack([np.full((n, d), 0.3), 0.5 + 1e-4 * rng.random((n, d))])
    points, a = lloyd.lloyd_relax(starts, density=8, iterations=8)
    ref, b = lloyd.lloyd_relax(starts, density=8, iterations=8, backend="numpy")
    assert np.array_equal(points, ref)
    assert np.array_equal(a.energy_history, b.energy_history)
    assert np.all(a.counts > 0)                            # re-seeded: no empty cell left
    assert np.all(np.diff(a.energy_history, axis=1) <= 0)
    assert np.all(a.energy_history[:, 0] <= a.initial_energy)


# -- CCVT --------------------------------------------------------------------------------
def _start(seed, r, n, p):
    sites = initial_sites(seed, np.arange(r), n)
    points = density.density_points(seed, np.arange(r), n * p)
    return sites, points, start.start_partition(sites, points, p)


@pytest.mark.parametrize("kind", density.DENSITIES)
@pytest.mark.parametrize("M", [1, 1000, 1009, 97 * 64])
def test_density_kernel_equals_reference(kind, M):
    a = density.density_points_device(12, np.arange(3, 6), M, kind).get()
    assert np.array_equal(a, density.density_points(12, np.arange(3, 6), M, kind))


@pytest.mark.parametrize("M", [1, 2, 1009, 97 * 64, 4096])     # 1009: prime
def test_jittered_density_has_one_point_in_every_stratum(M):
    pts = density.density_points(4, np.arange(2), M).astype(np.int64)
    k = density.density_rows(M)
    edges = np.arange(k + 1) * M // k                       # first point index of each row
    shift = philox.random_words(4, philox.Stream.INIT, np.arange(2)[:, None], 0,
                                np.array([6, 7])[None, :]).astype(np.int64) >> (32 - it.BITS)
    for q, s in zip(pts, shift, strict=True):
        x, y = (q[:, 0] - s[0]) & it.MASK, (q[:, 1] - s[1]) & it.MASK
        # the stratum a point lies in, found from its position alone
        row = np.searchsorted(edges * it.SIZE, y * M, side="right") - 1
        cells = edges[row + 1] - edges[row]
        assert np.array_equal(edges[row] + x * cells // it.SIZE, np.arange(M))
    if M > 1:
        assert not np.array_equal(pts[0], pts[1])          # jittered afresh per realization


def test_jittered_density_lowers_the_integration_error():
    # i.i.d. density points leave the cells' areas a random count (relative spread about
    # 1 / sqrt(points_per_site)): an error floor that the stratified density removes
    mse = {}
    for kind in density.DENSITIES:
        s = clsamp.make_sampler("ccvt", seed=5, points_per_site=32, density=kind)
        mse[kind] = clsamp.convergence(s, "gaussian", [64], realizations=16, seed=1,
                                          progress=False).mse[0]
    assert mse["jittered"] < mse["random"] / 10


def test_start_partition_is_exact():
    sites, points, members = _start(1, 2, 13, 7)
    assert members.shape == (2, 13, 7)
    for k in range(2):
        assert np.array_equal(np.sort(members[k].ravel()), np.arange(13 * 7))
    sites, points, members = _start(3, 3, 300, 20)          # on the grid, with leftovers
    for k in range(3):
        assert np.array_equal(np.sort(members[k].ravel()), np.arange(300 * 20))
        assert np.all(np.diff(members[k].astype(np.int64), axis=1) > 0)


def test_start_partition_of_crowded_sites():
    # 1000 sites on one spot, and one set of spread sites beside it in the batch
    sites = initial_sites(4, np.arange(2), 1000)
    sites[1] = 7654321 % it.SIZE
    points = density.density_points(4, np.arange(2), 1000 * 6)
    members = start.start_partition(sites, points, 6)
    for k in range(2):
        assert np.array_equal(np.sort(members[k].ravel()), np.arange(1000 * 6))
    assert np.array_equal(members[0], start.start_partition(sites[:1], points[:1], 6)[0])
    assert np.array_equal(members[1], start.kd_partition(sites[1:], points[1:], 6)[0])


def _reach(sites, points, members):
    """Distance of every point to the site owning it, in site spacings (1 / sqrt(n))."""
    r, n, _ = members.shape
    x = points[np.arange(r)[:, None, None], members].astype(np.int64)
    s = sites[:, :, None, :].astype(np.int64)
    d2 = it.distance2(x[..., 0], x[..., 1], s[..., 0], s[..., 1])
    return np.sqrt(d2 * n) / it.SIZE


def test_power_kernel_equals_reference():
    rng = np.random.default_rng(3)
    corner = (rng.random((1, 40, 2)) * 0.2 * it.SIZE).astype(np.uint32)   # far points: no candidate
    cases = [initial_sites(2, np.arange(3), 12), initial_sites(2, np.arange(2), 300),
             corner, np.full((1, 9, 2), 4321, dtype=np.uint32)]                 # all distances tie
    for sites in cases:
        r, n, _ = sites.shape
        G = power.start_grid_size(n)
        points = density.density_points(5, np.arange(r), 777)
        spacing2 = it.SIZE ** 2 // n
        weight = rng.integers(-spacing2, spacing2, (r, n))
        # per realization, one shared set, and large weights
        for pts, wt in ((points, weight), (points[:1], weight), (points, weight << 20)):
            a = power.power_pass_device(pts, sites, wt, G)
            b = power.power_pass_reference(pts, sites, wt, G)
            for x, y in zip(a, b, strict=True):
                assert np.array_equal(x, y)
        b = power.power_pass_reference(points[:1], sites, weight, G)
        owner, second, margin = b
        if sites is corner:
            assert np.any(owner == pairs.NO_OWNER)
        lone = margin == pairs.NO_SECOND
        assert np.all(margin[~lone] >= 0) and np.array_equal(second[lone], owner[lone])
    # the owner is the power-nearest site, ties to the smaller index (G == 1: all candidates)
    sites = cases[0]
    weight = rng.integers(-2**30, 2**30, (3, 12))
    pts = density.density_points(5, np.arange(3), 500)
    s = sites.astype(np.int64)
    cost = it.distance2(pts[..., None, 0], pts[..., None, 1], s[:, None, :, 0],
                             s[:, None, :, 1]) - weight[:, None, :]
    owner, _, margin = power.power_pass_reference(pts, sites, weight, 1)
    assert np.array_equal(owner, np.argmin(cost, axis=2))
    assert np.array_equal(margin, np.sort(cost, axis=2)[..., 1] - np.sort(cost, axis=2)[..., 0])


def test_start_weights_balance_the_cells():
    # random sites: Voronoi cells hold 0 to 3 p points; the weights equalize them
    sites = initial_sites(3, np.arange(2), 256)
    points = density.density_points(3, np.arange(2), 256 * 256)
    G = power.start_grid_size(256)
    zero = np.zeros((2, 256), dtype=np.int64)
    before = power.power_counts(power.power_pass_reference(points, sites, zero, G)[0], 256)
    w = start.start_weights(sites, 256, G, power.PowerPass(sites, G, "opencl"))
    assert np.array_equal(w, start.start_weights(sites, 256, G, power.PowerPass(sites, G, "numpy")))
    after = power.power_counts(power.power_pass_device(points, sites, w, G)[0], 256)
    spread = [np.abs(c - 256).mean() / 256 for c in (before, after)]
    assert spread[0] > 0.3 and spread[1] < 0.08, spread


def test_start_sites_relax_the_sites_and_both_backends_agree():
    # random sites crowd in places: on the weights' lattice, a few capacity-constrained
    # Lloyd steps spread them, four duplicates included; the same integers with both
    # backends; a crowded realization stays where it is
    sites = initial_sites(6, np.arange(3), 90)
    sites[2] = 1234567                                        # crowded: left alone
    sites[1, :3] = sites[1, 3]                                # duplicates of site 3
    a, wa = start.start_sites(sites, 64, steps=8)
    b, wb = start.start_sites(sites, 64, backend="numpy", steps=8)
    assert np.array_equal(a, b) and np.array_equal(wa, wb)
    assert a.dtype == np.uint32 and wa.dtype == np.int64 and wa.shape == (3, 90)
    assert np.array_equal(a[2], sites[2]) and not wa[2].any()
    for k in range(2):
        before = metrics.relative_radius(it.to_unit(sites[k, 3:]))
        after = metrics.relative_radius(it.to_unit(a[k]))
        assert before < 0.3 and after > 0.55, (before, after)
    for k in range(2):                                        # realizations do not interact
        one, _ = start.start_sites(sites[k:k + 1], 64, steps=8)
        assert np.array_equal(one[0], a[k])
    same, none = start.start_sites(sites, 64, steps=0)             # no relaxation
    assert np.array_equal(same, sites) and none is None
    # the weights that come back balance the cells of the sites that come back
    G = power.start_grid_size(90)
    points = density.density_points(6, np.arange(1), 90 * 64)
    counts = power.power_counts(power.power_pass_device(points, a[:1], wa[:1], G)[0], 90)
    assert np.abs(counts - 64).mean() / 64 < 0.1
    with pytest.raises(InvalidArgumentError, match="backend"):
        start.start_sites(sites, 64, backend="cuda")


def test_ccvt_relax_starts_from_relaxed_sites():
    # relax=k runs start_sites(k) before the partition: the same set as the optimization
    # from those sites and weights, a lower energy than from the random sites here, the
    # same bits with both backends; bad values are refused by name
    sites = initial_sites(2, np.arange(2), 64)
    unit = it.to_unit(sites)
    a_points, a = ccvt_optimize(unit, points_per_site=32, iterations=500, seed=2, relax=6)
    b_points, b = ccvt_optimize(unit, points_per_site=32, iterations=500, seed=2, relax=6,
                                backend="numpy")
    assert np.array_equal(a_points, b_points)
    assert np.array_equal(a.energy_history, b.energy_history)
    relaxed, weight = start.start_sites(sites, 32, steps=6)
    points = density.density_points(2, np.arange(2), 64 * 32)
    members = start.start_partition(relaxed, points, 32, weight=weight)
    ref = reference.ccvt_reference(relaxed, points, members, 500)
    assert np.array_equal(it.to_unit(ref[0]), a_points)
    _, plain = ccvt_optimize(unit, points_per_site=32, iterations=500, seed=2)
    assert a.converged.all() and plain.converged.all()
    assert np.all(a.energy_history[:, -1] < plain.energy_history[:, -1])
    s = clsamp.make_sampler("ccvt", seed=2, points_per_site=32, relax=6)
    assert np.array_equal(s.sample(64, realizations=2), a_points)
    for bad in (-1, 1.5, start.MAX_RELAX + 1):
        with pytest.raises(InvalidArgumentError, match="relax"):
            clsamp.make_sampler("ccvt", relax=bad)
        with pytest.raises(InvalidArgumentError, match="relax"):
            ccvt_optimize(unit, relax=bad)


def test_start_partition_backends_agree_and_are_deterministic():
    sites = initial_sites(6, np.arange(3), 90)
    sites[2] = 1234567                                       # crowded: kd_partition
    points = density.density_points(6, np.arange(3), 90 * 10)
    a = start.start_partition(sites, points, 10)
    assert np.array_equal(a, start.start_partition(sites, points, 10, backend="numpy"))
    assert np.array_equal(a, start.start_partition(sites, points, 10))
    for k in range(3):                                       # realizations do not interact
        assert np.array_equal(a[k], start.start_partition(sites[k:k + 1], points[k:k + 1], 10)[0])
    with pytest.raises(InvalidArgumentError, match="backend"):
        start.start_partition(sites, points, 10, backend="cuda")


@pytest.mark.parametrize("seed, r, n, p", [(1, 2, 256, 64), (2, 1, 1024, 16), (4, 3, 20, 30)])
def test_start_partition_is_compact(seed, r, n, p):
    # excess is passed along to neighbouring sites, never to a far site with room: every
    # point stays within a few spacings of its site
    sites, points, members = _start(seed, r, n, p)
    for k in range(r):
        assert np.array_equal(np.sort(members[k].ravel()), np.arange(n * p))
        assert np.all(np.diff(members[k].astype(np.int64), axis=1) > 0)
    reach = _reach(sites, points, members)
    assert np.quantile(reach, 0.99) < 2.5 and reach.max() < 4.0, (np.quantile(reach, 0.99), reach.max())


def test_relay_shifts_excess_along_neighbours():
    # an 8 x 8 lattice of sites, each with p points around it except site 0, which has
    # p + 4, and the site half a torus away, which has p - 4: the excess travels there as
    # hand-overs between neighbours (closer than 2 spacings), never as a jump
    n, p, side = 64, 16, 8
    g = (np.arange(side) * it.SIZE) // side
    sites = np.stack(np.meshgrid(g, g), axis=-1).reshape(1, n, 2).astype(np.uint32)
    far = 4 * side + 4
    counts = np.full(n, p)
    counts[0], counts[far] = p + 4, p - 4
    home = np.repeat(np.arange(n), counts)
    jitter = (np.random.default_rng(1).random((n * p, 2)) - 0.5) * (0.5 * it.SIZE / side)
    points = ((sites[0, home] + jitter.astype(np.int64)) & it.MASK).astype(np.uint32)
    mat, over = relay.members_matrix(home, n, p)
    room = (mat < 0).sum(axis=1)
    assert len(over) == 4 and room.sum() == 4
    relay.relay(sites, points[None], mat, room, over, home[over])
    assert np.array_equal(np.sort(mat.ravel()), np.arange(n * p)) and not room.any()
    got = np.repeat(np.arange(n), p)[np.argsort(mat.ravel())]   # the new owner of each point
    hop = it.distance2(sites[0, got, 0], sites[0, got, 1], sites[0, home, 0], sites[0, home, 1])
    assert np.sqrt(hop.max() * n) / it.SIZE < 2.0       # one neighbour at most
    moved = np.flatnonzero(got != home)
    assert 4 * 2 <= len(moved) <= 4 * 8                      # chains of hand-overs


def test_ccvt_has_no_axis_cross_in_its_spectrum():
    # a start that cuts the unit square leaves seams on x = 0 and y = 0, which show as
    # excess power on the frequency axes
    pts = clsamp.make_sampler("ccvt", seed=1, points_per_site=64).sample(256, realizations=32)
    P = clsamp.power_spectrum(pts, resolution=64, method="direct", progress=False)
    c = P.shape[0] // 2
    axes = np.concatenate([P[c, c + 8:], P[c + 8:, c]]).mean()
    beside = np.concatenate([P[c + 3, c + 8:], P[c + 8:, c + 3]]).mean()
    assert axes / beside < 1.15, (axes, beside)


# kernels/ccvt.h's integer helpers, evaluated by a probe appended to ccvt.cl
_PROBE = """
__kernel void ccvt_probe(__global const long *x, __global const long *dot, __global long *out,
                         __global const uint *ns)
{
    const size_t t = get_global_id(0);
    __global long *o = out + 16 * t;
    o[0] = ccvt_isqrt(x[t]);
    o[1] = ccvt_sqrt_up(x[t]);
    for (int k = 0; k < 4; ++k)
        o[2 + k] = ccvt_ray_dot(k, dot[t]);
    const ccvt_t c = ccvt_state(ns[t], 1, 0, 0, 0, 0, 0, 0, 0, 0, 0);
    for (int b = 0; b < CCVT_BANDS - 1; ++b)
        o[6 + b] = c.edge[b];
    for (int b = 0; b < CCVT_BANDS; ++b)
        o[9 + b] = c.lo[b];
    o[13] = c.drift;
}
"""


def _at_least_over_sqrt2(u, d):
    """u >= d / sqrt(2), decided in integers."""
    return (d >= 0 and u >= 0 and 2 * u * u >= d * d) or (d < 0 and (u >= 0 or 2 * u * u <= d * d))


def test_ccvt_integer_bounds_are_exact():
    # the helpers that replaced ccvt.h's doubles: floor and ceiling square roots (a float
    # guess corrected in integers), the sector rays' e.D rounded up (|ray| 1, 13, sqrt 2),
    # the band edges and drift of n; built without fp64 (no double)
    rng = np.random.default_rng(4)
    k = np.concatenate([np.arange(0, 40), [2**21 - 1, 2**21, 2**22 - 1, 2**22, 2**23, 2**31 - 1],
                        rng.integers(0, 2**23, 200)]).astype(np.int64)
    x = np.clip(np.concatenate([k * k, k * k + 1, k * k - 1, k * k + 2 * k]), 0, None)
    x = np.concatenate([x, rng.integers(0, 2**46, 300), [2**62 - 1]])
    dot = rng.integers(-2**26, 2**26, x.size)
    dot[:40] = np.arange(-20, 20)
    ns = rng.integers(1, 2**20, x.size).astype(np.uint32)
    ns[:5] = (1, 2, 3, 1024, 4096)
    with runtime.without_fp64():
        kernel = runtime.kernel("ccvt.cl", "ccvt_probe", pairs.ccvt_defines(), appendix=_PROBE)
        q = runtime.queue()
        out = runtime.to_device(np.zeros((x.size, 16), dtype=np.int64))
        kernel(q, (x.size,), None, runtime.to_device(x).data, runtime.to_device(dot).data,
               out.data, runtime.to_device(ns).data)
        out = out.get()
    for t in range(x.size):
        v, d, n = int(x[t]), int(dot[t]), int(ns[t])
        r = math.isqrt(v)
        assert out[t, 0] == r and out[t, 1] == (r if r * r == v else r + 1), v
        up = [int(u) for u in out[t, 2:6]]                # rays 0 to 3: |ray| 1, 13, sqrt 2, 13
        assert up[0] == d and up[1] == up[3] == -(-d // 13)
        assert _at_least_over_sqrt2(up[2], d) and not _at_least_over_sqrt2(up[2] - 2, d), d
        edges = [(f << 44) // (g * n) for f, g in ((1764, 10**4), (2401, 10**4), (297025, 10**6))]
        assert list(out[t, 6:9]) == edges
        assert list(out[t, 9:13]) == [0] + [math.isqrt(e) for e in edges]
        assert out[t, 13] == math.isqrt(2**44 // (100 * n))


def test_ccvt_kernel_equals_reference():
    sites, points, members = _start(6, 2, 30, 24)
    a = device.ccvt_device(sites, points, members, 40)
    b = reference.ccvt_reference(sites, points, members, 40)
    assert np.array_equal(a[0], b[0])          # sites
    assert a[1] == b[1]                        # exact integer energies, every iteration
    assert np.array_equal(np.sort(a[2]), np.sort(b[2]))   # ownership (sets: slots are bucketed)
    assert np.array_equal(a[3], b[3])          # converged


def test_ccvt_kernel_equals_reference_through_the_buckets():
    # cells small enough (n = 144) that no site stays wide: the pairs read only the buckets
    # that face them and the sums are kept by exchanges and moves; the reference reads
    # and recomputes everything
    sites, points, members = _start(9, 1, 144, 24)
    a = device.ccvt_device(sites, points, members, 10)
    b = reference.ccvt_reference(sites, points, members, 10)
    assert np.array_equal(a[0], b[0])
    assert a[1] == b[1]
    assert np.array_equal(np.sort(a[2]), np.sort(b[2]))


def test_ccvt_prefetch_changes_no_result(monkeypatch):
    # CPU devices build ccvt.cl with CCVT_PREFETCH (software prefetch); other devices build
    # it without: both programs give the same bits, stepwise and in one launch
    sites, points, members = _start(9, 2, 144, 24)
    with_prefetch = [device.ccvt_device(sites, points, members, 10, fused=f) for f in (False, True)]
    plain = {k: v for k, v in pairs.ccvt_defines().items() if k != "CCVT_PREFETCH"}
    monkeypatch.setattr(device, "ccvt_defines", lambda: plain)
    for fused, a in zip((False, True), with_prefetch, strict=True):
        b = device.ccvt_device(sites, points, members, 10, fused=fused)
        assert np.array_equal(a[0], b[0])
        assert a[1] == b[1]
        assert np.array_equal(a[2], b[2])


def test_ccvt_one_workgroup_per_realization_equals_launch_per_step():
    sites, points, members = _start(7, 3, 45, 20)
    a = device.ccvt_device(sites, points, members, 50, fused=True)
    b = device.ccvt_device(sites, points, members, 50, fused=False)
    assert np.array_equal(a[0], b[0])
    assert a[1] == b[1]
    assert np.array_equal(a[2], b[2])
    assert np.array_equal(a[3], b[3])
    c = device.ccvt_device(sites, points, members, 3, fused=True)      # stopped by the cap
    assert [len(e) for e in c[1]] == [3, 3, 3] and not c[3].any()
    assert c[1][0] == b[1][0][:3]


def test_ccvt_tail_in_one_launch_equals_launch_per_step():
    # the stepwise launches hand the realizations still running to one ccvt_solve launch
    # once an iteration makes few exchanges: from the first iteration on (tail=n), at
    # the default share, or never (tail=-1), the same bits; also when the cap stops it
    sites, points, members = _start(7, 3, 45, 20)
    b = device.ccvt_device(sites, points, members, 50, fused=False, tail=-1)
    assert b[3].all()
    for tail in (45, None, 2):
        a = device.ccvt_device(sites, points, members, 50, fused=False, tail=tail)
        assert np.array_equal(a[0], b[0])
        assert a[1] == b[1]
        assert np.array_equal(a[2], b[2])
        assert np.array_equal(a[3], b[3])
    n = min(len(e) for e in b[1]) - 1
    c = device.ccvt_device(sites, points, members, n, fused=False, tail=45)
    assert [len(e) for e in c[1]] == [n] * 3 and not c[3].any()
    assert [e[:n] for e in b[1]] == c[1]


@pytest.mark.parametrize("n, p, kind, seed", [(64, 32, "jittered", 1), (200, 24, "random", 2),
                                             (500, 16, "jittered", 3)])
def test_ccvt_without_fp64_gives_the_bits_of_fp64_and_numpy(n, p, kind, seed):
    # kernels/ccvt.h is exact integers, its pruning bounds too: a device without fp64
    # (runtime.without_fp64: the build refuses any double) gives the bits of the fp64
    # device's build and of the NumPy twin, every realization, energies included
    params = dict(seed=seed, points_per_site=p, density=kind, progress=False)
    s = clsamp.make_sampler("ccvt", **params)
    here, here_info = s.sample(n, realizations=range(1, 4), return_info=True)
    with runtime.without_fp64():
        assert not runtime.current_device().fp64
        there, there_info = s.sample(n, realizations=range(1, 4), return_info=True)
    ref = clsamp.make_sampler("ccvt", backend="numpy", **params).sample(n, realizations=range(1, 4))
    assert np.array_equal(here.view(np.uint64), there.view(np.uint64))
    assert np.array_equal(here.view(np.uint64), ref.view(np.uint64))
    assert np.array_equal(here_info.energy_history, there_info.energy_history)
    assert np.array_equal(here_info.iterations, there_info.iterations)


@pytest.mark.parametrize("fused", [False, True], ids=["stepwise", "one-launch"])
def test_ccvt_without_fp64_equals_reference_from_degenerate_starts(fused):
    # duplicates and a tiny cluster keep sites wide (their buckets read whole, sums from
    # scratch) and the bounds at their extremes; n = 144 with p = 24 also prunes by bucket
    sites = it.to_torus(_degenerate_starts(144))
    points = density.density_points(6, np.arange(3), 144 * 24)
    members = start.start_partition(sites, points, 24)
    with runtime.without_fp64():
        a = device.ccvt_device(sites, points, members, 30, fused=fused)
    b = reference.ccvt_reference(sites, points, members, 30)
    assert np.array_equal(a[0], b[0])
    assert a[1] == b[1]
    assert np.array_equal(np.sort(a[2]), np.sort(b[2]))
    assert np.array_equal(a[3], b[3])


def test_ccvt_capacities_exact_after_every_iteration_and_energy_never_rises():
    sites, points, members = _start(8, 2, 40, 16)
    seen = []

    def check(owned, _sites):
        for k in range(owned.shape[0]):
            seen.append(np.array_equal(np.sort(owned[k].ravel()), np.arange(40 * 16)))

    _, result = ccvt_optimize(it.to_unit(sites), points_per_site=16, iterations=60, seed=8,
                              callback=check)
    assert len(seen) >= 4 and all(seen)       # every point owned exactly once, every time
    assert np.all(result.capacities == 16)
    h = result.energy_history
    assert np.all(np.diff(h, axis=1) <= 0)
    assert np.all(result.converged)


def test_ccvt_sampler():
    s = clsamp.make_sampler("ccvt", seed=3, points_per_site=32)
    pts, info = s.sample(64, return_info=True)
    assert pts.shape == (64, 2)
    assert info.capacities.shape == (1, 64) and np.all(info.capacities == 32)
    assert info.energy_history.shape[0] == 1 and np.all(np.diff(info.energy_history) <= 0)
    batch, info = s.sample(64, realizations=3, return_info=True)
    assert np.array_equal(batch[0], pts)
    assert info.capacities.shape == (3, 64) and np.all(info.capacities == 32)
    assert info.energy_history.shape[0] == 3 and info.iterations.shape == (3,)
    assert np.all(np.diff(info.energy_history, axis=1) <= 0)
    assert np.array_equal(s.sample(64, realizations=2), batch[:2])
    part, part_info = s.sample(64, realizations=range(2, 3), return_info=True)
    assert np.array_equal(part, batch[2:])
    assert np.array_equal(part_info.capacities, info.capacities[2:])
    length = part_info.energy_history.shape[1]       # padded to its own longest run
    assert np.array_equal(part_info.energy_history, info.energy_history[2:, :length])
    ref = clsamp.make_sampler("ccvt", seed=3, points_per_site=32, backend="numpy")
    assert np.array_equal(ref.sample(64), pts)


def test_ccvt_quality():
    s = clsamp.make_sampler("ccvt", seed=4, points_per_site=256)
    pts, info = s.sample(128, realizations=4, return_info=True)
    assert np.all(info.converged)
    # white noise 0.32, hexagonal 0.1604; Balzer's code reaches 0.1677 at 1024 x 1024.
    # Local optima spread N*E from realization to realization at this size, so the bound
    # holds each set and the Voronoi energy below the mean.
    capacity_ne = 128 * info.energy_history[:, -1]
    assert np.all(capacity_ne < 0.173)
    assert np.all(capacity_ne > metrics.HEXAGONAL_NE)
    # the energy of the sites' own Voronoi cells, on a fine grid: the continuous quality,
    # which the discrete E over the density points only estimates
    c = (np.arange(512) + 0.5) / 512
    grid = np.stack(np.meshgrid(c, c), -1).reshape(-1, 2)
    ne = [128 * np.mean(cKDTree(q, boxsize=1.0).query(grid)[0] ** 2) for q in pts]
    assert np.mean(ne) < 0.170 and np.all(np.array(ne) > metrics.HEXAGONAL_NE)
    assert np.all(metrics.relative_radius(pts) > 0.65)


def test_ccvt_degenerate_starts():
    starts = _degenerate_starts(24)
    points, a = ccvt_optimize(starts, points_per_site=16, iterations=80, seed=2)
    ref, b = ccvt_optimize(starts, points_per_site=16, iterations=80, seed=2, backend="numpy")
    assert np.array_equal(points, ref)
    assert np.array_equal(a.energy_history, b.energy_history)
    assert np.all(a.capacities == 16)
    assert np.all(np.diff(a.energy_history, axis=1) <= 0)
    assert np.all(metrics.min_distance(points) > 0)      # the duplicates separated
    assert np.all(a.capacities.shape == (3, 24))


# -- bad input -----------------------------------------------------------------------------
@pytest.mark.parametrize("name, params, word", [
    ("lloyd", {"iterations": 0}, "iterations"),
    ("lloyd", {"density": 0}, "density"),
    ("lloyd", {"d": 5}, "'d'"),
    ("ccvt", {"points_per_site": 0}, "points_per_site"),
    ("ccvt", {"iterations": 0}, "iterations"),
    ("ccvt", {"points_per_site": 2.5}, "points_per_site"),
    ("ccvt", {"d": 1}, "'d'"),
    ("ccvt", {"density": "sobol"}, "density"),
])
def test_bad_parameters(name, params, word):
    with pytest.raises(InvalidArgumentError, match=word):
        clsamp.make_sampler(name, **params)


@pytest.mark.parametrize("name", ["lloyd", "ccvt"])
def test_bad_n(name):
    s = clsamp.make_sampler(name)
    for n in (0, -3, None):
        with pytest.raises(InvalidArgumentError, match="'n'"):
            s.sample(n)


def test_lloyd_refuses_too_many_density_points_before_drawing_its_sites(monkeypatch):
    # 'density' * n >= 2^32 was refused after the 2^24 starting sites were drawn (8 s,
    # 3.9 GB); now before (the start would fail the test)
    from clsamp.samplers import optimizer
    monkeypatch.setattr(optimizer, "initial_sites", lambda *a, **k: pytest.fail("sites drawn"))
    with pytest.raises(InvalidArgumentError, match=r"'density' \* n must stay below 2\^32"):
        clsamp.make_sampler("lloyd", d=3).sample(2**24)


@pytest.mark.parametrize("name", ["lloyd", "ccvt"])
def test_start_other_than_zero_is_refused(name):
    s = clsamp.make_sampler(name, points_per_site=8) if name == "ccvt" else clsamp.make_sampler(name)
    for call in (s.sample, s.sample_device):
        with pytest.raises(InvalidArgumentError, match="'start'"):
            call(16, realizations=2, start=3)


def test_bad_sites():
    with pytest.raises(InvalidArgumentError, match="sites"):
        lloyd.lloyd_relax(np.full((4, 2), 1.5))
    with pytest.raises(InvalidArgumentError, match="points_per_site"):
        ccvt_optimize(np.full((4, 2), 0.5), points_per_site=0)
    with pytest.raises(InvalidArgumentError, match="density"):
        lloyd.lloyd_relax(np.full((4, 2), 0.5), density=0)


def test_ccvt_tail_in_chunks_gives_the_same_bits(monkeypatch):
    # ccvt_solve runs in launches of SOLVE_CHUNK iterations (so Ctrl-C is honoured between
    # them); chunks of 3, with realizations converging in between, change nothing
    from clsamp.samplers.ccvt import device
    cases = [(4096, 1, 16), (256, 8, 64)]          # a tail after stepwise launches; fused
    whole = [clsamp.make_sampler("ccvt", points_per_site=p, seed=3, progress=False)
             .sample(n, realizations=r, return_info=True) for n, r, p in cases]
    monkeypatch.setattr(device, "SOLVE_CHUNK", 3)
    for (n, r, p), (pts, info) in zip(cases, whole, strict=True):
        again, info2 = clsamp.make_sampler("ccvt", points_per_site=p, seed=3, progress=False).sample(
            n, realizations=r, return_info=True)
        assert np.array_equal(pts, again)
        assert np.array_equal(info.iterations, info2.iterations)
        assert max(info.iterations) > 3


def test_an_info_prints_in_a_line_and_an_early_stop_ends_its_bar_at_100(capsys):
    s = clsamp.make_sampler("ccvt", seed=2, points_per_site=64)
    _, info = s.sample(256, realizations=2, return_info=True)
    text = repr(info)
    assert len(text) < 400 and "capacities=<int64 (2, 256), 64..64>" in text
    from tqdm import tqdm

    from clsamp.samplers.ccvt.device import _finish
    bar = tqdm(total=100, delay=0, desc="early")
    bar.update(32)
    _finish(bar)
    assert "100%" in capsys.readouterr().err.replace(" ", "")
