"""Point validation: shapes, dtypes, ranges, NaN/inf, each error naming the argument."""

import numpy as np
import pytest

import clsamp
import clsamp.parallel
import clsamp.render
from clsamp.errors import ClsampError, InvalidArgumentError
from clsamp.validation import check_int, check_points, check_real


def test_single_and_batch_shapes():
    one, single = check_points(np.zeros((5, 2)))
    assert one.shape == (1, 5, 2) and single
    many, single = check_points(np.zeros((3, 5, 2)))
    assert many.shape == (3, 5, 2) and not single


def test_float32_is_widened_exactly():
    x = np.array([[0.1, 0.7]], dtype=np.float32)
    batch, _ = check_points(x)
    assert batch.dtype == np.float64 and batch[0, 0, 0] == np.float64(np.float32(0.1))


@pytest.mark.parametrize("points, fragment", [
    (np.zeros(5), "shape"),
    (np.zeros((2, 2, 2, 2)), "shape"),
    (np.zeros((0, 2)), "at least one point"),
    (np.zeros((4, 2), dtype=np.int64), "dtype"),
    (np.array([[0.5, np.nan]]), "NaN"),
    (np.array([[0.5, np.inf]]), "NaN or infinite"),
    (np.array([[0.5, 1.0]]), r"\[0, 1\)"),
    (np.array([[-1e-300, 0.5]]), r"\[0, 1\)"),
    ("not points", "NumPy array"),
])
def test_bad_points_are_refused_by_name(points, fragment):
    with pytest.raises(InvalidArgumentError, match=fragment) as info:
        check_points(points, name="pts")
    assert "'pts'" in str(info.value)
    assert isinstance(info.value, ValueError) and isinstance(info.value, ClsampError)


def test_dimension_and_batch_restrictions():
    with pytest.raises(InvalidArgumentError, match="2 dimensions"):
        check_points(np.zeros((4, 3)), d=2)
    with pytest.raises(InvalidArgumentError, match=r"\(n, d\)"):
        check_points(np.zeros((2, 4, 2)), allow_batch=False)
    assert check_points(np.zeros((4, 3)), d=(2, 3))[0].shape == (1, 4, 3)


def test_largest_double_below_one_is_accepted():
    x = np.array([[np.nextafter(1.0, 0.0), 0.0]])
    assert check_points(x)[0][0, 0, 0] == 1 - 2.0**-53


def test_scalar_checks():
    assert check_int(np.int64(4), "n", minimum=1) == 4
    with pytest.raises(InvalidArgumentError, match="'k' must be an integer >= 2"):
        check_int(1, "k", minimum=2)
    with pytest.raises(InvalidArgumentError, match="'x' must be finite"):
        check_real(float("nan"), "x")
    with pytest.raises(InvalidArgumentError, match="'x' must be > 0"):
        check_real(0.0, "x", minimum=0.0, open_minimum=True)


@pytest.mark.parametrize("call", [
    lambda: clsamp.make_sampler("ccvt", progress="no"),            # bool('no'): the bar shown
    lambda: clsamp.make_sampler("multijittered", progress="no"),
    lambda: clsamp.render.render("ao", "random", 4, 8, progress="no"),
    lambda: clsamp.render.reference("ao", 8, spp=4, progress="no", cache=False),
    lambda: clsamp.power_spectrum(np.full((4, 2), 0.5), resolution=8, progress="no"),
    lambda: clsamp.integrate(lambda x: x[:, 0], 2, progress="no"),
    lambda: clsamp.convergence("random", "gaussian", [16], 10, progress="no"),
    lambda: clsamp.parallel.run(len, [[1]], progress="no"),
])
def test_progress_is_true_or_false(call):
    with pytest.raises(InvalidArgumentError, match="'progress' must be True or False, got 'no'"):
        call()
