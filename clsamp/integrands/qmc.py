"""The standard QMC test functions: Genz's six families and Keister's integrand, each with
its exact integral and a case in ``kernels/integrands.cl`` (see :mod:`clsamp.integrands`)."""

import itertools
import math
from fractions import Fraction

import numpy as np

from .. import philox
from ..errors import InvalidArgumentError
from ..transforms import BLOCK, check_unit, quantile_block
from ..validation import check_choice, check_positive_int, check_seed, plain
from .base import GENZ, KEISTER, Integrand, _vector

# -- Genz's test families -----------------------------------------------------------------
GENZ_KINDS = ("oscillatory", "product_peak", "corner_peak", "gaussian", "continuous",
              "discontinuous")
# ||a||_1 of each family in d dimensions: Genz's difficulty (1984), as the Virtual Library
# of Simulation Experiments (Surjanovic and Bingham) lists it
GENZ_DIFFICULTY = {"oscillatory": lambda d: 110.0 / d**1.5, "product_peak": lambda d: 600.0 / d**2,
                   "corner_peak": lambda d: 600.0 / d**2, "gaussian": lambda d: 100.0 / d,
                   "continuous": lambda d: 150.0 / d**2, "discontinuous": lambda d: 100.0 / d**2}
MAX_GENZ_D = 16


class Genz(Integrand):
    """One of Genz's six test families on the unit cube, with its exact integral.

    ==============  ====================================================  ======================
    kind            f(x)                                                  character
    ==============  ====================================================  ======================
    oscillatory     cos(2 pi u_1 + sum a_j x_j)                           smooth
    product_peak    prod (a_j^-2 + (x_j - u_j)^2)^-1                      smooth, a peak at u
    corner_peak     (1 + sum a_j x_j)^-(d + 1)                            smooth, a corner peak
    gaussian        exp(-sum a_j^2 (x_j - u_j)^2)                         smooth
    continuous      exp(-sum a_j abs(x_j - u_j))                          kinks along x_j = u_j
    discontinuous   0 if x_1 > u_1 or x_2 > u_2, else exp(sum a_j x_j)    steps along axes
    ==============  ====================================================  ======================

    Parameters
    ----------
    kind : str
        One of :data:`GENZ_KINDS`.
    a : sequence of float
        The difficulty parameters (positive); their length sets d.
    u : sequence of float
        The shift parameters in [0, 1], as long as ``a``.

    Notes
    -----
    The integrals are products of one-dimensional ones (the oscillatory family's as the
    real part of a complex product, e^(2 pi i u_1) prod (e^(i a_j) - 1) / (i a_j)), except
    the corner peak's, which is the sum over the cube's 2^d vertices v of
    (-1)^|v| / (d! prod a_j (1 + a.v)), added here in exact rational arithmetic. On the
    device the functions are evaluated in the operation order of the NumPy reference
    (``cos`` and ``exp`` are the device's: within a few ulps of NumPy's).

    References
    ----------
    .. [1] A. Genz, "Testing multidimensional integration routines", in Tools, Methods and
       Languages for Scientific and Engineering Computation, North-Holland (1984), 81-94.
    .. [2] S. Surjanovic, D. Bingham, "Virtual Library of Simulation Experiments: test
       functions and datasets", Simon Fraser University (2013).
    """

    name = "genz"
    periodic = False

    def __init__(self, kind, a, u):
        self.kind = check_choice(kind, "kind", GENZ_KINDS)
        a, u = _vector(a, "a"), _vector(u, "u", len(np.atleast_1d(a)))
        if np.any(a <= 0):
            raise InvalidArgumentError(f"'a' must be positive, got {plain(a.tolist())}")
        if np.any(u < 0) or np.any(u > 1):
            raise InvalidArgumentError(f"'u' must lie in [0, 1], got {plain(u.tolist())}")
        super().__init__(a.size)
        if self.kind == "discontinuous" and self.d > MAX_GENZ_D:
            raise InvalidArgumentError(f"'a' may have at most {MAX_GENZ_D} entries")
        self.a, self.u = a, u
        self.name = f"genz_{self.kind}"
        self.kernel_code = GENZ + GENZ_KINDS.index(self.kind)
        self.smooth = self.kind not in ("continuous", "discontinuous")
        self.edges = "axis" if self.kind == "discontinuous" else "none"
        self.integral = self._integral()

    def _describe(self):
        return f"kind={self.kind!r}, a={self.a.tolist()}, u={self.u.tolist()}"

    def _integral(self):
        a, u, d = self.a, self.u, self.d
        if self.kind == "oscillatory":
            z = complex(math.cos(2 * math.pi * u[0]), math.sin(2 * math.pi * u[0]))
            for aj in a:            # (e^(i a) - 1) / (i a) = sin(a) / a + i 2 sin^2(a / 2) / a
                z *= complex(math.sin(aj) / aj, 2 * math.sin(aj / 2) ** 2 / aj)
            return z.real
        if self.kind == "product_peak":
            return math.prod(aj * (math.atan(aj * (1 - uj)) + math.atan(aj * uj))
                             for aj, uj in zip(a, u, strict=True))
        if self.kind == "corner_peak":
            fa = [Fraction(float(aj)) for aj in a]
            total = Fraction(0)
            for v in itertools.product((0, 1), repeat=d):
                total += (-1) ** sum(v) / (1 + sum(f for f, b in zip(fa, v, strict=True) if b))
            return float(total / (math.factorial(d) * math.prod(fa)))
        if self.kind == "gaussian":
            return math.prod(math.sqrt(math.pi) / (2 * aj) * (math.erf(aj * (1 - uj)) + math.erf(aj * uj))
                             for aj, uj in zip(a, u, strict=True))
        if self.kind == "continuous":
            return math.prod((-math.expm1(-aj * uj) - math.expm1(-aj * (1 - uj))) / aj
                             for aj, uj in zip(a, u, strict=True))
        return math.prod(math.expm1(aj * (uj if j < 2 else 1.0)) / aj
                         for j, (aj, uj) in enumerate(zip(a, u, strict=True)))

    def kernel_params(self):
        """The kernel's parameters: a, then u, then 2 pi u_1 (the oscillatory phase).

        Returns
        -------
        ndarray
            float64 of length 2 d + 1.
        """
        return np.concatenate([self.a, self.u, [2 * math.pi * self.u[0]]])

    def _evaluate(self, x):
        # the kernel's formulas, operation for operation
        a, u, d = self.a, self.u, self.d
        if self.kind == "oscillatory":
            s = np.full(x.shape[:-1], 2 * math.pi * u[0])
            for j in range(d):
                s = s + a[j] * x[..., j]
            return np.cos(s)
        if self.kind == "product_peak":
            f = np.ones(x.shape[:-1])
            for j in range(d):
                w = x[..., j] - u[j]
                f = f / (1.0 / (a[j] * a[j]) + w * w)
            return f
        if self.kind == "corner_peak":
            t = np.ones(x.shape[:-1])
            for j in range(d):
                t = t + a[j] * x[..., j]
            q = t
            for _ in range(d):
                q = q * t
            return 1.0 / q
        s = np.zeros(x.shape[:-1])
        for j in range(d):
            w = x[..., j] - u[j]
            if self.kind == "gaussian":
                w = a[j] * w
                s = s + w * w
            elif self.kind == "continuous":
                s = s + a[j] * np.abs(w)
            else:
                s = s + a[j] * x[..., j]
        if self.kind == "discontinuous":
            inside = x[..., 0] <= u[0]
            if d > 1:
                inside = inside & (x[..., 1] <= u[1])
            return np.where(inside, np.exp(s), 0.0)
        return np.exp(-s)


def genz(kind, d, seed=0):
    """A random member of one of Genz's test families: a and u drawn from the seed, a scaled
    to the family's difficulty ||a||_1 (Genz 1984).

    Parameters
    ----------
    kind : str
        One of :data:`GENZ_KINDS`.
    d : int
        Dimensions, 1 to 16.
    seed : int
        a'_j and u_j are ``philox.uniform(seed, Stream.FAMILY, k, j, 0 | 1)`` with k the
        family's index; a = a' ||a||_1 / sum a'.

    Returns
    -------
    Genz

    Examples
    --------
    >>> from clsamp.integrands import genz
    >>> f = genz("gaussian", 3, seed=1)
    >>> round(float(sum(f.a)), 12), f.d
    (33.333333333333, 3)
    """
    kind = check_choice(kind, "kind", GENZ_KINDS)
    d = check_positive_int(d, "d", maximum=MAX_GENZ_D)
    seed = check_seed(seed)
    j = np.arange(d, dtype=np.uint32)
    k = GENZ_KINDS.index(kind)
    raw = philox.uniform(seed, philox.Stream.FAMILY, k, j, 0)
    u = philox.uniform(seed, philox.Stream.FAMILY, k, j, 1)
    a = raw * (GENZ_DIFFICULTY[kind](d) / raw.sum())
    return Genz(kind, a, u)


class Keister(Integrand):
    """Keister's integrand, the QMC benchmark of qmcpy's documentation: the integral
    over R^d of cos(||x||) exp(-||x||^2), as an integral over the unit cube.

    f(u) = pi^(d/2) cos(||y||), y_j = Φ^-1(u_j) / sqrt(2) (:func:`clsamp.transforms.to_normal`).

    Parameters
    ----------
    d : int
        Dimensions, 1 to 64.

    Notes
    -----
    The exact value is pi^(d/2) 1F1(d/2; 1/2; -1/4) (integrating the radius against the
    sphere's surface, with ∫ cos(r) e^(-r^2) r^(d-1) dr = Γ(d/2) 1F1(d/2; 1/2; -1/4) / 2);
    d = 1 gives sqrt(pi) e^(-1/4) = 1.38038844704314. Smooth inside the cube, unbounded
    derivatives at its faces, not periodic.

    References
    ----------
    .. [1] B. D. Keister, "Multidimensional quadrature algorithms", Computers in Physics
       10(2), 1996, 119-122.

    Examples
    --------
    >>> from clsamp.integrands import keister
    >>> round(keister(1).integral, 14), round(keister(3).integral, 12)
    (1.38038844704314, 2.168309102165)
    """

    name = "keister"
    kernel_code = KEISTER
    smooth = True
    periodic = False
    edges = "none"
    MAX_D = 64

    def __init__(self, d=2):
        from scipy.special import hyp1f1
        super().__init__(check_positive_int(d, "d", maximum=self.MAX_D))
        self.scale = math.pi ** (self.d / 2)
        self.integral = float(self.scale * hyp1f1(self.d / 2, 0.5, -0.25))

    def kernel_params(self):
        """The kernel's parameters: pi^(d/2), then 1/sqrt(2).

        Returns
        -------
        ndarray
            float64 of length 2.
        """
        return np.array([self.scale, math.sqrt(0.5)])

    def _evaluate(self, x):
        check_unit(x, "points")
        flat = x.reshape(-1, self.d)
        out = np.empty(flat.shape[0])
        half = math.sqrt(0.5)
        # blocks of points whose temporaries stay in cache; per point the kernel's operations
        for start in range(0, flat.shape[0], BLOCK):
            block = flat[start:start + BLOCK]
            s = np.zeros(block.shape[0])
            for j in range(self.d):
                y = quantile_block(block[:, j])        # to_normal, the values checked above
                y *= half
                y *= y
                s += y
            np.sqrt(s, out=s)
            np.cos(s, out=s)
            s *= self.scale
            out[start:start + BLOCK] = s
        return out.reshape(x.shape[:-1])


def keister(d):
    """Keister's integrand in d dimensions (:class:`Keister`).

    Parameters
    ----------
    d : int

    Returns
    -------
    Keister
    """
    return Keister(d)
