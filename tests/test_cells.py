"""clsamp/geometry/cells.py: the stable order of integer keys by radix passes is NumPy's
stable argsort on every range of keys (one 16-bit pass, two, or the comparison sort past
2^32), with ties in index order; sorted_by_cell's starts count each cell."""

import numpy as np
import pytest

from clsamp.geometry.cells import sorted_by_cell, stable_order

rng = np.random.default_rng(20261206)


@pytest.mark.parametrize("bound", [1, 7, 2**16, 2**16 + 1, 3 * 2**20, 2**32, 2**33 + 5])
@pytest.mark.parametrize("size", [0, 1, 1000, 70000])
def test_the_stable_order_is_numpys(bound, size):
    # few distinct keys (many ties) and keys across the whole range, the largest included
    for key in (rng.integers(0, min(bound, 5), size), rng.integers(0, bound, size)):
        if size:
            key[-1] = bound - 1
        got = stable_order(key, bound)
        assert got.dtype == np.int64
        assert np.array_equal(got, np.argsort(key, kind="stable"))


def test_sorted_by_cell_starts_count_each_cell():
    batch = rng.random((3, 500, 2))
    pts, cell, start, order = sorted_by_cell(batch, 7)
    assert np.array_equal(pts, batch.reshape(-1, 2)[order])
    key = np.arange(3).repeat(500) * 49 + (np.minimum((batch * 7).astype(int), 6)
                                            @ np.array([7, 1])).ravel()
    assert np.array_equal(np.diff(start.astype(np.int64)), np.bincount(key, minlength=147))
    assert np.array_equal(order, np.argsort(key, kind="stable"))
