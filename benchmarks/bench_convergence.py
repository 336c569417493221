"""Convergence sweeps: the OpenCL path (points on the device, one kernel shifts,
evaluates and sums per realization) against the NumPy reference path, in the same run.

    python benchmarks/bench_convergence.py [--device all] [--quick] [--out FILE]

Case: 7 sample counts (4, 16, ..., 16384: squares, as jittered needs) x 1000
realizations x the Gaussian and the disk, for ``random`` and ``jittered``; one row per
(sampler, integrand) and one per sampler (both integrands). ``--quick``: 4 counts up to
256 x 100 realizations. clsamp's time is the median of 3 sweeps after a warm-up; the
NumPy reference (NumPy samplers too: Philox in NumPy) runs once. Quality: the largest
relative difference of the MSEs between the two paths, and clsamp's fitted slope.
"""

import numpy as np
from common import Row, main, on_device, short_name, timed

import clsamp

SAMPLERS = ("random", "jittered")
INTEGRANDS = ("gaussian", "disk")


def _sweep(name, ns, r, backend):
    sampler = clsamp.make_sampler(name, d=2, seed=1, backend=backend)
    return [clsamp.convergence(sampler, f, ns, realizations=r, seed=2, progress=False, backend=backend)
            for f in INTEGRANDS]


def run(devices, quick):
    ns, r = ([4, 16, 64, 256], 100) if quick else ([4**k for k in range(1, 8)], 1000)
    size = f"{len(ns)} ns {ns[0]}..{ns[-1]} x {r}"
    peers = {}
    for name in SAMPLERS:
        peers[name] = timed(lambda: _sweep(name, ns, r, "numpy"), repeats=1, warmup=0)
    rows = []
    for device in devices:
        on_device(device)
        dev = short_name(device)
        for name in SAMPLERS:
            t_cl, results = timed(lambda: _sweep(name, ns, r, "opencl"), repeats=3)
            t_np, reference = peers[name]
            gaps = []
            for res, ref in zip(results, reference, strict=True):
                gap = float(np.max(np.abs(res.mse - ref.mse) / ref.mse))
                gaps.append(gap)
                slope, stderr = res.rate()
                rows.append(Row(f"convergence {name} / {res.integrand}", size, dev,
                                float(res.seconds.sum()), "numpy reference", float(ref.seconds.sum()),
                                f"MSE rel. diff {gap:.1e}, slope {slope:.2f} +- {stderr:.2f}"))
            rows.append(Row(f"convergence {name} (both)", size, dev, t_cl, "numpy reference", t_np,
                            f"MSE rel. diff {max(gaps):.1e}"))
    return rows


if __name__ == "__main__":
    main(run, __doc__)
