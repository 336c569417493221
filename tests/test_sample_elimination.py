"""Weighted sample elimination (``sample_elimination``): the neighbour kernel equals its
NumPy twin bit for bit and a brute-force search over all pairs; the heap removes what a
from-scratch elimination removes; the output is n of the candidates, reproducibly;
quality at n = 1024 in 2-D against Poisson disk and random points measured in the same
test; progressive prefixes are eliminated sets with a good radius; 3-D, 4-D and the cube
run and spread. The contract matrix (test_sampler_contract.py) covers shapes, seeds,
realizations, chunks and both backends' bits."""

import dataclasses

import numpy as np
import pytest
from test_gbn import low_frequency_power

import clsamp
from clsamp import runtime
from clsamp.errors import InvalidArgumentError
from clsamp.geometry.cells import sorted_by_cell
from clsamp.geometry.torus import distance2
from clsamp.metrics import max_min_distance, nearest_neighbor_distances, relative_radius
from clsamp.samplers.sample_elimination import (
    Weighting,
    eliminate,
    eliminate_device,
    neighbour_weights_device,
    neighbour_weights_reference,
    slab_width,
)


def _candidates(sets, m, d, seed=3):
    return clsamp.make_sampler("random", d=d, seed=seed).sample(m, realizations=sets)


def _lanes(lanes):
    """The device's launch shape with its neighbour passes taking ``lanes`` points at once
    (16 on CPUs, in vector lanes; 1 on GPUs)."""
    return runtime.forced_shape(dataclasses.replace(runtime.shape(), pair_lanes=lanes))


@pytest.mark.parametrize("lanes", [1, 16])
@pytest.mark.parametrize("d, periodic", [(1, True), (2, True), (2, False), (3, True), (4, False),
                                         (8, True)])
def test_the_kernel_gives_the_twins_bits(d, periodic, lanes):
    # both passes (the counts, then the lists at their offsets), one point at a time or 16
    # in vector lanes: on 3^d cells whose rows wrap, cells skipped from 3-D on, and on one
    # cell (4-D, 8-D); with points on a cell's edges and on top of each other
    m, n = 600, 120
    weighting = Weighting.for_counts(m, n, d, periodic=periodic)
    cells = weighting.cells(m, d)
    cand = _candidates(3, m, d)
    cand[0, 0] = 0.0
    cand[0, 1, 0], cand[0, 1, -1] = 1.0 - 2.0**-53, 0.5
    cand[0, 2, 0] = 1.0 / cells if cells > 1 else 0.25
    cand[1, 5] = cand[1, 6]
    pts, _, start, _ = sorted_by_cell(cand, cells)
    ref = neighbour_weights_reference(pts, start, m, cells, weighting)
    with _lanes(lanes):
        dev = neighbour_weights_device(pts, start, m, cells, weighting)
    for a, b in zip(ref, dev, strict=True):
        assert a.dtype == b.dtype and np.array_equal(a, b)
    assert ref[0][-1] > m        # pairs were found


@pytest.mark.parametrize("d, periodic", [(2, True), (2, False), (3, True), (4, True)])
def test_the_grid_finds_every_pair_within_d_max_with_the_papers_weight(d, periodic):
    m, n = 800, 160
    weighting = Weighting.for_counts(m, n, d, periodic=periodic)
    cells = weighting.cells(m, d)
    assert d == 4 or cells >= 3      # the grid is in use, not one cell holding every pair
    pts, _, start, _ = sorted_by_cell(_candidates(1, m, d, seed=5), cells)
    offset, nbr, w, weight = neighbour_weights_reference(pts, start, m, cells, weighting)
    r2 = distance2(pts[:, None, :], pts[None, :, :], periodic=periodic)
    np.fill_diagonal(r2, np.inf)
    dist = np.sqrt(r2)
    expect = np.where(dist < weighting.d_max,
                      (1 - np.maximum(dist, weighting.d_min) / weighting.d_max) ** 8, 0.0)
    found = np.zeros((m, m))
    rows = np.repeat(np.arange(m), np.diff(offset))
    found[rows, nbr] = w
    assert np.array_equal(found > 0, expect > 0)
    assert np.allclose(found, expect, rtol=1e-13, atol=0)
    assert np.array_equal(found, found.T)               # w_ij == w_ji, to the bit
    assert np.allclose(weight, expect.sum(axis=1), rtol=1e-12, atol=0)


def _eliminate_from_scratch(adjacency, keep):
    """Remove the candidate of the largest weight (lowest index on ties), recomputing every
    weight from the remaining candidates each time."""
    alive = np.ones(len(adjacency), dtype=bool)
    order = []
    while alive.sum() > keep:
        weight = np.where(alive, adjacency[:, alive].sum(axis=1), -np.inf)
        i = int(np.argmax(weight))
        alive[i] = False
        order.append(i)
    return np.flatnonzero(alive), order


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_heap_removes_what_a_from_scratch_elimination_removes(seed):
    # dyadic weights keep every sum exact, so both orders of adding agree to the bit
    rng = np.random.default_rng(seed)
    m = 60
    adjacency = np.triu(rng.integers(0, 64, (m, m)) * (rng.random((m, m)) < 0.15), 1) / 64.0
    adjacency = adjacency + adjacency.T
    offset = np.concatenate(([0], np.cumsum((adjacency > 0).sum(axis=1))))
    nbr = np.concatenate([np.flatnonzero(row) for row in adjacency])
    w = np.concatenate([row[row > 0] for row in adjacency])
    survivors, gone, last = eliminate(adjacency.sum(axis=1), offset, nbr, w, 20)
    expect, order = _eliminate_from_scratch(adjacency, 20)
    assert survivors.tolist() == expect.tolist() and gone.tolist() == order
    assert last == adjacency[np.ix_(expect, expect)].sum(axis=1).max()


def _grid_candidates(sets, side, d):
    # every candidate has the same neighbours at the same distances: the weights tie
    axes = np.meshgrid(*[(np.arange(side) + 0.5) / side] * d, indexing="ij")
    grid = np.stack([a.ravel() for a in axes], axis=1)
    return np.broadcast_to(grid, (sets, *grid.shape)).copy()


@pytest.mark.parametrize("d, periodic, grid, slab", [
    (1, True, False, None), (2, True, False, None), (2, False, False, None),
    (3, True, False, None), (2, True, True, None), (2, False, True, None),
    (3, True, True, None),
    (2, True, False, 3),        # every list overflows its slots: the two-pass lists
    (3, False, False, 10**6),   # slots for every candidate
    (4, True, False, None), (4, True, True, None), (6, False, False, None)])  # stale keys
@pytest.mark.parametrize("lanes", [1, 16])
def test_the_elimination_kernel_removes_what_the_heap_removes(d, periodic, grid, slab, lanes,
                                                              monkeypatch):
    from clsamp.samplers import sample_elimination
    if slab is not None:
        monkeypatch.setattr(sample_elimination, "slab_width", lambda m, d, w: min(slab, m - 1))
    sets = 3
    side = 16 if d < 3 else 7 if d == 3 else 5
    cand = _grid_candidates(sets, side, d) if grid else _candidates(sets, 500, d)
    m = cand.shape[1]
    keep = m // 4
    weighting = Weighting.for_counts(m, keep, d, periodic=periodic)
    cells = weighting.cells(m, d)
    pts, _, start, _ = sorted_by_cell(cand, cells)
    with _lanes(lanes):
        gone, weight = eliminate_device(pts, start, m, cells, weighting, keep)
    offset, nbr, w, first = neighbour_weights_reference(pts, start, m, cells, weighting)
    assert gone.shape == (sets, m - keep) and weight.shape == (sets, m)
    for s in range(sets):
        lo, hi = s * m, (s + 1) * m
        a, b = offset[lo], offset[hi]
        survivors, order, last = eliminate(first[lo:hi], offset[lo:hi + 1] - a,
                                           nbr[a:b].astype(np.int64) - lo, w[a:b], keep)
        assert gone[s].tolist() == order.tolist()
        assert weight[s, survivors].max(initial=0.0) == last
    if grid:       # the ties were there, and went to the lower index
        assert np.unique(first[:m]).size < m // 4


def test_the_slots_hold_uniform_candidates_lists():
    # one pass writes each candidate's neighbours into slab_width slots; for uniform
    # candidates no list should need more (else the two passes run: right, but slower)
    for d, n in [(1, 512), (2, 1024), (3, 512), (4, 256), (8, 64)]:
        m = 5 * n
        weighting = Weighting.for_counts(m, n, d)
        cells = weighting.cells(m, d)
        pts, _, start, _ = sorted_by_cell(_candidates(4, m, d, seed=d), cells)
        offset = neighbour_weights_reference(pts, start, m, cells, weighting)[0]
        most = int(np.diff(offset).max())
        assert most <= slab_width(m, d, weighting) < 4 * np.diff(offset).mean() + 16, (d, most)


def test_a_discrete_gpu_runs_the_heap_on_the_host_with_the_same_bits(monkeypatch):
    import dataclasses

    from clsamp import runtime
    device = runtime.current_device()
    s = clsamp.make_sampler("sample_elimination", d=2, seed=4, progressive=True)
    here = s.sample(200, realizations=2)
    monkeypatch.setattr(runtime, "current_device",
                        lambda: dataclasses.replace(device, host_memory=False))
    from clsamp.samplers import sample_elimination
    monkeypatch.setattr(sample_elimination, "eliminate_device", None)     # not called
    assert np.array_equal(s.sample(200, realizations=2), here)


def test_n_of_the_candidates_reproducibly():
    n = 300
    s = clsamp.make_sampler("sample_elimination", d=2, seed=11, ratio=4)
    pts, info = s.sample(n, realizations=2, return_info=True)
    cand = clsamp.make_sampler("random", d=2, seed=11).sample(s.candidates(n), realizations=2)
    assert pts.shape == (2, n, 2) and info.candidates == 4 * n == s.candidates(n)
    for p, c in zip(pts, cand, strict=True):
        rows = {tuple(x) for x in c}
        assert len({tuple(x) for x in p}) == n and all(tuple(x) in rows for x in p)
    assert np.array_equal(pts, s.sample(n, realizations=2))
    twin = clsamp.make_sampler("sample_elimination", d=2, seed=11, ratio=4, backend="numpy")
    assert np.array_equal(pts, twin.sample(n, realizations=2))
    assert info.d_max == max_min_distance(n, 2)
    assert info.d_min == pytest.approx(info.d_max * (1 - 0.25 ** 1.5) * 0.65, rel=1e-15)


def test_quality_in_2d_against_poisson_disk_and_random():
    # n = 1024, three seeds, each figure measured here. Sample elimination's spectrum is
    # Poisson disk's kind: its low-frequency power is of the order of dart throwing's at
    # rho = 0.75 (measured 1.3x: not the half the issue hoped for; the author's
    # cySampleElim keeps the same points), far below white noise's 1
    n, seeds = 1024, 3
    disk = clsamp.make_sampler("poisson_disk", seed=1).sample(n, realizations=seeds)
    disk_power = low_frequency_power(disk)
    assert 0.03 < disk_power < 0.15
    pts = clsamp.make_sampler("sample_elimination", seed=1).sample(n, realizations=seeds)
    white = clsamp.make_sampler("random", seed=1).sample(n, realizations=seeds)
    rho = relative_radius(pts)
    assert np.all(rho > 0.65) and rho.min() > 5 * relative_radius(white).max(), rho
    power = low_frequency_power(pts)
    assert power < 1.6 * disk_power and power < 0.2 * low_frequency_power(white)
    more = clsamp.make_sampler("sample_elimination", seed=1, ratio=20).sample(n, realizations=seeds)
    assert relative_radius(more).min() > rho.max()       # more candidates, a larger radius


def test_progressive_prefixes_are_eliminated_sets():
    n, d = 1000, 2
    s = clsamp.make_sampler("sample_elimination", d=d, seed=2, progressive=True)
    pts, info = s.sample(n, realizations=2, return_info=True)
    plain = clsamp.make_sampler("sample_elimination", d=d, seed=2).sample(n, realizations=2)
    assert info.stages == 1 + 9      # 1000 -> 500 -> ... -> 3 -> 1
    for p, q in zip(pts, plain, strict=True):
        assert {tuple(x) for x in p} == {tuple(x) for x in q}
        # the first n // 2 are the survivors of eliminating the n with d_max for n // 2
        weighting = Weighting.for_counts(5 * n, n, d)
        half = Weighting(max_min_distance(n // 2, d), weighting.d_min, 8, True)
        cells = half.cells(n, d)
        sp, _, start, order = sorted_by_cell(q[None], cells)
        offset, nbr, w, weight = neighbour_weights_reference(sp, start, n, cells, half)
        survivors = eliminate(weight, offset, nbr, w, n // 2)[0]
        assert {tuple(x) for x in p[: n // 2]} == {tuple(x) for x in q[order[survivors]]}
    for k in (1, 2, 3, 4):
        rho = relative_radius(pts[:, : n >> k])
        assert np.all(rho > 0.55), (k, rho)


@pytest.mark.parametrize("d", [3, 4])
def test_3d_and_4d_sets_spread_far_better_than_random(d):
    n = 1024
    pts = clsamp.make_sampler("sample_elimination", d=d, seed=5).sample(n)
    white = clsamp.make_sampler("random", d=d, seed=5).sample(n)
    dmax = max_min_distance(n, d)
    mean = nearest_neighbor_distances(pts).mean() / dmax
    assert mean > 1.4 * nearest_neighbor_distances(white).mean() / dmax
    assert relative_radius(pts) > 0.5 > 3 * relative_radius(white)


def test_the_cube_variant_spreads_without_wrapping():
    n = 1024
    pts = clsamp.make_sampler("sample_elimination", seed=4, periodic=False).sample(n)
    white = clsamp.make_sampler("random", seed=4).sample(n)
    near = nearest_neighbor_distances(pts, periodic=False)
    assert near.min() > 3 * nearest_neighbor_distances(white, periodic=False).min()
    assert near.min() > 0.6 * max_min_distance(n, 2)


@pytest.mark.parametrize("params, name", [({"ratio": 1}, "ratio"), ({"ratio": "5"}, "ratio"),
                                          ({"alpha": 0}, "alpha"), ({"beta": 2}, "beta"),
                                          ({"gamma": 0}, "gamma"), ({"periodic": 1}, "periodic"),
                                          ({"progressive": "yes"}, "progressive"), ({"d": 9}, "d")])
def test_bad_parameters_are_refused_by_name(params, name):
    with pytest.raises(InvalidArgumentError, match=f"'{name}'"):
        clsamp.make_sampler("sample_elimination", **params)



def test_realizations_split_across_launches_give_the_same_sets(monkeypatch):
    from clsamp.runtime import memory
    from clsamp.samplers import sample_elimination
    s = clsamp.make_sampler("sample_elimination", d=3, seed=8, progressive=True)
    whole = s.sample(100, realizations=3)
    launches = []

    def spy(pts, *args):
        launches.append(len(pts))
        return eliminate_device(pts, *args)
    # room for the 3 sets of output (the base's chunk) but for one realization's pair lists
    monkeypatch.setattr(memory, "work_budget", lambda: 3 * 100 * 3 * 8 + 1)
    monkeypatch.setattr(sample_elimination, "eliminate_device", spy)
    assert np.array_equal(s.sample(100, realizations=3), whole)
    assert launches[:3] == [500] * 3           # the candidates, one realization a launch
