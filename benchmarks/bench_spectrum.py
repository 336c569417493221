"""Power spectra: the expected spectrum of r realizations of N points at R², clsamp's exact
(direct) and NUFFT (fast) paths against finufft (nufft2d1, isign=-1, same tolerance) and the
NumPy separable GEMM (``clsamp.spectrum.direct_reference``), in one run; one 3-D set of
4096 points at R³ (R = 32, 64): the fast path against the exact direct sum and finufft
(nufft3d1); and the direct sum in float-float (``precision="float-float"``, what a device
without fp64 computes) against the double one on the same device.

Max error is max_ω |P̃(ω) - P(ω)| / N against clsamp's direct result (itself checked
against the NumPy reference in the same run). The direct rows also report the kernel's rate
in GFLOP/s of the products it actually executes next to the NumPy GEMM's rate (all of
it, 8 flops per complex multiply-add). On a CPU device that is one real GEMM per set over
the quarter plane u, v in [0, R/2] (2(R + 2)²N flops); elsewhere the complex products of
the half u <= 0.
"""

import numpy as np
from common import Row, main, on_device, short_name, timed

from clsamp import philox, runtime, spectrum
from clsamp.spectrum import nufft_parameters, power_spectrum


def _points(r, n, d=2):
    return philox.uniform_block(1, philox.Stream.POINTS, np.arange(r), n, d, 0)


def twiddles_by_recurrence(x, f0, count, reseed=32):
    """e^{-2πi f x_k} for f = f0 .. f0 + count - 1 by recurrence: (count, n) complex128.

    One exactly reduced exponential per point for the step e^{-2πi x}, then each row the
    previous one times the step (one complex multiply per twiddle), re-seeded from an
    exactly reduced phase every ``reseed`` rows so that the rounding error of the
    recurrence stays below ~``reseed`` ulps however many frequencies there are
    (``reseed=None``: never re-seeded, the error grows with the row count). This is how a
    NumPy user builds the twiddle panels of the separable sum at the fewest
    transcendental calls: the twiddles of clsamp's peer.
    """
    X = spectrum.fixed_point(np.asarray(x, dtype=np.float64).ravel())

    def exact(f):
        theta = X * np.uint64(int(f) % 2**64)          # wraps modulo 2^64: exact reduction
        angle = theta.view(np.int64).astype(np.float64) * spectrum._PHASE
        return np.cos(angle) - 1j * np.sin(angle)

    step = exact(1)
    out = np.empty((count, X.size), np.complex128)
    out[0] = exact(f0)
    for m in range(1, count):
        if reseed is not None and m % reseed == 0:
            out[m] = exact(f0 + m)
        else:
            np.multiply(out[m - 1], step, out=out[m])
    return out


def gemm_peer(points, resolution):
    """The exact expected periodogram as well as NumPy does it: twiddles by recurrence with
    exact re-seeding, one complex128 GEMM A (R x N) @ B^T (N x R) per set, |S|^2 / N."""
    r, n, _ = points.shape
    f0 = -(resolution // 2)
    total = np.zeros((resolution, resolution))
    for block in points:
        S = twiddles_by_recurrence(block[:, 0], f0, resolution) @ \
            twiddles_by_recurrence(block[:, 1], f0, resolution).T
        total += S.real**2 + S.imag**2
    return total / (r * n)


def _finufft(points, resolution, tol):
    import finufft
    total = np.zeros((resolution, resolution))
    c = np.ones(points.shape[1], dtype=np.complex128)
    for block in points:
        f = finufft.nufft2d1(2 * np.pi * block[:, 0], 2 * np.pi * block[:, 1], c,
                             (resolution, resolution), eps=tol, isign=-1)
        total += f.real**2 + f.imag**2
    return total / (points.shape[0] * points.shape[1])


def _finufft3(points, resolution, tol):
    import finufft
    total = np.zeros((resolution,) * 3)
    c = np.ones(points.shape[1], dtype=np.complex128)
    for block in points:
        x, y, z = (2 * np.pi * block[:, a] for a in range(3))
        f = finufft.nufft3d1(x, y, z, c, (resolution,) * 3, eps=tol, isign=-1)
        total += f.real**2 + f.imag**2
    return total / (points.shape[0] * points.shape[1])


def run_3d(dev, quick, have_finufft):
    """One 3-D set of 4096 points: direct, then fast at three tolerances against finufft."""
    rows = []
    pts = _points(1, 4096, 3)
    for R in (32,) if quick else (32, 64):
        size = f"1x4096 at {R}^3"
        t_direct, exact = timed(lambda: power_spectrum(pts, R, method="direct", progress=False),
                                repeats=3)
        rows.append(Row("spectrum 3-D direct", size, dev, t_direct))
        for tol in (1e-3, 1e-6, 1e-12):
            rows.append(_fast_row("spectrum 3-D", size, dev, pts, R, tol, exact, 5,
                                  _finufft3 if have_finufft else None, t_direct))
    return rows


def _fast_row(case, size, dev, pts, R, tol, exact, repeats, peer, t_direct=None):
    """One row: the fast path at ``tol`` against the exact ``exact``, and against finufft
    (``peer``, a function of (points, R, tol); None: not installed)."""
    d, n = pts.shape[-1], pts.shape[1]
    sigma, width, _ = nufft_parameters(tol, d)
    t_fast, fast = timed(lambda: power_spectrum(pts, R, method="fast", tol=tol, progress=False),
                         repeats=repeats)
    quality = f"max err {np.abs(fast - exact).max() / n:.1e} (sigma {sigma}, w {width})"
    if t_direct is not None:
        quality += f"; {t_direct / t_fast:.0f}x direct"
    if peer is None:
        return Row(f"{case} fast tol={tol:g}", size, dev, t_fast, quality=quality)
    t_fi, fi = timed(lambda: peer(pts, R, tol), repeats=repeats)
    quality += f"; finufft err {np.abs(fi - exact).max() / n:.1e}"
    return Row(f"{case} fast tol={tol:g}", size, dev, t_fast, f"finufft nufft{d}d1", t_fi, quality)


def run(devices, quick):
    rows = []
    r, n, R = (8, 1024, 64) if quick else (64, 4096, 256)
    size = f"{r}x{n} at {R}^2"
    pts = _points(r, n)
    try:
        import finufft  # noqa: F401
        have_finufft = True
    except ImportError:
        have_finufft = False
    for device in [d for d in devices if d.fp64]:       # without fp64: the float-float rows only
        on_device(device)
        dev = short_name(device)
        t_direct, exact = timed(lambda: power_spectrum(pts, R, method="direct", progress=False),
                                repeats=1 if not quick else 3)
        t_gemm, ref = timed(lambda: gemm_peer(pts, R), repeats=1 if not quick else 3, warmup=0)
        if spectrum.HOST_GEMM and runtime.shape().host_gemm:   # one real GEMM (2c x n)(n x 2c)
            rate = 8.0 * r * n * (R // 2 + 1) ** 2 / t_direct / 1e9
        else:                                               # complex products over u <= 0
            half_rows = (R // 2 + 1 + 3) // 4 * 4
            cols = (R + 1 + 3) // 4 * 4
            rate = 8.0 * r * n * half_rows * cols / t_direct / 1e9
        rate_np = 8.0 * r * n * R * R / t_gemm / 1e9
        err = np.abs(exact - ref).max() / n
        rows.append(Row("spectrum direct", size, dev, t_direct, "numpy GEMM, recurrence twiddles", t_gemm,
                        f"max err {err:.1e}; {rate:.1f} vs numpy {rate_np:.1f} GFLOP/s "
                        f"({rate / rate_np:.0%})"))
        for tol in (1e-3, 1e-6, 1e-9, 1e-12):
            rows.append(_fast_row("spectrum", size, dev, pts, R, tol, exact, 3,
                                  _finufft if have_finufft else None))
        rows += run_3d(dev, quick, have_finufft)
    rows += _float_float_rows(devices, quick)
    return rows


def _float_float_rows(devices, quick):
    """The direct sum in float-float (a device without fp64 computes only this) against the
    double one on the same device; errors against the NumPy reference, relative to N."""
    rows = []
    r, n, R = (2, 1024, 64) if quick else (8, 2048, 128)
    pts = _points(r, n)
    ref = spectrum.direct_reference(pts, R)
    for device in devices:
        on_device(device)
        t_ff, ff = timed(lambda: power_spectrum(pts, R, method="fast", tol=1e-6, precision="float-float",
                                                progress=False), repeats=3)
        quality = f"max err {np.abs(ff - ref).max() / n:.1e}"
        t_d = None
        if device.fp64:
            t_d, fast = timed(lambda: power_spectrum(pts, R, method="fast", tol=1e-6, precision="double",
                                                     progress=False), repeats=3)
            quality += f"; double {np.abs(fast - ref).max() / n:.1e}"
        rows.append(Row("spectrum fast tol=1e-06 float-float", f"{r}x{n} at {R}^2", short_name(device), t_ff,
                        "clsamp fast in double" if device.fp64 else "", t_d, quality))
        t_ff, ff = timed(lambda: power_spectrum(pts, R, method="direct", precision="float-float",
                                                progress=False), repeats=3)
        quality = f"max err {np.abs(ff - ref).max() / n:.1e}"
        if device.fp64:
            t_d, exact = timed(lambda: power_spectrum(pts, R, method="direct", precision="double",
                                                      progress=False), repeats=3)
            quality += f"; double {np.abs(exact - ref).max() / n:.1e}"
            rows.append(Row("spectrum direct float-float", f"{r}x{n} at {R}^2", short_name(device), t_ff,
                            "clsamp direct in double", t_d, quality))
        else:
            rows.append(Row("spectrum direct float-float", f"{r}x{n} at {R}^2", short_name(device), t_ff,
                            quality=quality + "; double: no fp64 on this device"))
    return rows


if __name__ == "__main__":
    main(run, __doc__)
