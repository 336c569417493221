"""Fourier power spectra of point sets, their radial mean and anisotropy (pictures of them
are :mod:`clsamp.plots`'s).

The periodogram of N points x_1..x_N in [0, 1)^d at an integer frequency ω is

    P(ω) = |Σ_k exp(-2πi ω·x_k)|² / N,

so P(0) = N and white noise has E[P(ω)] = 1 at every ω ≠ 0. For r realizations the
expected spectrum is estimated by the mean of the r periodograms (Ulichney 1987; Lagae &
Dutré 2008; Heck, Schlömer & Deussen 2013).

Layout (docs/design.md, "Conventions"): a resolution R (even) gives frequencies ω in
[-R/2, R/2)^d and P[i, j] is frequency (i - R/2) along x and (j - R/2) along y, DC at
[R/2, R/2]. One dimensional points give a spectrum of length R, DC at [R/2].

Two ways to compute it, one knob between them:

- ``method="direct"``: the exact sum, as the separable product S = A Bᵀ of per-point twiddle
  panels A[k, u] = e^{-2πiux_k}, B[k, v] = e^{-2πivy_k} (a complex GEMM, blocked in an
  OpenCL kernel; on a CPU device one real GEMM in the host's BLAS over the quarter plane
  u, v >= 0, which gives S(u, ±v) at once). Phases are reduced exactly in 64-bit fixed
  point. Cost ~ 4·r·N·R² flops in 2-D (P(ω) = P(-ω) for real points, so only half the
  rows are computed), ~ 2·r·N·R² over the quarter plane.
- ``method="fast"``: a type-1 non-uniform FFT (Dutt & Rokhlin 1993; Barnett, Magland &
  af Klinteberg 2019; its parameters and kernel in :mod:`clsamp.nufft`): spread each
  point onto an oversampled grid with the "exponential of semicircle" kernel (OpenCL),
  FFT the grid (scipy.fft, on the host, all cores), divide by the kernel's Fourier
  transform. Cost ~ r·(N·w^d + (σR)^d log R).

Kernels are in ``kernels/spectrum.cl`` and ``kernels/nufft.cl``; every one has a NumPy
reference (:func:`twiddles_reference`, :func:`direct_reference`, :func:`spread_reference`), and
``backend="numpy"`` runs the whole computation on them.
"""

import math
import os

import numpy as np

from . import parallel, runtime, spectrum_ff
from .errors import InvalidArgumentError
from .float_float import check_precision
from .nufft import MIN_TOL, grid_size, kernel_transform, nufft_parameters, spread_reference
from .spectral_stats import anisotropy, check_spectrum, radial_mean  # noqa: F401  (public here)
from .validation import check_bool, check_choice, check_int, check_points, check_real, point_sets

__all__ = [
    "power_spectrum", "expected_spectrum", "radial_mean", "anisotropy", "normalized_frequency", "frequencies",
    "direct_reference", "spread_reference", "twiddles_reference", "nufft_parameters",
    "check_spectrum",
]

METHODS = ("auto", "direct", "fast")
BACKENDS = ("opencl", "numpy")
DEFAULT_FAST_TOL = 1e-12
_MAD = ("-cl-mad-enable",)
_PHASE = 2.0 * np.pi * 2.0**-64     # radians per unit of 64-bit fixed-point phase (exact scaling)
_FINE = 16                          # twiddles per exact sincos, as FINE in spectrum.cl
_TILE = 4                           # TILE_U = TILE_V in spectrum.cl
_SUPER = 4
HOST_GEMM = True                    # 2-D direct sums on a CPU device: product in the host BLAS
WORKING_SET = 256 * 2**20           # device bytes a chunk of work holds at most (runtime.fit)


# -- frequencies -------------------------------------------------------------------
def frequencies(resolution):
    """The integer frequencies of each axis of a spectrum: ``arange(-R/2, R/2)``.

    Parameters
    ----------
    resolution : int
        R, even.

    Returns
    -------
    ndarray of int
        Index i of a spectrum's axis is frequency ``frequencies(R)[i]``.
    """
    resolution = _check_resolution(resolution)
    return np.arange(-(resolution // 2), resolution // 2)


def normalized_frequency(freqs, n, convention="psa"):
    """Frequencies expressed as the point-set tools do, for plots that compare N.

    Parameters
    ----------
    freqs : array_like
        Integer frequencies ν (e.g. the first value :func:`radial_mean` returns).
    n : int
        Points per set.
    convention : {"psa", "utk"}
        ``"psa"`` (Heck et al. 2013): 2ν/√N, so 1 is the Nyquist frequency √N/2 of a
        regular grid of N points. ``"utk"``: ν/√N.

    Returns
    -------
    ndarray of float64

    Examples
    --------
    >>> normalized_frequency([32, 64], 4096)
    array([1., 2.])
    >>> normalized_frequency([32, 64], 4096, "utk")
    array([0.5, 1. ])
    """
    n = check_int(n, "n", minimum=1)
    check_choice(convention, "convention", ("psa", "utk"))
    scale = 2.0 if convention == "psa" else 1.0
    return scale * np.asarray(freqs, dtype=np.float64) / math.sqrt(n)


# -- argument checks ------------------------------------------------------------------
def _check_resolution(resolution):
    resolution = check_int(resolution, "resolution", minimum=2)
    if resolution % 2:
        raise InvalidArgumentError(
            f"'resolution' must be even (frequencies [-R/2, R/2) put DC at R/2), got {resolution}")
    return resolution


# -- the public entry point -------------------------------------------------------------
def power_spectrum(points, resolution=256, method="auto", tol=None, backend="opencl", progress=True,
                   precision=None):
    """Periodogram of a point set, or the expected spectrum of a batch of realizations.

    Parameters
    ----------
    points : ndarray or pyopencl.array.Array, shape (n, d) or (r, n, d), or a list of (n_k, d)
        Points in [0, 1)^d, d = 1, 2 or 3. A batch gives the mean of the r periodograms
        (never the transform of the union of the sets). A device array
        (``Sampler.sample_device``) is read where it is, with no copy to the host. A list
        of sets of different sizes (``sample_sets`` of maximal Poisson disk) gives the mean
        of their periodograms, each |S_k|^2 / n_k.
    resolution : int
        R, even, >= 2: frequencies [-R/2, R/2) along each axis.
    method : {"auto", "direct", "fast"}
        ``"direct"`` is exact to fp64 rounding; ``"fast"`` is a NUFFT whose error is below
        ``tol``; ``"auto"`` picks the cheaper one that meets ``tol`` (direct when ``tol``
        is None and the exact sum is cheap, else fast). Both in 1-D, 2-D and 3-D.
    tol : float, optional
        For ``"fast"``: the largest error allowed, relative to the DC value N, i.e.
        max_ω |P̃(ω) - P(ω)| <= tol·N. In [5e-13, 0.1] (in 3-D from about 7e-13);
        default 1e-12.
    backend : {"opencl", "numpy"}
        ``"numpy"`` runs the NumPy references of the kernels instead.
    progress : bool
        Show a progress bar when the work is long (several chunks).
    precision : {"double", "float-float"}, optional
        What the device computes the direct sum in; default ``"double"`` where the device
        has fp64, ``"float-float"`` where it has not (:mod:`clsamp.spectrum_ff`). Direct:
        exact integer phases, float-float sums, within :func:`clsamp.spectrum_ff.error_bound`
        (n) ≈ 2^-47·n·(400 + 5n/64) of the exact spectrum; fast: float-float spreading,
        ``tol`` >= 1e-11 (``spectrum_ff.FAST_MIN_TOL``), the FFT in float64 on the host, for
        1-D and 2-D spectra (a 3-D one in float-float is direct).

    Returns
    -------
    P : ndarray, shape (R,), (R, R) or (R, R, R), float64
        P[i, j] is frequency (i - R/2) along x and (j - R/2) along y; P[R/2, R/2] = N
        (and P[i, j, k] in 3-D).

    Notes
    -----
    *Direct.* With a_k(u) = e^{-2πiux_k} and b_k(v) = e^{-2πivy_k}, the 2-D sum is
    S(u, v) = Σ_k a_k(u) b_k(v): a complex matrix product of two R × N twiddle panels.
    Each coordinate becomes a 64-bit fixed-point fraction X = ⌊x·2^64⌋ (exact steps), so
    u·X wraps modulo 2^64 exactly: the phase is reduced modulo 1 without rounding, for any
    frequency. Twiddles are e((u0 + 16q)X)·e(sX), two exactly reduced sincos factors, so
    each is within a few ulps; a sum of N of them carries an error <= ~N·2^-50 and
    |ΔP| <= 2|S|·|ΔS|/N <= ~4N·2^-50 ≈ 4e-15·N, in practice ~1e-16·N (sums of
    random-sign rounding errors). Since P(-ω) = P(ω), only u <= 0 is computed. In 3-D,
    S(u, v, w) = Σ_k a_k(u) b_k(v) c_k(w) is, for each u, the product of the panel
    (a_k(u) b_k(v)) with the panel c: the twiddles come from the device, the R products of
    R × N by N × R complex matrices from the host's BLAS, so the work is R^3 N a set.

    *Fast.* Spreading the points onto a grid of M = σR nodes per axis with the kernel
    φ(z) = exp(β(√(1-z²) - 1)), |z| <= 1, w nodes wide, then an FFT, gives
    G(ω) = S(ω)·ψ̂(ω) + aliasing, where ψ̂ is the kernel's Fourier transform (computed by
    Gauss–Legendre quadrature); dividing by ψ̂ leaves an error of about e^{-πw√(1-1/σ)}
    relative to N (Barnett et al. 2019). clsamp picks σ in ``SIGMAS`` and w, β from
    ``tol`` (:func:`nufft_parameters`: the cheapest that meets it); at loose tolerances
    that is σ = 1.25, a grid 2.56× smaller than finufft's σ = 2 in 2-D, which matters
    since the FFT is the larger cost here. The FFT is of real data (rfft2), P(ω) = P(-ω)
    gives the other half, and Σ_r |G_r|² is divided by ψ̂² once. In 3-D the same: a grid of
    M³ nodes, w³ per point, an rfftn pruned to |ω_x|, |ω_y| <= R/2, ω_z in [0, R/2]; the
    bound ((1 + e)^{2d} - 1)·N <= tol·N has six factors instead of four. Timings and errors of
    both methods against finufft and NumPy are in docs/performance.md.

    References
    ----------
    .. [1] A. Lagae, P. Dutré, "A comparison of methods for generating Poisson disk
       distributions", Computer Graphics Forum 27(1), 2008.
    .. [2] D. Heck, T. Schlömer, O. Deussen, "Blue noise sampling with controlled
       aliasing", ACM TOG 32(3), 2013.
    .. [3] A. H. Barnett, J. Magland, L. af Klinteberg, "A parallel nonuniform fast
       Fourier transform library based on an 'exponential of semicircle' kernel",
       SIAM J. Sci. Comput. 41(5), 2019.

    Examples
    --------
    >>> import clsamp
    >>> pts = clsamp.make_sampler("random", seed=1).sample(256, realizations=4)
    >>> P = clsamp.power_spectrum(pts, resolution=32)
    >>> P.shape, float(P[16, 16])
    ((32, 32), 256.0)
    """
    check_bool(progress, "progress")
    check_choice(backend, "backend", BACKENDS)
    asked, precision = precision, check_precision(precision, backend)
    sets = point_sets(points, "points", d=(1, 2, 3))
    if sets is not None:
        return _sets_spectrum(sets, resolution, method, tol, backend, progress, asked)
    batch, _ = check_points(points, "points", d=(1, 2, 3), keep_device=backend == "opencl")
    resolution = _check_resolution(resolution)
    # the spectrum and the working copies of its halves
    runtime.check_host_bytes(3 * 8 * resolution ** batch.shape[-1],
                             f"a power spectrum at resolution {resolution} in {batch.shape[-1]}-D")
    check_choice(method, "method", METHODS)
    if tol is not None:
        tol = check_real(tol, "tol", minimum=0.0, maximum=0.1, open_minimum=True)
        if tol < MIN_TOL and method == "fast":
            raise InvalidArgumentError(
                f"'tol' must be >= {MIN_TOL:g} for method='fast' (the fp64 floor of the NUFFT); "
                f"got {tol:g}; method='direct' is exact")
    ff = precision == "float-float" and backend == "opencl"
    if ff:
        spectrum_ff.check_fast(batch.shape[-1], method, tol)
    if method == "auto":
        method = "direct" if ff and batch.shape[-1] == 3 else _choose_method(batch.shape, resolution, tol)
    if method == "fast":
        floor = spectrum_ff.FAST_MIN_TOL if ff else MIN_TOL
        return _fast(batch, resolution, max(floor, DEFAULT_FAST_TOL if tol is None else tol), backend,
                     progress, precision)
    return _direct(batch, resolution, backend, progress, precision)


def spectrum_block(sampler, n, lo, hi, resolution, method, tol, backend, precision=None):
    """One task of :func:`expected_spectrum`: the sum of the periodograms of realizations
    lo .. hi - 1 (the block's mean times its size).

    Parameters
    ----------
    sampler, n, lo, hi
        The sampler, its points per set, and the block.
    resolution, method, tol, backend, precision
        As :func:`power_spectrum` (``method`` already decided, not ``"auto"``).

    Returns
    -------
    ndarray
    """
    if backend == "opencl":
        points = sampler.sample_device(n, realizations=range(lo, hi))
    else:
        points = sampler.sample(n, realizations=range(lo, hi))
    return power_spectrum(points, resolution, method, tol, backend, progress=False,
                          precision=precision) * float(hi - lo)


def expected_spectrum(sampler, n, realizations, resolution=256, method="auto", tol=None,
                      backend="opencl", client=None, checkpoint=None, progress=True, precision=None):
    """The expected power spectrum of a sampler: the mean periodogram of ``realizations``
    sets of ``n`` points, in blocks of realizations, here or on a Dask cluster.

    Parameters
    ----------
    sampler : Sampler or str
        A sampler, or a name (``make_sampler(name, d=2)``).
    n, realizations : int
    resolution, method, tol, backend, precision
        As :func:`power_spectrum` (``method="auto"`` is decided once for the whole sweep).
    client : dask.distributed.Client, optional
        Compute the blocks there (:mod:`clsamp.parallel`). The blocks' sums are added in
        block order, so the result is the same bits here and on any cluster (of one kind
        of device: the direct spectrum's fused arithmetic may differ across devices).
    checkpoint : str or Path, optional
        A folder keeping every finished block, to resume a stopped sweep.
    progress : bool

    Returns
    -------
    P : ndarray (R, R) (or (R,) in 1-D)

    Examples
    --------
    >>> import clsamp
    >>> P = clsamp.expected_spectrum("jittered", 256, 8, resolution=32, progress=False)
    >>> P.shape, float(P[16, 16])
    ((32, 32), 256.0)
    """
    from .samplers import Sampler, make_sampler
    check_choice(backend, "backend", BACKENDS)
    if isinstance(sampler, str):
        sampler = make_sampler(sampler, d=2, backend=backend)
    elif not isinstance(sampler, Sampler):
        raise InvalidArgumentError(f"'sampler' must be a Sampler or a sampler name, got {sampler!r}")
    if sampler.d not in (1, 2, 3):
        raise InvalidArgumentError(
            f"'sampler' makes {sampler.d}-dimensional points; spectra need d = 1, 2 or 3")
    n = check_int(n, "n", minimum=1)
    if sampler.valid_n(n) != n:
        raise InvalidArgumentError(
            f"sampler {sampler.label!r} cannot make n={n} points; the nearest valid n is "
            f"{sampler.valid_n(n)}")
    realizations = check_int(realizations, "realizations", minimum=1)
    resolution = _check_resolution(resolution)
    runtime.check_host_bytes(3 * 8 * resolution ** sampler.d,
                             f"a power spectrum at resolution {resolution} in {sampler.d}-D")
    check_choice(method, "method", METHODS)
    precision = check_precision(precision, backend)
    if method == "auto":
        method = _choose_method((realizations, n, sampler.d), resolution, tol)
    tasks = [(sampler, n, lo, hi, resolution, method, tol, backend, precision)
             for lo, hi in parallel.block_ranges(realizations, n * resolution)]
    blocks, _ = parallel.run(spectrum_block, tasks, client=client, checkpoint=checkpoint,
                             progress=progress, desc=f"spectrum {sampler.label}")
    total = blocks[0].copy()
    for block in blocks[1:]:
        total += block
    return total / float(realizations)


def _sets_spectrum(sets, resolution, method, tol, backend, progress, precision):
    """Mean over sets of different sizes of |S_k|^2 / n_k: a batch per size, by counts."""
    groups = {}
    for k, s in enumerate(sets):
        groups.setdefault(s.shape[0], []).append(k)
    total = None
    for size in sorted(groups):
        members = groups[size]
        P = power_spectrum(np.stack([sets[k] for k in members]), resolution, method, tol, backend, progress,
                           precision)
        part = P * (len(members) / len(sets)) if len(groups) > 1 else P
        total = part if total is None else total + part
    return total


def _direct_seconds(r, n, resolution, d):
    """Rough cost of the exact sum at the direct path's rate on 2 CPU cores, plus twiddles."""
    # 2-D: the half plane u <= 0; 3-D: every (u, v, w)
    flops = 8.0 * r * n * resolution ** (d - 1) * {1: 1, 2: resolution / 2 + 1, 3: resolution}[d]
    return flops / 35e9 + r * n * resolution * d * 2e-9


def _fast_seconds(r, n, resolution, d, tol):
    sigma, width, _ = nufft_parameters(tol, d)
    grid = grid_size(resolution, sigma, width) ** d
    return r * (n * width**d * 2e-9 + grid * math.log2(grid) * 1e-9)


def _choose_method(shape, resolution, tol):
    r, n, d = shape
    direct = _direct_seconds(r, n, resolution, d)
    if tol is None:
        return "direct" if direct < 0.5 else "fast"
    return "direct" if direct <= _fast_seconds(r, n, resolution, d, max(tol, MIN_TOL)) else "fast"


def _progress(total, enabled, seconds, desc):
    if enabled and total > 1 and seconds > 2.0:
        from tqdm import tqdm
        return tqdm(total=total, desc=desc, unit="chunk")
    return None


# -- direct: NumPy reference ------------------------------------------------------------
def fixed_point(x):
    """x in [0, 1) as the 64-bit fixed-point fraction ⌊x·2^64⌋ (uint64), by exact steps.

    Parameters
    ----------
    x : array_like of float64
        Values in [0, 1).

    Returns
    -------
    ndarray of uint64
    """
    x = np.asarray(x, dtype=np.float64)
    s = x * 2.0**32
    h = np.floor(s)
    low = ((s - h) * 2.0**32).astype(np.uint64)
    return (h.astype(np.uint64) << np.uint64(32)) | low


def twiddles_reference(x, freqs):
    """e^{-2πi f x} for every coordinate x (shape (..., n)) and frequency f: (..., n, F).

    The NumPy reference of ``spectrum_twiddles``: phases reduced exactly in fixed point
    (f·X mod 2^64), and each twiddle the product of two exactly reduced factors
    e((f0 + 16q)X)·e(sX), as in the kernel.

    Parameters
    ----------
    x : array_like of float64
        (..., n) coordinates in [0, 1).
    freqs : array_like of int
        Consecutive integer frequencies (else InvalidArgumentError).

    Returns
    -------
    ndarray of complex128
    """
    freqs = np.asarray(freqs, dtype=np.int64)
    X = fixed_point(x)[..., None]
    count = freqs.size
    f0 = int(freqs[0])
    if not np.array_equal(freqs, np.arange(f0, f0 + count)):
        raise InvalidArgumentError("'freqs' must be consecutive integers")
    coarse = f0 + _FINE * np.arange(-(-count // _FINE), dtype=np.int64)
    fine = np.arange(_FINE, dtype=np.int64)

    def exact(f):
        theta = X * f.astype(np.uint64)        # wraps modulo 2^64: the exact phase reduction
        angle = theta.view(np.int64).astype(np.float64) * _PHASE
        return np.cos(angle) - 1j * np.sin(angle)

    tw = exact(coarse)[..., :, None] * exact(fine)[..., None, :]
    return tw.reshape(*tw.shape[:-2], -1)[..., :count]


def direct_reference(points, resolution):
    """The exact expected periodogram by the separable product in NumPy (complex128 GEMM).

    NumPy reference of the ``direct`` method: S_r = A_rᵀ B_r with the twiddle panels of
    :func:`twiddles_reference`, P = Σ_r |S_r|² / (r N); all R frequencies of every axis
    (no symmetry shortcut), one realization at a time.

    Parameters
    ----------
    points, resolution
        As :func:`power_spectrum` (d = 1, 2 or 3).

    Returns
    -------
    ndarray
        Laid out as :func:`power_spectrum`'s.
    """
    batch, _ = check_points(points, "points", d=(1, 2, 3))
    resolution = _check_resolution(resolution)
    r, n, d = batch.shape
    freqs = frequencies(resolution)
    P = np.zeros((resolution,) * d)
    for k in range(r):
        A = twiddles_reference(batch[k, :, 0], freqs)
        if d == 1:
            S = A.sum(axis=0)
        elif d == 2:
            S = A.T @ twiddles_reference(batch[k, :, 1], freqs)
        else:
            S = _sum3(A, twiddles_reference(batch[k, :, 1], freqs),
                      twiddles_reference(batch[k, :, 2], freqs))
        P += S.real**2 + S.imag**2
    return P / (r * n)


def _sum3(A, B, C):
    """S(u, v, w) = Σ_k A[k, u] B[k, v] C[k, w]: the products A[k, u] B[k, v] of a group of
    u as one (g R × N) panel, times C in one GEMM (groups of at most 64 MiB of panel)."""
    n, R = A.shape
    group = max(1, min(R, (64 << 20) // max(1, 16 * n * R)))
    out = np.empty((R, B.shape[1], C.shape[1]), dtype=np.complex128)
    for u0 in range(0, R, group):
        u1 = min(R, u0 + group)
        panel = (A[:, u0:u1, None] * B[:, None, :]).reshape(n, -1)
        out[u0:u1] = (panel.T @ C).reshape(u1 - u0, B.shape[1], C.shape[1])
    return out


def _direct3(batch, resolution, progress, precision):
    """The 3-D direct sum: each axis' twiddle panel from ``spectrum_twiddles`` into host
    memory (from ``spectrum_ff_twiddles`` in float-float), the products by :func:`_sum3` in
    the host's BLAS, a set and a chunk of points at a time."""
    (r, n, _), R = batch.shape, resolution
    points_per_chunk = min(n, runtime.fit(3 * 2 * R * 8 + 24, WORKING_SET))
    if precision == "double":
        twiddles = runtime.kernel("spectrum.cl", "spectrum_twiddles",
                                  {"SUPER": _SUPER, "KBLOCK": 128, "FINE": _FINE}, _MAD)
    queue, local = runtime.queue(), runtime.local_size(64)
    point_chunks = [(a, min(n, a + points_per_chunk)) for a in range(0, n, points_per_chunk)]
    bar = _progress(r * len(point_chunks), progress, _direct_seconds(r, n, R, 3), "spectrum (direct)")
    P = np.zeros((R, R, R))
    for k in range(r):
        S = np.zeros((R, R, R), dtype=np.complex128)
        for k0, k1 in point_chunks:
            nc = k1 - k0
            pts = _block(batch, k, k + 1, k0, k1)
            if precision == "float-float":
                panels = (spectrum_ff.twiddles(pts, -(R // 2), R, axis).get()[0, ..., 0] for axis in range(3))
                S += _sum3(*(spectrum_ff.to_complex(panel).T for panel in panels))
                if bar is not None:
                    bar.update(1)
                continue
            panels = [runtime.Output(None, host=np.empty((1, nc, 2, R))) for _ in range(3)]
            for axis, out in enumerate(panels):
                twiddles(queue, (_pad(nc, local), 1), (local, 1), pts.data, out.buffer, np.uint32(nc),
                         np.uint32(3), np.uint32(axis), np.int64(-(R // 2)), np.uint32(R), np.uint32(R))
            A, B, C = (panel.finish()[0] for panel in panels)
            S += _sum3(*(T[:, 0] + 1j * T[:, 1] for T in (A, B, C)))
            if bar is not None:
                bar.update(1)
        P += S.real**2 + S.imag**2
    if bar is not None:
        bar.close()
    return P / (r * n)


# -- direct: OpenCL ----------------------------------------------------------------------
def _pad(count, multiple):  # count rounded up to a multiple
    return -(-count // multiple) * multiple


def _block(batch, r0, r1, k0=0, k1=None):
    """Realizations r0..r1, points k0..k1 of the batch as a contiguous device array (a
    device batch stays on the device)."""
    if runtime.is_device_array(batch):
        return runtime.device_block(batch, r0, r1, k0, k1)
    return runtime.to_device(np.ascontiguousarray(batch[r0:r1, k0:k1]))


def _direct(batch, resolution, backend, progress, precision):
    if backend == "numpy":
        return direct_reference(batch, resolution)
    import pyopencl.array as cla
    if batch.shape[-1] == 3:
        return _direct3(batch, resolution, progress, precision)
    if precision == "float-float":
        return _direct_ff(batch, resolution, progress)
    if HOST_GEMM and batch.shape[-1] == 2 and runtime.shape().host_gemm:
        return _direct_host_gemm(batch, resolution, progress)
    queue = runtime.queue()
    r, n, d = batch.shape
    half = resolution // 2
    # u <= 0 only (P(-ω) = P(ω)); v over [-R/2, R/2] so that every mirrored (u, v) exists
    count_u = _pad(half + 1 if d == 2 else resolution, _TILE)
    count_v = _pad(resolution + 1, _TILE) if d == 2 else 0
    plane = count_u * max(count_v, 1)
    per_point = (count_u + count_v) * 16 + d * 8
    points_per_chunk = min(n, runtime.fit(per_point, WORKING_SET))
    reals_per_chunk = min(r, runtime.fit(per_point * points_per_chunk + plane * 16, WORKING_SET))
    defines = {"SUPER": _SUPER, "KBLOCK": 128, "FINE": _FINE}
    twiddles = runtime.kernel("spectrum.cl", "spectrum_twiddles", defines, _MAD)
    product = runtime.kernel("spectrum.cl", "spectrum_direct2" if d == 2 else "spectrum_direct1",
                             defines, _MAD)
    power_kernel = runtime.kernel("spectrum.cl", "spectrum_power", defines, _MAD)
    tile_group = runtime.shape().tile_group
    power = cla.zeros(queue, plane, np.float64)
    chunks = [(a, min(r, a + reals_per_chunk)) for a in range(0, r, reals_per_chunk)]
    point_chunks = [(a, min(n, a + points_per_chunk)) for a in range(0, n, points_per_chunk)]
    bar = _progress(len(chunks) * len(point_chunks), progress, _direct_seconds(r, n, resolution, d),
                    "spectrum (direct)")
    local = runtime.local_size(64)
    for r0, r1 in chunks:
        rc = r1 - r0
        S = cla.zeros(queue, rc * 2 * plane, np.float64)
        for k0, k1 in point_chunks:
            nc = k1 - k0
            pts = _block(batch, r0, r1, k0, k1)
            A = cla.empty(queue, rc * count_u * nc * 2, np.float64)
            glob = (_pad(nc, local), rc)
            twiddles(queue, glob, (local, 1), pts.data, A.data, np.uint32(nc), np.uint32(d),
                     np.uint32(0), np.int64(-half), np.uint32(count_u), np.uint32(_TILE))
            if d == 1:
                tiles = count_u // _TILE
                product(queue, (_pad(tiles, local), rc), (local, 1), A.data, S.data, np.uint32(nc),
                        np.uint32(tiles))
            else:
                B = cla.empty(queue, rc * count_v * nc * 2, np.float64)
                twiddles(queue, glob, (local, 1), pts.data, B.data, np.uint32(nc), np.uint32(d),
                         np.uint32(1), np.int64(-half), np.uint32(count_v), np.uint32(_TILE))
                tiles_u, tiles_v = count_u // _TILE, count_v // _TILE
                grid = (-(-tiles_v // _SUPER), -(-tiles_u // _SUPER))
                # PoCL's implicit vectorization across work-items fights the explicit double4
                # code: one work-item per group on the CPU, a row of them elsewhere
                group = (min(tile_group, local), 1)
                product(queue, (_pad(grid[0], group[0]), grid[1]), group, A.data, B.data, S.data,
                        np.uint32(nc), np.uint32(tiles_u), np.uint32(tiles_v), np.uint32(rc))
            if bar is not None:
                queue.finish()
                bar.update(1)
        power_kernel(queue, (_pad(plane, local),), (local,), S.data, power.data, np.uint32(plane),
                     np.uint32(rc), np.float64(1.0 / (r * n)))
    if bar is not None:
        bar.close()
    H = power.get()
    if d == 1:
        return H[:resolution]
    return _unfold(H.reshape(count_u, count_v), resolution)


def _direct_ff(batch, resolution, progress):
    """The 1-D and 2-D direct sums in float-float (:mod:`clsamp.spectrum_ff`): S(u, v) over
    the half plane u <= 0 on the device (a 1-D set as a 2-D one with u = 0 only), squared
    and summed over realizations on the host."""
    import pyopencl.array as cla
    (r, n, d), half = batch.shape, resolution // 2
    count_u, count_v = (half + 1, _pad(resolution + 1, spectrum_ff.LANES)) if d == 2 else (1, resolution)
    per_point = (count_u + count_v) * 16 + d * 8
    # (a work-item of the product loops ~1.02 times per point: llvmpipe's limit caps a chunk)
    points_per_chunk = min(n, runtime.fit(per_point, WORKING_SET), (runtime.loop_limit() or 2**62) // 2)
    reals_per_chunk = min(r, runtime.fit(per_point * points_per_chunk + count_u * count_v * 16, WORKING_SET))
    chunks = [(a, min(r, a + reals_per_chunk)) for a in range(0, r, reals_per_chunk)]
    point_chunks = [(a, min(n, a + points_per_chunk)) for a in range(0, n, points_per_chunk)]
    bar = _progress(len(chunks) * len(point_chunks), progress, 10 * _direct_seconds(r, n, resolution, d),
                    "spectrum (direct, float-float)")
    H = np.zeros((count_u, count_v))
    for r0, r1 in chunks:
        lanes = spectrum_ff.LANES
        S = cla.zeros(runtime.queue(), (r1 - r0, count_u, count_v // lanes, 4, lanes), np.float32)
        for k0, k1 in point_chunks:
            pts = _block(batch, r0, r1, k0, k1)
            # (1-D: u = 0 only, a panel of ones; the frequencies along v)
            A = spectrum_ff.twiddles(pts, -half if d == 2 else 0, count_u, 0)
            spectrum_ff.accumulate(A, spectrum_ff.twiddles(pts, -half, count_v, d - 1, lanes), S)
            if bar is not None:
                bar.update(1)
        H += spectrum_ff.power(S.get())
    if bar is not None:
        bar.close()
    H /= r * n
    return H[0] if d == 1 else _unfold(H, resolution)


def _unfold(H, resolution):
    """The whole spectrum from its half u <= 0 (rows u = -R/2..0, columns v = -R/2..R/2)."""
    half = resolution // 2
    P = np.empty((resolution, resolution))
    P[:half + 1] = H[:half + 1, :resolution]
    P[half + 1:] = H[half - 1:0:-1, resolution:0:-1]
    return P


def _direct_host_gemm(batch, resolution, progress):
    """The 2-D direct sum on a CPU device: ``spectrum_twiddles`` panels in host memory, then
    the products in the host's BLAS (docs/performance.md says why), over a quarter plane.

    With a_k(u) = e^{-2πiux_k} and b_k(v) = e^{-2πivy_k} for u, v in [0, R/2], the four real
    products G1 = Re a·Re b, G2 = Im a·Im b, G3 = Re a·Im b, G4 = Im a·Re b (one GEMM of
    the panels side by side) give both
    S(u, v) = G1 - G2 + i(G3 + G4) and S(u, -v) = G1 + G2 + i(G4 - G3); P(-u, -v) = P(u, v)
    gives the rest: half the products of the half plane u <= 0."""
    (r, n, _), half = batch.shape, resolution // 2
    count = half + 1                                 # u, v in [0, R/2]
    per_point = 2 * count * 16 + 16
    points_per_chunk = min(n, runtime.fit(per_point, WORKING_SET))
    reals_per_chunk = min(r, runtime.fit(per_point * points_per_chunk + 4 * count * count * 8,
                                         WORKING_SET))
    twiddles = runtime.kernel("spectrum.cl", "spectrum_twiddles",
                              {"SUPER": _SUPER, "KBLOCK": 128, "FINE": _FINE}, _MAD)
    queue, local = runtime.queue(), runtime.local_size(64)
    chunks = [(a, min(r, a + reals_per_chunk)) for a in range(0, r, reals_per_chunk)]
    point_chunks = [(a, min(n, a + points_per_chunk)) for a in range(0, n, points_per_chunk)]
    bar = _progress(len(chunks) * len(point_chunks), progress, _direct_seconds(r, n, resolution, 2),
                    "spectrum (direct)")
    plus = np.zeros((count, count))                  # Σ_r |S(u, v)|², u, v in [0, R/2]
    minus = np.zeros((count, count))                 # Σ_r |S(u, -v)|²
    m = np.uint32(count)
    # the panels' memory, reused by every chunk: page faults once, not once a chunk
    scratch = [np.empty(reals_per_chunk * points_per_chunk * 2 * count) for _ in range(2)]
    for r0, r1 in chunks:
        rc = r1 - r0
        G = np.zeros((rc, 2 * count, 2 * count))     # [[G1, G3], [G4, G2]] per set
        for k0, k1 in point_chunks:
            nc = k1 - k0
            pts = _block(batch, r0, r1, k0, k1)
            shape = (rc, nc, 2, count)
            panels = [runtime.Output(None, host=memory[:rc * nc * 2 * count].reshape(shape))
                      for memory in scratch]
            for axis, out in enumerate(panels):     # one tile of all frequencies: contiguous writes
                twiddles(queue, (_pad(nc, local), rc), (local, 1), pts.data, out.buffer, np.uint32(nc),
                         np.uint32(2), np.uint32(axis), np.int64(0), m, m)
            A, B = (panel.finish() for panel in panels)
            for k in range(rc):                     # one GEMM: (Re a | Im a)ᵀ (Re b | Im b)
                G[k] += A[k].reshape(nc, 2 * count).T @ B[k].reshape(nc, 2 * count)
            if bar is not None:
                bar.update(1)
        g1, g2 = G[:, :count, :count], G[:, count:, count:]
        g3, g4 = G[:, :count, count:], G[:, count:, :count]
        plus += np.sum((g1 - g2) ** 2 + (g3 + g4) ** 2, axis=0)
        minus += np.sum((g1 + g2) ** 2 + (g4 - g3) ** 2, axis=0)
    if bar is not None:
        bar.close()
    # the half plane u <= 0 that _unfold takes: P(-u, v) = P(u, -v)
    H = np.empty((count, resolution + 1))
    H[:, :half + 1] = plus[::-1, ::-1]               # v = -R/2 .. 0
    H[:, half:] = minus[::-1]                        # v = 0 .. R/2
    return _unfold(H / (r * n), resolution)


# -- fast: OpenCL spreading, host FFT --------------------------------------------------
def _accumulate_power(grids, resolution, total):
    """Add Σ_r |FFT(grid_r)|² at the frequencies [-R/2, R/2] (last axis >= 0) to ``total``.

    In 2-D and 3-D only the frequencies kept along the last axis go through the transforms
    of the others, and in 3-D only the planes |kx| <= R/2 through the last one; only the
    rows |kx| <= R/2 are squared and summed."""
    # scipy.fft rather than numpy.fft for its ``workers``; imported here to keep it out of
    # `import clsamp`
    import scipy.fft as fft
    options = {"workers": os.cpu_count() or 1}
    half = resolution // 2
    M = grids.shape[-1]
    F = fft.rfft(grids, axis=-1, **options)[..., :half + 1]
    if grids.ndim == 4:
        F = fft.fft(F, axis=-2, overwrite_x=True, **options)
        F = np.concatenate([F[:, :, M - half:], F[:, :, :half + 1]], axis=2)   # ky = -R/2 .. R/2
    if grids.ndim >= 3:
        F = fft.fft(F, axis=1, overwrite_x=True, **options)
        _add_squares(F[:, M - half:], total[:half])              # kx = -R/2 .. -1
        _add_squares(F[:, :half + 1], total[half:])              # kx = 0 .. R/2
    else:
        _add_squares(F, total)


def _add_squares(F, total):
    """total += Σ_r |F_r|² for complex F (r, ..., m) into a longdouble ``total``: the sum
    over realizations is where float64 would lose ulps (all its terms have one sign)."""
    for part in F:
        parts = part.view(np.float64)                      # (..., 2m): re, im interleaved
        squares = parts * parts
        total += squares[..., 0::2] + squares[..., 1::2]


def _fast(batch, resolution, tol, backend, progress, precision="double"):
    r, n, d = batch.shape
    sigma, width, beta = nufft_parameters(tol, d)
    M = grid_size(resolution, sigma, width)
    half = resolution // 2
    # Σ_r |G_r|² for kx (and ky in 3-D) in [-R/2, R/2], the last axis in [0, R/2]
    total = np.zeros((resolution + 1,) * (d - 1) + (half + 1,), np.longdouble)
    size = M**d
    if backend == "opencl":
        import pyopencl.array as cla
        queue = runtime.queue()
        device = runtime.current_device()
        defines = {"DIM": d, "WIDTH": width}
        if precision == "double":
            spread = runtime.kernel("nufft.cl", "spectrum_spread", defines, _MAD)
            sum_copies = runtime.kernel("nufft.cl", "spectrum_sum_copies", defines, _MAD)
        local = runtime.local_size(64)
        # a work-item spreads a block of points onto its own grid copy: enough of them to
        # keep every compute unit busy, never blocks of fewer than 1024 points; in 3-D a
        # copy (zeroed, then summed) must save its size in spreading (docs/performance.md)
        most = n // 1024 if d < 3 else n * width**3 // (8 * size)
        blocks = max(1, min(-(-4 * device.compute_units // r), most))
        while blocks > 1 and (blocks + 1) * size * 8 > WORKING_SET:
            blocks //= 2
        per_real = 8 * size * (blocks + 1 if blocks > 1 else 1) + 8 * n * d
    else:
        per_real = 8 * size + 8 * n * d
    reals_per_chunk = min(r, runtime.fit(per_real, WORKING_SET))
    chunks = [(a, min(r, a + reals_per_chunk)) for a in range(0, r, reals_per_chunk)]
    bar = _progress(len(chunks), progress, _fast_seconds(r, n, resolution, d, tol), "spectrum (fast)")
    for r0, r1 in chunks:
        rc = r1 - r0
        if backend == "numpy":
            grids = spread_reference(batch[r0:r1], M, width, beta)
        else:
            pts = _block(batch, r0, r1)
            if precision == "float-float":
                grids = spectrum_ff.spread(pts, M, width, beta, blocks)
            else:
                # the grids the FFT reads are written into host memory (on a CPU device in place)
                # (read-write: with one block the spreading adds into it)
                grids = runtime.Output(None, host=np.empty((rc,) + (M,) * d), read_write=True)
                if blocks > 1:
                    copies = cla.empty(queue, rc * blocks * size, np.float64)
                    spread(queue, (blocks, rc), (1, 1), pts.data, copies.data, np.uint32(n), np.uint32(M),
                           np.uint32(blocks), np.float64(beta))
                    sum_copies(queue, (_pad(size, local), rc), (local, 1), copies.data, grids.buffer,
                               np.uint32(size), np.uint32(blocks))
                else:
                    spread(queue, (1, rc), (1, 1), pts.data, grids.buffer, np.uint32(n), np.uint32(M),
                           np.uint32(1), np.float64(beta))
                grids = grids.finish()
        _accumulate_power(grids, resolution, total)
        if bar is not None:
            bar.update(1)
    if bar is not None:
        bar.close()
    # deconvolved in longdouble, rounded once
    psi = kernel_transform(np.arange(-half, half + 1), M, width, beta, extended=True)
    if d == 1:
        Q = (total / psi[half:] ** 2).astype(np.float64)          # k = 0 .. R/2
        P = np.concatenate([Q[half:0:-1], Q[:half]])       # k = -R/2 .. R/2 - 1
        return P / (r * n)
    if d == 3:
        Q = (total / (psi[:, None, None] * psi[None, :, None] * psi[None, None, half:]) ** 2)
        Q = Q.astype(np.float64)                            # kz = 0 .. R/2
        P = np.empty((resolution,) * 3)
        P[:, :, half:] = Q[:resolution, :resolution, :half]
        P[:, :, :half] = Q[resolution:0:-1, resolution:0:-1, half:0:-1]   # P(-ω) = P(ω)
        return P / (r * n)
    Q = (total / (psi[:, None] * psi[None, half:]) ** 2).astype(np.float64)   # ky = 0..R/2
    P = np.empty((resolution, resolution))
    P[:, half:] = Q[:resolution, :half]                     # ky >= 0
    # ky < 0: P(kx, ky) = Q(-kx, -ky); row of -kx in Q is R - i, column of -ky is half - (j - half)
    P[:, :half] = Q[resolution:0:-1, half:0:-1]
    return P / (r * n)
