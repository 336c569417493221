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
