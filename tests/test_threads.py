"""Four threads at once give the same bits as one after the other: samplers, spectra,
convergence sweeps and renders share the device, never a kernel's arguments."""

import threading

import numpy as np
import pytest

import clsamp
from clsamp import render


def _jobs():
    jobs = {}
    for k, name in enumerate(("random", "jittered", "sobol:owen", "halton:owen", "latin_hypercube",
                              "poisson_disk", "lloyd", "ccvt")):
        params = {"iterations": 5} if name == "lloyd" else {}
        if name == "ccvt":
            params = {"points_per_site": 16}
        sampler = clsamp.make_sampler(name, seed=k + 1, **params)
        jobs[f"sample {name}"] = (lambda s=sampler: s.sample(64, realizations=3))
    pts = clsamp.make_sampler("jittered", seed=9).sample(256, realizations=4)
    jobs["spectrum direct"] = lambda: clsamp.power_spectrum(pts, resolution=32, method="direct",
                                                            progress=False)
    jobs["spectrum fast"] = lambda: clsamp.power_spectrum(pts, resolution=32, method="fast", tol=1e-6,
                                                          progress=False)
    jobs["convergence"] = lambda: np.concatenate(
        clsamp.convergence("jittered", "disk", [16, 64], realizations=16, progress=False).errors)
    jobs["family"] = lambda: np.concatenate(
        clsamp.convergence("random", "random_boxes", [32], realizations=8, members=8, progress=False).errors)
    jobs["render"] = lambda: render.render("ao", "jittered", 16, 12, seed=2, progress=False)
    jobs["discrepancy"] = lambda: np.atleast_1d(clsamp.discrepancy(pts, "CD"))
    jobs["pcf"] = lambda: clsamp.pair_correlation(pts)[1]
    return jobs


@pytest.mark.parametrize("rounds", [2])
def test_threads_give_the_serial_bits(rounds):
    jobs = _jobs()
    serial = {name: job() for name, job in jobs.items()}
    names = list(jobs)
    found, failures = {}, []

    def worker(offset):
        try:
            for step in range(rounds * len(names)):
                name = names[(offset + step) % len(names)]     # each thread its own order
                found.setdefault(name, []).append(jobs[name]())
        except Exception as error:              # reported below, not lost in the thread
            failures.append(repr(error))

    threads = [threading.Thread(target=worker, args=(3 * t,)) for t in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=600)
    assert not failures, failures
    for name, values in found.items():
        assert len(values) == 4 * rounds
        for value in values:
            assert np.array_equal(value, serial[name]), name
