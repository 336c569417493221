"""The sampler base, the registry and the `random` sampler (the first real sampler)."""

import numpy as np
import pytest

import clsamp
from clsamp.errors import InvalidArgumentError


def test_same_seed_same_points_other_seed_other_points():
    a = clsamp.make_sampler("random", d=3, seed=11).sample(1000)
    b = clsamp.make_sampler("random", d=3, seed=11).sample(1000)
    assert a.dtype == np.float64 and a.shape == (1000, 3)
    np.testing.assert_array_equal(a, b)
    assert a.min() >= 0.0 and a.max() < 1.0
    c = clsamp.make_sampler("random", d=3, seed=12).sample(1000)
    assert not np.any(np.all(a == c, axis=1))


def test_realizations_are_distinct_and_independent_of_their_count():
    sampler = clsamp.make_sampler("random", d=3, seed=11)
    five = sampler.sample(1000, realizations=5)
    assert five.shape == (5, 1000, 3)
    for i in range(5):
        for j in range(i):
            assert not np.array_equal(five[i], five[j])
    np.testing.assert_array_equal(sampler.sample(1000, realizations=2), five[:2])
    np.testing.assert_array_equal(five[0], sampler.sample(1000))


def test_kernel_equals_numpy_reference_bit_for_bit():
    for d in (1, 2, 3, 8):
        cl = clsamp.make_sampler("random", d=d, seed=2**40 + 7).sample(777, realizations=3, start=5)
        ref = clsamp.make_sampler("random", d=d, seed=2**40 + 7, backend="numpy").sample(
            777, realizations=3, start=5)
        np.testing.assert_array_equal(cl, ref)


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5, 7, 9])
def test_kernel_lanes_cover_every_tail(n):
    # four points a work-item: n not a multiple of four leaves 1..3 lanes in the last one
    for d in (1, 2, 5):
        cl = clsamp.make_sampler("random", d=d, seed=3).sample(n, realizations=2, start=3)
        ref = clsamp.make_sampler("random", d=d, seed=3, backend="numpy").sample(
            n, realizations=2, start=3)
        np.testing.assert_array_equal(cl, ref)


def test_start_continues_the_sequence():
    sampler = clsamp.make_sampler("random", d=2, seed=1)
    whole = sampler.sample(300)
    np.testing.assert_array_equal(np.concatenate([sampler.sample(100), sampler.sample(200, start=100)]),
                                  whole)


def test_sample_device_keeps_points_on_device():
    sampler = clsamp.make_sampler("random", d=2, seed=9)
    on_device = sampler.sample_device(64, realizations=4)
    assert on_device.shape == (4, 64, 2)
    np.testing.assert_array_equal(on_device.get(), sampler.sample(64, realizations=4))


def test_chunked_generation_equals_one_launch(monkeypatch):
    from clsamp import runtime
    sampler = clsamp.make_sampler("random", d=2, seed=4)
    whole = sampler.sample(100, realizations=7)
    monkeypatch.setattr(runtime.memory, "chunk_ranges",
                        lambda total, _: [(lo, min(total, lo + 2)) for lo in range(0, total, 2)])
    np.testing.assert_array_equal(sampler.sample(100, realizations=7), whole)


@pytest.mark.parametrize("n, message", [(0, "'n'"), (-3, "'n'"), (2.5, "'n'"), (True, "'n'"),
                                        ("10", "'n'")])
def test_bad_n_names_the_argument(n, message):
    with pytest.raises(InvalidArgumentError, match=message):
        clsamp.make_sampler("random").sample(n)


def test_bad_arguments_name_themselves():
    with pytest.raises(InvalidArgumentError, match="'n' is required"):
        clsamp.make_sampler("random").sample()
    with pytest.raises(InvalidArgumentError, match="'realizations'"):
        clsamp.make_sampler("random").sample(4, realizations=0)
    with pytest.raises(InvalidArgumentError, match="'start'"):
        clsamp.make_sampler("random").sample(4, start=-1)
    with pytest.raises(InvalidArgumentError, match="'d'"):
        clsamp.make_sampler("random", d=0)
    with pytest.raises(InvalidArgumentError, match="'seed'"):
        clsamp.make_sampler("random", seed=-1)
    with pytest.raises(InvalidArgumentError, match="'backend'"):
        clsamp.make_sampler("random", backend="cuda")
    with pytest.raises(InvalidArgumentError, match="'start' \\+ 'n'"):
        clsamp.make_sampler("random").sample(10, start=2**32 - 5)


def test_unknown_sampler_lists_known_names():
    with pytest.raises(InvalidArgumentError) as info:
        clsamp.make_sampler("randon")
    message = str(info.value)
    assert "'randon'" in message and "did you mean 'random'?" in message
    for name in clsamp.sampler_names():
        assert name in message


def test_sampler_names_include_random():
    assert "random" in clsamp.sampler_names()
