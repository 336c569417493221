"""pmj02 and pmj02bn: every prefix of 2^k points is a (0, k, 2)-net for k = 0..16, for several
seeds; the kernels equal the references bit for bit (any n, realization ranges, start=); the
xor masks follow from generator matrices of a (0, 2)-sequence; pmj02bn's points are farther
apart than pmj02's."""

import numpy as np
import pytest
from conftest import is_net

import clsamp
from clsamp.metrics import relative_radius
from clsamp.samplers import pmj


@pytest.mark.parametrize("name", ["pmj02", "pmj02bn"])
def test_every_power_of_two_prefix_is_a_0k2_net(name):
    for seed in (0, 1, 2024):
        pts = clsamp.make_sampler(name, seed=seed).sample(2**16, realizations=range(seed % 5, seed % 5 + 2))
        for k in range(17):
            for r in range(len(pts)):
                assert is_net(pts[r, :2**k], k), (name, seed, r, k)


def test_a_prefix_between_powers_of_two_is_stratified_at_the_coarser_one():
    pts = clsamp.make_sampler("pmj02", seed=5).sample(1000, realizations=4)
    for r in range(4):
        for axis in range(2):
            cells = np.floor(pts[r, :, axis] * 512).astype(int)
            assert len(np.unique(cells)) == 512         # no 1/512 stratum left empty
            assert np.bincount(cells, minlength=512).max() == 2


@pytest.mark.parametrize("n, realizations, start", [
    (1, range(0, 1), 0), (2, range(3, 5), 0), (3, range(0, 2), 0), (5, range(7, 8), 0),
    (1000, range(2, 5), 0), (4096, range(0, 3), 0), (300, range(1, 3), 700), (1, range(0, 2), 2047)])
def test_pmj02_kernel_equals_reference(n, realizations, start):
    ref = clsamp.make_sampler("pmj02", seed=9, backend="numpy").sample(n, realizations, start=start)
    dev = clsamp.make_sampler("pmj02", seed=9).sample(n, realizations, start=start)
    assert np.array_equal(ref, dev)


@pytest.mark.parametrize("n, realizations, start", [
    (1, range(0, 1), 0), (2, range(3, 5), 0), (7, range(0, 2), 0), (600, range(5, 7), 0),
    (150, range(1, 2), 362)])
def test_pmj02bn_kernel_equals_reference(n, realizations, start):
    ref = clsamp.make_sampler("pmj02bn", seed=4, backend="numpy").sample(n, realizations, start=start)
    dev = clsamp.make_sampler("pmj02bn", seed=4).sample(n, realizations, start=start)
    assert np.array_equal(ref, dev)


@pytest.mark.parametrize("name", ["pmj02", "pmj02bn"])
def test_start_continues_the_sequence_and_realizations_are_independent(name):
    s = clsamp.make_sampler(name, seed=3)
    whole = s.sample(2048, realizations=range(0, 3))
    assert np.array_equal(s.sample(548, realizations=range(1, 3), start=1500), whole[1:, 1500:])
    assert not np.array_equal(whole[0], whole[1])
    assert np.array_equal(s.sample(2048, realizations=range(2, 3))[0], whole[2])


def test_masks_follow_from_generator_matrices_of_a_0_2_sequence():
    cx, cy = pmj.generator_matrices()
    assert np.array_equal(np.diag(cx), np.ones(len(cx))) and not np.tril(cx, -1).any()
    # the digital sequence with generators (C_x, C_y): every prefix 2^k a (0, k, 2)-net
    index = np.arange(2**12)
    bits = (index[:, None] >> np.arange(12)[None, :]) & 1
    for k in range(13):
        digits = [(bits[:2**k, :k] @ c[:k, :k].T) % 2 for c in (cx, cy)]
        pts = np.stack([(d * 2.0 ** -(1 + np.arange(k))).sum(axis=1) for d in digits], axis=1)
        assert is_net(pts, k), k
    masks = pmj.xor_masks()
    for axis, c in enumerate((cx, cy)):
        for m in range(1, 20):                    # C[:m, :m] a = C[:m, m] over GF(2)
            a = (masks[axis, m] >> np.arange(m)) & 1
            assert np.array_equal((c[:m, :m].astype(int) @ a) % 2, c[:m, m]), (axis, m)


def test_pmj02bn_points_are_farther_apart_than_pmj02s():
    for n in (64, 256):
        plain = relative_radius(clsamp.make_sampler("pmj02", seed=1).sample(n, realizations=64))
        blue = relative_radius(clsamp.make_sampler("pmj02bn", seed=1).sample(n, realizations=64))
        assert blue.mean() > plain.mean() * 1.1, (n, blue.mean(), plain.mean())


def test_pmj02_is_two_dimensional_and_any_n_is_valid():
    with pytest.raises(clsamp.InvalidArgumentError, match="'d'"):
        clsamp.make_sampler("pmj02", d=3)
    assert clsamp.make_sampler("pmj02bn").valid_n(37) == 37
