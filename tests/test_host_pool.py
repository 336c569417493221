"""Host output memory that is recycled (host_memory.host_empty): a sampler's output is
written in place (zero-copy on a CPU device) into memory an earlier output freed, never into
memory an array or view still uses, and gives the same bits as the copied and the NumPy
paths."""

import gc

import numpy as np
import pytest

import clsamp
from clsamp import host_memory

N = 2**18                       # 4 MiB of 2-D points (512², for jittered): above HOST_POOL_MIN


@pytest.fixture(autouse=True)
def empty_pool():
    host_memory.release_host_memory()
    yield
    host_memory.release_host_memory()


def address(a):
    return a.__array_interface__["data"][0]


@pytest.mark.parametrize("name, params", [("random", {}), ("halton", {"randomize": "shift"}),
                                          ("sobol", {"randomize": "owen"}), ("jittered", {})])
def test_recycled_output_equals_a_fresh_and_a_copied_one(name, params, monkeypatch):
    s = clsamp.make_sampler(name, d=2, seed=5, **params)
    first = s.sample(N, realizations=2)
    where, kept = address(first), first.copy()
    first[:] = -1.0                                          # what the memory held before
    del first
    gc.collect()
    again = s.sample(N, realizations=2)
    assert address(again) == where                           # the same memory, reused ...
    assert np.array_equal(again, kept)                       # ... and wholly rewritten
    monkeypatch.setattr(host_memory, "HOST_POOL_BYTES", 0)       # no pool: np.empty
    assert np.array_equal(s.sample(N, realizations=2), kept)
    reference = clsamp.make_sampler(name, d=2, seed=5, backend="numpy", **params)
    assert np.array_equal(reference.sample(N, realizations=2), kept)


def test_memory_a_view_still_uses_is_never_handed_out():
    s = clsamp.make_sampler("random", d=2, seed=1)
    a = s.sample(N)
    view = a[::3]                  # keeps a's memory alive after a is gone
    column = a[:, 1]
    expected = view.copy(), column.copy()
    where = address(a)
    del a
    gc.collect()
    others = [s.sample(N) for _ in range(3)]
    assert all(address(b) != where for b in others)
    assert np.array_equal(view, expected[0]) and np.array_equal(column, expected[1])
    freed = {where} | {address(b) for b in others}
    del view, column, others
    gc.collect()
    assert host_memory._host_pool.held == 4 * N * 2 * 8          # all four blocks came back
    assert address(s.sample(N)) in freed


def test_the_pool_holds_at_most_its_cap(monkeypatch):
    monkeypatch.setattr(host_memory, "HOST_POOL_BYTES", 5 * 2**20)
    arrays = [host_memory.host_empty((2**20 // 8,)) for _ in range(8)]     # 1 MiB each
    del arrays
    gc.collect()
    assert host_memory._host_pool.held <= 5 * 2**20
    assert host_memory._host_pool.held == 5 * 2**20


def test_small_and_huge_outputs_are_plain_numpy_arrays(monkeypatch):
    small = host_memory.host_empty((100, 2))
    assert small.base is None and small.flags.owndata
    monkeypatch.setattr(host_memory, "HOST_POOL_BYTES", 2**21)
    huge = host_memory.host_empty((2**19,))                      # 4 MiB > the cap
    assert huge.base is None
    pooled = host_memory.host_empty((2**17,))                    # 1 MiB
    assert pooled.base is not None and pooled.flags.c_contiguous and pooled.flags.writeable
    assert pooled.dtype == np.float64 and pooled.shape == (2**17,)


def test_outputs_survive_pickling_and_threads():
    import pickle
    import threading

    s = clsamp.make_sampler("random", d=2, seed=3)
    a = s.sample(N)
    assert np.array_equal(pickle.loads(pickle.dumps(a)), a)
    results = {}

    def work(k):
        results[k] = clsamp.make_sampler("random", d=2, seed=k).sample(N)

    threads = [threading.Thread(target=work, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    addresses = {address(v) for v in results.values()}
    assert len(addresses) == 4                               # four live outputs, four blocks
    for k, v in results.items():
        assert np.array_equal(v, clsamp.make_sampler("random", d=2, seed=k, backend="numpy").sample(N))
