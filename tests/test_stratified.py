"""The stratified family: stratification of every realization, kernels against their
NumPy references, decorrelation of uncorrelated jitter, and argument errors."""

import numpy as np
import pytest
from scipy import stats

import clsamp
from clsamp.errors import InvalidArgumentError
from clsamp.samplers.stratified import stratum_point

R = 12   # realizations per property check


def sample(name, n, d=2, seed=1, realizations=R, start=0, backend="opencl", **params):
    return clsamp.make_sampler(name, d=d, seed=seed, backend=backend, **params).sample(
        n, realizations=realizations, start=start)


def cells(points, strata):
    """Flat index of each point's cell of a grid with strata[j] cells along axis j."""
    strata = np.asarray(strata)
    idx = np.floor(points * strata).astype(np.int64)
    assert np.all(idx >= 0) and np.all(idx < strata)
    flat = np.zeros(points.shape[:-1], dtype=np.int64)
    for j in reversed(range(points.shape[-1])):
        flat = flat * strata[j] + idx[..., j]
    return flat


def one_per_cell(points, strata):
    """True when every realization has exactly one point in every cell of the grid."""
    c = cells(points, strata)
    total = int(np.prod(strata))
    return all(np.array_equal(np.sort(row), np.arange(total)) for row in c.reshape(-1, c.shape[-1]))


# -- kernels against references -------------------------------------------------------
CASES = [
    ("regular", 2, {}, 16), ("regular", 3, {"strata": (2, 3, 5)}, 30),
    ("jittered", 2, {}, 64), ("jittered", 3, {}, 27), ("jittered", 4, {"strata": (3, 1, 2, 2)}, 12),
    ("uncorrelated_jitter", 5, {}, 16), ("uncorrelated_jitter", 3, {"groups": (1, 2)}, 9),
    ("uncorrelated_jitter", 5, {"groups": (3, 2)}, 64),
    ("latin_hypercube", 1, {}, 33), ("latin_hypercube", 8, {}, 50), ("n_rooks", 2, {}, 1),
    ("multijittered", 2, {}, 12), ("multijittered", 2, {"strata": (5, 3)}, 15),
    ("multijittered", 2, {}, 13),
    ("correlated_multijittered", 2, {}, 16), ("correlated_multijittered", 2, {}, 10),
    ("correlated_multijittered", 2, {}, 1),
]


@pytest.mark.parametrize("name,d,params,n", CASES)
def test_kernel_equals_reference(name, d, params, n):
    kw = dict(d=d, seed=2**40 + 9, realizations=4, start=3, **params)
    got = sample(name, n, **kw)
    want = sample(name, n, backend="numpy", **kw)
    assert got.shape == (4, n, d)
    assert np.array_equal(got, want)
    assert np.all(got >= 0) and np.all(got < 1)


@pytest.mark.parametrize("name", ["jittered", "latin_hypercube", "multijittered",
                                  "correlated_multijittered", "uncorrelated_jitter"])
def test_realization_does_not_depend_on_how_many(name):
    s = clsamp.make_sampler(name, d=2, seed=5)
    many = s.sample(16, realizations=6)
    few = s.sample(16, realizations=4)
    assert np.array_equal(many[:4], few)
    assert np.array_equal(s.sample(16), many[0])
    assert not np.array_equal(many[0], many[1])
    assert not np.array_equal(clsamp.make_sampler(name, d=2, seed=6).sample(16), many[0])


def test_stratum_point_stays_inside_its_stratum_at_the_edges():
    # u just below 1 rounds k + u up to k + 1; u = 0 with count not a power of two
    # can round k / count below the stratum; both are nudged back.
    count = np.array([3, 7, 10, 1000003, 2**32 - 1])
    for k in (count - 1, count // 2, np.zeros_like(count)):
        for u in (0.0, 1 - 2**-53, 0.5):
            x = stratum_point(k, u, count)
            assert np.all(np.floor(x * count) == k)
            assert np.all(x < 1)


# -- stratification ---------------------------------------------------------------------
def test_regular_points_are_exact_centres():
    pts = sample("regular", 12, d=3, strata=(2, 3, 2), realizations=None)
    i = np.arange(12)
    digits = np.stack([i % 2, (i // 2) % 3, i // 6], axis=1)
    assert np.array_equal(pts, (digits + 0.5) / np.array([2.0, 3.0, 2.0]))
    pts = sample("regular", 64, d=2, realizations=None, seed=7)
    assert np.array_equal(pts, sample("regular", 64, d=2, realizations=None, seed=8))
    g = (np.arange(8) + 0.5) / 8
    assert np.array_equal(pts, np.stack(np.meshgrid(g, g), -1).reshape(-1, 2))


@pytest.mark.parametrize("d,n,strata", [(2, 64, None), (2, 15, (3, 5)), (3, 27, None),
                                        (3, 24, (2, 3, 4))])
def test_jittered_has_one_point_per_stratum(d, n, strata):
    params = {} if strata is None else {"strata": strata}
    pts = sample("jittered", n, d=d, **params)
    grid = strata or (round(n ** (1 / d)),) * d
    assert one_per_cell(pts, grid)
    # the offset inside each cell is uniform
    offsets = (pts * np.asarray(grid)) % 1.0
    assert stats.kstest(offsets.ravel(), "uniform").pvalue > 1e-4


@pytest.mark.parametrize("d", [1, 2, 3, 8])
def test_latin_hypercube_has_one_point_per_slab_in_every_dimension(d):
    n = 37
    pts = sample("latin_hypercube", n, d=d)
    for j in range(d):
        assert one_per_cell(pts[..., j:j + 1], (n,))
    # dimensions are combined at random: the slab pairs of two axes are not aligned
    if d >= 2:
        a, b = cells(pts[..., 0:1], (n,)), cells(pts[..., 1:2], (n,))
        assert np.mean(a == b) < 0.2


@pytest.mark.parametrize("n,params,grid", [(16, {}, (4, 4)), (12, {}, (3, 4)),
                                           (15, {"strata": (5, 3)}, (5, 3)), (13, {}, (1, 13)),
                                           (2048, {}, (32, 64))])
def test_multijittered_is_jittered_and_n_rooks_at_once(n, params, grid):
    pts = sample("multijittered", n, realizations=6, **params)
    assert one_per_cell(pts, grid)
    assert one_per_cell(pts[..., 0:1], (n,)) and one_per_cell(pts[..., 1:2], (n,))


@pytest.mark.parametrize("n,grid", [(16, (4, 4)), (12, (3, 4)), (30, (5, 6)), (1024, (32, 32))])
def test_correlated_multijittered_is_jittered_and_n_rooks_at_once(n, grid):
    pts = sample("correlated_multijittered", n)
    assert one_per_cell(pts, grid)
    assert one_per_cell(pts[..., 0:1], (n,)) and one_per_cell(pts[..., 1:2], (n,))


def test_correlated_multijittered_any_n():
    n = 10                      # m = 3 columns, 4 rows, 12 cells of which 10 are used
    pts = sample("correlated_multijittered", n)
    assert one_per_cell(pts[..., 1:2], (n,))
    x = cells(pts[..., 0:1], (12,))
    assert all(np.unique(row).size == n for row in x)
    c = cells(pts, (3, 4))
    assert all(np.unique(row).size == n for row in c)


def independence_pvalue(points, first, second):
    """Chi-square p-value of independence between the cells of two groups of dimensions.

    ``first`` and ``second`` are (dims, strata-per-dim); over all points of all
    realizations the pair (cell in group 1, cell in group 2) should be uniform on the
    product of the cells, given that each group alone is stratified.
    """
    (dims1, k1), (dims2, k2) = first, second
    c1 = cells(points[..., dims1], (k1,) * len(dims1)).ravel()
    c2 = cells(points[..., dims2], (k2,) * len(dims2)).ravel()
    size1, size2 = k1 ** len(dims1), k2 ** len(dims2)
    table = np.bincount(c1 * size2 + c2, minlength=size1 * size2)
    return stats.chisquare(table).pvalue


def test_uncorrelated_jitter_is_stratified_within_each_group():
    pts = sample("uncorrelated_jitter", 16, d=5)
    assert one_per_cell(pts[..., 0:2], (4, 4))
    assert one_per_cell(pts[..., 2:4], (4, 4))
    assert one_per_cell(pts[..., 4:5], (16,))
    pts = sample("uncorrelated_jitter", 64, d=5, groups=(3, 2))
    assert one_per_cell(pts[..., 0:3], (4, 4, 4))
    assert one_per_cell(pts[..., 3:5], (8, 8))


def test_uncorrelated_jitter_groups_are_decorrelated():
    n, r = 16, 300
    pts = sample("uncorrelated_jitter", n, d=5, realizations=r, seed=3)
    assert independence_pvalue(pts, ([0, 1], 4), ([2, 3], 4)) > 1e-4
    assert independence_pvalue(pts, ([0, 1], 4), ([4], 16)) > 1e-4
    assert independence_pvalue(pts, ([2, 3], 4), ([4], 16)) > 1e-4


def test_decorrelation_check_fails_for_a_correlated_combination():
    # The same statistic on a combination that is stratified within each group but
    # pairs the groups' cells in a fixed order (as jittering each group alone and
    # concatenating would) must reject independence; so must a shared permutation.
    n, r = 16, 300
    a = sample("jittered", n, d=2, realizations=r, seed=1)
    b = sample("jittered", n, d=2, realizations=r, seed=2)
    correlated = np.concatenate([a, b], axis=-1)
    assert independence_pvalue(correlated, ([0, 1], 4), ([2, 3], 4)) < 1e-12
    shuffle = np.random.default_rng(0).permutation(n)
    shared = np.concatenate([a[:, shuffle], b[:, shuffle]], axis=-1)
    assert independence_pvalue(shared, ([0, 1], 4), ([2, 3], 4)) < 1e-12


def test_uncorrelated_jitter_default_groups():
    assert clsamp.make_sampler("uncorrelated_jitter", d=5).groups == (2, 2, 1)
    assert clsamp.make_sampler("uncorrelated_jitter", d=1).groups == (1,)
    assert clsamp.make_sampler("uncorrelated_jitter", d=4).groups == (2, 2)


# -- errors -------------------------------------------------------------------------------
def test_jittered_names_the_nearest_valid_n():
    with pytest.raises(InvalidArgumentError, match=r"n=63.*nearest valid n is 64"):
        clsamp.make_sampler("jittered", d=2).sample(63)
    with pytest.raises(InvalidArgumentError, match=r"nearest valid n is 27"):
        clsamp.make_sampler("jittered", d=3).sample(30)
    with pytest.raises(InvalidArgumentError, match=r"nearest valid n is 12"):
        clsamp.make_sampler("jittered", d=2, strata=(3, 4)).sample(16)
    with pytest.raises(InvalidArgumentError, match=r"nearest valid n is 16"):
        clsamp.make_sampler("regular", d=2).sample(17)
    with pytest.raises(ValueError, match="strata"):
        clsamp.make_sampler("jittered", d=2, strata=(3, 4, 5))
    assert clsamp.make_sampler("jittered", d=2, strata=(3, 4)).sample().shape == (12, 2)


def test_multijittered_without_an_accepted_factorization_names_valid_n():
    with pytest.raises(InvalidArgumentError, match=r"n=13.*1 x 13.*nearest valid n is 12"):
        clsamp.make_sampler("multijittered", max_aspect=2).sample(13)
    with pytest.raises(InvalidArgumentError, match=r"nearest valid n is 15"):
        clsamp.make_sampler("multijittered", strata=(3, 5)).sample(16)
    with pytest.raises(InvalidArgumentError, match="max_aspect"):
        clsamp.make_sampler("multijittered", max_aspect=0.5)
    assert clsamp.make_sampler("multijittered", max_aspect=2).sample(12).shape == (12, 2)


@pytest.mark.parametrize("name", ["regular", "jittered", "uncorrelated_jitter", "latin_hypercube",
                                  "multijittered", "correlated_multijittered"])
def test_dimension_must_be_positive(name):
    with pytest.raises(InvalidArgumentError, match="'d'"):
        clsamp.make_sampler(name, d=0)


def test_two_dimensional_samplers_refuse_other_d():
    for name in ("multijittered", "correlated_multijittered"):
        with pytest.raises(InvalidArgumentError, match="'d'"):
            clsamp.make_sampler(name, d=3)


def test_groups_must_add_up_to_d():
    with pytest.raises(InvalidArgumentError, match=r"'groups' must add up to d=5"):
        clsamp.make_sampler("uncorrelated_jitter", d=5, groups=(2, 2))
    with pytest.raises(InvalidArgumentError, match="groups"):
        clsamp.make_sampler("uncorrelated_jitter", d=2, groups=(0, 2))
    with pytest.raises(InvalidArgumentError, match=r"n = k\^6.*nearest valid n is 64"):
        clsamp.make_sampler("uncorrelated_jitter", d=5, groups=(3, 2)).sample(60)
    with pytest.raises(InvalidArgumentError, match=r"nearest valid n is 16"):
        clsamp.make_sampler("uncorrelated_jitter", d=5).sample(15)


def test_alias_and_names():
    names = clsamp.sampler_names(aliases=True)
    for name in ("regular", "jittered", "uncorrelated_jitter", "latin_hypercube", "n_rooks",
                 "multijittered", "correlated_multijittered"):
        assert name in names
    assert type(clsamp.make_sampler("n_rooks")) is type(clsamp.make_sampler("latin_hypercube"))


def test_strata_and_groups_as_command_line_text():
    a = clsamp.make_sampler("jittered", d=2, seed=1, strata="3x4").sample()
    b = clsamp.make_sampler("jittered", d=2, seed=1, strata=(3, 4)).sample()
    assert np.array_equal(a, b)
    assert clsamp.make_sampler("uncorrelated_jitter", d=3, groups="1,2").groups == (1, 2)
    with pytest.raises(InvalidArgumentError, match="strata"):
        clsamp.make_sampler("jittered", d=2, strata="3xfour")


@pytest.mark.parametrize("name,d", [("jittered", 2), ("uncorrelated_jitter", 3), ("latin_hypercube", 3),
                                    ("multijittered", 2), ("correlated_multijittered", 2)])
def test_a_chunk_of_realizations_equals_the_same_rows_of_the_whole(name, d):
    # A range of realizations that does not start at 0 gives the same rows, on the device
    # and in the reference, with the jitter offset by start.
    s = clsamp.make_sampler(name, d=d, seed=21)
    whole = s.sample(16, realizations=5, start=2)
    assert np.array_equal(s.sample_device(16, range(3, 5), 2).get(), whole[3:5])
    ref = clsamp.make_sampler(name, d=d, seed=21, backend="numpy")
    assert np.array_equal(ref.sample(16, range(3, 5), 2), whole[3:5])


def test_latin_hypercube_pairs_slabs_uniformly():
    # Over many realizations the pair (x-slab, y-slab) of point 0 is uniform on n x n:
    # the dimensions' permutations are independent.
    n = 5
    pts = sample("latin_hypercube", n, realizations=2000, seed=4)
    pair = cells(pts[:, 0, 0:1], (n,)) * n + cells(pts[:, 0, 1:2], (n,))
    assert stats.chisquare(np.bincount(pair, minlength=n * n)).pvalue > 1e-4
