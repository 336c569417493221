"""Densities for adaptive sampling (``clsamp.density``): a callable or an array, normalized
to mean 1; the array multilinear between cell centres with its exact gradient; a
callable's gradient by central differences; starting points drawn by rejection, each
realization on its own; a bad density refused in one line naming it."""

import numpy as np
import pytest

import clsamp
from clsamp.density import as_density
from clsamp.errors import InvalidArgumentError


def ramp(x):
    return 0.2 + 1.6 * x[:, 0]


def test_a_callable_is_normalized_to_mean_one():
    density = as_density(lambda x: 5.0 * ramp(x), d=2)
    x = np.array([[0.0, 0.3], [0.5, 0.9], [0.999, 0.1]])
    assert np.allclose(density(x), ramp(x), rtol=1e-12)
    assert np.allclose(density.gradient(x), [[1.6, 0.0]] * 3, rtol=1e-6, atol=1e-9)


def test_an_array_is_multilinear_between_cell_centres():
    rng = np.random.default_rng(0)
    image = rng.random((5, 7)) + 0.1
    density = as_density(image, d=2)
    assert density.image.mean() == pytest.approx(1.0)
    x = np.array([[0.5 / 5, 0.5 / 7], [1.5 / 5, 3.5 / 7], [0.0, 0.0], [0.99, 0.99]])
    ref = image / image.mean()
    assert np.allclose(density(x), [ref[0, 0], ref[1, 3], ref[0, 0], ref[4, 6]])
    # half-way between four centres: their mean
    mid = np.array([[1.0 / 5, 1.0 / 7]])
    assert density(mid)[0] == pytest.approx(ref[:2, :2].mean())
    # the gradient against central differences, inside the cells
    x = rng.uniform(0.15, 0.85, (50, 2))
    h = 1e-7
    for k in range(2):
        up, down = x.copy(), x.copy()
        up[:, k] += h
        down[:, k] -= h
        assert np.allclose(density.gradient(x)[:, k], (density(up) - density(down)) / (2 * h),
                           rtol=1e-5, atol=1e-5)


def test_the_start_follows_the_density_and_each_realization_stands_alone():
    from scipy.stats import kstest
    density = as_density(ramp, d=2)
    pts = density.sample(3, range(4), 2000)
    assert pts.shape == (4, 2000, 2) and np.all((pts >= 0) & (pts < 1))
    assert np.array_equal(density.sample(3, range(2, 3), 2000)[0], pts[2])
    for p in pts:
        assert kstest(p[:, 0], lambda t: 0.2 * t + 0.8 * t * t).pvalue > 0.001
        assert kstest(p[:, 1], "uniform").pvalue > 0.001


@pytest.mark.parametrize("density, message", [
    (lambda x: x[:, 0] - 0.5, "non-negative"),
    (lambda x: np.zeros(len(x)), "positive integral"),
    (lambda x: x, "one value a point"),
    (lambda x: np.full(len(x), np.nan), "finite"),
    (lambda: 1.0, "callable taking points"),
    (-np.ones((4, 4)), "non-negative"),
    (np.zeros((4, 4)), "positive integral"),
    (np.ones((4, 4, 4)), "2 axes"),
    (np.ones(4), "2 axes"),
    ("ramp", "callable or an array"),
])
def test_a_bad_density_gets_one_line_naming_it(density, message):
    with pytest.raises(InvalidArgumentError, match=message) as raised:
        as_density(density, d=2)
    assert "'density'" in str(raised.value) and "\n" not in str(raised.value)
    with pytest.raises(InvalidArgumentError, match="density"):
        clsamp.make_sampler("gbn", density=density)


@pytest.mark.parametrize("d", [1, 8, 20])
def test_a_callable_is_probed_in_any_dimension(d):
    # a grid of about 4096 cells up to d = 13, fixed uniform points beyond
    density = as_density(lambda x: 1.0 + x[:, 0], d=d)
    x = np.full((1, d), 0.5)
    assert density(x)[0] == pytest.approx(1.5 / 1.5, rel=0.02)
    assert density.sample(1, range(1), 50).shape == (1, 50, d)
