"""Low-discrepancy samplers: kernels against references, scipy, exact rationals, net properties."""

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import clsamp
from clsamp import number_theory as nt
from clsamp.errors import InvalidArgumentError

qmc = pytest.importorskip("scipy.stats.qmc")

SAMPLERS = {
    "sobol": (None, "shift", "xor", "owen", "lms", "lms+shift"),
    "halton": (None, "shift", "xor", "owen", "permute"),
    "hammersley": (None, "shift", "xor", "owen"),
    "van_der_corput": (None, "shift", "xor", "owen", "permute"),
}
CASES = [(name, rz) for name, rzs in SAMPLERS.items() for rz in rzs]


def make(name, randomize=None, d=None, seed=5, backend="opencl", **params):
    if name == "van_der_corput":
        d = 1
        params.setdefault("base", 3)
    return clsamp.make_sampler(name, d=4 if d is None else d, seed=seed, randomize=randomize,
                               backend=backend, **params)


# -- the kernels agree with the NumPy references -------------------------------------
@pytest.mark.parametrize("name,randomize", CASES)
def test_kernel_matches_reference(name, randomize):
    start = 0 if name == "hammersley" else 1000
    # 333 points: not a multiple of the per-work-item block; start moves the digit carries
    a = make(name, randomize).sample(333, realizations=3, start=start)
    b = make(name, randomize, backend="numpy").sample(333, realizations=3, start=start)
    assert a.shape == (3, 333, 1 if name == "van_der_corput" else 4)
    np.testing.assert_array_equal(a, b)
    assert a.min() >= 0.0 and a.max() < 1.0


@pytest.mark.parametrize("base", [2, 5, 7, 1021])
@pytest.mark.parametrize("randomize", [None, "xor", "owen", "permute"])
def test_van_der_corput_bases_match_reference(base, randomize):
    start = 2**32 - 300
    a = make("van_der_corput", randomize, base=base).sample(300, realizations=2, start=start)
    b = make("van_der_corput", randomize, base=base, backend="numpy").sample(300, realizations=2,
                                                                               start=start)
    np.testing.assert_array_equal(a, b)


def test_sobol_large_start_matches_reference():
    for randomize in (None, "owen"):
        a = make("sobol", randomize, d=6).sample(200, realizations=2, start=2**31 - 77)
        b = make("sobol", randomize, d=6, backend="numpy").sample(200, realizations=2, start=2**31 - 77)
        np.testing.assert_array_equal(a, b)


# -- textbook definitions and scipy --------------------------------------------------
@pytest.mark.parametrize("d", range(2, 17))
def test_sobol_equals_scipy(d):
    ours = clsamp.make_sampler("sobol", d=d).sample(1024)
    np.testing.assert_array_equal(ours, qmc.Sobol(d, scramble=False).random(1024))


def test_sobol_high_dimension_equals_scipy():
    ours = clsamp.make_sampler("sobol", d=1024).sample(64)
    np.testing.assert_array_equal(ours, qmc.Sobol(1024, scramble=False).random(64))
    np.testing.assert_array_equal(clsamp.make_sampler("sobol", d=1024, backend="numpy").sample(64), ours)


@pytest.mark.parametrize("d", [1, 2, 5, 16, 64])
def test_halton_equals_scipy(d):
    ours = clsamp.make_sampler("halton", d=d).sample(2000)
    theirs = qmc.Halton(d, scramble=False).random(2000)
    # scipy adds digit terms in floating point; ours is the exact rational rounded once.
    np.testing.assert_allclose(ours, theirs, rtol=0, atol=2**-52)
    # and ours is the correctly rounded radical inverse
    for j, base in enumerate(nt.first_primes(d)[:6]):
        for i in (1, 7, 1999):
            assert ours[i, j] == float(_radical_inverse_fraction(i, int(base)))


def test_first_points_are_the_origin():
    for name in SAMPLERS:
        assert np.all(make(name).sample(8)[0] == 0.0)


def test_hammersley_definition():
    n = 12
    pts = clsamp.make_sampler("hammersley", d=3).sample(n)
    for i in range(n):
        assert pts[i, 0] == float(Fraction(i, n))
        assert pts[i, 1] == float(_radical_inverse_fraction(i, 2))
        assert pts[i, 2] == float(_radical_inverse_fraction(i, 3))


def test_sequences_continue():
    for name, randomize in [("sobol", "owen"), ("halton", "owen"), ("halton", "permute"),
                            ("van_der_corput", "xor"), ("sobol", "shift")]:
        s = make(name, randomize)
        whole = s.sample(300, realizations=2)
        parts = np.concatenate([s.sample(123, realizations=2), s.sample(177, realizations=2, start=123)],
                               axis=1)
        np.testing.assert_array_equal(whole, parts)


def test_realization_independent_of_count():
    for name, randomize in [("sobol", "owen"), ("halton", "permute"), ("hammersley", "shift")]:
        s = make(name, randomize)
        np.testing.assert_array_equal(s.sample(64, realizations=4)[3], s.sample(64, realizations=9)[3])
        # and seeds matter
        assert not np.array_equal(s.sample(64), make(name, randomize, seed=6).sample(64))


# -- exactness -----------------------------------------------------------------------
def _radical_inverse_fraction(i, base):
    value, scale = Fraction(0), Fraction(1, base)
    while i:
        i, digit = divmod(i, base)
        value += digit * scale
        scale /= base
    return value


def test_large_indices_exact():
    for backend in ("opencl", "numpy"):
        vdc = clsamp.make_sampler("van_der_corput", d=1, backend=backend)
        got = vdc.sample(2, start=2**32 - 2)[:, 0]
        assert got[0] == float(_radical_inverse_fraction(2**32 - 2, 2))
        assert got[1] == float(_radical_inverse_fraction(2**32 - 1, 2))
        assert got[1] == 1.0 - 2.0**-32
        halton = clsamp.make_sampler("halton", d=2, backend=backend)
        got = halton.sample(3, start=3**20 - 1)[:, 1]
        for k, i in enumerate(range(3**20 - 1, 3**20 + 2)):
            assert got[k] == float(_radical_inverse_fraction(i, 3))
        assert got[1] == 3.0**-21


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from([2, 3, 5, 7, 11, 13, 31, 97, 1009, 2**20]))
def test_radical_inverse_correctly_rounded(i, base):
    assert float(nt.radical_inverse(i, base)) == float(_radical_inverse_fraction(i, base))


# -- net and stratification properties -----------------------------------------------
def _elementary_interval_counts(points, m):
    """Counts of points in every elementary interval 2^-a x 2^-(m-a) of area 2^-m."""
    x = np.floor(points[:, 0] * 2.0**32).astype(np.uint64)
    y = np.floor(points[:, 1] * 2.0**32).astype(np.uint64)
    for a in range(m + 1):
        cell = (x >> np.uint64(32 - a)) * np.uint64(2 ** (m - a)) + (y >> np.uint64(32 - (m - a)))
        yield a, np.bincount(cell.astype(np.int64), minlength=2**m)


@pytest.mark.parametrize("name", ["sobol", "hammersley"])
@pytest.mark.parametrize("randomize", [None, "xor", "owen", "shift"])
def test_net_property(name, randomize):
    m = 8
    pts = make(name, randomize, d=2, seed=3).sample(2**m, realizations=6)
    perfect = [all(np.all(c == 1) for _, c in _elementary_interval_counts(p, m)) for p in pts]
    if randomize == "shift":
        assert not any(perfect)   # a random rotation breaks the elementary intervals
    else:
        assert all(perfect)


@pytest.mark.parametrize("randomize", [None, "xor", "owen", "permute"])
def test_halton_stratified_in_each_base(randomize):
    pts = make("halton", randomize, d=4, seed=9).sample(7**3, realizations=3)
    for j, base in enumerate((2, 3, 5, 7)):
        k = int(np.floor(np.log(7**3) / np.log(base)))
        n = base**k
        for p in pts:
            # points are v / b^M, more than 1e-9 (in cells) from a cell edge unless on it
            # (n / b^M > 1e-9); the offset absorbs the rounding of (v / b^M) * n
            counts = np.bincount(np.floor(p[:n, j] * n + 1e-9).astype(np.int64), minlength=n)
            assert np.all(counts == 1), (randomize, base)


# -- Owen scrambling is really nested ------------------------------------------------
def test_owen_points_uniform_and_gaps_vary():
    from scipy import stats
    r = 4096
    sobol = make("sobol", "owen", d=2, seed=21).sample(8, realizations=r)
    xor = make("sobol", "xor", d=2, seed=21).sample(8, realizations=r)
    for j in range(2):
        for i in (0, 3, 7):
            assert stats.kstest(sobol[:, i, j], "uniform").pvalue > 1e-3
    ints = lambda a: np.floor(a * 2.0**32).astype(np.uint64)  # noqa: E731
    owen_gaps = np.unique(ints(sobol[:, 2, 0]) ^ ints(sobol[:, 5, 0]))
    xor_gaps = np.unique(ints(xor[:, 2, 0]) ^ ints(xor[:, 5, 0]))
    assert len(xor_gaps) == 1            # a digit xor moves both points alike
    assert len(owen_gaps) > r // 4       # nested: the lower digits' flips depend on the upper
    # base 3 (Halton dimension 1): uniform, and the digit-shift gap is fixed mod 1 in the
    # leading digit while Owen's varies
    halton = make("halton", "owen", d=2, seed=21).sample(8, realizations=r)
    for i in (0, 4):
        assert stats.kstest(halton[:, i, 1], "uniform").pvalue > 1e-3
    assert len(np.unique(np.round((halton[:, 1, 1] - halton[:, 2, 1]) % 1.0, 12))) > r // 4


def test_owen_base2_is_a_nested_bijection():
    rng = np.random.default_rng(0)
    seed = np.uint32(0x9E3779B9)
    x = np.arange(2**12, dtype=np.uint32) << np.uint32(20)
    y = nt.owen_scramble_base2(x, seed)
    assert len(np.unique(y >> np.uint32(20))) == 2**12          # a permutation of the top digits
    for _ in range(50):
        a, b = rng.integers(0, 2**32, 2, dtype=np.uint64).astype(np.uint32)
        ya, yb = nt.owen_scramble_base2(np.array([a, b]), seed)
        # digits above the first difference agree, and the first difference stays the first
        assert (int(ya) ^ int(yb)).bit_length() == (int(a) ^ int(b)).bit_length()


@pytest.mark.parametrize("length", [2, 3, 5, 7, 17, 64, 311, 1048573])
def test_permutation_element_is_a_permutation(length):
    # p near 2^32 too: the final rotation (i + p) mod length must not wrap in 32 bits
    for p in (0, 1, 12345, 0xDEADBEEF, 2**32 - length, 2**32 - length + 1, 2**32 - 1):
        perm = nt.permutation_element(np.arange(length), length, p)
        assert np.array_equal(np.sort(perm), np.arange(length)), p


@pytest.mark.parametrize("randomize, realization", [("permute", 1968), ("owen", 1899)])
def test_large_base_digits_stay_permutations(randomize, realization):
    # base 1048573, seed 0: these realizations draw a top-digit permutation hash above
    # 2^32 - 1048573, where a 32-bit rotation left 12288 strata empty; every stratum
    # floor(x b) of the first b points holds exactly one, kernel and reference alike
    b = 1048573
    s = clsamp.make_sampler("van_der_corput", d=1, base=b, seed=0, randomize=randomize)
    x = s.sample(b, realizations=range(realization, realization + 1))[0, :, 0]
    assert np.array_equal(np.sort(np.floor(x * b).astype(np.int64)), np.arange(b))
    ref = clsamp.make_sampler("van_der_corput", d=1, base=b, seed=0, randomize=randomize,
                              backend="numpy")
    assert np.array_equal(ref.sample(2048, realizations=range(realization, realization + 1))[0, :, 0],
                          x[:2048])


def test_first_primes():
    assert nt.first_primes(10).tolist() == [2, 3, 5, 7, 11, 13, 17, 19, 23, 29]
    assert int(nt.first_primes(1000)[-1]) == 7919
    assert int(nt.first_primes(10000)[-1]) == 104729
    assert len(nt.first_primes(21201)) == 21201


# -- bad input -----------------------------------------------------------------------
def test_bad_input():
    with pytest.raises(InvalidArgumentError, match="base"):
        clsamp.make_sampler("van_der_corput", d=1, base=1)
    with pytest.raises(InvalidArgumentError, match="'d'"):
        clsamp.make_sampler("sobol", d=nt.sobol_max_dimension() + 1)
    with pytest.raises(InvalidArgumentError, match="'d'"):
        clsamp.make_sampler("van_der_corput", d=2)
    with pytest.raises(InvalidArgumentError, match="randomize"):
        clsamp.make_sampler("sobol", randomize="permute")
    with pytest.raises(InvalidArgumentError, match="unknown randomization 'owan'.*'halton:owen'"):
        clsamp.make_sampler("halton:owan")
    sobol = clsamp.make_sampler("sobol", d=2)
    with pytest.raises(InvalidArgumentError, match="'n'"):
        sobol.sample(2**32)
    with pytest.raises(InvalidArgumentError, match="'start'"):
        sobol.sample(4, start=-1)
    with pytest.raises(InvalidArgumentError, match="'start'"):
        sobol.sample(4, start=2**32 - 2)
    with pytest.raises(InvalidArgumentError, match="'start'"):
        clsamp.make_sampler("hammersley").sample(4, start=1)


def test_make_sampler_variants():
    s = clsamp.make_sampler("sobol:owen", d=3, seed=2)
    assert s.randomize == "owen" and s.randomized
    assert not clsamp.make_sampler("halton").randomized
    for name in SAMPLERS:
        assert name in clsamp.sampler_names()


@pytest.mark.parametrize("name,randomize", [("sobol", "owen"), ("sobol", None), ("halton", "xor"),
                                            ("hammersley", "owen")])
def test_sample_device_matches_sample(name, randomize):
    # sample() writes into host memory on a CPU device; sample_device() keeps a device array
    s = make(name, randomize, d=11)
    np.testing.assert_array_equal(s.sample_device(257, realizations=2).get(), s.sample(257, realizations=2))


# -- the bit reversal Oclgrind builds (kernels/lowdiscrepancy.h, CLSAMP_OCLGRIND) ----------------

# every kernel path that reverses bits: Sobol' Owen (vector lanes, d = 5), the base-2 digits of
# Halton and Hammersley (Owen, xor, shift), Van der Corput, the lattice's radical-inverse order
# and ZSobol
REVERSING = [("sobol", "owen", 5), ("halton", "owen", 3), ("halton", "xor", 2), ("halton", "shift", 2),
             ("hammersley", "owen", 2), ("van_der_corput", "owen", 1), ("lattice", None, 5),
             ("zsobol", None, 2)]


def test_the_oclgrind_bit_reversal_gives_the_same_bits(monkeypatch):
    """On Oclgrind the runtime builds with CLSAMP_OCLGRIND, and the kernels reverse bits by
    delta swaps instead of the form LLVM turns into llvm.bitreverse; forced here on the
    default device, the samplers whose kernels reverse bits give the same bits."""
    from clsamp.runtime import programs

    def points():
        out = []
        for name, randomize, d in REVERSING:
            params = {"randomize": randomize} if randomize else {}
            s = clsamp.make_sampler(name, d=d, seed=6, **params)
            out.append(s.sample(s.valid_n(300), realizations=range(2, 4)))
        return out

    plain = points()
    device_defines = programs.device_defines
    built = programs.build_count()
    monkeypatch.setattr(programs, "device_defines", lambda d: {**device_defines(d), "CLSAMP_OCLGRIND": 1})
    swapped = points()
    assert programs.build_count() > built                      # the other form was built
    for a, b in zip(plain, swapped, strict=True):
        assert np.array_equal(a.view(np.uint64), b.view(np.uint64))


def test_remembered_shifts_are_the_streams_and_fresh_arrays():
    # shift_vectors keeps the shifts of a few realizations (a sequence sampled in chunks
    # asks for them again): the same philox values, in an array the caller may change
    from clsamp import philox
    from clsamp.samplers.lowdiscrepancy import shift_vectors
    stream = philox.uniform(5, philox.Stream.SHIFT, np.arange(2, 5, dtype=np.uint32)[:, None], 0,
                            np.arange(3, dtype=np.uint32)[None, :])
    first = shift_vectors(5, range(2, 5), 3)
    assert np.array_equal(first, stream)
    first[:] = 0.0
    assert np.array_equal(shift_vectors(5, np.arange(2, 5), 3), stream)
    assert np.array_equal(shift_vectors(5, np.arange(100), 3)[2:5], stream)   # not remembered
