"""Requests sized before any work: outputs that cannot fit are refused at once with the
bytes needed and available; sets larger than one device buffer stream in pieces; a
legal but weaker request warns."""

import dataclasses
import time
import warnings

import numpy as np
import pytest

import clsamp
from clsamp import runtime
from clsamp.errors import InvalidArgumentError


@pytest.mark.parametrize("name,d,n,r", [("random", 2, 2**31, None), ("random", 2, 10, 2**30),
                                        ("jittered", 2, 2**26, 64), ("sobol:owen", 16, 2**30, 4)])
def test_huge_outputs_are_refused_at_once(name, d, n, r):
    sampler = clsamp.make_sampler(name, d=d)
    t0 = time.perf_counter()
    with pytest.raises(InvalidArgumentError, match=r"needs .* GiB.* available"):
        sampler.sample(n, realizations=r)
    assert time.perf_counter() - t0 < 1.0


@pytest.fixture
def small_device(monkeypatch):
    """The current device as if its largest buffer were 64 KiB (global memory 1 MiB)."""
    record = dataclasses.replace(runtime.current_device(), max_allocation=2**16, global_memory=2**20)
    monkeypatch.setattr(runtime.discovery, "current_device", lambda: record)
    return record


def test_sets_larger_than_a_buffer_stream_in_pieces(small_device):
    for name in ("random", "sobol:owen", "halton"):
        sampler = clsamp.make_sampler(name, d=3, seed=4)
        assert len(sampler._pieces(16384)) > 1
        streamed = sampler.sample(16384, realizations=2)
        reference = clsamp.make_sampler(name, d=3, seed=4, backend="numpy").sample(16384, realizations=2)
        assert np.array_equal(streamed, reference), name


def test_sets_that_cannot_stream_are_refused_clearly(small_device):
    with pytest.raises(InvalidArgumentError, match="one set of 16384 points .* one device buffer"):
        clsamp.make_sampler("jittered", d=2).sample(16384)
    with pytest.raises(InvalidArgumentError, match="device memory"):
        clsamp.make_sampler("random", d=2).sample_device(4096, realizations=64)
    with pytest.raises(InvalidArgumentError, match="one device buffer"):
        clsamp.make_sampler("random", d=2).sample_device(8192)
    # the NumPy reference has no device buffer to outgrow
    assert clsamp.make_sampler("jittered", d=2, backend="numpy").sample(16384).shape == (16384, 2)


def test_sobol_warns_where_the_prefix_is_not_a_net():
    sobol = clsamp.make_sampler("sobol:owen", d=2, seed=1)
    with pytest.warns(UserWarning, match="power of two"):
        sobol.sample(100)
    with pytest.warns(UserWarning, match="power of two"):
        sobol.sample_device(64, start=1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sobol.sample(256)
        sobol.sample(256, start=256)
        clsamp.make_sampler("halton", d=2).sample(100)


@pytest.mark.parametrize("call", [
    lambda: clsamp.power_spectrum(np.full((8, 2), 0.5), resolution=2**20, progress=False),
    lambda: clsamp.expected_spectrum("random", 16, 4, resolution=2**18, progress=False),
    lambda: clsamp.convergence("random", "disk", [16], realizations=2**32 - 1, progress=False),
    lambda: clsamp.convergence("random", "random_boxes", [16], realizations=2**20, members=2**16,
                               progress=False),
])
def test_huge_analyses_are_refused_at_once(call):
    t0 = time.perf_counter()
    with pytest.raises(InvalidArgumentError, match=r"needs .* GiB; this machine has"):
        call()
    # refused before any work: the work itself would take hours, so a loose bound tells
    # the two apart on a loaded machine (tests do not time what they check)
    assert time.perf_counter() - t0 < 60.0


@pytest.mark.parametrize("name, params, n, share", [
    ("gbn", {}, 2**21, 95 * 2),
    ("sot", {"d": 4}, 2**20, 1270 + 27 * 4),
    ("sample_elimination", {}, 2**18, (80 + 310 * 2) * 5),
    ("bnot", {"points_per_site": 64}, 2**18, 151 * 64),
    ("bnot", {"cells": "exact"}, 2**18, 3325),
])
def test_optimizers_count_their_working_memory_before_the_work(monkeypatch, name, params, n, share):
    # the optimizers' working memory (bytes a point, measured: docs/performance.md) is
    # counted with the output; a machine with a little more room than the output alone
    # refuses the call in one line
    from clsamp.runtime import memory
    sampler = clsamp.make_sampler(name, **params)
    output = n * sampler.d * 8
    assert sampler._work_bytes(n) == share * n
    monkeypatch.setattr(memory, "host_memory_available", lambda: output + 2**20)
    with pytest.raises(InvalidArgumentError, match="its output.* and one set's working memory"):
        sampler.sample(n)


@pytest.mark.parametrize("name", ["gbn", "sot", "bnot", "lloyd", "ccvt"])
def test_optimizers_cap_their_iterations_and_count_each_sets_history(name):
    # each set keeps its history, 8 bytes an iteration: 2 * 10^9 iterations were taken and
    # failed in the device's allocator; 10^6 iterations of 10^6 sets are refused up front
    with pytest.raises(InvalidArgumentError, match=r"'iterations' must be an integer <= 1000000"):
        clsamp.make_sampler(name, iterations=2_000_000_000)
    sampler = clsamp.make_sampler(name, iterations=10**6)
    assert sampler._history_bytes() == 8 * 10**6
    with pytest.raises(InvalidArgumentError, match="each set's history"):
        sampler.sample(64, realizations=10**6)


def test_bnot_refuses_more_density_points_than_it_can_count():
    with pytest.raises(InvalidArgumentError, match=r"'points_per_site' \* n must stay below 2\^32"):
        clsamp.make_sampler("bnot", points_per_site=4096).sample(2**20)
