"""Power spectra in float-float, for devices without fp64: the kernels of
``kernels/spectrum_ff.cl`` and the error bound of the direct sum; :func:`spread` is the
fast (NUFFT) path's spreading, whose error, with the FFT in float64 on the host, stays
within ``tol``·N for ``tol`` >= :data:`FAST_MIN_TOL` (measured, tests/test_float_float.py).

:func:`clsamp.spectrum.power_spectrum` runs these with ``precision="float-float"`` (the
default on a device without fp64). Phases are exact integers (the coordinate as the 64-bit
fixed-point fraction X = ⌊x·2^64⌋, the phase f·X modulo 2^64), each twiddle comes from two
tables of float-float sines and cosines and a two-term series, and the products and sums are
float-float (``kernels/float_float.h``); the host squares the sums in float64.

Error bound (u = 2^-24; the float-float operations' relative errors are at most 3u² for
an addition and 5u² for a product, Joldes, Muller & Popescu 2017). A table entry is within
u² + 2^-53 of e(t) and the two-term series within 4e-17; the two complex products that make
a twiddle and the one of a_k(u)·b_k(v) keep every term within 128u² of its value (256u²
is taken). The kernel sums blocks of 64 terms apart and then the M block sums (M <=
⌈N/64⌉ + the chunks of points, one below millions of points): each addition errs by at
most 3u² times the partial sum, <= 1.5u²·64·N over the blocks and 3u²·N·M over their sums,
times √2 for a complex sum. So |ΔS| <= u²·N·(400 + 5M) and, with |S| <= N and the float64
squaring on the host,

    |ΔP(ω)| <= (2|S||ΔS| + |ΔS|²) / N <= 2.01·u²·N·(400 + 5M),

3.5e-12·N at N = 1024 and 1.2e-11·N at N = 16384 (:func:`error_bound`). A batch's mean
keeps the bound. Measured errors are random-signed and far below it (docs/performance.md).

References
----------
.. [1] M. Joldes, J.-M. Muller, V. Popescu, "Tight and rigorous error bounds for basic
   building blocks of double-word arithmetic", ACM TOMS 44(2), 2017.
"""

import numpy as np

from . import runtime
from .errors import InvalidArgumentError
from .float_float import U2, argument, exp_coefficients, split

__all__ = ["sincos_tables", "error_bound", "twiddles", "accumulate", "power", "to_complex", "spread",
           "FAST_MIN_TOL"]

FAST_MIN_TOL = 1e-11   # the fast path's floor in float-float (tests/test_float_float.py)

BLOCK = 64             # terms per partial sum, as BLOCK in spectrum_ff.cl
LANES = 8              # frequencies v a work-item of spectrum_ff_product (float8)


def check_fast(d, method, tol):
    """Refuse, in one line naming the argument, what the float-float fast path does not do:
    3-D (the float-float spreading is 1-D and 2-D; 3-D is direct) and tolerances below
    :data:`FAST_MIN_TOL`.

    Parameters
    ----------
    d : int
        The points' dimension.
    method : str
        As :func:`clsamp.spectrum.power_spectrum` takes it.
    tol : float or None

    Raises
    ------
    InvalidArgumentError

    Examples
    --------
    >>> check_fast(2, "fast", 1e-6)
    """
    if d == 3 and method == "fast":
        raise InvalidArgumentError("'method' 'fast' in float-float computes 1-D and 2-D spectra; a 3-D "
                                   "spectrum in float-float is 'direct'")
    if method == "fast" and tol is not None and tol < FAST_MIN_TOL:
        raise InvalidArgumentError(f"'tol' must be >= {FAST_MIN_TOL:g} for method='fast' in float-float; "
                                   f"got {tol:g}")


def sincos_tables():
    """The two tables of the kernel's twiddles: e(i/2^10) and e(j/2^20), i, j < 1024.

    Returns
    -------
    ndarray of float32, shape (2, 1024, 4)
        (cos hi, cos lo, sin hi, sin lo) of 2π·i/2^10 (first table) and 2π·j/2^20 (second),
        from float64 ``cos``/``sin`` split into float-float pairs.
    """
    t = np.arange(1024, dtype=np.float64)
    angles = 2.0 * np.pi * np.stack([t / 2.0**10, t / 2.0**20])
    return np.concatenate([split(np.cos(angles)), split(np.sin(angles))], axis=-1)


def error_bound(n):
    """The largest difference between the float-float and the exact periodogram of a set
    of ``n`` points (or the mean over sets of ``n``), at any frequency.

    Parameters
    ----------
    n : int

    Returns
    -------
    float
        2.01·u²·n·(400 + 5M), u = 2^-24 and M = ⌈n/64⌉ + 1 (the module's docstring
        derives it).

    Examples
    --------
    >>> f"{error_bound(1024) / 1024:.2g}"
    '3.5e-12'
    """
    blocks = -(-n // BLOCK) + 1
    return 2.01 * U2 * n * (400.0 + 5.0 * blocks)


def _defines():
    delta = split(2.0 * np.pi * 2.0**-20)
    return {"DELTA_HI": _literal(delta[0]), "DELTA_LO": _literal(delta[1]), "BLOCK": BLOCK}


def _literal(value):
    return f"{float(value).hex()}f"


def twiddles(points, f0, count, axis, tile=1):
    """Twiddles e^{-2πi f x_k} of one axis of a block of points, on the device.

    Parameters
    ----------
    points : pyopencl.array.Array
        (r, n, d) float64 points in [0, 1), contiguous (read as bit patterns).
    f0, count : int
        The frequencies f0 .. f0 + count - 1 (count a multiple of ``tile``).
    axis : int
        The coordinate.
    tile : int, optional
        Frequencies a panel (8 for the B side of :func:`accumulate`).

    Returns
    -------
    pyopencl.array.Array
        (r, count / tile, n, 4, tile) float32, the parts (re hi, re lo, im hi, im lo).
    """
    import pyopencl.array as cla
    r, n, d = points.shape
    coarse, fine = (runtime.table(("spectrum_ff_sincos", level), lambda level=level: sincos_tables()[level],
                                  np.float32) for level in (0, 1))
    kernel = runtime.kernel("spectrum_ff.cl", "spectrum_ff_twiddles", _defines())
    out = cla.empty(runtime.queue(), (r, count // tile, n, 4, tile), np.float32)
    local = runtime.local_size(64)
    kernel(runtime.queue(), (-(-n // local) * local, r), (local, 1), points.data, out.data,
           coarse.data, fine.data, np.uint32(n), np.uint32(d), np.uint32(axis), np.int64(f0),
           np.uint32(count), np.uint32(tile))
    return out


def accumulate(A, B, S):
    """S[r, u, v] += Σ_k A[r, u, k]·B[r, v, k] in complex float-float, on the device.

    Parameters
    ----------
    A, B : pyopencl.array.Array
        Twiddle panels from :func:`twiddles`: (r, count_u, n, 4, 1) and
        (r, count_v / 8, n, 4, 8).
    S : pyopencl.array.Array
        (r, count_u, count_v / 8, 4, 8) float32, added to in place (:func:`power` reads it).
    """
    r, count_u, n = A.shape[:3]
    tiles_v = B.shape[1]
    kernel = runtime.kernel("spectrum_ff.cl", "spectrum_ff_product", _defines())
    local = runtime.local_size(64)
    kernel(runtime.queue(), (-(-tiles_v // local) * local, count_u, r), (local, 1, 1), A.data, B.data,
           S.data, np.uint32(n), np.uint32(count_u), np.uint32(tiles_v))


def to_complex(pairs):
    """Complex float-float values (last axis (re hi, re lo, im hi, im lo)) as complex128.

    Parameters
    ----------
    pairs : ndarray of float32, shape (..., 4)

    Returns
    -------
    ndarray of complex128
    """
    w = pairs.astype(np.float64)
    return (w[..., 0] + w[..., 1]) + 1j * (w[..., 2] + w[..., 3])


def power(S):
    """Σ_r |S_r|² in float64 of the sums :func:`accumulate` made (read back to the host).

    Parameters
    ----------
    S : ndarray of float32, shape (r, count_u, tiles, 4, lanes)

    Returns
    -------
    ndarray of float64, shape (count_u, tiles·lanes)
    """
    r, count_u, tiles, _, lanes = S.shape
    z = to_complex(np.swapaxes(S, -1, -2).reshape(r, count_u, tiles * lanes, 4))
    return np.sum(z.real**2 + z.imag**2, axis=0)


def spread(points, M, width, beta, blocks):
    """The NUFFT's spreading in float-float (``spectrum_spread_ff``): the grids of a block of
    sets, read back as float64.

    Parameters
    ----------
    points : pyopencl.array.Array
        (r, n, d) float64 points, d = 1 or 2, contiguous (read as bit patterns).
    M, width, beta : int, int, float
        Nodes per axis, the kernel's width and shape (:func:`clsamp.nufft.nufft_parameters`).
    blocks : int
        Grid copies a set's points are split over (one work-item each).

    Returns
    -------
    ndarray of float64, shape (r, M) or (r, M, M)
        Each node's float-float sum, hi + lo.
    """
    import pyopencl.array as cla
    r, n, d = points.shape
    q = runtime.queue()
    size = M ** d
    defines = {**_defines(), "DIM": d, "WIDTH": width}
    coef = runtime.table("float_float exp", exp_coefficients, np.float32)
    limit = runtime.loop_limit()
    if limit is not None:
        # llvmpipe's limit: a work-item's points times the loops a point takes
        blocks = max(blocks, -(-n * 2 * (width * width + 30 * width) // limit))
        if r * blocks * size * 8 > 2**28:
            runtime.require_short_loops("the float-float fast spectrum of this many points")
    copies = cla.zeros(q, (r, blocks, size, 2), np.float32)
    runtime.kernel("spectrum_ff.cl", "spectrum_spread_ff", defines)(
        q, (blocks, r), (1, 1), points.data, copies.data, np.uint32(n), np.uint32(M), np.uint32(blocks),
        argument(beta), argument(2.0 / width), coef.data)
    if blocks > 1:
        out = cla.empty(q, (r, size, 2), np.float32)
        local = runtime.local_size(64)
        runtime.kernel("spectrum_ff.cl", "spectrum_sum_copies_ff", defines)(
            q, (-(-size // local) * local, r), (local, 1), copies.data, out.data, np.uint32(size),
            np.uint32(blocks))
        copies = out
    grids = copies.get().astype(np.float64)
    return (grids[..., 0] + grids[..., 1]).reshape((r,) + (M,) * d)
