"""kernels/f64bits.h: float64 bit patterns by hardware double and by integer arithmetic
(and the torus geometry on them, kernels/torus.h).

Both paths must give the correctly rounded IEEE-754 result, which Python's exact integer
and fraction arithmetic gives here; the integer path is what devices without fp64 run.
"""

import math
from fractions import Fraction

import numpy as np
import pyopencl.array as cla
import pytest

import clsamp
from clsamp import runtime
from clsamp.errors import NoDeviceError
from clsamp.geometry import torus
from clsamp.samplers import sampler_class

rng = np.random.default_rng(20261204)


def _doubles(count):
    """Doubles in [0, 1) with every exponent from 2^-1 to 2^-70, random significands,
    some with few significant bits (exact sums, halfway cases), and zeros."""
    exponents = rng.integers(-70, 0, count)
    significands = rng.integers(2**52, 2**53, count, dtype=np.uint64)
    short = rng.random(count) < 0.3
    significands[short] &= ~np.uint64(2**40 - 1)
    x = np.ldexp(significands.astype(np.float64), exponents - 53)
    x[rng.random(count) < 0.02] = 0.0
    return x


def _integers(count, bits_low=1, bits_high=53):
    bits = rng.integers(bits_low, bits_high + 1, count)
    return np.array([int(rng.integers(0, 2**62)) % (1 << int(k)) | (1 << (int(k) - 1)) for k in bits],
                    dtype=np.uint64)


def _cases(count=4000):
    x, y = _doubles(count), _doubles(count)
    # halfway cases of the sum: 1 + 2^-53 (to even: 1), 1 + 3 2^-53 (up), 0.5 + 2^-54 ...
    ties = [(0.5, 2.0**-54), (0.5, 3 * 2.0**-54), (0.75, 2.0**-54), (2.0**-10, 2.0**-63),
            (1 - 2.0**-53, 2.0**-53), (1 - 2.0**-53, 1 - 2.0**-53), (0.999, 0.5),
            # differences: below a power of two the gap halves (0.5 - 2^-55 ties to 0.5,
            # 0.5 - 3 2^-56 rounds down), y at and past 2^-74 x, equal operands, zero
            (0.5, 2.0**-55), (0.5, 3 * 2.0**-56), (0.5, 2.0**-75), (0.5, 3 * 2.0**-76),
            (0.5, 2.0**-76), (0.5, 2.0**-80), (0.25, 0.25), (0.375, 0.0), (0.0, 0.0),
            (0.75, 0.25), (0.3, 0.8)]
    x[:len(ties)], y[:len(ties)] = zip(*ties, strict=True)
    a = _integers(count)
    b = _integers(count)
    b[b == 0] = 1
    a[:4] = [0, 1, 2**53 - 1, 3]
    b[:4] = [7, 3, 2**53 - 1, 1]
    e = rng.integers(-80, 1, count).astype(np.int32)
    # m 2^e with more than 53 bits rounds: 64-bit integers for f64_scaled
    wide = _integers(count, 54, 64)
    return x, y, a, b, e, wide


def _expected(x, y, a, b, e, wide):
    out = np.empty((len(x), len(NAMES)), np.float64)
    for i in range(len(x)):
        s = float(Fraction(x[i]) + Fraction(y[i]))
        out[i, 0] = s
        out[i, 1] = float(Fraction(int(a[i]), int(b[i])) * Fraction(2) ** int(e[i])) if a[i] else 0.0
        out[i, 2] = float(Fraction(x[i]) / int(b[i]))
        out[i, 3] = float(Fraction(x[i]) * int(b[i]))
        out[i, 4] = math.ldexp(float(int(wide[i])), int(e[i]))
        out[i, 5] = s - 1.0 if s >= 1.0 else s
        out[i, 6] = float(Fraction(x[i]) * Fraction(y[i]))
        out[i, 7] = float(abs(Fraction(x[i]) - Fraction(y[i])))
        out[i, 8] = math.floor(out[i, 3])
    # the torus geometry as clsamp.geometry.torus computes it in float64
    out[:, 9] = torus.wrapped_delta(x, y)
    j = np.minimum(np.arange(len(x)), len(x) - 2)
    out[:, 10] = torus.distance2(np.stack([x, y], 1), np.stack([y[j], y[j + 1]], 1))
    out[:, 11] = x < y
    out[:, 12] = np.maximum(x, y)
    out[:, 13] = out[:, 10] < x
    out[:, 14] = 0.0                                        # not below itself
    out[:, 15] = out[:, 10] < np.nextafter(out[:, 10], 1.0)   # 1
    return out


def _device(x, y, a, b, e, wide):
    q = runtime.queue()
    args = [cla.to_device(q, np.ascontiguousarray(v)) for v in
            (x.view(np.uint64), y.view(np.uint64), a, b, e)]
    out = cla.empty(q, (len(x), len(NAMES)), np.uint64)
    kernel = runtime.kernel("f64bits_probe.cl", "f64bits_ops")
    kernel(q, (len(x),), None, *(v.data for v in args), out.data, np.uint32(len(x)))
    first = out.get()
    # column 4 takes the wide integers
    args[2] = cla.to_device(q, wide)
    kernel(q, (len(x),), None, *(v.data for v in args), out.data, np.uint32(len(x)))
    first[:, 4] = out.get()[:, 4]
    return first.view(np.float64)


NAMES = ["add", "div", "div_int", "mul_int", "scaled", "shift_mod1", "mul", "sub", "floor",
         "torus_delta", "torus_distance2", "less", "max", "closer", "closer_equal",
         "closer_next"]
CASES = _cases()
EXPECTED = _expected(*CASES)


@pytest.mark.parametrize("integer_path", [False, True], ids=["fp64", "integer"])
def test_every_operation_is_correctly_rounded(integer_path):
    if integer_path:
        with runtime.without_fp64():
            got = _device(*CASES)
    else:
        got = _device(*CASES)
    for column, name in enumerate(NAMES):
        bad = np.flatnonzero(got[:, column].view(np.uint64) != EXPECTED[:, column].view(np.uint64))
        assert bad.size == 0, (name, [(CASES[0][i], CASES[1][i], got[i, column], EXPECTED[i, column])
                                      for i in bad[:3]])


def test_the_integer_path_uses_no_double():
    source = runtime.active_source(runtime.kernel_source("f64bits_probe.cl"), fp64=False)
    assert "double" not in source
    assert "double" in runtime.active_source(runtime.kernel_source("f64bits_probe.cl"), fp64=True)


def _subtraction_cases(count=4000):
    """x >= y >= 0 from _doubles, with cancellations (y a few ulps below x, the same
    binade, one binade down), y far below x (74 and 75 binades, a power-of-two x) and
    halfway cases."""
    x, y = _doubles(count), _doubles(count)
    x, y = np.maximum(x, y), np.minimum(x, y)
    near = np.flatnonzero(x > 0)[:count // 6 * 2]
    half = len(near) // 2
    steps = rng.integers(0, 5, half).astype(np.uint64)
    y[near[:half]] = (x[near[:half]].view(np.uint64) - steps).view(np.float64)
    y[near[half:]] = x[near[half:]] * rng.uniform(0.25, 1.0, len(near) - half)
    special = [(1.0, 2.0**-54), (1.0, 2.0**-53), (1.0, 3 * 2.0**-54), (0.5, 2.0**-76),
               (0.5, 2.0**-200), (0.75, 0.75), (1.0, 1.0 - 2.0**-53), (2.0**-10, 2.0**-85),
               (2.0**-10, 2.0**-84 * 1.5), (1.0, 0.0), (0.0, 0.0), (0.3, 2.0**-76 * 1.75)]
    x[:len(special)], y[:len(special)] = zip(*special, strict=True)
    return x, y


@pytest.mark.parametrize("integer_path", [False, True], ids=["fp64", "integer"])
def test_subtraction_is_correctly_rounded(integer_path):
    x, y = _subtraction_cases()
    want = np.array([float(Fraction(a) - Fraction(b)) for a, b in zip(x, y, strict=True)])

    def run():
        # the probe's "sub" column, f64_sub(max(x, y), min(x, y)), on these x >= y (the
        # integer operands only feed the other columns)
        ones = np.ones(len(x), dtype=np.uint64)
        got = _device(x, y, ones, ones, np.zeros(len(x), dtype=np.int32), ones)
        return got[:, NAMES.index("sub")].view(np.uint64)

    if integer_path:
        with runtime.without_fp64():
            got = run()
    else:
        got = run()
    bad = np.flatnonzero(got != want.view(np.uint64))
    assert bad.size == 0, [(x[i], y[i], got[i].view(np.float64), want[i]) for i in bad[:3]]


def _sampler_cases():
    for name in clsamp.sampler_names():
        cls = sampler_class(name)
        d = 3 if cls.dimensions is None else cls.dimensions[-1] if 2 not in cls.dimensions else 2
        for randomize in cls.randomizations:
            yield name, d, randomize


@pytest.mark.parametrize("name, d, randomize", list(_sampler_cases()))
def test_every_sampler_gives_the_same_bits_without_fp64(name, d, randomize):
    """The integer path of every sampler kernel, on this device: the same bits as its fp64
    path (what a device without fp64 runs); the samplers that need double refuse."""
    params = {"randomize": randomize} if randomize is not None else {}
    s = clsamp.make_sampler(name, d=d, seed=9, **params)
    n = s.valid_n(100)
    start = 3 if s.sequence else 0

    def points():
        return s.sample(n, realizations=range(2, 4), **({"start": start} if start else {}))

    if s.needs_fp64:
        with runtime.without_fp64(), pytest.raises(NoDeviceError, match="fp64"):
            points()
        return
    here = points()
    with runtime.without_fp64():
        there = points()
    assert np.array_equal(here.view(np.uint64), there.view(np.uint64))


@pytest.mark.parametrize("randomize", [None, "shift", "xor"])
def test_sobol64_gives_the_same_bits_without_fp64(randomize):
    s = clsamp.make_sampler("sobol", d=5, seed=9, randomize=randomize, bits=64)
    here = s.sample(64, realizations=range(2, 4), start=2**40 + 3)
    with runtime.without_fp64():
        there = s.sample(64, realizations=range(2, 4), start=2**40 + 3)
    assert np.array_equal(here.view(np.uint64), there.view(np.uint64))


@pytest.mark.parametrize("name, d, params", [
    ("random", 7, {}), ("sobol", 9, {"randomize": "shift"}), ("sobol", 6, {"randomize": "owen"}),
    ("sobol", 6, {"bits": 64, "randomize": "xor"}), ("faure", 9, {"randomize": "xor"}),
    ("halton", 7, {"randomize": "owen"}), ("hammersley", 5, {"randomize": "xor"}),
    ("latin_hypercube", 7, {}), ("uncorrelated_jitter", 7, {"groups": (2, 3, 2)}),
    ("jittered", 4, {}), ("latin_hypercube", 2, {"n": 5000}), ("multijittered", 2, {"n": 4900})])
def test_a_dimension_split_gives_the_same_bits(monkeypatch, name, d, params):
    """What a loop-limited device (llvmpipe) runs: a few dimensions per work-item, chunks
    starting inside a stratification group and on odd dimensions, and permutations whose
    swaps come in pieces (a limit of 2000 here: 1000 swaps a launch)."""
    params = dict(params)
    n = params.pop("n", None)
    s = clsamp.make_sampler(name, d=d, seed=4, **params)
    n = s.valid_n(81 if n is None else n)
    whole = s.sample(n, realizations=2)
    split = runtime.dimension_split
    monkeypatch.setattr(runtime.discovery, "loop_limit", lambda: 2000)
    # 4 for random (pairs) and Sobol' (4-wide), 3 for the others
    monkeypatch.setattr(runtime.discovery, "dimension_split",
                        lambda d, per_item, *a: split(d, 4 if per_item == 256 else 3, *a))
    parts = s.sample(n, realizations=2)
    assert np.array_equal(whole.view(np.uint64), parts.view(np.uint64))
