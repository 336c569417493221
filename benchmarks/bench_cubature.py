"""Guaranteed adaptive cubature (``integrate(method="digital" | "lattice")``) against qmcpy.

    python benchmarks/bench_cubature.py [--device all] [--quick] [--out FILE]
    python benchmarks/bench_cubature.py --genz 200 [--abs-tol 1e-6] [--rel-tol 1e-3]
    python benchmarks/bench_cubature.py --ceiling

- ``clsamp.integrate(f, d, method="digital")`` against qmcpy's ``CubQMCNetG`` (on its
  ``DigitalNetB2``: LMS + digital shift, radical-inverse order) and ``method="lattice"``
  against ``CubQMCLatticeG`` (``Lattice``, random shift, Baker's tent on both sides), on the
  same NumPy integrand handed to both (qmcpy through ``CustomFun(Uniform(...))``): Keister
  in d = 4 and 8 (:func:`clsamp.integrands.keister`) and a Genz Gaussian in d = 3
  (``genz("gaussian", 3, seed=1)``), at abs_tol 1e-3 .. 1e-5 (Keister d = 4), 1e-3 and 1e-4
  (Keister d = 8: qmcpy's net needs minutes past that) and 1e-3 .. 1e-7 (the Gaussian)
  (``--quick``, CI-sized: Keister d = 4 and the Gaussian at 1e-3, one call after the
  warm-up). qmcpy's lattice is capped at its default generating vector's 2^20 points
  (``n_limit``), where it stops unconverged at the tightest tolerances. Seconds: median of
  3 calls after a warm-up (one call after the warm-up where the warm-up took over 10 s),
  each side in the same run, one after the other; quality:
  the points each used and the error each reached. qmcpy is optional (``pip install
  clsamp[bench]``); without it the rows have no peer.
- The same cases with the integrand on the device (rows "device integrand"): the
  :mod:`clsamp.integrands` object itself handed to ``integrate``, whose kernel makes the
  points and evaluates f in one launch (:mod:`clsamp.fused`), against the same qmcpy
  timing (qmcpy has no device path: its integrand is the NumPy one).
- ``--genz N``: the reliability study. N random members of each of Genz's six families
  (``genz(kind, d, seed)``, d = 2 + seed mod 7, so 2..8), each integrated by both methods
  to max(abs_tol, rel_tol |I|); per family and method the share of members whose estimate
  meets the tolerance, the share that converged before ``max_n`` = 2^22, and the median
  points used.
- A doubling of the digital rule's state (Walsh transform of 2^18 or 2^21 new values, the
  butterfly, the wavenumber ordering, the bound's terms) on the device
  (:mod:`clsamp.cubature_device`) against its NumPy twin, the same bits.
- ``--ceiling``: qmcpy's seconds over the NumPy integrand's own seconds on qmcpy's points,
  the most any code that evaluates that integrand on those points can gain.
- :func:`clsamp.transforms.to_normal` (AS 241 in NumPy, the device's bits), which the
  Keister integrand calls once a coordinate, against ``scipy.special.ndtri`` on the same
  2^21 uniform values (2^18 with ``--quick``), on the host: median of 5 after a warm-up,
  and the largest relative difference.
"""

import argparse
import sys
import time
import warnings

import numpy as np
from common import Row, main, on_device, short_name, timed

import clsamp
from clsamp.integrands import genz, keister
from clsamp.integrands.qmc import GENZ_KINDS

# per case: the Gaussian down to 1e-7 (qmcpy's net about 3 s there), Keister d = 4 to 1e-5,
# Keister d = 8 to 1e-4 (qmcpy's net needs 2^24 points and about 33 s at 1e-4, far more at 1e-5)
TOLERANCES = {"Keister d=4": (1e-3, 1e-4, 1e-5), "Keister d=8": (1e-3, 1e-4),
              "Genz Gaussian d=3": (1e-3, 1e-4, 1e-5, 1e-6, 1e-7)}
METHODS = {"digital": "CubQMCNetG", "lattice": "CubQMCLatticeG"}


def _cases(quick=False):
    cases = [("Keister d=4", keister(4)), ("Keister d=8", keister(8)),
             ("Genz Gaussian d=3", genz("gaussian", 3, seed=1))]
    return [cases[0], cases[2]] if quick else cases


def _qmcpy(f, d, tol, method):
    import qmcpy
    if method == "digital":
        solver = qmcpy.CubQMCNetG(qmcpy.CustomFun(qmcpy.Uniform(qmcpy.DigitalNetB2(d, seed=7)), g=f),
                                  abs_tol=tol, n_limit=2**30)
    else:
        solver = qmcpy.CubQMCLatticeG(qmcpy.CustomFun(qmcpy.Uniform(qmcpy.Lattice(d, seed=7)), g=f),
                                      abs_tol=tol, n_limit=2**20)
    from qmcpy.util import MaxSamplesWarning
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        estimate, data = solver.integrate()
    converged = not any(issubclass(w.category, MaxSamplesWarning) for w in caught)
    return float(np.asarray(estimate).reshape(-1)[0]), int(data.n_total), converged


def _timed(fn, quick=False):
    t0 = time.perf_counter()
    fn()                                    # the warm-up
    if quick or time.perf_counter() - t0 > 10.0:
        return timed(fn, repeats=1, warmup=0)
    return timed(fn, repeats=3, warmup=0)


def run(devices, quick):
    try:
        import qmcpy  # noqa: F401
        have_qmcpy = True
    except ImportError:
        have_qmcpy = False
    rows = []
    for device in devices:
        on_device(device)
        dev = short_name(device)
        for label, f in _cases(quick):
            g = f.__call__                          # the NumPy integrand, the same for both
            for method, peer_name in METHODS.items():
                for tol in TOLERANCES[label][:1] if quick else TOLERANCES[label]:
                    peer, t_peer, peer_quality, extra = "", None, "", {}
                    if have_qmcpy:
                        t_peer, (estimate, n, converged) = _timed(
                            lambda g=g, f=f, tol=tol, m=method: _qmcpy(g, f.d, tol, m), quick)
                        peer = f"qmcpy {peer_name}"
                        peer_quality = (f"; qmcpy {n} points, error {abs(estimate - f.integral):.1e}"
                                        + ("" if converged else " (stopped at its n_limit, unconverged)"))
                        # a peer that gave up is no comparison of speed (run.py's summary skips it)
                        extra = {} if converged else {"peer_unconverged": True}
                    for integrand, kind in ((g, "NumPy integrand"), (f, "device integrand")):
                        t, res = _timed(lambda h=integrand, f=f, tol=tol, m=method: clsamp.integrate(
                            h, f.d, abs_tol=tol, method=m, max_n=2**26, progress=False), quick)
                        quality = (f"clsamp {res.n} points, error {abs(res.estimate - f.integral):.1e}, "
                                   f"bound {res.half_width:.1e}{peer_quality}")
                        rows.append(Row(f"integrate {method} {label}, abs_tol {tol:g}", kind,
                                        dev, t, peer, t_peer, quality, dict(extra)))
    return rows + _walsh_rows(devices, quick) + [_to_normal_row(short_name(devices[0]), quick)]


def _to_normal_row(dev, quick):
    """to_normal against scipy's ndtri, both on the host (the row names the first device)."""
    from scipy.special import ndtri

    from clsamp.transforms import to_normal
    u = np.random.default_rng(3).random(2**18 if quick else 2**21)
    t, z = timed(lambda: to_normal(u))
    t_peer, reference = timed(lambda: ndtri(u))
    rel = float(np.max(np.abs(z - reference) / np.maximum(np.abs(reference), 1e-300)))
    return Row("to_normal on the host (AS 241 in NumPy)", f"{u.size} values", dev, t,
               "scipy.special.ndtri", t_peer, f"max relative difference {rel:.1e}")


def _walsh_rows(devices, quick):
    """One doubling of the digital rule's state (transform of the new half, butterfly,
    ordering, the bound's terms) on the device against its NumPy twin, the same bits."""
    from clsamp import runtime
    from clsamp.cubature import R_LAG, _order_wavenumbers, walsh_coefficients
    from clsamp.cubature_device import DeviceWalsh
    rows = []
    for device in [d for d in devices if d.fp64]:
        on_device(device)
        for m in (18,) if quick else (18, 21):
            n = 2**m
            rng = np.random.default_rng(m)
            c = walsh_coefficients(rng.standard_normal(n))
            kappa = _order_wavenumbers(np.arange(n), np.abs(c), m - 1, 0, m)
            y = rng.standard_normal(n)
            low = 2**(m + 1 - R_LAG - 1)
            state = DeviceWalsh()

            def on_device_once():
                state.load(c, kappa)          # outside the timing below: a fresh state each call
                runtime.queue().finish()
                t0 = time.perf_counter()
                state.double(y, m - R_LAG)
                _, terms = state.summary(low)
                return time.perf_counter() - t0, terms

            def numpy_once():
                t0 = time.perf_counter()
                new = walsh_coefficients(y)
                both = np.empty(2 * n)
                np.add(c, new, out=both[:n])
                np.subtract(c, new, out=both[n:])
                both *= 0.5
                k2 = _order_wavenumbers(np.concatenate([kappa, n + kappa]), np.abs(both), m,
                                        m - R_LAG, m + 1)
                return time.perf_counter() - t0, np.abs(both[k2[low:2 * low]])

            runs = [on_device_once() for _ in range(4)][1:]
            twin = [numpy_once() for _ in range(3)]
            same = all(np.array_equal(a[1], b[1]) for a, b in zip(runs, twin, strict=True))
            rows.append(Row("integrate digital: a doubling's Walsh state", f"2^{m} new values",
                            short_name(device), float(np.median([r[0] for r in runs])),
                            "clsamp NumPy twin", float(np.median([r[0] for r in twin])),
                            "the same bits" if same else "BITS DIFFER"))
    return rows


def genz_reliability(instances, abs_tol, rel_tol, max_n=2**22):
    """Per (family, method): (met, converged, median n, seconds) over ``instances`` members."""
    out = {}
    warnings.simplefilter("ignore", UserWarning)
    for kind in GENZ_KINDS:
        for method in METHODS:
            t0, met, converged, ns = time.perf_counter(), 0, 0, []
            for seed in range(instances):
                d = 2 + seed % 7
                f = genz(kind, d, seed)
                res = clsamp.integrate(f, d, abs_tol=abs_tol, rel_tol=rel_tol, method=method,
                                       max_n=max_n, seed=seed, progress=False)
                met += abs(res.estimate - f.integral) <= max(abs_tol, rel_tol * abs(f.integral))
                converged += res.converged
                ns.append(res.n)
            out[(kind, method)] = (met / instances, converged / instances, int(np.median(ns)),
                                   time.perf_counter() - t0)
            print(f"{kind:14s} {method:8s} met {met / instances:6.1%}  converged "
                  f"{converged / instances:6.1%}  median n {int(np.median(ns)):8d}  "
                  f"{time.perf_counter() - t0:6.1f} s", flush=True)
    return out


def ceiling(tolerances=(1e-3, 1e-4)):
    """Per case, method and tolerance: qmcpy's seconds and the seconds of the NumPy integrand
    alone on as many points, called once per doubling (1024, then 2^m more) as a cubature
    calls it; their ratio bounds the speed-up of any code that evaluates that integrand on
    those points (docs/performance.md, "Against qmcpy: seconds and points")."""
    print("| case | method | points | qmcpy s | f alone s | ceiling |")
    for name, f in _cases():
        for tol in tolerances:
            for method in METHODS:
                qmcpy_seconds, (_, n, _) = timed(lambda: _qmcpy(f.__call__, f.d, tol, method), repeats=3)
                x = np.random.default_rng(0).random((n, f.d))
                chunks = [x[:min(n, 1024)]] + [x[2**m:2**(m + 1)] for m in range(10, n.bit_length() - 1)]
                f_seconds = timed(lambda: [f(c) for c in chunks], repeats=3)[0]
                print(f"| {name}, {tol:g} | {method} | {n} | {qmcpy_seconds:.4g} | {f_seconds:.4g} | "
                      f"{qmcpy_seconds / f_seconds:.1f}x |", flush=True)


if __name__ == "__main__":
    if "--ceiling" in sys.argv:
        ceiling()
    elif "--genz" in sys.argv:
        p = argparse.ArgumentParser(description=__doc__)
        p.add_argument("--genz", type=int, required=True)
        p.add_argument("--abs-tol", type=float, default=1e-6)
        p.add_argument("--rel-tol", type=float, default=1e-3)
        a = p.parse_args()
        genz_reliability(a.genz, a.abs_tol, a.rel_tol)
    else:
        main(run, __doc__)
