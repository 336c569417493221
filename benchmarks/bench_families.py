"""Variance over integrand families, and integration to a tolerance, against their peers.

    python benchmarks/bench_families.py [--device all] [--quick] [--out FILE]

- A family sweep: 1024 random Heavisides x 7 sample counts (4, 16, ..., 16384) x 64
  realizations, for ``sobol:owen`` and ``jittered``, against the same sweep in NumPy
  (``backend="numpy"``: the samplers' NumPy references and the family evaluated
  vectorised over points and members). ``--quick``: 256 members, 5 counts up to 1024, 16
  realizations. Quality: the largest difference of the members' MSEs between the two.
- ``clsamp.integrate`` (16 replications of Owen-scrambled Sobol', doubling n) against
  qmcpy's ``CubQMCNetG`` on a ``DigitalNetB2`` (when qmcpy is installed), on the same
  vectorised NumPy integrands and tolerances: a Gaussian in d = 3 at abs_tol 1e-3, 1e-5,
  1e-7 and a disk indicator in d = 2 at 1e-3, 1e-4 (``--quick``: the looser ones).
  Quality: the points each used, the error each achieved and clsamp's half-width.
"""

import math

import numpy as np
from common import Row, main, on_device, short_name, timed

import clsamp


def _gaussian(x):
    return np.exp(-8.0 * np.sum((x - 0.5) ** 2, axis=1))


def _disk(x):
    return (np.sum((x - 0.5) ** 2, axis=1) < 0.16).astype(np.float64)


GAUSSIAN = (math.sqrt(math.pi / 8) * math.erf(math.sqrt(8) * 0.5)) ** 3
DISK = math.pi * 0.16
CASES = ((_gaussian, 3, GAUSSIAN, "Gaussian d=3", (1e-3, 1e-5, 1e-7)),
         (_disk, 2, DISK, "disk d=2", (1e-3, 1e-4)))


def _qmcpy(f, d, tol):
    import qmcpy
    net = qmcpy.DigitalNetB2(d, seed=7)
    solver = qmcpy.CubQMCNetG(qmcpy.CustomFun(qmcpy.Uniform(net), g=f), abs_tol=tol)
    estimate, data = solver.integrate()
    return float(np.asarray(estimate).reshape(-1)[0]), int(data.n_total)


def _sweep(name, ns, r, members, backend):
    sampler = clsamp.make_sampler(name, d=2, seed=1, backend=backend)
    return clsamp.convergence(sampler, "random_heavisides", ns, realizations=r, members=members,
                              seed=2, progress=False, backend=backend)


def run(devices, quick):
    ns, r, members = ([4, 16, 64, 256, 1024], 16, 256) if quick else ([4**k for k in range(1, 8)], 64, 1024)
    size = f"{members} Heavisides x {len(ns)} ns {ns[0]}..{ns[-1]} x {r}"
    peers = {name: timed(lambda n=name: _sweep(n, ns, r, members, "numpy"), repeats=1, warmup=0)
             for name in ("sobol:owen", "jittered")}
    try:
        import qmcpy  # noqa: F401
        have_qmcpy = True
    except ImportError:
        have_qmcpy = False
    cases = [(f, d, exact, label, tol) for f, d, exact, label, tols in CASES
             for tol in (tols[:2] if quick else tols)]
    qmc = {}
    if have_qmcpy:
        for f, d, _, label, tol in cases:
            t, (estimate, n) = timed(lambda f=f, d=d, tol=tol: _qmcpy(f, d, tol), repeats=3)
            qmc[(label, tol)] = (t, estimate, n)
    rows = []
    for device in devices:
        on_device(device)
        dev = short_name(device)
        for name, (t_np, reference) in peers.items():
            t_cl, res = timed(lambda n=name: _sweep(n, ns, r, members, "opencl"), repeats=3)
            gap = float(np.max(np.abs(res.mse - reference.mse) / reference.mse))
            slope, lo, hi = res.rate("mean")
            rows.append(Row(f"family sweep {name}", size, dev, t_cl, "numpy reference", t_np,
                            f"MSE rel. diff {gap:.1e}; mean slope {slope:.2f} [{lo:.2f}, {hi:.2f}]"))
        for f, d, exact, label, tol in cases:
            t, res = timed(lambda f=f, d=d, tol=tol: clsamp.integrate(f, d, abs_tol=tol, progress=False),
                           repeats=5)
            quality = (f"clsamp {res.evaluations} points, error {abs(res.estimate - exact):.1e}, "
                       f"half-width {res.half_width:.1e}")
            peer, t_peer = "", None
            if (label, tol) in qmc:
                t_peer, estimate, n = qmc[(label, tol)]
                peer = "qmcpy CubQMCNetG (DigitalNetB2)"
                quality += f"; qmcpy {n} points, error {abs(estimate - exact):.1e}"
            rows.append(Row(f"integrate {label}, abs_tol {tol:g}", "16 replications", dev, t, peer,
                            t_peer, quality))
    return rows


if __name__ == "__main__":
    main(run, __doc__)
