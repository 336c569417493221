"""Sweeps on a Dask LocalCluster against the same sweep in-process, in the same run.

    python benchmarks/bench_parallel.py [--quick] [--out FILE]

Case: 6 samplers (random, jittered, latin_hypercube, multijittered, sobol:owen,
halton:owen) x 2 integrands (Gaussian, disk) x 8 N (1, 4, ..., 16384) x 4096
realizations, in-process, then on a LocalCluster of 1 worker process with 2 threads and
of 2 single-threaded workers (each worker's PoCL given its share of the 2 cores); the
cluster's start is not timed. ``--quick``: 2 samplers x 4 N x 64 realizations. Quality:
whether every error is the same bits as in-process, the tasks and the scheduler's rate
(tasks per second for 2000 empty tasks). Needs ``clsamp[dask]``; the rows are skipped
without it.
"""

import os
import time

import numpy as np
from common import Row, main, short_name

import clsamp
from clsamp import parallel

SAMPLERS = ("random", "jittered", "latin_hypercube", "multijittered", "sobol:owen", "halton:owen")


def _sweep(samplers, ns, r, client):
    results = []
    for name in samplers:
        for f in ("gaussian", "disk"):
            results.append(clsamp.convergence(name, f, ns, realizations=r, seed=1, progress=False,
                                              client=client))
    return results


def _noop(x):
    return x


def _scheduler_rate(client, count=2000):
    client.gather(client.map(_noop, range(50), pure=False))
    t0 = time.perf_counter()
    client.gather(client.map(_noop, range(count), pure=False))
    return count / (time.perf_counter() - t0)


def run(devices, quick):
    try:
        import distributed
    except ImportError:
        print("bench_parallel: dask.distributed is not installed (pip install 'clsamp[dask]'); skipped")
        return []
    if quick:
        samplers, ns, r = SAMPLERS[:2], [1, 4, 16, 64], 64
    else:
        samplers, ns, r = SAMPLERS, [4**k for k in range(8)], 4096
    size = f"{len(samplers)} samplers x 2 integrands x {len(ns)} N x {r}"
    dev = short_name(clsamp.current_device())
    _sweep(samplers, ns[:1], 2, None)                      # builds every program first
    t0 = time.perf_counter()
    here = _sweep(samplers, ns, r, None)
    t_here = time.perf_counter() - t0
    tasks = sum(len(parallel.block_ranges(r, n)) for n in ns) * len(samplers) * 2
    rows = [Row("sweep in-process", size, dev, t_here, quality=f"{tasks} tasks' worth")]
    cores = os.cpu_count() or 1
    for workers, threads in ((1, 2), (2, 1)):
        cluster = distributed.LocalCluster(n_workers=workers, threads_per_worker=threads, processes=True,
                                           dashboard_address=":0",
                                           env={"POCL_MAX_PTHREAD_COUNT": str(max(1, cores // workers))})
        client = distributed.Client(cluster)
        try:
            _sweep(samplers, ns[:1], 2, client)            # every worker builds its programs
            t0 = time.perf_counter()
            there = _sweep(samplers, ns, r, client)
            t_there = time.perf_counter() - t0
            same = all(np.array_equal(a, b) for x, y in zip(here, there, strict=True)
                       for a, b in zip(x.errors, y.errors, strict=True))
            rate = _scheduler_rate(client)
        finally:
            client.close()
            cluster.close()
        rows.append(Row(f"sweep on LocalCluster {workers} x {threads}", size, dev, t_there,
                        "in-process", t_here,
                        f"same bits: {same}; {tasks} tasks; scheduler {rate:.0f} tasks/s"))
    return rows


if __name__ == "__main__":
    main(run, __doc__)
