"""clsamp.transforms (issue 38): the normal quantile against scipy's ndtri within a stated
ulp bound, its device twin in the Keister kernel, Baker's tent; Keister's integrand."""

import math

import numpy as np
import pytest

import clsamp
from clsamp.errors import InvalidArgumentError
from clsamp.integrands import keister, make_integrand
from clsamp.transforms import SMALLEST, tent, to_normal

ULPS = 8            # to_normal within 8 ulps of scipy.special.ndtri (7 seen on the points below)


def test_to_normal_is_within_a_few_ulps_of_scipy_ndtri_across_every_branch():
    from scipy.special import ndtri
    rng = np.random.default_rng(0)
    u = np.concatenate([rng.random(400_000),                      # the central branch mostly
                        10.0 ** -rng.uniform(1, 307, 100_000),    # the lower tails, r <= 5 and r > 5
                        1 - 10.0 ** -rng.uniform(1, 16, 100_000),  # the upper tail
                        [0.075, 0.925, 0.5 - 0.425, 0.5 + 0.425, 1e-300, 2.0**-1022]])
    u = u[(u > 0) & (u < 1)]
    z, ref = to_normal(u), ndtri(u)
    ok = ref != 0
    ulps = np.abs(z[ok] - ref[ok]) / np.spacing(np.abs(ref[ok]))
    assert ulps.max() <= ULPS, (ulps.max(), u[ok][np.argmax(ulps)])
    assert to_normal([0.5])[0] == 0.0
    assert np.all(np.diff(to_normal(np.sort(u))) >= 0)        # monotone
    assert to_normal([0.0])[0] == to_normal([SMALLEST])[0] and np.isfinite(to_normal([0.0])[0])


def test_to_normal_refuses_what_is_not_in_the_unit_interval():
    for bad in ([1.0], [-0.1], [np.nan]):
        with pytest.raises(InvalidArgumentError, match="'u'"):
            to_normal(bad)


def test_tent_periodizes():
    x = np.linspace(0, 1, 9)
    np.testing.assert_array_equal(tent(x), 1 - np.abs(2 * x - 1))
    np.testing.assert_array_equal(tent(x), tent(1 - x))


@pytest.mark.parametrize("d, value", [(1, math.sqrt(math.pi) * math.exp(-0.25)),
                                      (2, None), (3, None), (8, None)])
def test_keister_integral_and_the_device_twin(d, value):
    from scipy import integrate
    f = keister(d)
    if value is None:       # the radial integral, numerically
        radial = integrate.quad(lambda r: math.cos(r) * math.exp(-r * r) * r ** (d - 1), 0, np.inf,
                                epsabs=0, epsrel=1e-13, limit=200)[0]
        value = 2 * math.pi ** (d / 2) / math.gamma(d / 2) * radial
    assert f.integral == pytest.approx(value, rel=1e-12)
    from clsamp.estimates import IntegrandErrors
    s = clsamp.make_sampler("sobol", d=d, randomize="owen", seed=3)
    res = clsamp.convergence(s, f, [4096], realizations=4, seed=9, progress=False)
    want = IntegrandErrors(s, f, True, 9, "numpy").block(4096, 0, 4)
    np.testing.assert_allclose(res.errors[0], want, rtol=0, atol=1e-14 * abs(f.integral))
    assert make_integrand("keister", d=d).integral == f.integral


def test_keister_estimates_converge_to_it():
    f = keister(4)
    res = clsamp.convergence("sobol:owen", f, [256, 1024, 4096, 16384], realizations=16, seed=2,
                             progress=False)
    rmse = np.sqrt(res.mse)
    assert rmse[-1] < 1e-3 * abs(f.integral) and rmse[-1] < rmse[0] / 20
    with pytest.raises(InvalidArgumentError, match="'d'"):
        keister(0)
