"""``bnot`` with ``cells="exact"``: the clipping kernel gives its NumPy twin's bits; the
cells are the exact power cells (areas against a fine raster and the squares of a grid,
the Hessian against finite differences, a widened stencil against every site); Newton
meets the capacities; the sampler's device and twin give the same sets, the cost never
rises beyond the capacities' tolerance (the issue's quality at n = 1024: test_bnot.py)."""

import numpy as np
import pytest

import clsamp
from clsamp.errors import InvalidArgumentError
from clsamp.samplers import bnot_cells as bc


def _random(n, spread, seed=1):
    rng = np.random.default_rng(seed)
    return rng.random((n, 2)), rng.normal(0.0, spread / n, n)


def _same(a, b):
    return all(np.array_equal(x, y) for x, y in zip(a[:3], b[:3], strict=True)) and (a[3] != b[3]).nnz == 0


@pytest.mark.parametrize("n, spread", [(1, 0.0), (2, 0.3), (7, 0.3), (40, 0.2), (300, 0.2),
                                       (1000, 0.5)])
def test_the_kernel_gives_the_twins_bits(n, spread):
    sites, w = _random(n, spread)
    a = bc.PowerCells(sites, "opencl")(w)
    b = bc.PowerCells(sites, "numpy")(w)
    assert _same(a, b)
    assert abs(a[0].sum() - 1.0) < 1e-12


def test_a_grid_gives_squares():
    # every vertex on four cells' bisectors: the ties of the clipping, in both backends
    k = 12
    g = (np.arange(k) + 0.5) / k
    sites = np.stack(np.meshgrid(g, g), axis=-1).reshape(-1, 2)
    a = bc.PowerCells(sites, "opencl")(np.zeros(k * k))
    assert _same(a, bc.PowerCells(sites, "numpy")(np.zeros(k * k)))
    area, centroid, moment, L = a
    assert np.allclose(area, 1.0 / k**2, rtol=1e-12)
    assert np.abs(centroid).max() < 1e-15
    assert np.allclose(moment, (1.0 / k) ** 4 / 6.0, rtol=1e-12)
    # four neighbours across edges of length 1/k at distance 1/k: 1/2 each
    dense = -L.toarray()
    np.fill_diagonal(dense, 0.0)
    assert np.allclose(np.sort(dense, axis=1)[:, -4:], 0.5)
    # (the diagonal neighbours meet a cell at a corner: edges of rounding length at most)
    assert np.count_nonzero(dense > 1e-12) == 4 * k * k


def test_the_areas_match_a_raster():
    n, side = 60, 600
    sites, w = _random(n, 0.3, seed=2)
    area, centroid, _, _ = bc.PowerCells(sites, "opencl")(w)
    c = (np.arange(side) + 0.5) / side
    y = np.stack(np.meshgrid(c, c), axis=-1).reshape(-1, 2)
    d = y[:, None, :] - sites[None]
    d -= np.round(d)
    own = np.argmin((d**2).sum(-1) - w[None], axis=1)
    raster = np.bincount(own, minlength=n) / side**2
    # a pixel counts wrong only where a boundary crosses it: perimeter / side of area
    assert np.abs(raster - area).max() < 4.0 / np.sqrt(n) / side
    big = np.flatnonzero(raster * side**2 >= 200)      # (a few cells are empty)
    assert big.size > n // 2
    offset = np.array([np.mean(d[own == i, i], axis=0) for i in big])
    assert np.abs(offset - centroid[big]).max() < 2e-3


def test_the_hessian_is_the_areas_derivative():
    n = 80
    sites, w = _random(n, 0.2, seed=4)
    cells = bc.PowerCells(sites, "numpy")
    L = cells(w)[3].toarray()
    assert np.abs(L - L.T).max() < 1e-12
    eps = 1e-7 / n
    for j in range(0, n, 9):
        up, down = w.copy(), w.copy()
        up[j] += eps
        down[j] -= eps
        numeric = (cells(up)[0] - cells(down)[0]) / (2 * eps)
        assert np.abs(numeric - L[:, j]).max() < 1e-5 * np.abs(L[:, j]).max()


def test_a_wider_stencil_where_a_cell_is_not_certified():
    # one heavy site: its cell reaches past the first ring, the host widens the stencil
    n = 400
    sites, w = _random(n, 0.1, seed=5)
    w[7] = 4.0 / n
    cells = bc.PowerCells(sites, "opencl")
    area = cells(w)[0]
    assert cells.R > 1
    everything = bc.power_cells_reference(sites, w, np.array([0, n], dtype=np.uint32), 1, 2,
                                          2.0, float(w.max()))
    assert np.all(everything[3] == 0)
    assert np.allclose(area, everything[0][:, 0], rtol=0, atol=1e-15)


@pytest.mark.parametrize("pattern", ["heavy far away", "light far away", "one heavy", "spread"])
def test_certified_cells_are_the_cells_of_every_site(pattern):
    # a cell is certified by the largest weight in the next ring of grid cells and the
    # largest of all beyond it: weights that differ by region test both bounds, and the
    # cells clipped again (a wider stencil for the uncertified ones only) the retries
    n = 400
    sites, w = _random(n, 0.05, seed=8)
    far = np.hypot(*(((sites - 0.25 + 0.5) % 1.0) - 0.5).T) < 0.15     # a disc around (1/4, 1/4)
    if pattern == "heavy far away":
        w[far] += 3.0 / n
    elif pattern == "light far away":
        w[~far] += 3.0 / n
    elif pattern == "one heavy":
        w[11] = 2.0 / n
    else:
        w = np.random.default_rng(9).normal(0.0, 1.5 / n, n)
    device, twin = bc.PowerCells(sites, "opencl"), bc.PowerCells(sites, "numpy")
    a = device(w)
    assert _same(a, twin(w))
    everything = bc.power_cells_reference(sites, w, np.array([0, n], dtype=np.uint32), 1, 3,
                                          3.0, float(w.max()))
    assert np.all(everything[3] == 0)
    assert np.allclose(a[0], everything[0][:, 0], rtol=0, atol=1e-15)
    assert np.allclose(a[2], everything[0][:, 3], rtol=0, atol=1e-15)


@pytest.mark.parametrize("n", [50, 700])
def test_newton_meets_the_capacities(n):
    sites, _ = _random(n, 0.0, seed=6)
    w, state, steps = bc.solve_exact_weights(bc.PowerCells(sites, "opencl"), np.zeros(n),
                                             bc.LaplacianSolver())
    assert 0 < steps <= bc.NEWTON
    assert np.abs(state[0] * n - 1.0).max() <= bc.CAPACITY_TOL


@pytest.mark.parametrize("n", [3, 90])
def test_the_device_gives_the_twins_sets(n):
    kw = dict(seed=5, iterations=5, cells="exact", progress=False)
    a, ia = clsamp.make_sampler("bnot", **kw).sample(n, realizations=2, return_info=True)
    b, ib = clsamp.make_sampler("bnot", backend="numpy", **kw).sample(
        n, realizations=2, return_info=True)
    assert np.array_equal(a, b)
    for field in ("energy_history", "dual_history", "newton_steps", "capacities",
                  "iterations", "converged"):
        assert np.array_equal(getattr(ia, field), getattr(ib, field)), field
    assert np.all((a >= 0) & (a < 1))


def test_the_cost_does_not_rise():
    _, info = clsamp.make_sampler("bnot", seed=4, cells="exact", tol=0, iterations=30,
                                  progress=False).sample(256, realizations=2, return_info=True)
    h = info.energy_history
    # the cells are exact to CAPACITY_TOL of their area: the cost may move by as much
    assert np.all(np.diff(h, axis=1) <= 2 * bc.CAPACITY_TOL * h[:, 1:])
    assert np.all(h[:, -1] < 0.9 * h[:, 0])
    assert np.abs(info.capacities - 1.0).max() <= bc.CAPACITY_TOL


@pytest.mark.parametrize("kw, name", [({"cells": "polygons"}, "cells"),
                                      ({"cells": "exact", "density": "random"}, "density")])
def test_bad_arguments_name_themselves(kw, name):
    with pytest.raises(InvalidArgumentError, match=f"'{name}'"):
        clsamp.make_sampler("bnot", **kw)
