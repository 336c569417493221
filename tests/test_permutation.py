"""Random permutations: Kensler's hash permutation and Fisher–Yates driven by Philox,
kernels against their NumPy references, and the properties that matter (bijection,
uniformity, independence of realization and permutation numbers)."""

import math
from collections import Counter

import numpy as np
import pytest
from scipy import stats

import clsamp
from clsamp import permutation, philox
from clsamp.errors import InvalidArgumentError
from clsamp.philox import Stream


def kensler_listing(i, length, p):
    """Kensler (2013), listing "permute", transcribed one scalar at a time in Python ints."""
    mask = 0xFFFFFFFF
    w = length - 1
    w |= w >> 1
    w |= w >> 2
    w |= w >> 4
    w |= w >> 8
    w |= w >> 16
    while True:
        i ^= p
        i = (i * 0xE170893D) & mask
        i ^= p >> 16
        i ^= (i & w) >> 4
        i ^= p >> 8
        i = (i * 0x0929EB3F) & mask
        i ^= p >> 23
        i ^= (i & w) >> 1
        i = (i * (1 | p >> 27)) & mask
        i = (i * 0x6935FA69) & mask
        i ^= (i & w) >> 11
        i = (i * 0x74DCB303) & mask
        i ^= (i & w) >> 2
        i = (i * 0x9E501CC3) & mask
        i ^= (i & w) >> 2
        i = (i * 0xC860A3DF) & mask
        i &= w
        i ^= i >> 5
        if i < length:
            break
    return (i + p) % length  # Python ints: no 32-bit wrap


@pytest.mark.parametrize("length", [2, 3, 5, 16, 17, 100, 1000, 4097])
def test_permute_is_a_bijection_equal_to_the_listing(length):
    patterns = [0, 1, 0x1234, 0xDEADBEEF, 0xFFFFFFFF]
    for p in patterns:
        values = permutation.permute(np.arange(length), length, p)
        assert sorted(values.tolist()) == list(range(length))
        for i in range(0, length, max(1, length // 23)):
            assert values[i] == kensler_listing(i, length, p)


def test_permute_device_equals_numpy():
    i = np.tile(np.arange(1000), 7)
    p = np.repeat(np.array([0, 3, 0x9E3779B9, 0xFFFFFFFF, 77, 1 << 31, 12345], dtype=np.uint32), 1000)
    for length in (1000, 1001, 1024, 2**31 + 5, 2**32 - 1):
        got = permutation.permute_device(i, length, p)
        assert np.array_equal(got, permutation.permute(i, length, p))
        assert np.all(got < length)
    assert permutation.permute(0, 1, 99) == 0


def test_permute_patterns_differ():
    a = permutation.permute(np.arange(64), 64, 1)
    b = permutation.permute(np.arange(64), 64, 2)
    assert not np.array_equal(a, b)


@pytest.mark.parametrize("length", [1, 2, 3, 4, 5, 7, 64, 1000, 4099])
def test_fisher_yates_device_equals_numpy_and_is_a_permutation(length):
    reals, perms = range(3, 6), range(2, 5)
    a = permutation.random_permutations(11, Stream.PERMUTATION, reals, length, perms)
    b = permutation.random_permutations_device(11, Stream.PERMUTATION, reals, length, perms).get()
    assert a.shape == (3, 3, length) and a.dtype == np.uint32
    assert np.array_equal(a, b)
    assert np.array_equal(np.sort(a, axis=-1), np.broadcast_to(np.arange(length), a.shape))


def test_permutation_k_does_not_depend_on_what_else_was_asked():
    whole = permutation.random_permutations_device(5, Stream.PERMUTATION, 6, 50, 4).get()
    part = permutation.random_permutations_device(5, Stream.PERMUTATION, range(2, 4), 50,
                                                  range(1, 3)).get()
    assert np.array_equal(whole[2:4, 1:3], part)
    other_stream = permutation.random_permutations(5, Stream.SCRAMBLE, 1, 50, 1)
    assert not np.array_equal(whole[0, 0], other_stream[0, 0])
    other_seed = permutation.random_permutations(6, Stream.PERMUTATION, 1, 50, 1)
    assert not np.array_equal(whole[0, 0], other_seed[0, 0])


def test_fisher_yates_is_uniform_over_all_permutations():
    # 4! = 24 permutations, 4800 draws: chi-square against the uniform law.
    perms = permutation.random_permutations_device(2, Stream.PERMUTATION, 1200, 4, 4).get()
    counts = Counter(tuple(p) for p in perms.reshape(-1, 4).tolist())
    assert len(counts) == 24
    observed = np.array(list(counts.values()))
    assert stats.chisquare(observed).pvalue > 1e-4


def test_fisher_yates_positions_are_uniform_and_rows_independent():
    n = 9
    perms = permutation.random_permutations_device(3, Stream.PERMUTATION, 2000, n, 2).get()
    # where element 0 lands: uniform over the n positions
    landing = np.argmax(perms == 0, axis=-1).ravel()
    assert stats.chisquare(np.bincount(landing, minlength=n)).pvalue > 1e-4
    # the two permutations of a realization are independent: joint first entries uniform
    joint = perms[:, 0, 0].astype(int) * n + perms[:, 1, 0]
    assert stats.chisquare(np.bincount(joint, minlength=n * n)).pvalue > 1e-4


def test_bounded_integers_with_rejections_device_equals_numpy():
    # Ranges just above 2^31 reject about half of the first draws: the retry path runs.
    ranges = np.array([2**31 + 1, 3 * 2**30 + 7, 2**32 - 1, 5, 6], dtype=np.uint64)
    ranges = np.tile(ranges, 400)
    steps = np.arange(ranges.size)
    a = permutation.bounded_integers(3, Stream.PERMUTATION, 7, steps, 5, ranges)
    b = permutation.bounded_integers_device(3, Stream.PERMUTATION, 7, steps, 5, ranges)
    assert np.array_equal(a, b)
    assert np.all(a < ranges)
    # with range 2^31 + 1, a biased x * range >> 32 would favour even values; the
    # rejection keeps both halves of [0, range) equally likely
    big = a[ranges == 2**31 + 1].astype(np.int64)
    assert 0.4 < np.mean(big < 2**30) < 0.6
    # Fisher-Yates draws are exactly bounded_integers(.., t, perm, t + 1)
    draws = permutation.fisher_yates_draws(3, Stream.PERMUTATION, range(1, 2), 40, range(2, 3))
    t = np.arange(1, 40)
    assert np.array_equal(draws[0, 0, 1:],
                          permutation.bounded_integers(3, Stream.PERMUTATION, 1, t, 2, t + 1))


def test_fisher_yates_of_a_million_is_a_permutation():
    length = 2**20 + 3
    p = permutation.random_permutations_device(1, Stream.PERMUTATION, 1, length, 1).get()[0, 0]
    assert np.array_equal(np.sort(p), np.arange(length))
    # far from the identity and from its reverse: about one fixed point expected
    assert np.count_nonzero(p == np.arange(length)) < 20
    assert math.isclose(np.corrcoef(p, np.arange(length))[0, 1], 0.0, abs_tol=0.01)


def test_bad_arguments():
    with pytest.raises(InvalidArgumentError, match="length"):
        permutation.random_permutations(0, 1, 1, 0, 1)
    with pytest.raises(InvalidArgumentError, match="perms"):
        permutation.random_permutations(0, 1, 1, 4, range(2**22, 2**22 + 1))
    with pytest.raises(InvalidArgumentError, match="realizations"):
        permutation.random_permutations_device(0, 1, range(3, 3), 4, 1)
    with pytest.raises(InvalidArgumentError, match="length"):
        permutation.permute([0], 0, 1)
    with pytest.raises(InvalidArgumentError, match="'i'"):
        permutation.permute_device([5], 5, 1)


def test_inline_fisher_yates_equals_the_batch():
    # clsamp_fisher_yates (one work-item, for use inside other kernels) makes the same
    # permutations as the parallel draws + sequential swaps of random_permutations_device.
    import pyopencl.array as cla

    from clsamp import runtime
    length, reals, perms = 37, range(2, 5), range(1, 4)
    out = cla.empty(runtime.queue(), (3, 3, length), np.uint32)
    runtime.kernel("permutation.cl", "fisher_yates_inline")(
        runtime.queue(), (9,), None, out.data, np.uint32(length), np.uint32(3), np.uint32(3),
        np.uint32(1), np.uint32(2), *philox.seed_key(8), np.uint32(Stream.PERMUTATION))
    want = permutation.random_permutations(8, Stream.PERMUTATION, reals, length, perms)
    assert np.array_equal(out.get(), want)


def test_long_numpy_shuffles_show_a_bar_that_progress_false_hides(monkeypatch, capsys):
    monkeypatch.setattr(permutation, "SLOW_SWAPS", 10)
    a = permutation.random_permutations(1, Stream.PERMUTATION, 2, 20, 1)
    assert "permutations (NumPy)" in capsys.readouterr().err
    b = permutation.random_permutations(1, Stream.PERMUTATION, 2, 20, 1, progress=False)
    assert "permutations" not in capsys.readouterr().err
    assert np.array_equal(a, b)
    clsamp.make_sampler("latin_hypercube", backend="numpy", progress=False).sample(20)
    assert "permutations" not in capsys.readouterr().err
