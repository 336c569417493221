"""Integrand families (exact integrals, kernel against NumPy), convergence over a family
(summaries, bootstrap rates, the published rates), and integrate (coverage, errors)."""

import json
import math
import warnings

import numpy as np
import pytest

import clsamp
from clsamp import families, results, theory
from clsamp.errors import InvalidArgumentError

NAMES = families.family_names()


def test_the_names_the_issue_promises():
    assert {"random_gaussians", "random_heavisides", "random_disks", "random_boxes"} <= set(NAMES)
    assert families.make_family("heavisides").name == "random_heavisides"
    assert families.is_family("disks") and not families.is_family("disk")


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("d", [1, 2, 3, 8])
def test_kernel_equals_numpy_reference(name, d):
    sampler = clsamp.make_sampler("random", d=d, seed=4)
    for homogenize in (True, False):
        kwargs = dict(realizations=3, members=9, seed=5, homogenize=homogenize, progress=False)
        a = clsamp.convergence(sampler, name, [17, 300], **kwargs)
        b = clsamp.convergence(sampler, name, [17, 300], backend="numpy", **kwargs)
        for ea, eb in zip(a.errors, b.errors, strict=True):
            assert ea.shape == (3, 9)
            np.testing.assert_allclose(ea, eb, rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("d", [1, 2, 3])
def test_gaussian_integrals_are_exact(d):
    # the midpoint rule of a smooth periodic function converges faster than any power:
    # on this grid it holds the integral to rounding
    fam = families.make_family("random_gaussians", d=d, members=6, seed=2)
    m = {1: 4096, 2: 400, 3: 120}[d]
    axis = (np.arange(m) + 0.5) / m
    grid = np.stack(np.meshgrid(*([axis] * d), indexing="ij"), axis=-1).reshape(-1, d)
    quadrature = fam(grid).mean(axis=0)
    np.testing.assert_allclose(quadrature, fam.integrals, rtol=1e-11)


@pytest.mark.parametrize("name", ["random_heavisides", "random_disks", "random_boxes",
                                  "random_clipped_gaussians"])
@pytest.mark.parametrize("d", [1, 2, 3])
def test_discontinuous_integrals_against_many_points(name, d):
    # 2^18 Owen-scrambled Sobol points in 8 replications: the exact integral lies within
    # 6 standard errors of the replications' mean, give or take 4/n (a net's error is a
    # few discrete values, so 8 replications can agree and show no spread at all)
    n = 2**18
    fam = families.make_family(name, d=d, members=12, seed=3)
    sampler = clsamp.make_sampler("sobol:owen", d=d, seed=9)
    res = clsamp.convergence(sampler, fam, [n], realizations=8, homogenize=False, progress=False)
    e = res.errors[0]
    mean = e.mean(axis=0)
    stderr = e.std(axis=0, ddof=1) / math.sqrt(len(e))
    assert np.all(np.abs(mean) <= 6 * stderr + 4.0 / n), (mean, stderr)
    assert np.all(np.abs(mean) < 2e-4)


def test_heaviside_and_box_integrals_are_the_exact_rationals():
    from fractions import Fraction

    from clsamp.integrands import halfspace_volume
    fam = families.make_family("random_heavisides", d=4, members=5, seed=1)
    for p, value in zip(fam.params, fam.integrals, strict=True):
        assert value == halfspace_volume(p[:4], p[4])
    boxes = families.make_family("random_boxes", d=3, members=5, seed=1)
    for p, value in zip(boxes.params, boxes.integrals, strict=True):
        assert value == float(Fraction(p[3]) * Fraction(p[4]) * Fraction(p[5]))


def test_members_are_reproducible_and_independent_of_the_count():
    for name in NAMES:
        a = families.make_family(name, d=3, members=16, seed=7)
        b = families.make_family(name, d=3, members=8, seed=7)
        c = families.make_family(name, d=3, members=8, seed=8)
        assert np.array_equal(a.params[:8], b.params) and np.array_equal(a.integrals[:8], b.integrals)
        assert not np.array_equal(b.params, c.params)


def test_heavisides_include_axis_aligned_members():
    fam = families.make_family("random_heavisides", d=2, members=400, seed=1)
    normals = fam.params[:, :2]
    exact_axis = np.sum(np.count_nonzero(normals, axis=1) == 1)
    near = np.sum((np.max(np.abs(normals), axis=1) > 0.999) & (np.count_nonzero(normals, axis=1) == 2))
    assert 30 < exact_axis < 70 and 30 < near < 70


def test_family_result_summaries_and_json():
    res = clsamp.convergence("jittered", "random_disks", [16, 64, 256, 1024], realizations=16,
                             members=10, seed=2, progress=False)
    assert isinstance(res, results.FamilyResult)
    assert res.mse.shape == (4, 10)
    np.testing.assert_allclose(res.mean, res.mse.mean(axis=1))
    np.testing.assert_allclose(res.max, res.mse.max(axis=1))
    assert np.all(res.median <= res.q90) and np.all(res.q90 <= res.max)
    slope, lo, hi = res.rate("mean")
    assert lo <= slope <= hi
    assert res.rate("mean") == res.rate("mean")          # the bootstrap is seeded
    json.dumps(res.to_dict())
    assert "random_disks" in repr(res)


def test_rates_over_families_match_the_theory():
    ns = [16, 64, 256, 1024, 4096, 16384]
    kw = dict(realizations=48, members=48, seed=1, progress=False)
    jit = clsamp.convergence("jittered", "random_heavisides", ns, **kw)
    assert theory.compare(jit)["verdict"] in ("matches", "pre-asymptotic")
    assert abs(jit.rate("mean")[0] + 1.5) < 0.15
    # a regular grid's worst members stall at N^-1: no better than random points
    grid = clsamp.convergence("regular", "random_heavisides", ns, **kw)
    assert grid.rate("max")[0] > -1.2 > jit.rate("max")[0] + 0.1
    smooth = clsamp.convergence("jittered", "random_gaussians", ns, **kw)
    assert theory.compare(smooth)["verdict"] in ("matches", "pre-asymptotic")
    owen = clsamp.convergence("sobol:owen", "random_gaussians", [2**k for k in range(8, 17, 2)], **kw)
    check = theory.compare(owen)
    assert check["expected"] == -3 and check["verdict"] in ("matches", "pre-asymptotic")
    assert owen.rate("mean")[0] < -2.6


def test_family_bad_input_names_the_argument():
    with pytest.raises(InvalidArgumentError, match="Did you mean"):
        families.make_family("random_heaviside_planes")
    with pytest.raises(InvalidArgumentError, match="'members'"):
        families.make_family("random_disks", members=0)
    with pytest.raises(InvalidArgumentError, match="'d'"):
        families.make_family("random_disks", d=9)
    with pytest.raises(InvalidArgumentError, match="'members' is for integrand families"):
        clsamp.convergence("random", "disk", [16], realizations=4, members=8, progress=False)
    fam = families.make_family("random_boxes", d=3, members=4)
    with pytest.raises(InvalidArgumentError, match="3-dimensional"):
        clsamp.convergence(clsamp.make_sampler("random", d=2), fam, [16], realizations=4, progress=False)
    with pytest.raises(InvalidArgumentError, match="differs from the family"):
        clsamp.convergence("random", fam, [16], realizations=4, members=5, progress=False)
    with pytest.raises(InvalidArgumentError, match="'sigma'"):
        families.RandomGaussians(sigma=(0.01, 0.2))


# -- integrate -----------------------------------------------------------------------------
def _gauss(x):
    return np.exp(-8.0 * np.sum((x - 0.5) ** 2, axis=1))


GAUSS = (math.sqrt(math.pi / 8) * math.erf(math.sqrt(8) * 0.5)) ** 3


def _disk(x):
    return (np.sum((x - 0.5) ** 2, axis=1) < 0.16).astype(np.float64)


@pytest.mark.parametrize("f,d,exact,tol", [(_gauss, 3, GAUSS, 1e-5), (_disk, 2, math.pi * 0.16, 1e-3)])
def test_integrate_intervals_cover_the_integral(f, d, exact, tol):
    covered, runs = 0, 200
    for seed in range(runs):
        res = clsamp.integrate(f, d, abs_tol=tol, seed=seed, progress=False)
        assert res.converged and res.half_width <= tol
        covered += abs(res.estimate - exact) <= res.half_width
    assert covered >= 0.9 * runs, covered


def test_integrate_result_and_integrand_objects():
    res = clsamp.integrate(lambda x: np.prod(x, axis=1), 3, rel_tol=1e-4, progress=False)
    assert abs(res.estimate - 0.125) <= max(3 * res.half_width, 1e-4)
    assert res.evaluations >= res.replications * res.n and res.history[-1][0] == res.n
    assert res.sampler == "sobol:owen"
    g = clsamp.integrands.make_integrand("gaussian")
    by_kernel = clsamp.integrate("gaussian", 2, abs_tol=1e-7, progress=False)
    assert by_kernel.converged and abs(by_kernel.estimate - g.integral) < 5 * by_kernel.half_width + 1e-12
    jit = clsamp.integrate(_disk, 2, sampler="jittered", abs_tol=2e-3, progress=False)
    assert jit.converged and round(math.sqrt(jit.n)) ** 2 == jit.n


def test_integrate_warns_at_max_n():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = clsamp.integrate(_disk, 2, abs_tol=1e-9, max_n=4096, progress=False)
    assert not res.converged and res.n <= 4096
    assert any(issubclass(w.category, UserWarning) and "max_n" in str(w.message) for w in caught)


def test_integrate_bad_input_names_the_problem():
    f = _gauss
    with pytest.raises(InvalidArgumentError, match="abs_tol"):
        clsamp.integrate(f, 3, progress=False)
    for bad in (-1e-3, 0.0, float("nan")):
        with pytest.raises(InvalidArgumentError, match="abs_tol"):
            clsamp.integrate(f, 3, abs_tol=bad, progress=False)
    with pytest.raises(InvalidArgumentError, match="rel_tol"):
        clsamp.integrate(f, 3, rel_tol="tight", progress=False)
    with pytest.raises(InvalidArgumentError, match="one value per point"):
        clsamp.integrate(lambda x: x, 3, abs_tol=1e-3, progress=False)
    with pytest.raises(InvalidArgumentError, match="NaN or infinite"):
        clsamp.integrate(lambda x: np.where(x[:, 0] < 0.5, np.nan, 1.0), 3, abs_tol=1e-3, progress=False)
    with pytest.raises(InvalidArgumentError, match="deterministic"):
        clsamp.integrate(f, 3, sampler="sobol", abs_tol=1e-3, progress=False)
    with pytest.raises(InvalidArgumentError, match="'replications'"):
        clsamp.integrate(f, 3, abs_tol=1e-3, replications=1, progress=False)
    with pytest.raises(InvalidArgumentError, match="'confidence'"):
        clsamp.integrate(f, 3, abs_tol=1e-3, confidence=1.0, progress=False)
    with pytest.raises(InvalidArgumentError, match="'f'"):
        clsamp.integrate(42, 3, abs_tol=1e-3, progress=False)
