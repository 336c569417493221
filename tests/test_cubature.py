"""Guaranteed adaptive cubature: integrate(method="digital" | "lattice") (clsamp.cubature)."""

import math
import warnings

import numpy as np
import pytest

import clsamp
from clsamp import generating_matrices as gm
from clsamp import number_theory as nt
from clsamp.cubature import Cubature, combine, fourier_coefficients, walsh_coefficients
from clsamp.integrands import genz, keister
from clsamp.integrands.qmc import GENZ_KINDS
from clsamp.transforms import sidi


def test_the_transforms_equal_their_definitions():
    rng = np.random.default_rng(3)
    y = rng.random(32)
    k, i = np.meshgrid(np.arange(32), np.arange(32), indexing="ij")
    walsh = np.array([[(-1) ** bin(a & b).count("1") for b in range(32)] for a in range(32)])
    assert np.allclose(walsh_coefficients(y), walsh @ y / 32, rtol=0, atol=1e-14)
    # sequence position i holds the lattice's point j = bitreverse_5(i)
    j = (nt.reverse_bits32(np.arange(32)) >> np.uint32(27)).astype(np.int64)
    dft = np.exp(-2j * np.pi * np.outer(np.arange(32), j) / 32) @ y / 32
    assert np.allclose(fourier_coefficients(y), dft, rtol=0, atol=1e-14)


@pytest.mark.parametrize("method", ["digital", "lattice"])
def test_doubling_updates_equal_a_fresh_transform(method):
    seen = []

    def f(x):
        seen.append(x)
        return np.exp(np.sum(x, axis=1))

    rule = Cubature(f, 3, method, 5, "none")
    for _ in range(3):
        mean, _ = rule.step()
    assert rule.n == 4096
    y = f(np.concatenate(seen[:3]))
    fresh = walsh_coefficients(y) if method == "digital" else fourier_coefficients(y)
    assert np.allclose(rule.coefficients, fresh, rtol=0, atol=1e-13)
    assert math.isclose(mean, float(np.mean(y)), rel_tol=1e-14)
    if method == "digital":                   # a net's mean is its coefficient 0
        assert mean == rule.coefficients[0]


def test_the_lattice_spectrum_keeps_its_twiddles_accurate():
    # a doubling's odd twiddles are the last doubling's times e^(-i pi / n): after 14
    # doublings still within a few ulps of e^(-i pi k / n), and the spectrum of 2^16 values
    # built by doublings equals one FFT of them all
    from clsamp.cubature import _LatticeSpectrum
    spectrum = _LatticeSpectrum()
    y = np.random.default_rng(5).random(2**16)
    spectrum.add(y[:4])
    n = 4
    while n < y.size:
        spectrum.add(y[n:2 * n])
        n *= 2
    exact = np.exp(-1j * np.pi * np.arange(n // 4 + 1) / (n // 2))
    assert np.max(np.abs(spectrum._w - exact)) <= 1e-15
    np.testing.assert_allclose(np.concatenate([spectrum.half, np.conj(spectrum.half[1:-1][::-1])]),
                               fourier_coefficients(y), rtol=0, atol=1e-15)


@pytest.mark.parametrize("method", ["digital", "lattice"])
def test_the_device_state_has_the_numpy_bits(monkeypatch, method):
    # kernels/walsh.cl does walsh_coefficients, the butterfly and _order_wavenumbers in the
    # NumPy order (a lattice: its magnitudes put in wavenumber order, then the ordering): the
    # same coefficients, ordering and bounds, bit for bit
    from clsamp import cubature
    monkeypatch.setattr(cubature, "DEVICE_FROM", 2**11)      # on the device from 4096 points

    def f(x):
        return np.exp(np.sum(x, axis=1)) * np.cos(9.0 * x[:, 0]) + (x[:, 1] > 0.3)

    rules = [Cubature(f, 3, method, 6, device=device) for device in (False, True)]
    assert rules[0].walsh is None and rules[1].walsh is not None
    for _ in range(6):
        assert rules[0].step() == rules[1].step()
    assert rules[1]._kappa is None                            # the ordering is on the device
    assert rules[1].n == 2**15
    host, device = rules[0].coefficients, rules[1].coefficients
    assert np.array_equal(host.view(np.uint64), device.view(np.uint64))
    assert np.array_equal(rules[0].kappa, rules[1].kappa)
    # the ordering did reorder: not the identity
    assert not np.array_equal(rules[1].kappa, np.arange(rules[1].n))


@pytest.mark.parametrize("method", ["digital", "lattice"])
def test_sampling_in_chunks_changes_nothing(method, monkeypatch):
    from clsamp import cubature
    runs = []
    for chunk in (2**20, 128):
        monkeypatch.setattr(cubature, "CHUNK", chunk)
        rule = Cubature(lambda x: np.exp(np.sum(x, axis=1)) + x[:, 0] ** 3, 3, method, 4, "none")
        runs.append([rule.step() for _ in range(3)])
    assert runs[0] == runs[1]


@pytest.mark.parametrize("method", ["digital", "lattice"])
def test_a_chunk_holds_at_most_chunk_coordinates(method, monkeypatch):
    # in many dimensions the host holds CHUNK coordinates at a time, not 2^20 points
    from clsamp import cubature
    monkeypatch.setattr(cubature, "CHUNK", 2**12)
    sizes = []
    rule = Cubature(lambda x: sizes.append(x.shape) or np.zeros(len(x)), 100, method, 1, "none")
    rule.step()
    rule.step()
    assert max(rows * d for rows, d in sizes) == 32 * 100       # 2^12 // 100 = 40 -> 32 points
    assert sum(rows for rows, _ in sizes) == 2048

def test_the_digital_points_are_in_natural_order():
    # x_(2^k) xor x_0 is column k of the generating matrix (in Gray-code order it would be
    # columns k and k - 1 together)
    got = []
    rule = Cubature(lambda x: got.append(x) or np.zeros(len(x)), 4, "digital", 9)
    rule.step()
    bits = (got[0] * 2.0**32).astype(np.uint64).astype(np.uint32)
    # LMS + digital shift (qmcpy's default): the columns are realization 0's L C
    columns = gm.lms_apply(gm.lms_row_masks(9, [0], 4), nt.sobol_matrices(4)[None])[0]
    for k in range(10):
        assert np.array_equal(bits[2**k] ^ bits[0], columns[:, k])


@pytest.mark.parametrize("seed", [0, 7])
def test_the_digital_bound_holds_for_a_product_of_coordinates(seed):
    # with a digital shift alone (no LMS) x0 x1 x2 stopped at 1e-8 with errors 8e-8..4e-7
    # (qmcpy's DigitalNetB2(randomize="DS") as well): its Walsh coefficients outside the
    # sequence's 1-D ordering go unseen. With LMS + shift the error is the 32-bit floor
    # 2^-33 * 3/4 = 8.7e-11 (the shift averages f over a grid of 2^-32).
    res = clsamp.integrate(lambda x: x[:, 0] * x[:, 1] * x[:, 2], 3, abs_tol=1e-8, method="digital",
                           seed=seed, progress=False)
    assert res.converged and abs(res.estimate - 0.125) <= 1e-8, res


@pytest.mark.parametrize("method", ["digital", "lattice"])
@pytest.mark.parametrize("tol", [1e-3, 1e-4, 1e-5])
def test_keister_meets_the_tolerance(method, tol):
    f = keister(3)
    res = clsamp.integrate(f, 3, abs_tol=tol, method=method, seed=2, progress=False)
    assert res.converged and res.method == method
    assert res.half_width <= tol
    assert abs(res.estimate - f.integral) <= tol
    assert res.evaluations == res.n and res.n & (res.n - 1) == 0 and res.n >= 1024
    assert res.replications == 1 and res.confidence == 1.0


# Families where the cone holds for nearly every member: over 200 members each method meets
# the tolerance in >= 96 % of them (docs/performance.md holds the rates of all six and the
# command; the corner peak's, 65-71 %, are the method failing where its assumption does).
# The 40 members here are a sample of those 200: >= 37 of 40 (oscillatory on the lattice
# meets 37, its 200-member rate being 96 %).
CONE_FAMILIES = ("oscillatory", "product_peak", "gaussian", "continuous", "discontinuous")


@pytest.mark.parametrize("method", ["digital", "lattice"])
@pytest.mark.parametrize("kind", GENZ_KINDS)
def test_genz_members_meet_the_tolerance(kind, method):
    abs_tol, rel_tol, members = 1e-6, 1e-3, 40
    met = converged = 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        for seed in range(members):
            d = 2 + seed % 7
            f = genz(kind, d, seed)
            res = clsamp.integrate(f, d, abs_tol=abs_tol, rel_tol=rel_tol, method=method,
                                   max_n=2**22, seed=seed, progress=False)
            met += abs(res.estimate - f.integral) <= max(abs_tol, rel_tol * abs(f.integral))
            converged += res.converged
    if kind in CONE_FAMILIES:
        assert met >= 37, (kind, method, met, converged)
    else:
        assert met >= 0.5 * members, (kind, method, met, converged)


def test_relative_tolerance_and_periodizations():
    f = keister(2)
    for periodization in ("none", "baker", "sidi"):
        res = clsamp.integrate(f, 2, rel_tol=1e-5, method="lattice", periodization=periodization,
                               progress=False)
        assert res.converged and abs(res.estimate - f.integral) <= 1e-5 * abs(f.integral)
        assert res.sampler.endswith(periodization) or periodization == "none"
    # the estimate meets max(abs, rel |I|) for every I in mean +- bound
    for mean, bound in ((1.0, 0.0009), (-2.0, 0.0019), (0.0, 0.9e-4)):
        estimate, half, met = combine(mean, bound, 1e-4, 1e-3)
        assert met
        for truth in np.linspace(mean - bound, mean + bound, 101):
            assert abs(estimate - truth) <= max(1e-4, 1e-3 * abs(truth)) + 1e-15
        assert math.isclose(half, max(estimate - mean + bound, mean + bound - estimate))
    assert not combine(1.0, 0.01, 1e-4, 1e-3)[2]


def test_sidi_preserves_the_integral():
    from scipy.integrate import quad
    for k in (1, 2, 3, 4):
        assert quad(lambda t, k=k: float(sidi(t, k)[1]), 0, 1, epsabs=1e-14)[0] == pytest.approx(1, abs=1e-12)
        t = np.linspace(0, 1, 33)
        psi, _ = sidi(t, k)
        assert psi[0] == 0 and psi[-1] == 1 and np.all(np.diff(psi) > 0)
        for x in (0.1, 0.37, 0.8):
            assert quad(lambda t, k=k: float(sidi(t, k)[1]), 0, x, epsabs=1e-14)[0] == pytest.approx(
                float(sidi(x, k)[0]), abs=1e-12)


def test_max_n_warns_and_the_default_method_is_unchanged():
    with pytest.warns(UserWarning, match="max_n"):
        res = clsamp.integrate(genz("discontinuous", 2, 0), 2, abs_tol=1e-9, method="digital",
                               max_n=4096, progress=False)
    assert not res.converged and res.n == 4096
    rep = clsamp.integrate(lambda x: np.prod(x, axis=1), 3, abs_tol=1e-5, progress=False)
    assert rep.method == "replications" and rep.replications == 16


@pytest.mark.parametrize("kwargs, match", [
    ({"method": "sobol"}, r"'method' must be one of"),
    ({"method": "lattice", "periodization": "tent"}, r"'periodization' must be one of"),
    ({"method": "digital", "periodization": "baker"}, r"method='lattice' only"),
    ({"method": "digital", "max_n": 512}, r"'max_n' must be at least 1024"),
    ({"method": "lattice", "abs_tol": None}, r"give 'abs_tol' or 'rel_tol'"),
])
def test_bad_arguments_are_one_line(kwargs, match):
    args = {"abs_tol": 1e-3, **kwargs}
    with pytest.raises(clsamp.ClsampError, match=match) as info:
        clsamp.integrate(lambda x: x[:, 0], 2, progress=False, **args)
    assert "\n" not in str(info.value)


def test_bad_integrand_values_are_named():
    with pytest.raises(ValueError, match="one value per point"):
        clsamp.integrate(lambda x: x, 2, abs_tol=1e-3, method="digital", progress=False)
    with pytest.raises(ValueError, match="NaN or infinite"):
        clsamp.integrate(lambda x: np.where(x[:, 0] < 0.5, np.nan, 1.0), 2, abs_tol=1e-3, method="lattice",
                         progress=False)
    # a complex value lost its imaginary part (a ComplexWarning, a 'converged' result), text
    # failed inside NumPy's float conversion
    for f in (lambda x: x[:, 0] + 1j, lambda x: np.array(["a"] * len(x))):
        for method in ("replications", "digital"):
            with pytest.raises(clsamp.InvalidArgumentError, match="'f' must return real numbers"):
                clsamp.integrate(f, 2, abs_tol=1e-3, method=method, progress=False)
    assert clsamp.integrate(lambda x: x[:, 0] < 2.0, 2, abs_tol=1e-3, progress=False).estimate == 1.0
