"""Digital nets: LMS (Matoušek's linear matrix scrambling) and the generic, Faure and
Niederreiter nets; kernels against their NumPy twins, published points, net properties."""

import numpy as np
import pytest
from conftest import is_tms_net

import clsamp
from clsamp import generating_matrices as gm
from clsamp import number_theory as nt
from clsamp.errors import InvalidArgumentError

BASE2 = (None, "xor", "owen", "lms", "lms+shift")


def sobol_t(d):
    """t of the first d Joe-Kuo Sobol' dimensions: Σ_j (e_j - 1), dimension 0 counting 0."""
    poly = nt.sobol_table()[0][:d]
    return sum(max(0, int(p).bit_length() - 2) for p in poly)


# -- LMS ---------------------------------------------------------------------------
@pytest.mark.parametrize("randomize", ["lms", "lms+shift"])
@pytest.mark.parametrize("d", [1, 3, 33])
def test_lms_kernel_equals_twin(randomize, d):
    kw = dict(d=d, seed=11, randomize=randomize)
    a = clsamp.make_sampler("sobol", **kw).sample(512, realizations=range(3, 6), start=512)
    b = clsamp.make_sampler("sobol", backend="numpy", **kw).sample(512, realizations=range(3, 6),
                                                                    start=512)
    np.testing.assert_array_equal(a, b)
    whole = clsamp.make_sampler("sobol", **kw).sample(1024, realizations=6)
    np.testing.assert_array_equal(whole[3:, 512:], a)


def test_lms_matrices_are_lower_triangular_and_scramble():
    rows = gm.lms_row_masks(5, np.arange(3), 4)
    k = np.arange(32, dtype=np.uint64)
    diagonal = (np.uint64(1) << (np.uint64(31) - k)).astype(np.uint32)
    assert np.all(rows & diagonal == diagonal)                       # non-singular
    assert np.all(rows & (diagonal - np.uint32(1)) == 0)             # nothing right of it
    assert len(np.unique(rows[..., 20:])) > 100                      # random left of it
    plain = clsamp.make_sampler("sobol", d=4).sample(64)
    lms = clsamp.make_sampler("sobol", d=4, randomize="lms", seed=1).sample(64, realizations=2)
    assert np.all(lms[:, 0] == 0)              # L maps 0 to 0: no shift
    assert not np.array_equal(lms[0], plain) and not np.array_equal(lms[0], lms[1])


@pytest.mark.parametrize("randomize", BASE2)
def test_every_prefix_keeps_the_sobol_net_property(randomize):
    d, m_max = 4, 9
    t = sobol_t(d)
    pts = clsamp.make_sampler("sobol", d=d, seed=3, randomize=randomize).sample(2**m_max,
                                                                                 realizations=3)
    for p in pts:
        for m in range(1, m_max + 1):
            assert is_tms_net(p[:2**m], min(t, m), m), (randomize, m)
            assert is_tms_net(p[:2**m, :2], 0, m), (randomize, m)


def test_lms_shift_is_uniform_over_realizations():
    from scipy import stats
    pts = clsamp.make_sampler("sobol", d=2, randomize="lms+shift", seed=4).sample(8, realizations=400)
    for i in (0, 5):
        for j in (0, 1):
            assert stats.kstest(pts[:, i, j], "uniform").pvalue > 1e-3


def test_lms_names_and_did_you_mean():
    assert {"lms", "lms+shift"} <= set(clsamp.samplers.sampler_class("sobol").randomizations)
    with pytest.raises(InvalidArgumentError, match="did you mean 'sobol:lms'"):
        clsamp.make_sampler("sobol:lsm")
    with pytest.raises(InvalidArgumentError, match="randomize"):
        clsamp.make_sampler("sobol", randomize="lms+xor")


# -- Faure, Niederreiter, user matrices -------------------------------------------------
def test_faure_matches_published_points_and_qmcpy():
    # Faure 1982; qmcpy's Faure docstring lists the first 25 points in d = 4 (base 5)
    pts = clsamp.make_sampler("faure", d=4).sample(25)
    np.testing.assert_allclose(pts[5], [0.04, 0.24, 0.44, 0.64], rtol=0, atol=1e-15)
    np.testing.assert_allclose(pts[24], [0.96, 0.76, 0.56, 0.36], rtol=0, atol=1e-15)
    qmcpy = pytest.importorskip("qmcpy")
    for d in (3, 4, 6):
        ours = clsamp.make_sampler("faure", d=d).sample(gm.faure_base(d) ** 3)
        theirs = qmcpy.Faure(d, randomize="FALSE")(len(ours), warn=False)
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-12)


def test_faure_dimension_zero_is_van_der_corput():
    for d in (3, 5, 11):
        b = gm.faure_base(d)
        ours = clsamp.make_sampler("faure", d=d).sample(1000, start=123456)[:, 0]
        vdc = clsamp.make_sampler("van_der_corput", d=1, base=b).sample(1000, start=123456)[:, 0]
        np.testing.assert_array_equal(ours, vdc)


def test_niederreiter_matches_gsl():
    # GSL's qrng/test.c (gsl_qrng_niederreiter_2, Bratley-Fox-Niederreiter 1992): the 3rd,
    # 4th and 7th points in 2 and 3 dimensions
    for d, expected in [(2, [[0.75, 0.25], [0.25, 0.75], [0.625, 0.125]]),
                        (3, [[0.75, 0.25, 0.3125], [0.25, 0.75, 0.5625], [0.625, 0.125, 0.6875]])]:
        pts = clsamp.make_sampler("niederreiter", d=d).sample(8)
        assert pts[[2, 3, 6]].tolist() == expected
    # GSL's 12 polynomials: x, 1+x, 1+x+x^2, 1+x+x^3, 1+x^2+x^3, 1+x+x^4, 1+x^3+x^4, ...
    assert gm.irreducible_polynomials_gf2(12) == [2, 3, 7, 11, 13, 19, 25, 31, 37, 41, 47, 55]


@pytest.mark.parametrize("randomize", BASE2)
def test_niederreiter_keeps_its_net_property(randomize):
    for d in (3, 4, 5):
        t = gm.niederreiter_t(d)
        p = clsamp.make_sampler("niederreiter", d=d, seed=2, randomize=randomize).sample(2**9)
        for m in range(1, 10):
            assert is_tms_net(p[:2**m], min(t, m), m), (d, randomize, m)
    assert gm.niederreiter_t(4) == 3 and not is_tms_net(
        clsamp.make_sampler("niederreiter", d=4).sample(2**9), 2, 9)   # t is sharp here


@pytest.mark.parametrize("randomize", [None, "xor", "lms", "lms+shift"])
def test_faure_is_a_zero_m_s_net_in_its_base(randomize):
    for d, m_max in ((3, 6), (5, 4)):
        b = gm.faure_base(d)
        p = clsamp.make_sampler("faure", d=d, seed=4, randomize=randomize).sample(b**m_max,
                                                                                   realizations=2)
        for k in range(2):
            for m in range(1, m_max + 1):
                assert is_tms_net(p[k, :b**m], 0, m, base=b), (d, randomize, m)


def test_base_b_lms_is_lower_triangular_and_scrambles():
    eye = np.eye(6, dtype=np.int64)[None].repeat(3, 0)
    lower = gm.lms_digits(4, np.arange(5), eye, 7)           # L C with C = I: L itself
    q, k = np.indices((6, 6))
    assert np.all(lower[..., q < k] == 0) and np.all(lower[..., q == k] > 0)
    assert np.all(lower < 7) and len(np.unique(lower[..., q > k])) == 7
    plain = clsamp.make_sampler("faure", d=5).sample(125)
    lms = clsamp.make_sampler("faure", d=5, randomize="lms", seed=1).sample(125, realizations=2)
    assert np.all(lms[:, 0] == 0) and not np.array_equal(lms[0], plain)
    assert not np.array_equal(lms[0], lms[1])


def test_faure_shift_breaks_the_net():
    p = clsamp.make_sampler("faure", d=3, seed=4, randomize="shift").sample(3**4)
    assert not is_tms_net(p, 0, 4, base=3)


@pytest.mark.parametrize("name,d,randomize", [("faure", 20, "xor"), ("faure", 40, "shift"),
                                              ("faure", 12, "lms+shift"), ("faure", 30, "lms"),
                                              ("niederreiter", 40, "lms+shift"),
                                              ("niederreiter", 9, "owen")])
def test_kernels_equal_twins_far_into_the_sequence(name, d, randomize):
    kw = dict(d=d, seed=8, randomize=randomize)
    a = clsamp.make_sampler(name, **kw).sample(300, realizations=range(2, 4), start=10**6 + 3)
    b = clsamp.make_sampler(name, backend="numpy", **kw).sample(300, realizations=range(2, 4),
                                                                 start=10**6 + 3)
    np.testing.assert_array_equal(a, b)


def test_digital_net_is_its_definition():
    rng = np.random.default_rng(3)
    for base, shape in ((2, (3, 32, 32)), (2, (2, 20, 12)), (3, (3, 20, 9)), (7, (2, 10, 5))):
        matrices = rng.integers(0, base, shape)
        n = min(base ** shape[2], 500)
        for backend in ("opencl", "numpy"):
            pts = clsamp.make_sampler("digital_net", d=shape[0], matrices=matrices, base=base,
                                      backend=backend).sample(n)
            digits = gm.digital_net_digits(np.arange(n), matrices, base)[..., :shape[1]]
            rows = min(shape[1], 32 if base == 2 else 33)
            exact = (digits[..., :rows] * float(base) ** -np.arange(1, rows + 1)).sum(-1)
            np.testing.assert_allclose(pts, exact, rtol=0, atol=1e-15)


def test_digital_net_default_and_faure_matrices():
    sobol = clsamp.make_sampler("sobol", d=5).sample(256)
    net = clsamp.make_sampler("digital_net", d=5).sample(256)           # natural order
    assert not np.array_equal(net, sobol)
    np.testing.assert_array_equal(np.unique(net, axis=0), np.unique(sobol, axis=0))
    for randomize in (None, "xor"):
        m = nt.digit_count(5)
        user = clsamp.make_sampler("digital_net", d=4, base=5, seed=1, randomize=randomize,
                                   matrices=gm.faure_matrices(4, 5, m)).sample(625, start=9)
        faure = clsamp.make_sampler("faure", d=4, seed=1, randomize=randomize).sample(625, start=9)
        np.testing.assert_array_equal(user, faure)
    lms = clsamp.make_sampler("digital_net", d=4, randomize="lms", seed=2).sample(2**8)
    assert is_tms_net(lms, sobol_t(4), 8)


def test_digital_net_bad_input():
    eye = np.eye(4, dtype=int)[None].repeat(2, 0)
    cases = [(dict(matrices=eye, base=4), "'base' must be a prime"),
             (dict(matrices=eye, base=3, randomize="owen"), "'randomize'"),
             (dict(base=3), "'matrices' must be given"),
             (dict(matrices=eye[0], base=3), "'matrices' must be an integer array"),
             (dict(matrices=eye * 3, base=3), r"digits in \[0, 3\)"),
             (dict(matrices=eye, base=3, d=3), "'d' must be in"),
             (dict(d=4, base=2, matrices=np.ones((4, 8, 8), dtype=float)), "integer array")]
    for kw, message in cases:
        with pytest.raises(InvalidArgumentError, match=message):
            clsamp.make_sampler("digital_net", **kw)
    small = clsamp.make_sampler("digital_net", d=2, matrices=eye, base=3)
    assert small.sample(81).shape == (81, 2)
    with pytest.raises(InvalidArgumentError, match="'start' \\+ 'n' must stay within the 81"):
        small.sample(4, start=80)
    with pytest.raises(InvalidArgumentError, match="'randomize'"):
        clsamp.make_sampler("faure", d=3, randomize="owen")


def test_base2_nets_equal_qmcpy_digital_net_b2():
    # qmcpy's DigitalNetB2 given the same column words (most significant digit first)
    qmcpy = pytest.importorskip("qmcpy")
    rng = np.random.default_rng(0)
    user = rng.integers(0, 2, (5, 32, 32))
    for name, params, columns, order in [
            ("digital_net", {"matrices": user}, gm.columns_base2(user), "RADICAL INVERSE"),
            ("niederreiter", {}, gm.columns_base2(gm.niederreiter_matrices(5)), "GRAY")]:
        theirs = qmcpy.DigitalNetB2(5, randomize="FALSE", generating_matrices=columns.astype(np.uint64),
                                    msb=True, t=32, order=order)(2**12, warn=False)
        np.testing.assert_array_equal(clsamp.make_sampler(name, d=5, **params).sample(2**12), theirs)


# -- Sobol' with 64-bit indices -------------------------------------------------------
@pytest.mark.parametrize("randomize", [None, "shift", "xor"])
def test_sobol64_equals_sobol32_then_continues(randomize):
    kw = dict(d=7, seed=5, randomize=randomize)
    wide = clsamp.make_sampler("sobol", bits=64, **kw)
    pts = wide.sample(16, realizations=2, start=2**32 - 8)
    np.testing.assert_array_equal(
        pts, clsamp.make_sampler("sobol", bits=64, backend="numpy", **kw).sample(
            16, realizations=2, start=2**32 - 8))
    if randomize != "xor":      # xor's 64-bit digit vector only begins with the 32-bit one
        narrow = clsamp.make_sampler("sobol", **kw).sample(8, realizations=2, start=2**32 - 8)
        np.testing.assert_array_equal(pts[:, :8], narrow)
    assert len(np.unique(pts[0], axis=0)) == 16        # no wrap to point 0 past 2^32
    if randomize is None:
        i = np.arange(2**32 - 8, 2**32 + 8, dtype=np.uint64)
        g = i ^ (i >> np.uint64(1))
        reversed64 = np.array([int(f"{int(v):064b}"[::-1], 2) for v in g], dtype=np.uint64)
        np.testing.assert_array_equal(pts[0, :, 0], (reversed64 >> np.uint64(11)) * 2.0**-53)


def test_sobol64_blocks_past_2_to_32_are_nets():
    # indices [k 2^m, (k + 1) 2^m) of a digital sequence form a (digitally shifted) net
    wide = clsamp.make_sampler("sobol", d=4, bits=64)
    for start in (2**32, 2**40 + 2**20, 2**63):
        assert is_tms_net(wide.sample(2**9, start=start), sobol_t(4), 9), start
    with pytest.raises(InvalidArgumentError, match="'start'"):
        wide.sample(8, start=2**64 - 4)
    assert wide.sample(4, start=2**64 - 4).shape == (4, 4)


def test_sobol64_direction_numbers_and_points_equal_scipy():
    from scipy.stats import qmc
    engine = qmc.Sobol(40, scramble=False, bits=64)
    wide = clsamp.make_sampler("sobol", d=40, bits=64)
    np.testing.assert_array_equal(wide.sample(1024), engine.random(1024))
    if hasattr(engine, "_sv"):       # scipy's 64-bit direction numbers (fast_forward refuses 64)
        m = clsamp.make_sampler("sobol", d=40, bits=64, backend="numpy")
        top = m.sample(1, start=2**63)[0]          # index 2^63: Gray code 2^63 + 2^62
        expected = (engine._sv[:, 63] ^ engine._sv[:, 62]) >> np.uint64(11)
        np.testing.assert_array_equal(top, expected * 2.0**-53)


def test_sobol64_bad_input():
    with pytest.raises(InvalidArgumentError, match="'bits'"):
        clsamp.make_sampler("sobol", bits=48)
    with pytest.raises(InvalidArgumentError, match="'randomize'.*bits=64"):
        clsamp.make_sampler("sobol", bits=64, randomize="owen")
    with pytest.raises(InvalidArgumentError, match="'start'"):
        clsamp.make_sampler("sobol").sample(16, start=2**32 - 8)
