"""clsamp.metrics: L2-type discrepancies, the star discrepancy, the pair correlation
function and nearest-neighbour distances, against exact rationals, scipy, brute force,
their NumPy twins and the patterns whose values are known."""

import math
from fractions import Fraction

import numpy as np
import pytest

import clsamp
from clsamp import metrics
from clsamp.errors import InvalidArgumentError
from clsamp.metrics import l2, min_distance, neighbors, star

qmc = pytest.importorskip("scipy.stats.qmc")

SCIPY_METHODS = ("CD", "WD", "MD", "L2-star")
HALF = Fraction(1, 2)


# -- discrepancies ----------------------------------------------------------------------


def _exact_terms(method, a, b=None):
    """The textbook f(a) or g(a, b) of each method, in rationals."""
    if b is None:
        c = abs(a - HALF)
        return {"CD": 1 + c / 2 - c * c / 2, "WD": Fraction(1),
                "MD": Fraction(5, 3) - c / 4 - c * c / 4, "L2-star": 1 - a * a,
                "symmetric": 1 + 2 * a - 2 * a * a, "L2": a * (1 - a)}[method]
    t = abs(a - b)
    return {"CD": 1 + abs(a - HALF) / 2 + abs(b - HALF) / 2 - t / 2,
            "WD": Fraction(3, 2) - t + t * t,
            "MD": Fraction(15, 8) - abs(a - HALF) / 4 - abs(b - HALF) / 4 - 3 * t / 4 + t * t / 2,
            "L2-star": 1 - max(a, b), "symmetric": 1 - t, "L2": min(a, b) - a * b}[method]


def exact_discrepancy(points, method):
    """D^2 in rational arithmetic from the textbook formulas (Hickernell 1998; Warnock
    1972; Zhou et al. 2013; UTK's symmetric and unanchored forms)."""
    n, d = points.shape
    rows = [[Fraction(v) for v in row] for row in points]
    single = sum(math.prod(_exact_terms(method, a) for a in row) for row in rows)
    pairs = sum(math.prod(_exact_terms(method, a, b) for a, b in zip(p, q, strict=True))
                for p in rows for q in rows)
    c0 = {"CD": Fraction(13, 12) ** d, "WD": -Fraction(4, 3) ** d, "MD": Fraction(19, 12) ** d,
          "L2-star": Fraction(1, 3) ** d, "symmetric": Fraction(4, 3) ** d,
          "L2": Fraction(1, 12) ** d}[method]
    c1 = {"WD": 0, "L2-star": -Fraction(2) ** (1 - d), "L2": -Fraction(2) ** (1 - d)}.get(method, -2)
    c2 = Fraction(2) ** d if method == "symmetric" else Fraction(1)
    return c0 + c1 * single / n + c2 * pairs / n**2


@pytest.mark.parametrize("method", l2.METHODS)
@pytest.mark.parametrize("n,d", [(1, 3), (2, 1), (9, 2), (23, 3), (40, 4), (17, 6)])
def test_discrepancy_equals_exact_rationals(method, n, d):
    x = np.random.default_rng(n * 10 + d).random((n, d))
    exact = exact_discrepancy(x, method)
    want = math.sqrt(exact) if method in l2.ROOTED else float(exact)
    for backend in ("opencl", "numpy"):
        got = clsamp.discrepancy(x, method, backend=backend)
        assert got == pytest.approx(want, rel=1e-13, abs=1e-300), backend


def _scipy_tolerance(x, method):
    """How far scipy's value may be from the exact one: it adds the n^2 pair terms one by
    one, whose rounding errors grow with the largest of the formula's three terms."""
    n, d = x.shape
    c0, c1, c2 = l2._constants(method, d, n)
    single = float(np.sum(np.prod(l2._terms(method, x), axis=1)))
    scale = max(abs(float(c0)), abs(float(c1)) * single, abs(float(c0)) + abs(float(c1)) * single)
    return 16 * n * 2.0**-53 * scale


@pytest.mark.parametrize("method", SCIPY_METHODS)
@pytest.mark.parametrize("d", [1, 2, 3, 4, 5, 6])
def test_discrepancy_equals_scipy(method, d):
    rng = np.random.default_rng(d)
    for n in (7, 64, 1000, 4096):
        x = rng.random((n, d))
        ours = clsamp.discrepancy(x, method)
        theirs = qmc.discrepancy(x, method=method)
        if method in l2.ROOTED:            # scipy returns the root of L2-star
            ours, theirs = ours**2, theirs**2
        assert abs(ours - theirs) <= max(1e-12 * ours, _scipy_tolerance(x, method)), (n, ours, theirs)
        if n <= 64:                        # where scipy's sum is exact enough: 1e-12
            assert ours == pytest.approx(theirs, rel=1e-12)


@pytest.mark.parametrize("method", l2.METHODS)
def test_discrepancy_kernel_equals_numpy_twin(method):
    for n, d in [(4096, 2), (1031, 5), (333, 9)]:
        x = np.random.default_rng(n).random((n, d))
        assert clsamp.discrepancy(x, method) == pytest.approx(
            clsamp.discrepancy(x, method, backend="numpy"), rel=1e-12)


def test_discrepancy_batched_equals_looped():
    x = np.random.default_rng(2).random((5, 301, 3))
    for method in l2.METHODS:
        batched = clsamp.discrepancy(x, method)
        assert batched.shape == (5,)
        assert np.array_equal(batched, [clsamp.discrepancy(x[k], method) for k in range(5)])
    sets = [x[0], x[1, :100], x[2, :7]]
    assert np.array_equal(clsamp.discrepancy(sets, "WD"),
                          [clsamp.discrepancy(s, "WD") for s in sets])


def test_discrepancy_known_values():
    # 1-D midpoints (2i - 1) / 2n: Warnock's L2-star discrepancy is 1 / (sqrt(12) n)
    for n in (1, 4, 100, 1000):
        x = ((2 * np.arange(1, n + 1) - 1) / (2 * n))[:, None]
        assert clsamp.discrepancy(x, "L2-star") == pytest.approx(1 / (math.sqrt(12) * n), rel=1e-12)
    # low discrepancy beats random, and Sobol's L2-star falls faster than N^-1/2
    sobol = clsamp.make_sampler("sobol", d=2)
    rand = clsamp.make_sampler("random", d=2, seed=4)
    assert clsamp.discrepancy(sobol.sample(1024)) < clsamp.discrepancy(rand.sample(1024))
    coarse, fine = (clsamp.discrepancy(sobol.sample(n), "L2-star") for n in (256, 4096))
    ratio = coarse / fine
    assert ratio > 8.0                     # 16x the points: N^-1/2 would give 4


def test_discrepancy_bad_input():
    x = np.random.default_rng(0).random((10, 2))
    with pytest.raises(InvalidArgumentError, match="method"):
        clsamp.discrepancy(x, "centered")
    bad = x.copy()
    bad[3, 1] = np.nan
    with pytest.raises(InvalidArgumentError, match="points"):
        clsamp.discrepancy(bad)
    bad[3, 1] = 1.0
    with pytest.raises(InvalidArgumentError, match="points"):
        clsamp.discrepancy(bad)
    with pytest.raises(InvalidArgumentError, match="points"):
        clsamp.discrepancy(np.zeros((0, 2)))
    with pytest.raises(InvalidArgumentError, match="backend"):
        clsamp.discrepancy(x, backend="cuda")


# -- star discrepancy ---------------------------------------------------------------------


def _with_ties(x):
    x = x.copy()
    if len(x) > 4:
        x[1, 0] = x[0, 0]
        x[3, 1] = x[2, 1]
        x[4] = x[2]
    return x


@pytest.mark.parametrize("d", [2, 3])
def test_star_discrepancy_equals_brute_force(d):
    rng = np.random.default_rng(d)
    for n in (1, 2, 3, 8, 33, 64 if d == 2 else 40):
        x = _with_ties(rng.random((n, d)))
        exact = star.star_discrepancy_brute(x)
        assert clsamp.star_discrepancy(x) == exact
        assert clsamp.star_discrepancy(x, backend="numpy") == exact
    h = clsamp.make_sampler("hammersley", d=2).sample(64)
    assert clsamp.star_discrepancy(h) == star.star_discrepancy_brute(h)


def test_star_discrepancy_known_values():
    # 1-D midpoints: 1/(2n); the n points i/n: 1/n
    for n in (1, 5, 64, 1000):
        mid = ((2 * np.arange(1, n + 1) - 1) / (2 * n))[:, None]
        assert clsamp.star_discrepancy(mid) == pytest.approx(1 / (2 * n), rel=1e-12)
        assert clsamp.star_discrepancy((np.arange(n) / n)[:, None]) == pytest.approx(1 / n, rel=1e-12)
    # the centred m x m grid: the closed box up to the last point holds every point but
    # the last row and column's outer halves are missing: 1/m - 1/(4 m^2)
    for m in (2, 4, 7, 16):
        g = (np.stack(np.meshgrid(np.arange(m), np.arange(m)), -1).reshape(-1, 2) + 0.5) / m
        assert clsamp.star_discrepancy(g) == pytest.approx(1 / m - 1 / (4 * m * m), rel=1e-12)


def test_star_bounds_bracket_the_exact_value():
    rng = np.random.default_rng(7)
    for d, n in [(2, 50), (2, 300), (3, 60)]:
        x = rng.random((n, d))
        exact = clsamp.star_discrepancy(x)
        lo, hi = clsamp.star_discrepancy(x, bounds=True)
        assert lo <= exact <= hi
        b = clsamp.star_discrepancy(x, bounds=True, delta=0.05)
        assert isinstance(b, clsamp.StarBounds)
        assert b.lower <= exact <= b.upper <= b.lower + 0.05 + 1e-12
    x = clsamp.make_sampler("sobol", d=5).sample(256)
    b = clsamp.star_discrepancy(x, bounds=True, delta=0.3)
    assert 0 < b.lower <= b.upper <= b.lower + 0.3 + 1e-12
    assert clsamp.star_discrepancy(x, bounds=True, delta=0.3, backend="numpy") == b


def test_delta_partition_covers_the_cube():
    for d, delta in [(2, 0.1), (3, 0.2), (4, 0.3)]:
        lo, hi = star.delta_partition(d, delta)
        assert np.all(np.prod(hi, axis=1) - np.prod(lo, axis=1) <= delta + 1e-15)
        assert np.sum(np.prod(hi - lo, axis=1)) == pytest.approx(1.0, rel=1e-12)
        q = np.random.default_rng(d).random((500, d))           # every point in some box
        inside = np.all((lo[None] <= q[:, None]) & (q[:, None] <= hi[None]), axis=2)
        assert inside.any(axis=1).all()


def test_anchored_counts_kernel_equals_numpy_twin():
    rng = np.random.default_rng(3)
    x = rng.random((301, 4))
    corners = np.concatenate([rng.random((999, 4)), x[:50]])    # corners on points: ties
    for strict in (True, False):
        assert np.array_equal(star.anchored_counts(x, corners, strict),
                              star.anchored_counts_reference(x, corners, strict))


def test_star_discrepancy_bad_input():
    x = np.random.default_rng(0).random((20, 4))
    with pytest.raises(InvalidArgumentError, match="bounds=True"):
        clsamp.star_discrepancy(x)
    with pytest.raises(InvalidArgumentError, match="bounds=True"):
        clsamp.star_discrepancy(np.random.default_rng(0).random((3000, 3)))
    with pytest.raises(InvalidArgumentError, match="delta"):
        clsamp.star_discrepancy(x, bounds=True, delta=0.0)
    with pytest.raises(InvalidArgumentError, match="bounds"):
        clsamp.star_discrepancy(x[:, :2], bounds="yes")
    with pytest.raises(InvalidArgumentError, match="points"):
        clsamp.star_discrepancy(np.full((4, 2), np.nan))


# -- pair correlation ---------------------------------------------------------------------


def test_pcf_of_random_points_is_one():
    for d, n, r in [(1, 512, 32), (2, 2048, 16), (3, 2048, 16)]:
        pts = clsamp.make_sampler("random", d=d, seed=d).sample(n, realizations=r)
        radii, g = clsamp.pair_correlation(pts)
        spacing = neighbors.mean_spacing(n, d)
        assert radii[-1] == pytest.approx(3 * spacing) and len(radii) == 100
        # the expected pairs within a smoothing window: Poisson noise of the estimate
        sigma = 0.05 * spacing
        surface = 2 * math.pi ** (d / 2) / math.gamma(d / 2) * radii ** (d - 1)
        pairs = r * n * n * surface * 2.5 * sigma
        assert np.all(np.abs(g - 1) <= 5 / np.sqrt(pairs) + 1e-3), np.max(np.abs(g - 1) * np.sqrt(pairs))
        assert abs(np.mean(g[20:]) - 1) < 0.01


@pytest.mark.parametrize("d,n", [(1, 300), (1, 8), (2, 64), (3, 2000)])
def test_pcf_kernel_equals_numpy_twin_in_every_dimension(d, n):
    # (1, 8) and (2, 64) reach past a third of the torus: one cell, every pair
    pts = clsamp.make_sampler("random", d=d, seed=5).sample(n, realizations=2)
    _, g1 = clsamp.pair_correlation(pts)
    _, g2 = clsamp.pair_correlation(pts, backend="numpy")
    np.testing.assert_allclose(g1, g2, rtol=1e-12, atol=1e-12)


def test_pcf_kernel_equals_numpy_twin():
    pts = clsamp.make_sampler("jittered", d=2, seed=1).sample(1024, realizations=3)
    r1, g1 = clsamp.pair_correlation(pts)
    r2, g2 = clsamp.pair_correlation(pts, backend="numpy")
    assert np.array_equal(r1, r2)
    np.testing.assert_allclose(g1, g2, rtol=1e-12)
    # irregular radii take the direct Gaussian; a list of sets of different sizes
    radii = np.array([0.001, 0.01, 0.02, 0.05, 0.07])
    sets = [pts[0], pts[1, :700]]
    _, g3 = clsamp.pair_correlation(sets, radii=radii, sigma=0.004)
    _, g4 = clsamp.pair_correlation(sets, radii=radii, sigma=0.004, backend="numpy")
    np.testing.assert_allclose(g3, g4, rtol=1e-12)


def test_pcf_shows_blue_noise():
    n = 1024
    spacing = neighbors.mean_spacing(n, 2)
    jit = clsamp.make_sampler("jittered", d=2, seed=2).sample(n, realizations=8)
    radii, g = clsamp.pair_correlation(jit)
    assert np.all(g[radii < 0.2 * spacing] < 0.5)               # the dip
    ccvt = clsamp.make_sampler("ccvt", d=2, seed=2).sample(n, realizations=2)
    radii, g = clsamp.pair_correlation(ccvt)
    assert np.all(g[radii < 0.6 * spacing] < 0.05)              # an empty disc around each
    peak = radii[np.argmax(g)]
    assert g.max() > 2.0 and 0.9 * spacing < peak < 1.25 * spacing
    # the PCF and the spectrum agree on the spacing: neighbours at a put the first
    # spectral peak at 1 / a on a square grid, 2 / (sqrt(3) a) on a hexagonal one, and a
    # CCVT set lies between
    f, p = clsamp.radial_mean(clsamp.power_spectrum(ccvt, resolution=128))
    assert 0.95 < f[np.argmax(p)] * peak < 2 / math.sqrt(3)
    m = 32
    grid = (np.stack(np.meshgrid(np.arange(m), np.arange(m)), -1).reshape(-1, 2) + 0.5) / m
    radii, g = clsamp.pair_correlation(grid)
    f, p = clsamp.radial_mean(clsamp.power_spectrum(grid, resolution=128))
    assert f[np.argmax(p)] == m and radii[np.argmax(g)] == pytest.approx(1 / m, rel=0.02)


def test_pcf_bad_input():
    x = np.random.default_rng(0).random((100, 2))
    with pytest.raises(InvalidArgumentError, match="at least 2"):
        clsamp.pair_correlation(x[:1])
    with pytest.raises(InvalidArgumentError, match="'periodic' must be True or False"):
        clsamp.pair_correlation(x, periodic="no")
    with pytest.raises(InvalidArgumentError, match="'periodic' must be True or False"):
        clsamp.nearest_neighbor_distances(x, periodic=None)
    with pytest.raises(InvalidArgumentError, match="half the torus"):
        clsamp.pair_correlation(x, radii=[0.1, 0.49])
    with pytest.raises(InvalidArgumentError, match="half the cube's side"):
        clsamp.pair_correlation(x, radii=[0.1, 0.49], periodic=False)
    with pytest.raises(InvalidArgumentError, match="increasing"):
        clsamp.pair_correlation(x, radii=[0.1, 0.05])
    with pytest.raises(InvalidArgumentError, match="sigma"):
        clsamp.pair_correlation(x, sigma=-1.0)
    with pytest.raises(InvalidArgumentError, match="points"):
        clsamp.pair_correlation(np.full((10, 2), 1.5))
    with pytest.raises(InvalidArgumentError, match="'points' .* rows differ in length"):
        clsamp.pair_correlation([[0.1, 0.2], [0.3]])
    with pytest.raises(InvalidArgumentError, match="'sigma' must be a real number"):
        clsamp.pair_correlation(x, sigma=np.array(0.01))


def test_pcf_defaults_and_grids_in_many_dimensions():
    # the default radii stop where the reach would pass 1/2 (few points in many
    # dimensions); short radii in many dimensions take no more cells than memory holds;
    # sigma as a NumPy number; points in the other byte order
    for d, n in ((3, 64), (4, 1024), (6, 300)):
        pts = np.random.default_rng(d).random((n, d))
        radii, g = clsamp.pair_correlation(pts)
        assert len(radii) == 100 and radii[-1] + 5 * 0.05 * n ** (-1 / d) <= 0.5 + 1e-12
        _, twin = clsamp.pair_correlation(pts, backend="numpy")
        np.testing.assert_allclose(g, twin, rtol=1e-12, atol=1e-12)
    pts = np.random.default_rng(8).random((50, 8))
    for periodic in (True, False):
        got = clsamp.pair_correlation(pts, radii=[0.01, 0.02], sigma=0.001, periodic=periodic)
        assert got[1].tolist() == [0.0, 0.0]
    x = np.random.default_rng(0).random((300, 2))
    same = clsamp.pair_correlation(x, sigma=np.float32(0.01))[1]
    assert np.array_equal(clsamp.pair_correlation(x, sigma=np.float64(np.float32(0.01)))[1], same)
    with pytest.raises(InvalidArgumentError, match="'sigma' 1 leaves no radius within 1/2"):
        clsamp.pair_correlation(x, sigma=np.int64(1))     # a number, too wide for any radius
    assert np.array_equal(clsamp.pair_correlation(x.astype(">f8"))[1],
                          clsamp.pair_correlation(x)[1])
    assert clsamp.metrics.min_distance(x.astype(">f4")) == clsamp.metrics.min_distance(
        x.astype(np.float32))


@pytest.mark.parametrize("d", [4, 6])
def test_pcf_of_random_points_is_one_in_higher_dimensions(d):
    # issue 37: any d; the expected PCF of white noise is 1 within its Poisson noise
    n, r = 2048, 4
    pts = clsamp.make_sampler("random", d=d, seed=d).sample(n, realizations=r)
    radii, g = clsamp.pair_correlation(pts, radii=np.linspace(0.2, 0.4, 9), sigma=0.01)
    surface = 2 * math.pi ** (d / 2) / math.gamma(d / 2) * radii ** (d - 1)
    pairs = r * n * n * surface * 2.5 * 0.01
    assert np.all(np.abs(g - 1) <= 5 / np.sqrt(pairs)), np.abs(g - 1) * np.sqrt(pairs)


@pytest.mark.parametrize("d,n,radii", [(1, 300, None), (2, 700, None), (3, 1500, None),
                                        (4, 256, np.linspace(0.05, 0.3, 6))])
def test_pcf_in_the_cube_equals_its_twin(d, n, radii):
    pts = clsamp.make_sampler("random", d=d, seed=7).sample(n, realizations=2)
    _, g1 = clsamp.pair_correlation(pts, radii=radii, periodic=False)
    _, g2 = clsamp.pair_correlation(pts, radii=radii, periodic=False, backend="numpy")
    np.testing.assert_allclose(g1, g2, rtol=1e-12, atol=1e-12)


def test_pcf_in_the_cube_is_one_for_white_noise_by_its_edge_correction():
    # the translation correction keeps white noise at 1 in the cube; without it (the
    # pairs counted as they come) the pairs across the border are missing: 1 - 8r/(3 pi)
    # + r^2/(2 pi) of them at r in the unit square
    many = clsamp.make_sampler("random", d=2, seed=8).sample(2048, realizations=16)
    radii = np.linspace(0.05, 0.3, 11)
    _, corrected = clsamp.pair_correlation(many, radii=radii, sigma=0.005, periodic=False)
    assert np.all(np.abs(corrected - 1) < 0.03), corrected
    s = np.sqrt(neighbors.distance2(many[0][:, None, :], many[0][None, :, :], periodic=False))
    within = np.mean(s[np.triu_indices(2048, 1)] < 0.3)
    assert within == pytest.approx(math.pi * 0.09 - 8 * 0.3**3 / 3 + 0.3**4 / 2, rel=0.03)


def test_min_distance_in_the_cube_and_in_any_dimension():
    pts = np.array([[0.02, 0.5], [0.97, 0.5], [0.5, 0.9]])
    assert min_distance(pts) == pytest.approx(0.05)
    assert min_distance(pts, periodic=False) == pytest.approx(np.hypot(0.47, 0.4))
    assert min_distance(pts[:1], periodic=False) == np.inf and min_distance(pts[:1]) == 1.0
    for d, periodic in ((4, True), (4, False), (6, False)):
        x = clsamp.make_sampler("random", d=d, seed=d).sample(2000, realizations=2)
        nn = clsamp.nearest_neighbor_distances(x, periodic=periodic)
        np.testing.assert_array_equal(min_distance(x, periodic=periodic), nn.min(axis=1))
    with pytest.raises(InvalidArgumentError, match="'periodic'"):
        min_distance(pts, periodic=1)


def test_nearest_neighbors_in_the_cube_do_not_wrap():
    pts = np.array([[0.02, 0.5], [0.97, 0.5], [0.5, 0.5]])
    np.testing.assert_allclose(clsamp.nearest_neighbor_distances(pts), [0.05, 0.05, 0.47])
    np.testing.assert_allclose(clsamp.nearest_neighbor_distances(pts, periodic=False), [0.48, 0.47, 0.47])
    for d in (1, 2, 3, 5):
        x = clsamp.make_sampler("random", d=d, seed=d).sample(1500, realizations=2)
        assert np.array_equal(clsamp.nearest_neighbor_distances(x, periodic=False),
                              np.stack([neighbors.nearest_neighbor_reference(s, periodic=False)
                                        for s in x]))
        assert np.all(clsamp.nearest_neighbor_distances(x, periodic=False)
                      >= clsamp.nearest_neighbor_distances(x))


# -- nearest neighbours -------------------------------------------------------------------


def test_nearest_neighbors_equal_the_twin_bit_for_bit():
    rng = np.random.default_rng(5)
    for d in (1, 2, 3, 4):
        for n in (2, 3, 60, 2000):
            x = rng.random((n, d))
            assert np.array_equal(clsamp.nearest_neighbor_distances(x),
                                  neighbors.nearest_neighbor_reference(x))
    # a cluster and a few far points: neighbours beyond the grid's reach
    x = np.concatenate([0.5 + 1e-3 * rng.random((3000, 2)), rng.random((5, 2))])
    assert np.array_equal(clsamp.nearest_neighbor_distances(x), neighbors.nearest_neighbor_reference(x))


def test_nearest_neighbors_known_sets_and_min_distance():
    m = 16
    g = (np.stack(np.meshgrid(np.arange(m), np.arange(m)), -1).reshape(-1, 2) + 0.5) / m
    assert np.all(clsamp.nearest_neighbor_distances(g) == 1 / m)
    pd = clsamp.make_sampler("poisson_disk", d=2, seed=1)
    pts = pd.sample(1000, realizations=3)
    nn = clsamp.nearest_neighbor_distances(pts)
    assert nn.shape == (3, 1000)
    assert np.array_equal(nn.min(axis=1), min_distance(pts))
    sets = [pts[0], pts[1, :10]]
    out = clsamp.nearest_neighbor_distances(sets)
    assert isinstance(out, list) and [len(o) for o in out] == [1000, 10]


def test_nearest_neighbors_bad_input():
    with pytest.raises(InvalidArgumentError, match="at least 2"):
        clsamp.nearest_neighbor_distances(np.array([[0.5, 0.5]]))
    with pytest.raises(InvalidArgumentError, match="backend"):
        clsamp.nearest_neighbor_distances(np.random.default_rng(0).random((5, 2)), backend="gpu")


def test_discrepancy_sweep_slopes_match_the_known_rates():
    from clsamp import theory
    from clsamp.metrics import discrepancy_sweep
    ns = [64, 256, 1024, 4096, 16384]
    for name in ("random", "jittered", "sobol"):
        sweeps = discrepancy_sweep(clsamp.make_sampler(name, d=2, seed=5), ns, realizations=8)
        known, _ = theory.discrepancy_rate(name)
        for method, sweep in sweeps.items():
            slope, stderr = sweep.slope()
            assert sweep.ns.tolist() == ns and np.all(sweep.values > 0)
            # low discrepancy: the log factor keeps the slope a little above -1
            assert known - 0.08 < slope < known + (0.15 if known == -1.0 else 0.08), (name, method, slope)
    regular = discrepancy_sweep(clsamp.make_sampler("regular", d=2), [60, 250], realizations=1)
    assert regular["CD"].ns.tolist() == [64, 256]      # moved to valid counts (squares)


_X = np.random.default_rng(0).random((64, 2))


@pytest.mark.parametrize("call, match", [
    # sums past a double's range: '-inf + inf in fsum', an OverflowError or a NaN conversion
    (lambda: clsamp.discrepancy(np.full((3, 600), 0.5), "MD"), r"terms reach 5\^d, past a double's range"),
    (lambda: clsamp.discrepancy(np.full((1, 20000), 0.5), "CD"), r"at most d = 1748 for n = 1"),
    (lambda: clsamp.discrepancy(np.full((3, 2000), 0.5), "symmetric", backend="numpy"), "past a double"),
    # public twins that answered for another method, or for the first two coordinates
    (lambda: metrics.discrepancy_reference(_X, "cd"), "'method' must be one of"),
    (lambda: metrics.star_discrepancy_reference(np.full((10, 3), 0.5)), "'points' must have 2 dimensions"),
    (lambda: metrics.mean_spacing(-4, 2), "'n' must be an integer >= 1"),        # a complex number
    (lambda: metrics.mean_spacing(4, 0), "'d' must be an integer >= 1"),         # ZeroDivisionError
    (lambda: clsamp.star_discrepancy(_X, delta="abc"), "'delta' is the bounds' gap"),   # ignored
    (lambda: clsamp.star_discrepancy(np.full((200, 3), 0.5), backend="numpy"), "takes n <= 128"),  # days
    (lambda: metrics.normalized_energy(_X, backend="x"), "'backend' must be one of"),    # ran OpenCL
    (lambda: metrics.normalized_energy(_X, density=10**9), "'density' must be an integer <="),
    (lambda: clsamp.pair_correlation(_X, sigma=1e-300), "'sigma' 1e-300 is too small"),  # ZeroDivision
    (lambda: clsamp.pair_correlation(_X, sigma=1e-20), "too small for the radii"),       # all NaN
    (lambda: metrics.discrepancy_sweep(None, [16]), "'sampler' must be a Sampler"),
    (lambda: metrics.discrepancy_sweep("random", [16], methods=[]), "'methods' must name"),
    (lambda: metrics.discrepancy_sweep("random", [16], realizations=0), "'realizations' must be"),
    (lambda: metrics.discrepancy_sweep("random", 16), "'ns' must be a sequence"),
    (lambda: metrics.discrepancy_sweep("random", [16.7]), "'ns' must be an integer"),    # was 16
    (lambda: metrics.discrepancy_sweep("random", [16, 2**33]), r"'ns' must be an integer <="),
    (lambda: metrics.discrepancy_sweep("random", [16], checkpoint=5), "'checkpoint' must be a folder"),
])
def test_metric_arguments_are_one_line_before_any_work(call, match):
    with pytest.raises(InvalidArgumentError, match=match):
        call()


def test_bounds_take_a_numpy_bool_and_a_sweep_a_name_and_one_method():
    assert clsamp.star_discrepancy(_X, bounds=np.True_).lower <= clsamp.star_discrepancy(_X)
    sweep = metrics.discrepancy_sweep("random", [16, 64], methods="CD")     # 'C' and 'D' before
    assert list(sweep) == ["CD"] and list(sweep["CD"].ns) == [16, 64]


@pytest.mark.parametrize("n, d", [(3, 1), (9, 2), (21, 2), (14, 3), (52, 3), (78, 4), (37, 5), (22, 6)])
def test_pair_correlation_takes_its_own_default_radii(n, d):
    # the last default radius rounded one ulp up, past 1/2 - 5 sigma: its own check refused it
    radii, g = clsamp.pair_correlation(np.random.default_rng(n).random((n, d)))
    assert len(radii) == len(g) and np.all(np.isfinite(g))
