"""Transforms of uniform points for QMC: the standard normal's inverse CDF (``to_normal``),
exactly as the device computes it (``kernels/normal.h``), and the periodizing maps of the
lattice rules (``tent``, ``sidi``).

References
----------
.. [1] M. J. Wichura, "Algorithm AS 241: the percentage points of the normal
   distribution", Applied Statistics 37(3), 1988, 477-484.
"""

import numpy as np

from .errors import InvalidArgumentError

__all__ = ["to_normal", "tent", "sidi", "SMALLEST"]

SMALLEST = 2.0**-1022        # u = 0 is taken as this (the smallest normal double): finite z
BLOCK = 32768                # values a block of to_normal (its temporaries stay in L2)

# AS 241 (PPND16): numerator and denominator coefficients, highest degree first (Horner)
_A = (2.5090809287301226727e+3, 3.3430575583588128105e+4, 6.7265770927008700853e+4,
      4.5921953931549871457e+4, 1.3731693765509461125e+4, 1.9715909503065514427e+3,
      1.3314166789178437745e+2, 3.3871328727963666080e+0)
_B = (5.2264952788528545610e+3, 2.8729085735721942674e+4, 3.9307895800092710610e+4,
      2.1213794301586595867e+4, 5.3941960214247511077e+3, 6.8718700749205790830e+2,
      4.2313330701600911252e+1, 1.0)
_C = (7.74545014278341407640e-4, 2.27238449892691845833e-2, 2.41780725177450611770e-1,
      1.27045825245236838258e+0, 3.64784832476320460504e+0, 5.76949722146069140550e+0,
      4.63033784615654529590e+0, 1.42343711074968357734e+0)
_D = (1.05075007164441684324e-9, 5.47593808499534494600e-4, 1.51986665636164571966e-2,
      1.48103976427480074590e-1, 6.89767334985100004550e-1, 1.67638483018380384940e+0,
      2.05319162663775882187e+0, 1.0)
_E = (2.01033439929228813265e-7, 2.71155556874348757815e-5, 1.24266094738807843860e-3,
      2.65321895265761230930e-2, 2.96560571828504891230e-1, 1.78482653991729133580e+0,
      5.46378491116411436990e+0, 6.65790464350110377720e+0)
_F = (2.04426310338993978564e-15, 1.42151175831644588870e-7, 1.84631831751005468180e-5,
      7.86869131145613259100e-4, 1.48753612908506148525e-2, 1.36929880922735805310e-1,
      5.99832206555887937690e-1, 1.0)


def _horner(coefficients, x):
    """(((c_0 x + c_1) x + c_2) ...) x + c_7, in place on one temporary."""
    value = x * coefficients[0]
    value += coefficients[1]
    for c in coefficients[2:]:
        value *= x
        value += c
    return value


def _tail(p, q):
    """AS 241 outside the central region: the quantile of p (q = p - 1/2)."""
    tail = np.sqrt(-np.log(np.where(q < 0, p, 1.0 - p)))
    t = tail - 1.6
    value = _horner(_C, t)
    value /= _horner(_D, t)
    far = tail > 5.0
    if far.any():
        r = tail[far] - 5.0
        value[far] = _horner(_E, r) / _horner(_F, r)
    return np.where(q < 0, -value, value)


def to_normal(u):
    """The standard normal quantile Φ^-1(u), elementwise: uniform points to normal ones.

    Parameters
    ----------
    u : array_like of float
        In [0, 1).

    Returns
    -------
    ndarray of float64
        z with Φ(z) = u; u = 0 gives Φ^-1(2^-1022), about -37.5 (finite, so that a point
        set holding the origin maps to finite points).

    Raises
    ------
    InvalidArgumentError
        Values outside [0, 1) or not finite.

    Notes
    -----
    Wichura's AS 241 (PPND16): a rational function of degree 7 in r = 0.180625 - q^2 for
    |q| = |u - 1/2| <= 0.425, else of r = sqrt(-log(min(u, 1 - u))) - 1.6 (r <= 5) or
    r - 5, each evaluated by Horner's rule in the order of ``kernels/normal.h``, so the
    device gives the same bits wherever its ``log`` does (OpenCL allows ``log`` 3 ulps;
    the tests state the agreement they see). Against ``scipy.special.ndtri`` the relative
    difference stays within a few ulps (tests/test_transforms.py measures it).

    Examples
    --------
    >>> from clsamp.transforms import to_normal
    >>> [round(float(z), 12) for z in to_normal([0.5, 0.975, 0.025])]
    [0.0, 1.95996398454, -1.95996398454]
    """
    x = np.asarray(u, dtype=np.float64)
    check_unit(x, "u")
    out = np.empty(x.shape)
    flat, result = x.reshape(-1), out.reshape(-1)
    # blocks that stay in cache: the temporaries are reused instead of faulted in afresh
    for start in range(0, flat.size, BLOCK):
        result[start:start + BLOCK] = quantile_block(flat[start:start + BLOCK])
    return out


def check_unit(x, name):
    """Check that every value of an array is finite and in [0, 1).

    Parameters
    ----------
    x : ndarray of float64
    name : str
        The argument's name, for the message.

    Raises
    ------
    InvalidArgumentError
        A value outside [0, 1) or not finite.
    """
    if x.size and not (x.min() >= 0 and x.max() < 1):       # NaN fails both comparisons
        raise InvalidArgumentError(f"'{name}' must hold finite values in [0, 1)")


def quantile_block(x):
    """:func:`to_normal` of a block of values already checked (:func:`check_unit`), for
    callers that work a block at a time.

    Parameters
    ----------
    x : ndarray of float64
        1-D, in [0, 1); about :data:`BLOCK` values, so that the temporaries stay in cache.

    Returns
    -------
    ndarray of float64
        Φ^-1(x), the bits of :func:`to_normal`.

    Notes
    -----
    AS 241's central formula runs at every value (its denominator stays above 0.002 for
    every |q| <= 1/2, so the tails' values are finite, and replaced), the tails' formulas
    at theirs: the same operations, so the same bits, as each region alone.
    """
    p = np.maximum(x, SMALLEST)
    q = p - 0.5
    r = q * q
    np.subtract(0.180625, r, out=r)
    out = _horner(_A, r)
    out *= q
    out /= _horner(_B, r)
    # integer indices: a boolean mask's gathers and scatter cost more than the formulas
    outside = np.flatnonzero(np.abs(q) > 0.425)
    out.put(outside, _tail(p.take(outside), q.take(outside)))
    return out


def tent(u):
    """Baker's tent transform 1 - |2u - 1|: a lattice rule on the transformed integrand
    (periodized) reaches the rates of periodic ones (Hickernell 2002).

    Parameters
    ----------
    u : array_like of float
        In [0, 1].

    Returns
    -------
    ndarray of float64

    References
    ----------
    .. [1] F. J. Hickernell, "Obtaining O(N^(-2+ε)) convergence for lattice quadrature
       rules", in Monte Carlo and Quasi-Monte Carlo Methods 2000, Springer (2002).

    Examples
    --------
    >>> from clsamp.transforms import tent
    >>> tent([0.0, 0.25, 0.5, 0.75]).tolist()
    [0.0, 0.5, 1.0, 0.5]
    """
    y = np.array(u, dtype=np.float64)
    y *= 2.0
    y -= 1.0
    np.abs(y, out=y)
    np.subtract(1.0, y, out=y)
    return y if y.ndim else y[()]


def sidi(u, k=2):
    """Sidi's sin^k transform and its derivative: ψ_k(u) = ∫_0^u sin^k(πt) dt / ∫_0^1 sin^k(πt) dt.

    A lattice rule applied to f(ψ_k(x)) prod ψ_k'(x_j) (the same integral) sees an integrand
    whose derivatives up to order k - 1 vanish at the faces of the cube: periodic in that
    order, which lattice rules need for their fast rates.

    Parameters
    ----------
    u : array_like of float
        In [0, 1].
    k : {1, 2, 3, 4}
        The power of the sine; k = 2, 3, 4 are qmcpy's ``"C1SIN"``, ``"C2SIN"``,
        ``"C3SIN"``.

    Returns
    -------
    psi, weight : ndarray of float64
        ψ_k(u) in [0, 1] and ψ_k'(u), elementwise.

    Notes
    -----
    Closed forms: ψ_1 = (1 - cos πu) / 2, ψ_2 = u - sin(2πu) / (2π),
    ψ_3 = (8 - 9 cos πu + cos 3πu) / 16, ψ_4 = (12πu - 8 sin 2πu + sin 4πu) / (12π); their
    derivatives (π/2) sin πu, 2 sin^2 πu, (3π/4) sin^3 πu, (8/3) sin^4 πu.

    References
    ----------
    .. [1] A. Sidi, "A new variable transformation for numerical integration", in Numerical
       Integration IV, Birkhäuser (1993), 359-373.

    Examples
    --------
    >>> from clsamp.transforms import sidi
    >>> psi, w = sidi([0.0, 0.5, 1.0])
    >>> psi.tolist(), w.round(12).tolist()
    ([0.0, 0.5, 1.0], [0.0, 2.0, 0.0])
    """
    if k not in (1, 2, 3, 4):
        raise InvalidArgumentError(f"'k' must be 1, 2, 3 or 4, got {k!r}")
    x = np.asarray(u, dtype=np.float64)
    s = np.sin(np.pi * x)
    if k == 1:
        psi, weight = (1.0 - np.cos(np.pi * x)) / 2.0, np.pi / 2.0 * s
    elif k == 2:
        psi, weight = x - np.sin(2 * np.pi * x) / (2 * np.pi), 2.0 * s * s
    elif k == 3:
        psi, weight = (8.0 - 9.0 * np.cos(np.pi * x) + np.cos(3 * np.pi * x)) / 16.0, 0.75 * np.pi * s**3
    else:
        psi = (12 * np.pi * x - 8.0 * np.sin(2 * np.pi * x) + np.sin(4 * np.pi * x)) / (12 * np.pi)
        weight = 8.0 / 3.0 * s**4
    return np.clip(psi, 0.0, 1.0), weight
