"""Philox4x32-10: the Random123 known answers, and the kernel bit-identical to NumPy."""

import numpy as np
import pyopencl.array as cla
import pytest

from clsamp import philox, runtime

# Random123's kat_vectors for philox4x32_10: (counter, key, expected output).
KNOWN_ANSWERS = [
    ((0, 0, 0, 0), (0, 0), (0x6627E8D5, 0xE169C58D, 0xBC57AC4C, 0x9B00DBD8)),
    ((0xFFFFFFFF,) * 4, (0xFFFFFFFF,) * 2, (0x408F276D, 0x41C83B0E, 0xA20BC7C6, 0x6D5451FD)),
    ((0x243F6A88, 0x85A308D3, 0x13198A2E, 0x03707344), (0xA4093822, 0x299F31D0),
     (0xD16CFE09, 0x94FDCCEB, 0x5001E420, 0x24126EA1)),
]

PROBE_KERNEL = "philox_probe.cl"


@pytest.mark.parametrize("counter, key, expected", KNOWN_ANSWERS)
def test_numpy_known_answers(counter, key, expected):
    assert tuple(int(x) for x in philox.philox4x32(counter, key)) == expected


def _device_words(counters, keys):
    q = runtime.queue()
    c = cla.to_device(q, np.ascontiguousarray(counters, dtype=np.uint32))
    k = cla.to_device(q, np.ascontiguousarray(keys, dtype=np.uint32))
    out = cla.empty(q, counters.shape, np.uint32)
    kernel = runtime.kernel(PROBE_KERNEL, "philox_words")
    kernel(q, (counters.shape[0],), None, c.data, k.data, out.data)
    return out.get()


def test_kernel_known_answers():
    counters = np.array([kat[0] for kat in KNOWN_ANSWERS], dtype=np.uint32)
    keys = np.array([kat[1] for kat in KNOWN_ANSWERS], dtype=np.uint32)
    expected = np.array([kat[2] for kat in KNOWN_ANSWERS], dtype=np.uint32)
    np.testing.assert_array_equal(_device_words(counters, keys), expected)


def test_million_words_bit_identical():
    rng = np.random.default_rng(5)
    counters = rng.integers(0, 2**32, size=(250_000, 4), dtype=np.uint32)
    keys = rng.integers(0, 2**32, size=(250_000, 2), dtype=np.uint32)
    np.testing.assert_array_equal(_device_words(counters, keys), philox.philox4x32(counters, keys))


def test_uniform_bits_identical_between_kernel_and_numpy():
    """The helpers built on Philox (uniform doubles, words) agree bit for bit."""
    n, realizations, d = 50_000, 4, 5
    q = runtime.queue()
    out = cla.empty(q, (realizations, n, d), np.float64)
    words = cla.empty(q, (realizations, n, d), np.uint32)
    seed = 0x1234_5678_9ABC_DEF0
    kernel = runtime.kernel(PROBE_KERNEL, "uniform_probe")
    kernel(q, (n, realizations), None, out.data, words.data, np.uint32(n), np.uint32(d),
           *philox.seed_key(seed), np.uint32(philox.Stream.SHIFT))
    r = np.arange(realizations)[:, None, None]
    i = np.arange(n)[None, :, None]
    j = np.arange(d)[None, None, :]
    expected = philox.uniform(seed, philox.Stream.SHIFT, r, i, j)
    np.testing.assert_array_equal(out.get(), expected)
    np.testing.assert_array_equal(words.get(), philox.random_words(seed, philox.Stream.SHIFT, r, i, j))


def test_uniform_has_53_bits_and_stays_below_one():
    assert philox.words_to_unit(0xFFFFFFFF, 0xFFFFFFFF) == 1.0 - 2.0**-53
    assert philox.words_to_unit(0, 0) == 0.0
    assert philox.words_to_unit(0, 1 << 6) == 2.0**-53


def test_uniform_is_uniform():
    u = philox.uniform(3, 0, 0, np.arange(200_000), 0)
    counts = np.bincount((u * 20).astype(int), minlength=20)
    expected = len(u) / 20
    chi2 = ((counts - expected) ** 2 / expected).sum()
    assert chi2 < 43.8  # 99.9% quantile of chi-square with 19 degrees of freedom


def test_streams_and_seeds_differ():
    a = philox.uniform(1, 0, 0, np.arange(8), 0)
    assert not np.array_equal(a, philox.uniform(2, 0, 0, np.arange(8), 0))
    assert not np.array_equal(a, philox.uniform(1, 1, 0, np.arange(8), 0))
    assert not np.array_equal(a, philox.uniform(1, 0, 1, np.arange(8), 0))
