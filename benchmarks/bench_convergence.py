"""Convergence sweeps: the OpenCL path (points on the device, one kernel shifts,
evaluates and sums per realization) against the NumPy reference path, in the same run.

    python benchmarks/bench_convergence.py [--device all] [--quick] [--out FILE]

Case: 7 sample counts (4, 16, ..., 16384: squares, as jittered needs) x 1000
realizations x the Gaussian and the disk, for ``random`` and ``jittered``; one row per
(sampler, integrand) and one per sampler (both integrands). ``--quick``: 4 counts up to
256 x 100 realizations. clsamp's time is the median of 3 sweeps after a warm-up; the
NumPy reference (NumPy samplers too: Philox in NumPy) runs once. Quality: the largest
relative difference of the MSEs between the two paths, and clsamp's fitted slope.

Float-float rows (``precision="float-float"``, :mod:`clsamp.experiments_ff`): the
Gaussian and the disk with ``sobol:owen`` and ``jittered``, Keister's 4-D integrand and 64
random Gaussians, against ``precision="double"`` on the same device (against the default
device's double errors where the device has no fp64); quality: the largest |e_ff - e_64|
over every realization and n, the stated bound, and the MSEs' largest relative difference.
"""

import numpy as np
from common import Row, main, on_device, short_name, timed

import clsamp
from clsamp import families, runtime
from clsamp.experiments_ff import error_bound
from clsamp.integrands import make_integrand
from clsamp.integrands.qmc import keister

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
    return rows + _float_float_rows(devices, quick)


def _ff_cases(quick):
    squares, powers, r = ([16, 64, 256, 1024], [16, 64, 256, 1024], 8) if quick else \
        ([4**k for k in range(2, 8)], [2**k for k in range(4, 15, 2)], 64)
    return [("sobol:owen", make_integrand("gaussian"), squares, r),
            ("jittered", make_integrand("disk"), squares, r), ("sobol:owen", keister(4), powers, r),
            ("random", families.make_family("random_gaussians", d=2, members=64, seed=1), squares[:3], r)]


def _float_float_rows(devices, quick):
    def sweep(sampler, f, ns, r, precision):
        return clsamp.convergence(sampler, f, ns, realizations=r, seed=2, progress=False, precision=precision)

    cases = _ff_cases(quick)
    reference = [sweep(*case, "double") for case in cases]      # the default device, fp64
    rows = []
    for device in devices:
        on_device(device)
        fp64 = runtime.current_device().fp64
        for case, ref in zip(cases, reference, strict=True):
            sampler, f, ns, r = case
            t_ff, res = timed(lambda case=case: sweep(*case, "float-float"), repeats=3)
            t_64 = timed(lambda case=case: sweep(*case, "double"), repeats=3)[0] if fp64 else None
            gap = max(float(np.max(np.abs(a - b))) for a, b in zip(res.errors, ref.errors, strict=True))
            bound = max(error_bound(f, n) for n in ns)
            mse = float(np.max(np.abs(res.mse / ref.mse - 1)))
            size = f"{len(ns)} ns {ns[0]}..{ns[-1]} x {r}"
            rows.append(Row(f"convergence {sampler} / {f.name} float-float", size, short_name(device), t_ff,
                            "double (same device)" if fp64 else "", t_64,
                            f"max |e_ff - e_64| {gap:.1e} (bound {bound:.1e}), MSE rel. diff {mse:.1e}"))
    return rows


if __name__ == "__main__":
    main(run, __doc__)
