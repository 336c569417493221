"""Analyses without fp64 (kernels/float_float.h, clsamp.spectrum_ff, the float-float paths
of clsamp.metrics.l2 and .neighbors): the arithmetic within its published bounds against
exact fractions; the direct power spectrum, the L2-type discrepancies, the pair
correlation and the nearest-neighbour distances within their stated bounds of the float64 results; the star
discrepancy's certified bounds (comparisons of bit patterns) equal to them. With fp64 on
PoCL, under ``runtime.without_fp64()`` (what a device without fp64 runs) and on a real
device without fp64 where one is installed (Mesa's rusticl on llvmpipe)."""

from fractions import Fraction

import numpy as np
import pytest

import clsamp
from clsamp import runtime
from clsamp.errors import InvalidArgumentError, NoDeviceError
from clsamp.float_float import U2, check_precision, join, split
from clsamp.metrics import discrepancy, nearest_neighbor_distances, neighbors, pair_correlation
from clsamp.metrics.l2 import METHODS, ROOTED, float_float_bound
from clsamp.metrics.star import anchored_counts, star_bounds
from clsamp.spectrum import direct_reference, power_spectrum, twiddles_reference
from clsamp.spectrum_ff import error_bound, sincos_tables, twiddles

DEFAULT = runtime.current_device()
WITHOUT_FP64 = [d for d in runtime.devices()
                if not d.fp64 and not d.simulator and runtime.compiles(d.index)]


def _pairs(rng, count, scale):
    x = rng.uniform(-1.0, 1.0, count) * scale
    return split(x * (1.0 + rng.uniform(-1e-9, 1e-9, count)))


def _exact(pair):
    return Fraction(float(pair[0])) + Fraction(float(pair[1]))


def test_float_float_operations_keep_their_bounds():
    """ff_add within 3u² + 13u³ and ff_mul within 5u², ff_mul_f within 2u² of the exact
    result (Joldes, Muller & Popescu 2017), on operands of mixed signs and magnitudes."""
    import pyopencl.array as cla
    rng = np.random.default_rng(4)
    count = 3000
    x = _pairs(rng, count, 10.0 ** rng.integers(-6, 7, count))
    y = _pairs(rng, count, 10.0 ** rng.integers(-6, 7, count))
    y[:200] = -x[:200] * np.float32(rng.uniform(0.5, 2.0, (200, 1)))      # near cancellations
    f = rng.uniform(-3.0, 3.0, count).astype(np.float32)
    q = runtime.queue()
    out = cla.empty(q, (count, 3, 2), np.float32)
    args = [cla.to_device(q, np.ascontiguousarray(v)) for v in (x, y, f)]
    runtime.kernel("float_float_probe.cl", "float_float_ops")(
        q, (count,), None, *(a.data for a in args), out.data, np.uint32(count))
    got = out.get()
    runtime.kernel("float_float_probe.cl", "float_float_ops8")(
        q, (count // 8,), None, *(a.data for a in args), out.data, np.uint32(count))
    assert np.array_equal(out.get(), got)                  # the float8 lanes: the same bits
    u = Fraction(1, 2**24)
    for i in range(count):
        a, b = _exact(x[i]), _exact(y[i])
        for k, (want, bound) in enumerate(((a + b, 3 * u**2 + 13 * u**3), (a * b, 5 * u**2),
                                           (a * Fraction(float(f[i])), 2 * u**2))):
            assert abs(_exact(got[i, k]) - want) <= bound * abs(want), (i, k)


def test_float_float_division_keeps_its_bound():
    """FF_DIV within 15u² + 56u³ (their Algorithm 17), here and on every device without fp64."""
    import pyopencl.array as cla
    rng = np.random.default_rng(5)
    count = 2000
    x = _pairs(rng, count, 10.0 ** rng.integers(-6, 7, count))
    y = _pairs(rng, count, 10.0 ** rng.integers(-6, 7, count))
    u = Fraction(1, 2**24)

    def divide():
        q = runtime.queue()
        args = [cla.to_device(q, np.ascontiguousarray(v)) for v in (x, y)]
        out = cla.empty(q, (count, 2), np.float32)
        runtime.kernel("float_float_probe.cl", "float_float_div")(
            q, (count,), None, args[0].data, args[1].data, out.data, np.uint32(count))
        return out.get()

    results = [divide()]
    for device in WITHOUT_FP64:
        runtime.use_device(device.index)
        try:
            results.append(divide())
        finally:
            runtime.use_device(DEFAULT.index)
    for got in results:
        for i in range(count):
            want = _exact(x[i]) / _exact(y[i])
            assert abs(_exact(got[i]) - want) <= (15 * u**2 + 56 * u**3) * abs(want), i


def test_split_and_join():
    x = np.random.default_rng(1).random(1000)
    pairs = split(x)
    assert pairs.dtype == np.float32 and pairs.shape == (1000, 2)
    assert np.all(np.abs(join(pairs) - x) <= U2 * x)


def test_the_sincos_tables_are_within_u2():
    t = sincos_tables().astype(np.float64)
    i = np.arange(1024)
    for level, scale in ((0, 2.0**-10), (1, 2.0**-20)):
        angle = 2 * np.pi * i * scale
        assert np.all(np.abs(t[level, :, 0] + t[level, :, 1] - np.cos(angle)) <= 1.1 * U2)
        assert np.all(np.abs(t[level, :, 2] + t[level, :, 3] - np.sin(angle)) <= 1.1 * U2)


def test_twiddles_match_the_float64_reference():
    """Exact integer phases for any frequency, then the tables: each twiddle within 64u²
    (the bound's budget for a factor of a term), at frequencies up to 2^40."""
    rng = np.random.default_rng(2)
    x = rng.random((2, 300, 2))
    x[0, :4, 0] = [0.0, 0.5, 2.0**-60, np.nextafter(1.0, 0.0)]         # zero, exact, tiny, largest
    for f0, count in ((-64, 129), (2**40, 16), (-(2**33) - 5, 8)):
        got = twiddles(runtime.to_device(x), f0, count, 0).get()
        w = got[..., 0].astype(np.float64)
        z = (w[..., 0] + w[..., 1]) + 1j * (w[..., 2] + w[..., 3])
        want = twiddles_reference(x[:, :, 0], np.arange(f0, f0 + count))
        assert np.max(np.abs(np.swapaxes(z, 1, 2) - want)) <= 64 * U2, f0


def _sets(d, n=700, r=3, seed=5):
    return np.random.default_rng(seed).random((r, n, d))


@pytest.mark.parametrize("d, resolution", [(1, 64), (2, 48), (3, 12)])
def test_the_float_float_spectrum_is_within_its_bound(d, resolution):
    pts = _sets(d)
    want = direct_reference(pts, resolution)
    got = power_spectrum(pts, resolution, method="direct", precision="float-float", progress=False)
    assert got.shape == want.shape
    error = np.max(np.abs(got - want))
    assert error <= error_bound(pts.shape[1])
    assert error <= 1e-12 * pts.shape[1]            # typical errors: random signs, far below
    assert got[(resolution // 2,) * d] == pytest.approx(pts.shape[1], rel=1e-13)


def test_without_fp64_the_default_is_float_float():
    pts = _sets(2, n=500, r=2)
    explicit = power_spectrum(pts, 32, method="direct", precision="float-float", progress=False)
    with runtime.without_fp64():
        assert check_precision(None) == "float-float"
        for method in ("auto", "direct"):
            got = power_spectrum(pts, 32, method=method, progress=False)
            assert np.array_equal(got, explicit)
        with pytest.raises(NoDeviceError, match="'precision' 'double' needs fp64"):
            power_spectrum(pts, 32, precision="double", progress=False)
        fast = power_spectrum(pts, 32, method="fast", tol=1e-6, progress=False)
        assert np.max(np.abs(fast - explicit)) <= 2e-6 * pts.shape[1]
    assert check_precision(None) == "double"


def test_precision_is_checked_in_one_line():
    pts = _sets(2, n=16, r=1)
    with pytest.raises(InvalidArgumentError, match="'precision' must be one of 'double', 'float-float'"):
        power_spectrum(pts, 16, precision="single")
    with pytest.raises(InvalidArgumentError, match="'tol' must be >= 1e-11 for method='fast' in float-float"):
        power_spectrum(pts, 16, method="fast", tol=1e-12, precision="float-float")


def test_a_grid_in_float_float():
    """The k x k grid: P = N at multiples of k, 0 elsewhere (up to the bound)."""
    k, R = 8, 32
    g = (np.stack(np.meshgrid(np.arange(k), np.arange(k), indexing="ij"), -1).reshape(-1, 2) + 0.5) / k
    P = power_spectrum(g, R, precision="float-float", progress=False)
    f = np.arange(-R // 2, R // 2)
    peak = (f[:, None] % k == 0) & (f[None, :] % k == 0)
    assert np.allclose(P[peak], k * k, rtol=0, atol=error_bound(k * k))
    assert np.max(np.abs(P[~peak])) <= error_bound(k * k)


def test_sets_of_different_sizes_and_expected_spectrum():
    rng = np.random.default_rng(3)
    sets = [rng.random((n, 2)) for n in (100, 130, 100)]
    got = power_spectrum(sets, 16, precision="float-float", progress=False)
    want = power_spectrum(sets, 16, backend="numpy", progress=False)
    assert np.max(np.abs(got - want)) <= error_bound(130)
    s = clsamp.make_sampler("jittered", seed=1)
    got = clsamp.expected_spectrum(s, 256, 4, resolution=16, precision="float-float", progress=False)
    want = clsamp.expected_spectrum(s, 256, 4, resolution=16, method="direct", progress=False)
    assert np.max(np.abs(got - want)) <= error_bound(256)


@pytest.mark.parametrize("device", WITHOUT_FP64, ids=lambda d: f"{d.index}-{d.platform[:12]}")
def test_a_device_without_fp64_computes_spectra_in_float_float(device):
    pts = _sets(2, n=600, r=2)
    want = direct_reference(pts, 32)
    runtime.use_device(device.index)
    try:
        got = power_spectrum(pts, 32, progress=False)
        got1 = power_spectrum(pts[..., :1], 32, progress=False)
    finally:
        runtime.use_device(DEFAULT.index)
    assert np.max(np.abs(got - want)) <= error_bound(600)
    assert np.max(np.abs(got1 - direct_reference(pts[..., :1], 32))) <= error_bound(600)


def _squared(method, value):
    return value * value if method in ROOTED else value


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("d", [1, 3, 8])
def test_float_float_discrepancies_are_within_their_bound(method, d):
    pts = _sets(d, n=301, r=2, seed=d)
    pts[0, 0] = 0.5                                     # the CD's side of 1/2 at its edge
    want = _squared(method, discrepancy(pts, method, precision="double"))
    got = _squared(method, discrepancy(pts, method, precision="float-float"))
    assert np.all(np.abs(got - want) <= float_float_bound(method, d)), (got - want)
    with runtime.without_fp64():
        assert np.array_equal(_squared(method, discrepancy(pts, method)), got)


@pytest.mark.parametrize("n", [1, 2, 7, 9, 17])
def test_float_float_discrepancies_of_small_sets(n):
    """Sets that fill part of a tile of eight rows, one tile or an odd count of them."""
    pts = np.random.default_rng(n).random((n, 3))
    for method in METHODS:
        want = _squared(method, discrepancy(pts, method, precision="double"))
        got = _squared(method, discrepancy(pts, method, precision="float-float"))
        assert abs(got - want) <= float_float_bound(method, 3), method


def test_discrepancy_precision_is_checked():
    pts = _sets(2, n=16, r=1)[0]
    with pytest.raises(InvalidArgumentError, match="'precision' must be one of"):
        discrepancy(pts, "CD", precision="half")
    with runtime.without_fp64(), pytest.raises(NoDeviceError, match="'precision' 'double' needs fp64"):
        discrepancy(pts, "CD", precision="double")


def test_float_float_discrepancy_of_a_larger_set_ranks_as_double():
    """Sobol' against random at n = 4096 in 4-D: both paths agree to the bound and order."""
    sob = clsamp.make_sampler("sobol", d=4).sample(4096)
    rnd = clsamp.make_sampler("random", d=4, seed=2).sample(4096)
    for pts in (sob, rnd):
        assert abs(discrepancy(pts, precision="float-float") - discrepancy(pts)) <= float_float_bound("CD", 4)
    assert discrepancy(sob, precision="float-float") < discrepancy(rnd, precision="float-float")


@pytest.mark.parametrize("device", WITHOUT_FP64, ids=lambda d: f"{d.index}-{d.platform[:12]}")
def test_a_device_without_fp64_computes_discrepancies_in_float_float(device):
    pts = _sets(3, n=200, r=2)
    want = {m: _squared(m, discrepancy(pts, m)) for m in METHODS}
    runtime.use_device(device.index)
    try:
        got = {m: _squared(m, discrepancy(pts, m)) for m in METHODS}
    finally:
        runtime.use_device(DEFAULT.index)
    for m in METHODS:
        assert np.all(np.abs(got[m] - want[m]) <= float_float_bound(m, 3)), m


@pytest.mark.parametrize("strict", [True, False])
def test_anchored_counts_without_fp64_are_the_same(strict):
    """Bit patterns compared as integers: the same counts, corners on points, 0 and 1 included."""
    rng = np.random.default_rng(6)
    pts = rng.random((400, 3))
    corners = rng.random((1001, 3))
    corners[:20] = pts[:20]
    corners[20], corners[21] = 1.0, 0.0
    corners[22] = [pts[0, 0], 1.0, 0.0]
    want = anchored_counts(pts, corners, strict)
    with runtime.without_fp64():
        assert np.array_equal(anchored_counts(pts, corners, strict), want)
    assert np.array_equal(want, anchored_counts(pts, corners, strict, backend="numpy"))


def test_star_bounds_without_fp64_are_the_same():
    pts = _sets(3, n=150, r=1)[0]
    want = star_bounds(pts, delta=0.1)
    with runtime.without_fp64():
        assert star_bounds(pts, delta=0.1) == want
        assert clsamp.star_discrepancy(pts, bounds=True, delta=0.1) == want
    for device in WITHOUT_FP64:
        runtime.use_device(device.index)
        try:
            assert star_bounds(pts, delta=0.1) == want, str(device)
        finally:
            runtime.use_device(DEFAULT.index)


@pytest.mark.parametrize("periodic", [True, False])
@pytest.mark.parametrize("d", [1, 2, 4])
def test_float_float_nearest_neighbours_are_within_their_bound(d, periodic):
    pts = _sets(d, n=1500, r=2, seed=10 + d)
    pts[0, 1] = pts[0, 0] + 1e-12                         # a pair closer than float's ulp
    want = nearest_neighbor_distances(pts, periodic=periodic, precision="double")
    got = nearest_neighbor_distances(pts, periodic=periodic, precision="float-float")
    assert np.all(np.abs(got - want) <= neighbors.float_float_bound(want, d))
    assert np.mean(got == want) > 0.999                   # the double path's bits, but near ties
    with runtime.without_fp64():
        assert np.array_equal(nearest_neighbor_distances(pts, periodic=periodic), got)
        with pytest.raises(NoDeviceError, match="'precision' 'double' needs fp64"):
            nearest_neighbor_distances(pts, precision="double")


def test_float_float_nearest_neighbours_of_a_grid_and_of_sets():
    g = (np.stack(np.meshgrid(np.arange(8), np.arange(8)), -1).reshape(-1, 2) + 0.5) / 8
    assert set(nearest_neighbor_distances(g, precision="float-float").tolist()) == {0.125}
    sets = [np.random.default_rng(k).random((n, 2)) for k, n in enumerate((50, 80))]
    got = nearest_neighbor_distances(sets, precision="float-float")
    for a, b in zip(got, nearest_neighbor_distances(sets, backend="numpy"), strict=True):
        assert np.all(np.abs(a - b) <= neighbors.float_float_bound(b, 2))


@pytest.mark.parametrize("device", WITHOUT_FP64, ids=lambda d: f"{d.index}-{d.platform[:12]}")
def test_a_device_without_fp64_computes_nearest_neighbours(device):
    pts = _sets(2, n=500, r=2)
    want = nearest_neighbor_distances(pts)
    runtime.use_device(device.index)
    try:
        got = nearest_neighbor_distances(pts)
    finally:
        runtime.use_device(DEFAULT.index)
    assert np.all(np.abs(got - want) <= neighbors.float_float_bound(want, 2))


@pytest.mark.parametrize("periodic", [True, False])
@pytest.mark.parametrize("d", [1, 2, 3])
def test_float_float_pair_correlation_is_within_its_bound(d, periodic):
    pts = _sets(d, n=600, r=2, seed=20 + d)
    radii, want = pair_correlation(pts, periodic=periodic, precision="double")
    _, got = pair_correlation(pts, periodic=periodic, precision="float-float")
    sigma = neighbors.SIGMA_SPACING * neighbors.mean_spacing(600, d)
    eps = neighbors.pcf_float_float_bound(600, d, radii, sigma, periodic)
    assert np.all(np.abs(got - want) <= eps * want)
    assert np.max(np.abs(got - want)) <= 1e-11                # typical: far below the bound
    with runtime.without_fp64():
        assert np.array_equal(pair_correlation(pts, periodic=periodic)[1], got)


def test_float_float_pair_correlation_of_white_noise_and_given_radii():
    pts = clsamp.make_sampler("random", d=2, seed=3).sample(2048, realizations=2)
    radii = np.linspace(0.002, 0.05, 7)                      # not uniform: each radius apart
    radii[3] += 1e-4
    _, got = pair_correlation(pts, radii=radii, sigma=0.002, precision="float-float")
    _, want = pair_correlation(pts, radii=radii, sigma=0.002)
    eps = neighbors.pcf_float_float_bound(2048, 2, radii, 0.002)
    assert np.all(np.abs(got - want) <= eps * want)
    assert abs(got.mean() - 1) < 0.1


@pytest.mark.parametrize("device", WITHOUT_FP64, ids=lambda d: f"{d.index}-{d.platform[:12]}")
def test_a_device_without_fp64_computes_the_pair_correlation(device):
    pts = _sets(2, n=300, r=1)
    radii, want = pair_correlation(pts)
    runtime.use_device(device.index)
    try:
        _, got = pair_correlation(pts)
    finally:
        runtime.use_device(DEFAULT.index)
    sigma = neighbors.SIGMA_SPACING * neighbors.mean_spacing(300, 2)
    assert np.all(np.abs(got - want) <= neighbors.pcf_float_float_bound(300, 2, radii, sigma) * want)


def test_device_arrays_are_checked_without_fp64():
    """check_points reads a device array's range by bit patterns where there is no fp64:
    the same answers, so sample_device output and expected_spectrum run there."""
    vals = np.array([0.5, 0.25, -0.0, 0.0, 0.999, 1e-300, -1e-5, 2.0, np.inf, np.nan, -np.inf, 5e-324])
    for pick in ([0, 1, 2, 3, 4, 5], [0, 1, 6], [0, 7], [0, 8], [0, 9], [1, 10], [3, 11], [2]):
        want = runtime.bounds(runtime.to_device(vals[pick]))
        with runtime.without_fp64():
            assert runtime.bounds(runtime.to_device(vals[pick])) == want, pick
    bad = runtime.to_device(np.array([[[0.5, 1.0]]]))
    with runtime.without_fp64(), pytest.raises(InvalidArgumentError, match=r"\[0, 1\)"):
        power_spectrum(bad, 16)
    s = clsamp.make_sampler("jittered", seed=1)
    want = power_spectrum(s.sample(256, realizations=2), 16, progress=False)
    with runtime.without_fp64():
        got = power_spectrum(s.sample_device(256, realizations=2), 16, progress=False)
        assert np.max(np.abs(got - want)) <= error_bound(256)
        assert np.array_equal(clsamp.expected_spectrum(s, 256, 2, resolution=16, progress=False), got)
    for device in WITHOUT_FP64:
        runtime.use_device(device.index)
        try:
            got = clsamp.expected_spectrum(s, 256, 2, resolution=16, progress=False)
        finally:
            runtime.use_device(DEFAULT.index)
        assert np.max(np.abs(got - want)) <= error_bound(256), str(device)


@pytest.mark.parametrize("file", ["spectrum_ff.cl", "discrepancy_ff.cl", "neighbors_ff.cl",
                                  "anchored_counts.cl", "points.cl", "float_float_probe.cl"])
def test_these_kernels_use_no_double_without_fp64(file):
    assert not runtime.needs_fp64(file)


@pytest.mark.parametrize("d", [1, 2])
@pytest.mark.parametrize("tol", [1e-3, 1e-7, 1e-11])
def test_the_fast_spectrum_in_float_float_meets_its_tolerance(d, tol):
    """Float-float spreading (exact node and fraction from the fixed-point coordinate),
    the FFT in float64: within tol·N of the exact spectrum, as the double path."""
    pts = _sets(d, n=1500, r=2, seed=30 + d)
    want = direct_reference(pts, 48)
    got = power_spectrum(pts, 48, method="fast", tol=tol, precision="float-float", progress=False)
    double = power_spectrum(pts, 48, method="fast", tol=tol, precision="double", progress=False)
    assert np.max(np.abs(got - want)) <= tol * pts.shape[1]
    assert np.max(np.abs(got - double)) <= 1e-12 * pts.shape[1]


def test_the_fast_spectrum_in_float_float_with_many_blocks():
    """Sets long enough to be spread over several grid copies, summed in float-float."""
    pts = _sets(2, n=5000, r=1, seed=3)
    got = power_spectrum(pts, 32, method="fast", tol=1e-9, precision="float-float", progress=False)
    assert np.max(np.abs(got - direct_reference(pts, 32))) <= 1e-9 * 5000


@pytest.mark.parametrize("device", WITHOUT_FP64, ids=lambda d: f"{d.index}-{d.platform[:12]}")
def test_a_device_without_fp64_computes_the_fast_spectrum(device):
    pts = _sets(2, n=800, r=1)
    runtime.use_device(device.index)
    try:
        got = power_spectrum(pts, 32, method="fast", tol=1e-9, progress=False)
    finally:
        runtime.use_device(DEFAULT.index)
    assert np.max(np.abs(got - direct_reference(pts, 32))) <= 1e-9 * 800
