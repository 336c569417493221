"""The type-1 non-uniform FFT behind the fast power spectrum (``spectrum.power_spectrum``,
``method="fast"``): how the kernel width and oversampling follow from a tolerance, the
"exponential of semicircle" kernel φ and its Fourier transform ψ̂, and the NumPy
reference of the spreading kernel (``kernels/nufft.cl``). Barnett, Magland & af
Klinteberg, "A parallel non-uniform fast Fourier transform library based on an
'exponential of semicircle' kernel", SIAM J. Sci. Comput. 41 (2019).
"""

import functools
import math

import numpy as np

from .errors import InvalidArgumentError

MIN_TOL = 5e-13          # the fast path's floor in 2-D (w = 16, σ = 2: 1.7e-13 worst case)
COST_RESOLUTION = {1: 256, 2: 256, 3: 64}   # R of the case nufft_parameters' cost model weighs


SIGMAS = (1.25, 1.5, 2.0)     # oversampling factors the fast path chooses from
MAX_WIDTH = 16                # nufft.cl holds a point's weights on one axis in 16 doubles


@functools.cache
def kernel_error(sigma, width):
    """Worst relative error of one point's Fourier sum after spreading, FFT and deconvolution.

    Computed, not bounded: points at 64 offsets in a cell, spread, transformed and
    deconvolved on M = 128σ nodes; max |S̃(k)/S(k) - 1| over |k| <= M/(2σ). N points:
    |P̃ - P| <= (2e + e²)·N (the error depends on M/R, >= σ in use, not on R).

    Parameters
    ----------
    sigma : float
        The oversampling factor σ.
    width : int
        The kernel's width w in grid nodes.

    Returns
    -------
    float
        e.
    """
    beta = _beta(sigma, width)
    M = int(round(128 * sigma))
    half = int(M / (2 * sigma))
    x = (np.arange(64) + 0.5) / (64 * M) + 0.37
    grids = spread_reference(x[:, None, None], M, width, beta)
    k = np.arange(-half, half + 1)
    F = np.fft.fft(grids, axis=-1)[:, k % M] / kernel_transform(k, M, width, beta)
    return float(np.abs(F * np.exp(2j * np.pi * np.outer(x, k)) - 1.0).max())


def _beta(sigma, width):
    # finufft's shape parameter: 2.30 w for σ = 2, 0.97 π w (1 - 1/(2σ)) otherwise
    return 2.30 * width if sigma == 2.0 else 0.97 * math.pi * width * (1.0 - 0.5 / sigma)


def nufft_parameters(tol, d=2, sigma=None):
    """(σ, w, β) of the spreading for a ``d``-dimensional spectrum with error below ``tol·N``.

    For each σ in ``SIGMAS`` (or the one given) the smallest w <= 16 whose measured
    :func:`kernel_error` e bounds the error in the worst case, N coincident points:
    |S̃| <= (1 + e)^d |S|, so |P̃ - P| <= ((1 + e)^{2d} - 1)·N, required <= tol/1.2 (a
    margin for offsets between the measured ones). Among those, the σ with the lowest
    modelled cost (spreading ~ w^d per point against the FFT ~ (σR)^d per realization, in
    the proportions of the benchmark case, 4096 points at R = 256 in 1-D and 2-D, R = 64 in
    3-D). In 3-D the floor is about 7e-13 (six factors of 1 + e instead of four).

    Parameters
    ----------
    tol : float
        The error allowed, relative to N.
    d : int
        1, 2 or 3.
    sigma : float, optional
        Use this σ instead of choosing among ``SIGMAS``.

    Returns
    -------
    sigma : float
    width : int
    beta : float
        The kernel's shape parameter.

    Raises
    ------
    InvalidArgumentError
        ``tol`` below what a width of at most 16 reaches.
    """
    best = None
    for s in (SIGMAS if sigma is None else (sigma,)):
        for width in range(2, MAX_WIDTH + 1):
            e = kernel_error(s, width)
            if (1.0 + e) ** (2 * d) - 1.0 <= tol / 1.2:
                cost = 4096 * width**d * 3e-9 + (s * COST_RESOLUTION[d]) ** d * 6e-9
                if best is None or cost < best[0]:
                    best = (cost, s, width)
                break
    if best is None:
        raise InvalidArgumentError(
            f"'tol' {tol:g} is below what the fast path reaches in {d}-D (about {MIN_TOL:g}); "
            "use method='direct'")
    _, s, width = best
    return s, width, _beta(s, width)


def _smooth(m):
    """The smallest even 2^a 3^b 5^c >= m (sizes pocketfft transforms fastest)."""
    m = max(2, int(m))
    while True:
        k = m
        for p in (2, 3, 5):
            while k % p == 0:
                k //= p
        if k == 1 and m % 2 == 0:
            return m
        m += 1


def grid_size(resolution, sigma, width):
    """Nodes per axis of the oversampled grid: the smallest FFT-friendly size >= σR and >= 2w.

    Parameters
    ----------
    resolution : int
        The spectrum's R.
    sigma : float
    width : int

    Returns
    -------
    int
        An even 2^a 3^b 5^c.

    Examples
    --------
    >>> grid_size(256, 1.25, 8)
    320
    """
    return _smooth(max(math.ceil(sigma * resolution), 2 * width))


def es_kernel(z, beta):
    """φ(z) = exp(β(√(1 - z²) - 1)) on |z| <= 1, zero outside (Barnett et al. 2019).

    Parameters
    ----------
    z : array_like of float
    beta : float

    Returns
    -------
    ndarray of float64
        Evaluated as exp(-β z² / (1 + √(1 - z²))), which does not cancel.
    """
    z = np.asarray(z, dtype=np.float64)
    inside = np.abs(z) <= 1.0
    z2 = np.where(inside, z * z, 1.0)
    return np.where(inside, np.exp(-beta * z2 / (1.0 + np.sqrt(1.0 - z2))), 0.0)  # no cancellation


def kernel_transform(freqs, grid, width, beta, extended=False):
    """ψ̂(k) = (w/2)∫_{-1}^{1} φ(z) cos(πkwz/M) dz: what spreading multiplies S(k) by.

    Every point's error at k shares ψ̂(k)'s, so it adds up over the N points (at k = 0
    always): computed to about an ulp. With z = sin θ the integrand
    exp(-2β sin²(θ/2)) cos θ cos(πkw sin θ / M) is smooth, and 2w + 60 Gauss-Legendre
    nodes in extended precision (where NumPy's longdouble has it, as on x86-64 Linux)
    give it correctly rounded to float64 or one ulp off.

    Parameters
    ----------
    freqs : array_like of int
        Frequencies k.
    grid : int
        M, nodes per axis.
    width : int
    beta : float
    extended : bool
        Return longdouble values instead of float64.

    Returns
    -------
    ndarray
        ψ̂ at every frequency.
    """
    x, weight = _gauss_legendre(2 * width + 60)
    pi = np.arccos(np.longdouble(-1.0))
    theta, weight = x * (pi / 2), weight * (pi / 2)
    phi = np.exp(-2 * np.longdouble(beta) * np.sin(theta / 2) ** 2) * np.cos(theta)
    freqs = np.asarray(freqs, dtype=np.float64).astype(np.longdouble)
    phase = np.cos(pi * width / grid * np.outer(freqs, np.sin(theta)))
    transform = np.longdouble(0.5) * width * (phase @ (weight * phi))
    return transform if extended else transform.astype(np.float64)


@functools.cache
def _gauss_legendre(q):
    """Gauss-Legendre nodes and weights on [-1, 1] in longdouble: NumPy's nodes, refined by
    Newton's method on the three-term recurrence of P_q."""
    def legendre(x):                      # P_q(x) and P_q'(x)
        p0, p1 = np.ones_like(x), x
        for m in range(2, q + 1):
            p0, p1 = p1, ((2 * m - 1) * x * p1 - (m - 1) * p0) / m
        return p1, q * (x * p1 - p0) / (x * x - 1)
    x = np.polynomial.legendre.leggauss(q)[0].astype(np.longdouble)
    for _ in range(3):
        p, dp = legendre(x)
        x = x - p / dp
    _, dp = legendre(x)
    return x, 2 / ((1 - x * x) * dp * dp)


# -- spreading, NumPy reference ----------------------------------------------------------
def spread_reference(points, grid, width, beta):
    """Spread a batch (r, n, d) onto r periodic grids of ``grid`` nodes per axis.

    NumPy reference of ``spectrum_spread``: node j of an axis gets φ((j - xM)·2/w) from every
    point within w/2 nodes, a 2-D or 3-D node the product of its axes' weights (in 3-D
    (φ_x φ_y)·φ_z, the kernel's order).

    Parameters
    ----------
    points : array_like
        (r, n, d) points in [0, 1)^d, d = 1, 2 or 3.
    grid : int
        M, nodes per axis.
    width : int
    beta : float

    Returns
    -------
    ndarray of float64
        (r, M), (r, M, M) or (r, M, M, M).
    """
    batch = np.asarray(points, dtype=np.float64)
    r, n, d = batch.shape
    M = int(grid)
    offsets = np.arange(width)
    out = np.zeros((r,) + (M,) * d)
    for k in range(r):
        t = batch[k] * M
        first = np.ceil(t - 0.5 * width).astype(np.int64)          # (n, d)
        nodes = first[:, :, None] + offsets                        # (n, d, w)
        weights = es_kernel((nodes - t[:, :, None]) * (2.0 / width), beta)
        nodes %= M
        if d == 1:
            out[k] = np.bincount(nodes[:, 0].ravel(), weights[:, 0].ravel(), minlength=M)
        elif d == 2:
            flat = nodes[:, 0, :, None] * M + nodes[:, 1, None, :]
            w2 = weights[:, 0, :, None] * weights[:, 1, None, :]
            out[k] = np.bincount(flat.ravel(), w2.ravel(), minlength=M * M).reshape(M, M)
        else:
            step = max(1, 2**20 // width**3)               # points per bincount: bounded memory
            for a in range(0, n, step):
                nd, wt = nodes[a:a + step], weights[a:a + step]
                flat = (nd[:, 0, :, None, None] * M + nd[:, 1, None, :, None]) * M \
                    + nd[:, 2, None, None, :]
                w3 = (wt[:, 0, :, None] * wt[:, 1, None, :])[:, :, :, None] * wt[:, 2, None, None, :]
                out[k] += np.bincount(flat.ravel(), w3.ravel(), minlength=M**3).reshape(M, M, M)
    return out
