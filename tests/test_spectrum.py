"""Power spectra: the OpenCL kernels against their NumPy references, against an independent
sum and finufft, the fast path's error bound, hard cases, radial mean, anisotropy, pictures,
the command line and bad input."""

import math

import numpy as np
import pytest

import clsamp
from clsamp import nufft, philox, plots, spectrum
from clsamp.errors import InvalidArgumentError


def white(r, n, d=2, seed=5):
    return philox.uniform_block(seed, philox.Stream.POINTS, np.arange(r), n, d, 0)


def brute_force(points, resolution):
    """The periodogram by its definition, one exp per (point, frequency), in NumPy."""
    batch = points if points.ndim == 3 else points[None]
    f = np.arange(-resolution // 2, resolution // 2)
    total = 0.0
    for block in batch:
        if block.shape[1] == 1:
            S = np.exp(-2j * np.pi * np.outer(f, block[:, 0])).sum(axis=1)
        else:
            phase = f[:, None, None] * block[:, 0] + f[None, :, None] * block[:, 1]
            S = np.exp(-2j * np.pi * phase).sum(axis=-1)
        total = total + np.abs(S) ** 2
    return total / (batch.shape[0] * batch.shape[1])


@pytest.fixture(scope="module")
def small2():
    pts = white(3, 200, 2)
    return pts, brute_force(pts, 32)


@pytest.fixture(scope="module")
def medium2():
    pts = white(4, 1000, 2, seed=9)
    return pts, spectrum.power_spectrum(pts, 64, method="direct")


# -- direct ------------------------------------------------------------------------------
@pytest.mark.parametrize("d", [1, 2])
def test_direct_kernel_equals_reference_and_definition(d):
    pts = white(3, 200, d)
    R = 32 if d == 2 else 64
    exact = brute_force(pts, R)
    cl = clsamp.power_spectrum(pts, R, method="direct")
    ref = clsamp.power_spectrum(pts, R, method="direct", backend="numpy")
    assert cl.shape == (R,) * d
    assert np.abs(cl - ref).max() <= 1e-12 * 200
    assert np.abs(cl - exact).max() <= 1e-11 * 200   # the brute force's own phases round
    assert cl[(R // 2,) * d] == pytest.approx(200, rel=1e-14)


def test_direct_equals_finufft():
    finufft = pytest.importorskip("finufft")
    pts = white(2, 3000, 2, seed=2)
    R = 48
    P = clsamp.power_spectrum(pts, R, method="direct")
    total = 0.0
    for block in pts:
        f = finufft.nufft2d1(2 * np.pi * block[:, 0], 2 * np.pi * block[:, 1],
                             np.ones(len(block), complex), (R, R), eps=1e-14, isign=-1)
        total = total + np.abs(f) ** 2
    assert np.abs(P - total / (2 * 3000)).max() <= 1e-9 * 3000


def test_twiddles_reference_is_the_exponential():
    x = np.array([0.0, 0.1, 0.5, 0.7312, 1 - 2.0**-53, 2.0**-70])
    f = np.arange(-300, 45)
    tw = spectrum.twiddles_reference(x, f)
    naive = np.exp(-2j * np.pi * np.outer(x, f.astype(np.float64)))
    assert np.abs(tw - naive).max() < 1e-12


def test_fixed_point_is_exact():
    x = np.array([0.0, 0.5, 0.25 + 2.0**-40, 1 - 2.0**-53])
    X = spectrum.fixed_point(x)
    assert X.tolist() == [0, 2**63, 2**62 + 2**24, 2**64 - 2**11]


# -- fast --------------------------------------------------------------------------------
@pytest.mark.parametrize("tol", [1e-3, 1e-6, 1e-10])
def test_fast_within_tol(tol, medium2):
    pts, exact = medium2
    P = clsamp.power_spectrum(pts, 64, method="fast", tol=tol)
    assert np.abs(P - exact).max() <= tol * pts.shape[1]


@pytest.mark.parametrize("tol", [1e-3, 1e-6, 1e-10])
def test_fast_within_tol_worst_case_and_1d(tol):
    # coincident points: |S| = N at every frequency, the kernel error is not averaged away
    dup = np.full((1, 64, 2), 0.3141592653589793)
    P = clsamp.power_spectrum(dup, 32, method="fast", tol=tol)
    assert np.abs(P - 64).max() <= tol * 64
    line = white(2, 500, 1, seed=4)
    P1 = clsamp.power_spectrum(line, 64, method="fast", tol=tol)
    assert np.abs(P1 - brute_force(line, 64)).max() <= tol * 500


def test_spread_kernel_equals_reference():
    import pyopencl.array as cla

    from clsamp import runtime
    pts = white(2, 3000, 2, seed=8)
    sigma, width, beta = spectrum.nufft_parameters(1e-6)
    M = 96
    kernel = runtime.kernel("nufft.cl", "spectrum_spread", {"DIM": 2, "WIDTH": width}, ("-cl-mad-enable",))
    out = cla.empty(runtime.queue(), (2, M, M), np.float64)
    kernel(runtime.queue(), (1, 2), (1, 1), cla.to_device(runtime.queue(), pts).data, out.data,
           np.uint32(3000), np.uint32(M), np.uint32(1), np.float64(beta))
    ref = spectrum.spread_reference(pts, M, width, beta)
    assert np.abs(out.get() - ref).max() <= 1e-13 * np.abs(ref).max()


def test_fast_numpy_backend_and_split_blocks(monkeypatch):
    # one realization is split over several work-items' grid copies, then summed
    pts = white(1, 4096, 2, seed=3)
    cl = clsamp.power_spectrum(pts, 32, method="fast", tol=1e-10)
    ref = clsamp.power_spectrum(pts, 32, method="fast", tol=1e-10, backend="numpy")
    assert np.abs(cl - ref).max() <= 1e-12 * 4096
    # and chunks of realizations when the device budget is small
    monkeypatch.setattr(spectrum, "WORKING_SET", 100_000)
    batch = white(3, 300, 2)
    chunked = clsamp.power_spectrum(batch, 32, method="fast", tol=1e-10)
    assert np.abs(chunked - brute_force(batch, 32)).max() <= 1e-10 * 300


def test_direct_chunks_points_and_realizations(monkeypatch, small2):
    pts, exact = small2
    monkeypatch.setattr(spectrum, "WORKING_SET", 60_000)   # a few dozen points per chunk
    P = clsamp.power_spectrum(pts, 32, method="direct")
    assert np.abs(P - exact).max() <= 1e-11 * 200


EXTENDED = np.finfo(np.longdouble).eps < np.finfo(np.float64).eps


@pytest.mark.skipif(not EXTENDED, reason="NumPy's longdouble is float64 here")
@pytest.mark.parametrize("sigma, width", [(1.25, 8), (1.5, 11), (2.0, 15), (2.0, 16)])
def test_kernel_transform_to_an_ulp(sigma, width):
    # against 40 panels of 24 Gauss-Legendre nodes in z itself, graded towards z = ±1
    # where φ's derivative is singular: a different rule for the same integral
    beta, M = nufft._beta(sigma, width), 512
    k = np.array([0, 1, 17, 64, 128, M // (2 * sigma)], dtype=np.longdouble)   # as far as used
    x, wt = nufft._gauss_legendre(24)
    edges = 1 - (1 - np.linspace(0, 1, 41, dtype=np.longdouble)) ** 3       # 0 .. 1, graded
    total = np.zeros(k.size, np.longdouble)
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        z = (a + b) / 2 + (b - a) / 2 * x
        phi = np.exp(-beta * z * z / (1 + np.sqrt(1 - z * z)))
        total += (b - a) * (np.cos(np.outer(k, z) * (np.pi * width / M)) @ (wt * phi))  # 2x halves
    reference = (width / 2 * total).astype(np.float64)
    got = nufft.kernel_transform(k.astype(np.float64), M, width, beta)
    assert np.abs(got / reference - 1).max() <= 4 * np.finfo(np.float64).eps


@pytest.mark.skipif(not EXTENDED, reason="NumPy's longdouble is float64 here")
def test_fast_at_the_floor_is_exact_at_zero():
    # every point's error at k shares ψ̂(k)'s, so P(0) = N is where an inexact ψ̂ or a
    # float64 sum over realizations shows, N times over (old: 2.9e-14 relative); random
    # offsets average the kernel's own error at 0 away (a grid's do not: tol bounds that)
    pts = white(16, 2048, 2, seed=21)
    P = clsamp.power_spectrum(pts, 64, method="fast", tol=1e-12)
    assert abs(P[32, 32] - 2048) <= 8 * np.finfo(np.float64).eps * 2048


def test_kernel_error_decreases_with_width():
    errors = [nufft.kernel_error(2.0, w) for w in (4, 8, 12, 16)]
    assert all(a > b for a, b in zip(errors[:-1], errors[1:], strict=True))
    assert errors[-1] < 1e-13


# -- hard cases ----------------------------------------------------------------------------
@pytest.mark.parametrize("offset", [0.0, 0.5])
def test_regular_grid_has_no_power_off_the_aliases(offset):
    g = (np.arange(256) + offset) / 256
    pts = np.stack(np.meshgrid(g, g, indexing="ij"), axis=-1).reshape(-1, 2)
    N = len(pts)
    P = clsamp.power_spectrum(pts, 128, method="direct")
    assert P[64, 64] == pytest.approx(N, rel=1e-12)
    off = P.copy()
    off[64, 64] = 0.0      # within [-64, 64)^2 only DC is a multiple of 256
    assert np.abs(off).max() <= 1e-12 * N
    fast = clsamp.power_spectrum(pts, 128, method="fast", tol=1e-10)
    assert np.abs(fast - P).max() <= 1e-10 * N


def test_million_points_at_1024():
    pts = white(1, 2**20, 2, seed=11)
    P = clsamp.power_spectrum(pts, 1024, method="fast", tol=1e-6)
    assert P.shape == (1024, 1024)
    assert P[512, 512] == pytest.approx(2**20, rel=1e-6)
    off = np.delete(P.ravel(), 512 * 1024 + 512)
    assert abs(off.mean() - 1.0) < 0.01          # white noise: E[P] = 1, 2^20 frequencies
    # exactness at a few frequencies, summed directly
    for i, j in ((0, 0), (512, 513), (700, 3), (1023, 1023)):
        u, v = i - 512, j - 512
        S = np.exp(-2j * np.pi * (u * pts[0, :, 0] + v * pts[0, :, 1])).sum()
        assert P[i, j] == pytest.approx(abs(S) ** 2 / 2**20, abs=1e-6 * 2**20)


def test_edge_points_and_duplicates():
    edge = np.array([[0.0, 0.0], [1 - 2.0**-53, 1 - 2.0**-53]])
    for method in ("direct", "fast"):
        P = clsamp.power_spectrum(edge, 16, method=method, tol=1e-10)
        # the two points are 2^-53 apart on the torus: P = |1 + e^{2πiω·ε}|² / 2 = 2
        assert np.abs(P - 2).max() <= 1e-10 * 2
    dup = np.tile(np.array([[0.25, 0.75], [0.5, 0.125]]), (50, 1))
    exact = brute_force(dup, 16)
    for method in ("direct", "fast"):
        P = clsamp.power_spectrum(dup, 16, method=method, tol=1e-10)
        assert np.abs(P - exact).max() <= 1e-10 * 100


def test_white_noise_mean_and_anisotropy():
    r = 16
    P = clsamp.power_spectrum(white(r, 1024, 2, seed=21), 64, method="fast", tol=1e-6)
    f, m = clsamp.radial_mean(P)
    assert abs(m.mean() - 1.0) < 0.02
    f, a = clsamp.anisotropy(P)
    assert abs(np.mean(a[5:]) + 10 * math.log10(r)) < 0.5


@pytest.mark.parametrize("method", ["direct", "fast"])
def test_batch_is_the_mean_of_single_periodograms(method):
    batch = white(4, 300, 2, seed=6)
    P = clsamp.power_spectrum(batch, 32, method=method, tol=1e-10)
    singles = [clsamp.power_spectrum(b, 32, method=method, tol=1e-10) for b in batch]
    assert np.abs(P - np.mean(singles, axis=0)).max() <= 1e-12 * 300
    union = clsamp.power_spectrum(batch.reshape(1, -1, 2), 32, method=method, tol=1e-10)
    assert np.abs(P - union).max() > 0.1       # not the transform of the union


def test_auto_picks_by_size_and_tolerance(small2):
    pts, exact = small2
    assert spectrum._choose_method((3, 200, 2), 32, None) == "direct"
    assert spectrum._choose_method((64, 4096, 2), 256, 1e-6) == "fast"
    assert np.abs(clsamp.power_spectrum(pts, 32) - exact).max() <= 1e-11 * 200


# -- radial mean, anisotropy, frequencies ----------------------------------------------------
def test_radial_mean_and_anisotropy_against_a_loop():
    rng = np.random.default_rng(0)
    R = 16
    P = rng.random((R, R)) + 0.5
    f, m = clsamp.radial_mean(P)
    f2, a = clsamp.anisotropy(P)
    assert f.tolist() == list(range(1, R // 2)) and f2.tolist() == f.tolist()
    for b in f.astype(int):
        values = [P[i, j] for i in range(R) for j in range(R)
                  if 0 < math.hypot(i - R // 2, j - R // 2) and
                  b - 0.5 <= math.hypot(i - R // 2, j - R // 2) < b + 0.5]
        assert m[b - 1] == pytest.approx(np.mean(values), rel=1e-12)
        assert a[b - 1] == pytest.approx(10 * math.log10(np.var(values, ddof=1) / np.mean(values) ** 2),
                                         rel=1e-10)
    f3, m3 = clsamp.radial_mean(P, bin_width=2.0)
    assert f3.tolist() == [2.0, 4.0, 6.0]


def test_radial_mean_1d_and_constant():
    P = np.full(32, 3.0)
    P[16] = 999.0
    f, m = clsamp.radial_mean(P)
    assert np.allclose(m, 3.0) and f[0] == 1.0
    f, a = clsamp.anisotropy(np.full((16, 16), 2.0))
    assert np.all(np.isneginf(a))


def test_normalized_frequency():
    assert spectrum.normalized_frequency([16, 32], 1024).tolist() == [1.0, 2.0]
    assert spectrum.normalized_frequency([16, 32], 1024, "utk").tolist() == [0.5, 1.0]
    with pytest.raises(ValueError, match="convention"):
        spectrum.normalized_frequency([1], 4, "pbrt")


# -- pictures and command line -------------------------------------------------------------
def test_pictures(tmp_path, medium2):
    from clsamp import files
    pts, P = medium2
    png = plots.save_spectrum_png(tmp_path / "s.png", P)
    assert png.stat().st_size > 100
    plots.save_spectrum_png(tmp_path / "log.png", P, scale="log")
    plots.save_spectrum_exr(tmp_path / "s.exr", P)
    back = files.read_exr(tmp_path / "s.exr")
    assert np.allclose(back, P.T[::-1].astype(np.float32))             # +y up, as the PNG
    image = plots.spectrum_image(P)
    assert image.shape == (64, 64) and image[31, 32] == 1.0 and image.min() >= 0
    figure = plots.spectrum_figure(tmp_path / "plots.png", P, n=1000, realizations=4, label="white")
    assert figure.stat().st_size > 1000


def test_cli_spectrum(tmp_path):
    from clsamp import cli, files
    out = tmp_path / "random.npy"
    assert cli.main(["spectrum", "random", "-n", "256", "--realizations", "3", "--resolution", "32",
                     "-o", str(out), "--plots", str(tmp_path / "p.png")]) == 0
    P = np.load(out)
    pts = clsamp.make_sampler("random", seed=0).sample(256, realizations=3)
    assert np.abs(P - clsamp.power_spectrum(pts, 32)).max() < 1e-9
    points_file = tmp_path / "pts.txt"
    files.save_points(points_file, pts[0])
    assert cli.main(["spectrum", str(points_file), "--resolution", "32", "-o",
                     str(tmp_path / "f.png")]) == 0
    assert (tmp_path / "f.png").stat().st_size > 100
    assert cli.main(["spectrum", "random", "-o", str(tmp_path / "x.png")]) == 2   # no -n


# -- 3-D (issue 37) ------------------------------------------------------------------------
def test_a_3d_spectrum_is_the_direct_sum():
    pts = white(2, 300, d=3, seed=4)
    R = 8
    f = np.arange(-R // 2, R // 2)
    want = np.zeros((R, R, R))
    for s in pts:
        phase = (s[:, 0, None, None, None] * f[None, :, None, None]
                 + s[:, 1, None, None, None] * f[None, None, :, None]
                 + s[:, 2, None, None, None] * f[None, None, None, :])
        want += np.abs(np.exp(-2j * np.pi * phase).sum(axis=0)) ** 2
    want /= 2 * 300
    for backend in ("opencl", "numpy"):
        P = clsamp.power_spectrum(pts, R, backend=backend)
        assert P.shape == (R, R, R) and P[4, 4, 4] == pytest.approx(300.0, rel=1e-14)
        assert np.abs(P - want).max() < 1e-12 * 300, backend
    bigger = white(3, 2000, d=3, seed=5)
    np.testing.assert_allclose(clsamp.power_spectrum(bigger, 16),
                               clsamp.power_spectrum(bigger, 16, backend="numpy"), rtol=0, atol=1e-11 * 2000)


def test_3d_spectra_of_known_patterns_and_their_radial_statistics():
    # white noise: flat at 1, its shells as anisotropic as r periodograms (-10 log10 r dB)
    P = clsamp.power_spectrum(white(8, 2048, d=3, seed=6), 16)
    f, m = clsamp.radial_mean(P)
    assert f.tolist() == list(range(1, 8)) and abs(m.mean() - 1) < 0.05
    _, a = clsamp.anisotropy(P)
    assert abs(a[2:].mean() + 10 * math.log10(8)) < 1.5
    # a regular 8^3 grid: power N at multiples of 8 along every axis, none elsewhere
    g = (np.stack(np.meshgrid(*[np.arange(8)] * 3, indexing="ij"), -1).reshape(-1, 3) + 0.5) / 8
    P = clsamp.power_spectrum(g, 16)
    peaks = np.zeros((16, 16, 16), dtype=bool)
    peaks[np.ix_(*[[0, 8]] * 3)] = True
    assert np.allclose(P[peaks], 512, rtol=1e-12) and np.abs(P[~peaks]).max() < 1e-9
    # the expected spectrum of a 3-D sampler, and the refusals
    E = clsamp.expected_spectrum(clsamp.make_sampler("jittered", d=3, seed=1), 512, 2, resolution=8,
                                 progress=False)
    assert E.shape == (8, 8, 8) and E[4, 4, 4] == pytest.approx(512)
    with pytest.raises(InvalidArgumentError, match="equal sides"):
        clsamp.radial_mean(np.ones((8, 8, 4)))
    with pytest.raises(InvalidArgumentError, match="2 or more dimensions"):
        clsamp.anisotropy(np.ones(8))


def test_radial_statistics_of_a_4d_spectrum_and_what_they_refuse():
    # a 4-D spectrum (the sum over integer frequencies in NumPy): white noise's shells at 1,
    # as anisotropic as r periodograms; each shell the mean of its frequencies
    rng = np.random.default_rng(2)
    pts, R = rng.random((6, 200, 4)), 8
    f = np.arange(-R // 2, R // 2)
    k = np.stack(np.meshgrid(*[f] * 4, indexing="ij"), -1).reshape(-1, 4)
    P = np.mean([np.abs(np.exp(-2j * np.pi * (s @ k.T)).sum(0)) ** 2 / 200 for s in pts],
                axis=0).reshape((R,) * 4)
    freqs, m = clsamp.radial_mean(P)
    rho = np.sqrt((k * k).sum(1)).reshape((R,) * 4)
    assert freqs.tolist() == [1.0, 2.0, 3.0]
    for b, value in zip((1, 2, 3), m, strict=True):
        assert value == pytest.approx(P[(rho >= b - 0.5) & (rho < b + 0.5)].mean(), rel=1e-12)
    assert abs(m[1:].mean() - 1) < 0.15
    _, a = clsamp.anisotropy(P)
    assert abs(a[1:].mean() + 10 * math.log10(6)) < 2.0
    # complex or text arrays, and annuli narrower than there are frequencies, by name
    with pytest.raises(InvalidArgumentError, match="'P' must hold real numbers"):
        clsamp.radial_mean(np.ones((8, 8)) * 1j)
    with pytest.raises(InvalidArgumentError, match="'P' must hold real numbers"):
        clsamp.anisotropy(np.full((4, 4), "a"))
    for width in (1e-13, 1e-300):
        with pytest.raises(InvalidArgumentError, match="'bin_width'"):
            clsamp.radial_mean(np.ones((8, 8)), width)
    with pytest.raises(InvalidArgumentError, match="1-D, 2-D or 3-D"):
        clsamp.plots.spectrum_image(P)


@pytest.mark.parametrize("tol", [1e-3, 1e-6, 1e-10, 1e-12])
def test_3d_fast_within_tol_of_the_direct_sum(tol):
    pts = white(2, 700, d=3, seed=11)
    exact = clsamp.power_spectrum(pts, 16, method="direct")
    P = clsamp.power_spectrum(pts, 16, method="fast", tol=tol)
    assert P.shape == (16, 16, 16) and np.abs(P - exact).max() <= tol * 700
    # coincident points: |S| = N everywhere, the worst case of the bound
    dup = np.full((1, 50, 3), 0.7182818284590452)
    assert np.abs(clsamp.power_spectrum(dup, 16, method="fast", tol=tol) - 50).max() <= tol * 50


def test_3d_spread_kernel_and_fast_path_equal_their_references():
    import pyopencl.array as cla

    from clsamp import runtime
    pts = white(2, 500, 3, seed=12)
    sigma, width, beta = spectrum.nufft_parameters(1e-6, 3)
    M = 24
    kernel = runtime.kernel("nufft.cl", "spectrum_spread", {"DIM": 3, "WIDTH": width}, ("-cl-mad-enable",))
    out = cla.empty(runtime.queue(), (2, M, M, M), np.float64)
    kernel(runtime.queue(), (1, 2), (1, 1), cla.to_device(runtime.queue(), pts).data, out.data,
           np.uint32(500), np.uint32(M), np.uint32(1), np.float64(beta))
    ref = spectrum.spread_reference(pts, M, width, beta)
    assert np.abs(out.get() - ref).max() <= 1e-13 * np.abs(ref).max()
    # a realization split over several work-items' grid copies (n >= 2048), against NumPy
    pts = white(1, 4096, 3, seed=13)
    cl = clsamp.power_spectrum(pts, 16, method="fast", tol=1e-6)
    ref = clsamp.power_spectrum(pts, 16, method="fast", tol=1e-6, backend="numpy")
    assert np.abs(cl - ref).max() <= 1e-12 * 4096


def test_3d_jittered_spectrum_follows_its_expectation():
    # jittered, k³ strata: E P(ω) = 1 - Π_i sinc²(ω_i / k) for ω ≠ 0 (1 at k·Z³ \ {0}: no
    # grid's spike there). A periodogram of a sum of independent strata is about exponential with that
    # mean, so a shell's mean of r periodograms over its c/2 independent frequencies (P(-ω) =
    # P(ω)) has a standard error E/√(rc/2): within 4.5 of them, every shell
    k, R, r = 12, 32, 12
    pts = clsamp.make_sampler("jittered", d=3, seed=3).sample(k**3, realizations=r)
    P = clsamp.power_spectrum(pts, R, method="fast", tol=1e-6)
    f = np.arange(-R // 2, R // 2)
    s = np.sinc(f / k)
    expected = 1 - (s[:, None, None] * s[None, :, None] * s[None, None, :]) ** 2
    shell = np.rint(np.sqrt(f[:, None, None] ** 2 + f[None, :, None] ** 2 + f[None, None, :] ** 2))
    shell = shell.astype(int)
    for b in range(1, R // 2):
        inside = shell == b
        mean, want = P[inside].mean(), expected[inside].mean()
        assert abs(mean - want) <= 4.5 * want / math.sqrt(r * inside.sum() / 2), b
    _, mean = clsamp.radial_mean(P)
    assert P[R // 2 + k, R // 2, R // 2] < 10                   # no grid's peak (N = 1728) there
    assert mean[0] < 0.1 and mean[-1] > 0.8                      # blue: low power at low frequency
    # white noise in 3-D, for contrast, has no such hole
    _, white_mean = clsamp.radial_mean(clsamp.power_spectrum(white(4, k**3, 3), R, method="fast",
                                                              tol=1e-6))
    assert white_mean[0] > 0.5


# -- bad input ------------------------------------------------------------------------------
@pytest.mark.parametrize("points, match", [
    (np.array([[0.1, np.nan]]), "NaN"),
    (np.array([[0.1, 1.0]]), r"\[0, 1\)"),
    (np.array([[-0.1, 0.5]]), r"\[0, 1\)"),
    (np.zeros((4, 4)), "dimensions"),
    (np.zeros(5), "shape"),
    (np.zeros((2, 2), dtype=np.int64), "dtype"),
])
def test_bad_points(points, match):
    with pytest.raises(InvalidArgumentError, match=match):
        clsamp.power_spectrum(points, 16)


@pytest.mark.parametrize("kwargs, match", [
    ({"resolution": 1}, "resolution"),
    ({"resolution": 31}, "even"),
    ({"resolution": 16.0}, "resolution"),
    ({"method": "exact"}, "method"),
    ({"backend": "cuda"}, "backend"),
    ({"tol": 0.0}, "tol"),
    ({"tol": float("nan")}, "tol"),
    ({"method": "fast", "tol": 1e-15}, "tol"),
])
def test_bad_arguments(kwargs, match):
    pts = white(1, 10, 2)[0]
    args = {"resolution": 16, **kwargs}
    with pytest.raises(InvalidArgumentError, match=match):
        clsamp.power_spectrum(pts, **args)


def test_bad_spectra():
    with pytest.raises(InvalidArgumentError, match="square"):
        clsamp.radial_mean(np.ones((8, 6)))
    with pytest.raises(InvalidArgumentError, match="even"):
        clsamp.radial_mean(np.ones(7))
    with pytest.raises(InvalidArgumentError, match="2 or more dimensions"):
        clsamp.anisotropy(np.ones(8))
    with pytest.raises(InvalidArgumentError, match="bin_width"):
        clsamp.radial_mean(np.ones((8, 8)), bin_width=0)
    with pytest.raises(InvalidArgumentError, match="NaN"):
        clsamp.radial_mean(np.full((8, 8), np.nan))


@pytest.mark.parametrize("method", ["direct", "fast"])
def test_device_points_are_read_where_they_are(method, monkeypatch):
    # sample_device output goes straight to the kernels: the same bits as the host array,
    # whole and cut into chunks of realizations and points (copied on the device)
    sampler = clsamp.make_sampler("jittered", seed=4)
    on_device = sampler.sample_device(256, realizations=5)
    host = sampler.sample(256, realizations=5)
    for budget in (None, 60_000):
        if budget:
            monkeypatch.setattr(spectrum, "WORKING_SET", budget)
        a = clsamp.power_spectrum(on_device, 32, method=method, progress=False)
        b = clsamp.power_spectrum(host, 32, method=method, progress=False)
        assert np.array_equal(a, b)
    one = clsamp.power_spectrum(sampler.sample_device(256), 32, method=method, progress=False)
    assert np.array_equal(one, clsamp.power_spectrum(host[0], 32, method=method, progress=False))
    ref = clsamp.power_spectrum(on_device, 32, method=method, backend="numpy", progress=False)
    assert np.allclose(ref, b, rtol=0, atol=1e-10 * 256)


def test_bad_device_points_are_refused_on_the_device():
    import pyopencl.array as cla

    from clsamp import runtime
    good = np.full((2, 8, 2), 0.5)
    for value, match in ((np.nan, "NaN"), (np.inf, "NaN or infinite"), (1.0, r"\[0, 1\)"),
                         (-1e-300, r"\[0, 1\)")):
        bad = good.copy()
        bad[1, 3, 1] = value
        with pytest.raises(InvalidArgumentError, match=match):
            clsamp.power_spectrum(cla.to_device(runtime.queue(), bad), 16)
    with pytest.raises(InvalidArgumentError, match="float64"):
        clsamp.power_spectrum(cla.to_device(runtime.queue(), good.astype(np.float32)), 16)
    with pytest.raises(InvalidArgumentError, match="shape"):
        clsamp.power_spectrum(cla.to_device(runtime.queue(), good.ravel()), 16)


def test_recurrence_twiddles_need_reseeding():
    # 4096 frequencies by recurrence: re-seeded every 32 rows the error stays at a few ulps;
    # never re-seeded it grows with the row count, far past that
    x = white(1, 512, 1, seed=12)[0, :, 0]
    f0, count = -2048, 4096
    exact = spectrum.twiddles_reference(x, np.arange(f0, f0 + count)).T
    import sys
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
    from bench_spectrum import twiddles_by_recurrence  # the benchmark's NumPy peer
    reseeded = twiddles_by_recurrence(x, f0, count, reseed=32)
    drifting = twiddles_by_recurrence(x, f0, count, reseed=None)
    assert np.abs(reseeded - exact).max() < 2e-14
    assert np.abs(drifting - exact).max() > 1e-13


def test_host_gemm_path_equals_kernel_path(monkeypatch):
    # the CPU device's BLAS product and the OpenCL product give the same spectrum
    pts = white(3, 700, 2, seed=13)
    blas = clsamp.power_spectrum(pts, 48, method="direct")
    monkeypatch.setattr(spectrum, "HOST_GEMM", False)
    kernel = clsamp.power_spectrum(pts, 48, method="direct")
    assert np.abs(blas - kernel).max() <= 1e-13 * 700
    assert np.abs(blas - brute_force(pts, 48)).max() <= 1e-11 * 700
