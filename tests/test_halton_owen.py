"""Nested uniform ("owen") scrambling of Halton and Van der Corput in base b >= 3.

Every node of the digit tree (realization, dimension, depth k, prefix i mod b^k) gets a
uniformly random permutation of [0, b): kernel and reference agree bit for bit, the
permutations are uniform over seeds, and the scramble is nested.
"""

import itertools
import math

import numpy as np
import pytest

import clsamp
from clsamp import number_theory as nt
from clsamp.samplers.lowdiscrepancy import owen_table_layout

stats = pytest.importorskip("scipy.stats")

P_MIN = 1e-4          # chi-square threshold: a fixed seed, so a pass is a pass for good
REALIZATIONS = 6000


def vdc(base, seed=11, backend="opencl"):
    return clsamp.make_sampler("van_der_corput", d=1, base=base, seed=seed, randomize="owen",
                               backend=backend)


def scrambled_digits(x, base, k):
    """The first k scrambled digits of x = v / b^m, as the integer floor(x b^k) (exact: v // b^(m-k))."""
    m = nt.digit_count(base)
    v = np.rint(x * float(base**m)).astype(np.uint64)      # v < b^m <= 2^53: exact
    return v // np.uint64(base ** (m - k))


def node_permutations(points, base, k, prefix):
    """The permutation of node (k, prefix) in each realization: digit k of the points with
    indices prefix + t b^k, t = 0..b-1 (points: (r, n) values at indices 0..n-1)."""
    idx = prefix + np.arange(base) * base**k
    digits = scrambled_digits(points[:, idx], base, k + 1) % np.uint64(base)
    return digits.astype(np.int64)


def chi_square_of_permutations(perms, base):
    """p-value of the counts of the b! permutations (rows of perms) against uniform."""
    code = np.zeros(len(perms), dtype=np.int64)
    for t in range(base):
        code = code * base + perms[:, t]
    index = {}
    for p in itertools.permutations(range(base)):
        c = 0
        for t in p:
            c = c * base + t
        index[c] = len(index)
    cells = np.array([index[c] for c in code])         # KeyError if a row is no permutation
    counts = np.bincount(cells, minlength=math.factorial(base))
    return stats.chisquare(counts).pvalue


# -- the kernel agrees with the reference ---------------------------------------------
@pytest.mark.parametrize("base", [3, 5, 7, 13, 1009, 65537])
def test_van_der_corput_owen_kernel_matches_reference(base):
    a, b = vdc(base), vdc(base, backend="numpy")
    # base 65537: the root digit near b (one node shared), then small upper digits
    starts = [0, 3 * base + base - 237, 40 * base + base - 137] if base > 2**16 else [0, 12345, 2**32 - 400]
    for start, realizations in zip(starts, [range(0, 3), range(5, 7), range(40, 41)], strict=True):
        got = a.sample(400, realizations=realizations, start=start)
        np.testing.assert_array_equal(got, b.sample(400, realizations=realizations, start=start))
        assert got.min() >= 0.0 and got.max() < 1.0


@pytest.mark.parametrize("start, realizations", [(0, range(0, 2)), (777, range(3, 5)),
                                                 (2**31 + 5, range(9, 10))])
def test_halton_owen_kernel_matches_reference(start, realizations):
    # d = 16: bases 2..53, some digits from the tables, some shuffled per point
    a = clsamp.make_sampler("halton:owen", d=16, seed=4)
    b = clsamp.make_sampler("halton:owen", d=16, seed=4, backend="numpy")
    np.testing.assert_array_equal(a.sample(300, realizations=realizations, start=start),
                                  b.sample(300, realizations=realizations, start=start))


def test_halton_owen_large_dimension_matches_reference():
    # bases up to 7919 (dimension 1000): roots tabulated, three or four digits each
    a = clsamp.make_sampler("halton:owen", d=1000, seed=2)
    b = clsamp.make_sampler("halton:owen", d=1000, seed=2, backend="numpy")
    np.testing.assert_array_equal(a.sample(40, start=123456), b.sample(40, start=123456))


def test_rejected_words_are_replaced_alike():
    # base 1009 takes three draws per word (P = 1009 * 1008 * 1007); a few percent of the
    # words are rejected, and the comparisons above go through such nodes
    keys = nt.owen_node_key(np.uint64(99), np.arange(1009, 3009, dtype=np.uint64))
    x = nt.owen_word(keys, np.uint64(0))
    product = 1009 * 1008 * 1007
    rejected = (x * np.uint64(product)) % np.uint64(2**32) < np.uint64(2**32 % product)
    assert 10 < rejected.sum() < 400
    draws = nt.owen_chunk_draws(keys, 1009, 0)
    assert np.all(draws[:, 0] < 1009) and np.all(draws[:, 1] < 1008) and np.all(draws[:, 2] < 1007)


def test_tables_do_not_change_the_points():
    # one call of 5^5 points tabulates depths 0..4 of base 5; single points tabulate the
    # root only: the same permutations either way
    s = vdc(5)
    whole = s.sample(5**5, realizations=range(2, 4))
    for i in (0, 1, 7, 624, 3124):
        np.testing.assert_array_equal(s.sample(1, realizations=range(2, 4), start=i)[:, 0], whole[:, i])
    layout, segments, nodes, entries = owen_table_layout([2, 5], 5**5)
    assert segments == 5 and nodes == sum(5**k for k in range(5))
    assert entries == sum(5**(k + 1) for k in range(5))
    assert owen_table_layout([2, 5], 1)[1:] == (1, 1, 5)
    # a budget too small for every table drops the largest first
    layout, segments, nodes, entries = owen_table_layout([3, 1009], 10**6, realizations=10**4)
    assert entries * 4 * 10**4 <= 64 * 2**20 and layout[1] >= 1


def test_sequence_and_realizations_do_not_depend_on_the_call():
    s = clsamp.make_sampler("halton:owen", d=16, seed=8)
    whole = s.sample(1000, realizations=range(0, 6))
    parts = np.concatenate([s.sample(1, realizations=range(0, 6)),
                            s.sample(400, realizations=range(0, 6), start=1),
                            s.sample(599, realizations=range(0, 6), start=401)], axis=1)
    np.testing.assert_array_equal(whole, parts)
    np.testing.assert_array_equal(s.sample(1000, realizations=range(4, 5))[0], whole[4])


# -- uniformity over seeds ------------------------------------------------------------
@pytest.fixture(scope="module")
def many_vdc():
    """Points 0..n-1 in REALIZATIONS realizations, for bases 3, 5 and 7."""
    return {b: vdc(b, seed=2024).sample(n, realizations=REALIZATIONS)[:, :, 0]
            for b, n in ((3, 3**4), (5, 5**3), (7, 7**2))}


@pytest.mark.parametrize("base", [3, 5])
def test_root_permutation_uniform(many_vdc, base):
    perms = node_permutations(many_vdc[base], base, 0, 0)
    assert chi_square_of_permutations(perms, base) > P_MIN


@pytest.mark.parametrize("base, k, prefix", [(3, 1, 2), (3, 3, 17), (5, 1, 3), (5, 2, 24)])
def test_deeper_node_permutation_uniform(many_vdc, base, k, prefix):
    perms = node_permutations(many_vdc[base], base, k, prefix)
    assert chi_square_of_permutations(perms, base) > P_MIN


def test_base_7_pairs_uniform(many_vdc):
    for k, prefix in ((0, 0), (1, 5)):
        perms = node_permutations(many_vdc[7], 7, k, prefix)
        pair = perms[:, 0] * 7 + perms[:, 1]
        assert np.all(perms[:, 0] != perms[:, 1])
        counts = np.bincount(pair, minlength=49)[[a * 7 + b for a in range(7) for b in range(7) if a != b]]
        assert stats.chisquare(counts).pvalue > P_MIN


def test_nodes_independent(many_vdc):
    # the root's π(0) and the node (1, 0)'s π(0): independent
    root = node_permutations(many_vdc[5], 5, 0, 0)[:, 0]
    child = node_permutations(many_vdc[5], 5, 1, 0)[:, 0]
    table = np.zeros((5, 5))
    np.add.at(table, (root, child), 1)
    assert stats.chi2_contingency(table).pvalue > P_MIN


def test_deep_node_uniform_without_tables():
    # points drawn one at a time: only the root is tabulated, depth 3 is shuffled per point
    base, k, prefix = 5, 3, 77
    s = vdc(base, seed=31)
    x = np.stack([s.sample(1, realizations=3000, start=prefix + t * base**k)[:, 0, 0]
                  for t in range(base)], axis=1)
    perms = (scrambled_digits(x, base, k + 1) % np.uint64(base)).astype(np.int64)
    assert chi_square_of_permutations(perms, base) > P_MIN


def test_halton_dimension_root_uniform():
    # Halton dimension 2 (base 5) and 3 (base 7): seeds per dimension
    x = clsamp.make_sampler("halton:owen", d=4, seed=77).sample(7, realizations=REALIZATIONS)
    assert chi_square_of_permutations(node_permutations(x[:, :, 2], 5, 0, 0), 5) > P_MIN
    root7 = node_permutations(x[:, :, 3], 7, 0, 0)
    assert stats.chisquare(np.bincount(root7[:, 0] * 7 + root7[:, 1], minlength=49)[
        [a * 7 + b for a in range(7) for b in range(7) if a != b]]).pvalue > P_MIN


def test_reference_permutations_uniform():
    # the reference on its own, 24000 node keys in base 4: all 24 permutations alike
    keys = nt.owen_node_key(np.uint64(5), np.arange(24000, dtype=np.uint64) + np.uint64(1))
    perms = np.stack([nt.owen_permutation_element(keys, 4, t) for t in range(4)], axis=1).astype(np.int64)
    assert chi_square_of_permutations(perms, 4) > P_MIN
    for key in keys[:20]:
        np.testing.assert_array_equal(nt.owen_permutation(key, 4), perms[keys == key][0])


# -- nesting --------------------------------------------------------------------------
@pytest.mark.parametrize("base, start, n", [(3, 0, 3**6), (5, 0, 5**4), (7, 2**32 - 7**4, 7**4),
                                           (1009, 5 * 1009**2 + 17, 1009 * 40)])
def test_nested(base, start, n):
    levels = 3
    x = vdc(base, seed=5).sample(n, realizations=2, start=start)[:, :, 0]
    index = np.uint64(start) + np.arange(n, dtype=np.uint64)
    for k in range(1, levels + 1):
        prefix = index % np.uint64(base**k)
        scrambled = scrambled_digits(x, base, k)
        for r in range(2):
            # points sharing i mod b^k share their first k scrambled digits ...
            order = np.argsort(prefix, kind="stable")
            same = prefix[order][1:] == prefix[order][:-1]
            assert np.all(scrambled[r][order][1:][same] == scrambled[r][order][:-1][same])
            # ... and distinct prefixes map to distinct scrambled prefixes
            first = np.unique(prefix, return_index=True)[1]
            assert len(np.unique(scrambled[r][first])) == len(first) == min(n, base**k)


def test_points_uniform_over_seeds():
    x = clsamp.make_sampler("halton:owen", d=6, seed=3).sample(5, realizations=4000)
    for j in range(1, 6):
        for i in (0, 4):
            assert stats.kstest(x[:, i, j], "uniform").pvalue > P_MIN
