"""Statistics of power spectra in any dimension: the radial mean and the anisotropy over
annuli (shells) around DC, and the check that an array is a spectrum as
:func:`clsamp.power_spectrum` lays them out (DC at index R/2 of every axis).
"""

import math

import numpy as np

from .errors import InvalidArgumentError
from .validation import check_real

__all__ = ["check_spectrum", "radial_mean", "anisotropy", "low_frequency_power"]


def check_spectrum(P, name="P", dims=(1, 2, 3)):
    """Check that ``P`` is a spectrum as :func:`power_spectrum` returns them.

    Parameters
    ----------
    P : ndarray
        (R,), (R, R), (R, R, R), ... (R,) * d: R even and at least 2, real, finite (else
        InvalidArgumentError).
    name : str
        The argument's name in the error message.
    dims : tuple of int or None
        The dimensions accepted (default 1, 2 and 3, what :func:`power_spectrum` makes);
        None for any.

    Returns
    -------
    ndarray
        ``P`` as float64.
    """
    if not isinstance(P, np.ndarray) or P.ndim < 1 or (dims is not None and P.ndim not in dims):
        shape = getattr(P, "shape", type(P).__name__)
        which = "a d-dimensional" if dims is None else "a " + (
            ", ".join(f"{k}-D" for k in dims[:-1]) + f" or {dims[-1]}-D")
        raise InvalidArgumentError(f"'{name}' must be {which} spectrum array, got {shape}")
    if len(set(P.shape)) != 1:
        raise InvalidArgumentError(
            f"'{name}' must have equal sides, square (R, R), cube (R, R, R), ..., got {P.shape}")
    if P.shape[0] < 2 or P.shape[0] % 2:
        raise InvalidArgumentError(f"'{name}' must have an even side >= 2, got {P.shape}")
    if P.dtype.kind not in "biuf":
        raise InvalidArgumentError(f"'{name}' must hold real numbers, got dtype {P.dtype}")
    P = np.asarray(P, dtype=np.float64)
    if not np.all(np.isfinite(P)):
        raise InvalidArgumentError(f"'{name}' contains NaN or infinite values")
    return P


def _annuli(P, bin_width):
    """Annulus index of every frequency, and the number of complete annuli."""
    bin_width = check_real(bin_width, "bin_width", minimum=0.0, open_minimum=True)
    R = P.shape[0]
    count = math.floor((R // 2) / bin_width - 0.5)
    if count < 1:
        raise InvalidArgumentError(
            f"'bin_width' {bin_width:g} leaves no complete annulus in a spectrum of side {R}")
    if count > P.size:
        raise InvalidArgumentError(
            f"'bin_width' {bin_width:g} makes {count:g} annuli, more than the spectrum's "
            f"{P.size} frequencies; at least {(R // 2) / (P.size + 1.5):.4g}")
    f = np.arange(-(R // 2), R // 2, dtype=np.float64)
    grids = np.meshgrid(*([f] * P.ndim), indexing="ij")
    rho = np.sqrt(sum(g * g for g in grids))
    index = np.floor(rho / bin_width + 0.5).astype(np.int64)
    index[rho == 0] = 0                     # DC is never averaged
    index[index > count] = 0                # annuli cut by the square's edge are left out
    return index, count


def radial_mean(P, bin_width=1.0):
    """Radially averaged power spectrum: the mean of P over annuli (shells in 3-D) around DC.

    Parameters
    ----------
    P : ndarray, shape (R,), (R, R), (R, R, R), ... (R,) * d
        A spectrum as :func:`clsamp.power_spectrum` lays them out (DC at index R/2 of
        every axis), in any dimension.
    bin_width : float
        Width Δ of the annuli in integer frequencies (default 1).

    Returns
    -------
    freqs : ndarray
        Centres bΔ of the annuli, b = 1, 2, ..., up to the last annulus that lies whole
        inside the square or cube (bΔ + Δ/2 <= R/2).
    values : ndarray
        Mean of P(ω) over bΔ - Δ/2 <= |ω| < bΔ + Δ/2. DC (b = 0) is excluded.

    Notes
    -----
    As in Lagae & Dutré 2008 and PSA (Heck et al. 2013); white noise gives 1 at every
    frequency. :func:`clsamp.spectrum.normalized_frequency` rescales ``freqs`` for comparing N.

    Examples
    --------
    >>> import clsamp
    >>> pts = clsamp.make_sampler("random", seed=3).sample(1024, realizations=8)
    >>> f, m = clsamp.radial_mean(clsamp.power_spectrum(pts, resolution=64))
    >>> f[:3], bool(abs(m.mean() - 1) < 0.05)
    (array([1., 2., 3.]), True)
    """
    P = check_spectrum(P, dims=None)
    index, count = _annuli(P, bin_width)
    sums = np.bincount(index.ravel(), P.ravel(), minlength=count + 1)
    counts = np.bincount(index.ravel(), minlength=count + 1)
    b = np.arange(1, count + 1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return b * float(bin_width), sums[1:] / counts[1:]


def anisotropy(P, bin_width=1.0):
    """Anisotropy of a spectrum of 2 or more dimensions per annulus (shell), in dB:
    10·log10(s² / m²).

    s² is the variance of P over the annulus (unbiased, divided by count - 1) and m its
    mean (:func:`radial_mean`): 0 dB is as anisotropic as one white-noise periodogram,
    and the expected spectrum of r white-noise realizations gives about -10·log10(r) dB.

    Parameters
    ----------
    P, bin_width
        As :func:`radial_mean`; P must have at least 2 dimensions (else
        InvalidArgumentError).

    Returns
    -------
    freqs, values : ndarray
        Annulus centres as in :func:`radial_mean`; anisotropy in dB (-inf where P is
        constant on the annulus, NaN where its mean is 0).

    References
    ----------
    Lagae & Dutré 2008; Heck, Schlömer & Deussen 2013 (see :func:`clsamp.power_spectrum`).

    Examples
    --------
    >>> import clsamp
    >>> pts = clsamp.make_sampler("random", seed=3).sample(1024, realizations=10)
    >>> f, a = clsamp.anisotropy(clsamp.power_spectrum(pts, resolution=64))
    >>> bool(abs(a[10:].mean() + 10) < 1.5)
    True
    """
    P = check_spectrum(P, dims=None)
    if P.ndim < 2:
        raise InvalidArgumentError(
            f"'P' must be a spectrum of 2 or more dimensions for anisotropy, got shape {P.shape}")
    index, count = _annuli(P, bin_width)
    flat = index.ravel()
    counts = np.bincount(flat, minlength=count + 1)
    mean = np.bincount(flat, P.ravel(), minlength=count + 1) / np.maximum(counts, 1)
    # two passes: the variance of nearly equal values (regular grids) without cancellation
    squares = np.bincount(flat, (P.ravel() - mean[flat]) ** 2, minlength=count + 1)
    with np.errstate(invalid="ignore", divide="ignore"):
        variance = squares[1:] / (counts[1:] - 1)
        values = 10.0 * np.log10(variance / mean[1:] ** 2)
    return np.arange(1, count + 1) * float(bin_width), values


def low_frequency_power(P, n):
    """The mean of a spectrum over the integer frequencies 0 < |k| < sqrt(n) / 2: 1 for
    white noise, near 0 for blue noise (the figure issue 37 compares optimizers by).

    Parameters
    ----------
    P : ndarray, shape (R,) * d
        As :func:`clsamp.power_spectrum` lays them out (DC at R/2), with
        R/2 >= sqrt(n) / 2.
    n : int
        Points per set.

    Returns
    -------
    float

    Examples
    --------
    >>> import clsamp
    >>> from clsamp.spectral_stats import low_frequency_power
    >>> pts = clsamp.make_sampler("random", seed=1).sample(256, realizations=8)
    >>> bool(abs(low_frequency_power(clsamp.power_spectrum(pts, resolution=32), 256) - 1) < 0.2)
    True
    """
    P = check_spectrum(P, dims=None)
    R = P.shape[0]
    if R // 2 < math.sqrt(n) / 2:
        raise InvalidArgumentError(f"'P' of side {R} holds no frequency up to sqrt({n}) / 2")
    f = np.arange(-(R // 2), R // 2, dtype=np.float64)
    grids = np.meshgrid(*([f] * P.ndim), indexing="ij")
    rho = np.sqrt(sum(g * g for g in grids))
    return float(P[(rho > 0) & (rho < 0.5 * math.sqrt(n))].mean())
