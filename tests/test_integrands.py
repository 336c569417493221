"""Integrands: exact integrals against quadrature, periodicity, the kernel against the
NumPy functions, and argument errors."""

import math

import numpy as np
import pytest
from scipy import integrate

import clsamp
from clsamp import integrands as I  # noqa: N812
from clsamp.errors import InvalidArgumentError


def grid(m, d=2):
    """The midpoints of an m^d grid, (m^d, d)."""
    axes = [(np.arange(m) + 0.5) / m] * d
    return np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, d)


def grid_mean(f, m):
    """Midpoint rule over m^2 cells, in row chunks (memory)."""
    x = (np.arange(m) + 0.5) / m
    total = 0.0
    for row in np.array_split(x, max(1, m // 256)):
        pts = np.stack(np.meshgrid(row, x, indexing="ij"), -1).reshape(-1, 2)
        total += math.fsum(f(pts))
    return total / m**2


# -- exact integrals against quadrature ------------------------------------------------
def test_wrapped_gaussian_integral_against_quad_and_the_periodic_midpoint_rule():
    f = I.Gaussian(center=(0.1, 0.93), sigma=0.15)

    def g(t, c):     # one axis of the function, straight from the definition
        return sum(math.exp(-((t - c - round(t - c)) + k) ** 2 / (2 * 0.15**2)) for k in (-1, 0, 1))

    one = [integrate.quad(g, 0, 1, args=(c,), epsabs=0, epsrel=1e-13, limit=200)[0] for c in f.center]
    assert f.integral == pytest.approx(one[0] * one[1], rel=1e-13)
    # the midpoint rule is spectrally accurate for a smooth periodic function
    assert grid_mean(f, 128) == pytest.approx(f.integral, rel=1e-13)


def test_disk_integral_against_a_fine_grid():
    f = I.Disk()               # the default disk crosses both seams of the torus
    assert np.any(f(np.array([[0.99, 0.2], [0.7, 0.99]])) == 1.0)
    # lattice-point error of a disk of radius R = 0.34 * 2048 cells: ~R^(2/3) / m^2 ~ 2e-5
    assert grid_mean(f, 2048) == pytest.approx(math.pi * 0.3389**2, abs=1e-4)
    assert f.integral == math.pi * 0.3389**2


@pytest.mark.parametrize("normal,offset", [((0.9553, 0.2955), 0.6), ((-0.3, 0.8), 0.1),
                                           ((1.0, 0.0), 0.3), ((0.5, 0.5), 0.75), ((2.0, 1.0), 5.0),
                                           ((1.0, 1.0), -0.5)])
def test_heaviside_integral_against_quad_of_the_section(normal, offset):
    f = I.Heaviside(normal, offset)
    a, b = normal
    if b == 0:
        want = integrate.quad(lambda x: 1.0 if a * x < offset else 0.0, 0, 1, points=[offset / a])[0]
    else:
        def section(x):   # length of {y in [0, 1]: a x + b y < offset}
            t = (offset - a * x) / b
            return min(1.0, max(0.0, t)) if b > 0 else 1.0 - min(1.0, max(0.0, t))
        kinks = [v for v in ((offset - b) / a, offset / a) if 0 < v < 1] if a else []
        want = integrate.quad(section, 0, 1, points=kinks or None, epsabs=1e-14)[0]
    assert f.integral == pytest.approx(want, abs=1e-12)
    assert grid_mean(f, 1024) == pytest.approx(want, abs=2e-3)


def test_halfspace_volume_in_3d_against_a_grid():
    f = I.Heaviside((0.7, -0.4, 0.55), 0.5)
    pts = grid(100, 3)
    assert np.mean(f(pts)) == pytest.approx(f.integral, abs=5e-3)
    assert I.halfspace_volume((1, 1, 1), 1.5) == 0.5
    assert I.halfspace_volume((1, 1), 1.0) == 0.5


def test_pmj_integrals_against_quadrature():
    opts = dict(epsabs=0, epsrel=1e-12)
    gauss = integrate.dblquad(lambda y, x: math.exp(-x * x - y * y), 0, 1, 0, 1, **opts)[0]
    assert I.PMJGaussian().integral == pytest.approx(gauss, rel=1e-11)
    assert I.PMJBilinear().integral == pytest.approx(
        integrate.dblquad(lambda y, x: x * y, 0, 1, 0, 1, **opts)[0], rel=1e-12)
    r2 = 2.0 / math.pi
    disk = integrate.quad(lambda x: math.sqrt(max(0.0, r2 - x * x)), 0, math.sqrt(r2), **opts)[0]
    assert I.PMJDisk().integral == pytest.approx(disk, rel=1e-10)
    assert I.PMJStep().integral == 1.0 / math.pi
    assert I.PMJTriangle().integral == 0.5
    for f in I.pmj_set():
        assert grid_mean(f, 1024) == pytest.approx(f.integral, abs=2e-3), f.name


def test_ball_volume_in_3d():
    f = I.Disk(center=(0.5, 0.5, 0.5), radius=0.4)
    assert f.integral == pytest.approx(4 / 3 * math.pi * 0.4**3, rel=1e-15)
    assert np.mean(f(grid(100, 3))) == pytest.approx(f.integral, abs=5e-3)


# -- shape of the functions ------------------------------------------------------------
def test_torus_integrands_are_periodic():
    y = np.linspace(0, 1, 50, endpoint=False)
    lo = np.stack([np.zeros_like(y), y], -1)
    hi = np.stack([np.full_like(y, 1 - 2**-40), y], -1)
    g = I.Gaussian(center=(0.02, 0.5), sigma=0.1)
    np.testing.assert_allclose(g(lo), g(hi), rtol=1e-9, atol=0)
    d = I.Disk(center=(0.05, 0.5), radius=0.3)
    assert np.array_equal(d(lo), d(hi)) and d(lo).any()


def test_batch_shape_and_call():
    f = I.Gaussian()
    x = clsamp.make_sampler("random", seed=3).sample(10, realizations=4)
    assert f(x).shape == (4, 10)
    np.testing.assert_array_equal(f(x)[2], f(x[2]))


# -- the kernel against the NumPy functions --------------------------------------------
@pytest.mark.parametrize("name", I.integrand_names())
def test_kernel_evaluation_equals_numpy(name):
    from clsamp.estimates import IntegrandErrors
    f = I.make_integrand(name)
    sampler = clsamp.make_sampler("random", seed=4)
    res = clsamp.convergence(sampler, f, [37, 4096 + 5], realizations=6, seed=9, progress=False)
    for n, e in zip(res.ns, res.errors, strict=True):
        want = IntegrandErrors(sampler, f, True, 9, "numpy").block(int(n), 0, 6)
        np.testing.assert_allclose(e, want, rtol=1e-12, atol=1e-15)


# -- bad input -------------------------------------------------------------------------
def test_bad_parameters_name_the_argument():
    with pytest.raises(InvalidArgumentError, match="'sigma'"):
        I.Gaussian(sigma=0.3)
    with pytest.raises(InvalidArgumentError, match="'center'"):
        I.Gaussian(center=(0.5, 1.0))
    with pytest.raises(InvalidArgumentError, match="'radius'"):
        I.Disk(radius=0.5)
    with pytest.raises(InvalidArgumentError, match="'normal'"):
        I.Heaviside(normal=(0.0, 0.0))
    with pytest.raises(InvalidArgumentError, match="'points'"):
        I.Gaussian()(np.zeros((4, 3)))
    with pytest.raises(InvalidArgumentError, match="Known integrands: gaussian, disk"):
        I.make_integrand("gausian")
    with pytest.raises(InvalidArgumentError, match="2-dimensional"):
        I.make_integrand("pmj_step", d=3)
    assert I.make_integrand("disk", d=3).d == 3


# -- Genz's six families (issue 38) ----------------------------------------------------
@pytest.mark.filterwarnings("ignore:The occurrence of roundoff error")   # quad at its limit
@pytest.mark.parametrize("kind", I.GENZ_KINDS)
def test_genz_integrals_are_exact(kind):
    from scipy import integrate
    for d, seed in ((1, 3), (1, 8), (2, 5)):
        f = I.genz(kind, d, seed=seed)
        if d == 1:
            want = integrate.quad(lambda t, f=f: f(np.array([[t]]))[0], 0, 1, points=[f.u[0]],
                                  epsabs=0, epsrel=1e-13, limit=500)[0]
            assert f.integral == pytest.approx(want, rel=1e-11), (kind, seed)
        else:   # split at the kinks and steps along x_j = u_j
            total = 0.0
            for x0, x1 in ((0, f.u[0]), (f.u[0], 1)):
                for y0, y1 in ((0, f.u[1]), (f.u[1], 1)):
                    total += integrate.dblquad(lambda y, x, f=f: f(np.array([[x, y]]))[0], x0, x1, y0, y1,
                                               epsabs=0, epsrel=1e-12)[0]
            assert f.integral == pytest.approx(total, rel=1e-9), kind
    # in 4-D: an Owen-scrambled Sobol' estimate of 2^18 points lands on it
    f = I.genz(kind, 4, seed=1)
    est = f(clsamp.make_sampler("sobol:owen", d=4, seed=2).sample(2**18)).mean()
    # (the corner peak, 1.2e-5 of its peak value, and the steps converge slowest)
    assert est == pytest.approx(f.integral, rel=2e-2 if kind in ("corner_peak", "discontinuous") else 2e-4)


def test_genz_draws_are_seeded_and_scaled_to_the_difficulty():
    for kind in I.GENZ_KINDS:
        for d in (1, 3, 8):
            f = I.genz(kind, d, seed=7)
            assert f.d == d and f.name == f"genz_{kind}"
            assert math.fsum(f.a) == pytest.approx(I.GENZ_DIFFICULTY[kind](d), rel=1e-12)
            assert np.all((f.u >= 0) & (f.u < 1))
            assert np.array_equal(f.a, I.genz(kind, d, seed=7).a)
            assert not np.array_equal(f.u, I.genz(kind, d, seed=8).u)
    assert I.make_integrand("genz_corner_peak", d=3).d == 3
    assert I.genz("oscillatory", 2).smooth and not I.genz("continuous", 2).smooth
    assert I.genz("discontinuous", 2).edges_when_shifted() == "axis"


def test_genz_kernel_equals_numpy_in_higher_dimensions():
    from clsamp.estimates import IntegrandErrors
    sampler = clsamp.make_sampler("sobol", d=6, randomize="owen", seed=4)
    for kind in I.GENZ_KINDS:
        f = I.genz(kind, 6, seed=3)
        res = clsamp.convergence(sampler, f, [4096 + 5], realizations=3, seed=9, progress=False)
        want = IntegrandErrors(sampler, f, True, 9, "numpy").block(4101, 0, 3)
        np.testing.assert_allclose(res.errors[0], want, rtol=1e-12, atol=1e-15 * abs(f.integral))


@pytest.mark.parametrize("call, match", [
    (lambda: I.genz("gausian", 2), "'kind'"),
    (lambda: I.genz("gaussian", 0), "'d'"),
    (lambda: I.genz("gaussian", 17), "'d'"),
    (lambda: I.Genz("gaussian", [1.0, -1.0], [0.5, 0.5]), "'a' must be positive"),
    (lambda: I.Genz("gaussian", [1.0, 1.0], [0.5, 1.5]), "'u' must lie"),
    (lambda: I.Genz("gaussian", [1.0, 1.0], [0.5]), "'u'"),
])
def test_genz_bad_arguments(call, match):
    with pytest.raises(InvalidArgumentError, match=match):
        call()
