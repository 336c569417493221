"""Test integrands with exact integrals, for variance and convergence experiments.

Two families:

* On the unit torus (periodic, so a random toroidal shift -- homogenization -- creates
  no new edge): :class:`Gaussian` (wrapped; smooth, the best case of Pilleboue et al.
  2015) and :class:`Disk` (wrapping; discontinuous along a curve, the worst case).
* On the unit square (not periodic): :class:`Heaviside` (a straight edge) and the set
  used by Christensen, Kensler and Kilpatrick (2018) to compare progressive
  multi-jittered sequences with other samplers (:func:`pmj_set`): a quarter disk
  x^2 + y^2 < 2/pi, the Gaussian exp(-x^2 - y^2), the bilinear xy, the step x < 1/pi
  and the triangle y > x. A toroidal shift keeps their estimators unbiased but makes
  the square's sides edges of the shifted integrand; use ``homogenize=False`` in
  :func:`clsamp.convergence` to compare with that paper.

Each integrand is a callable on points of shape (n, d) or (r, n, d) (NumPy, the
reference), has its exact ``.integral`` over [0, 1)^d, and an OpenCL evaluation in
``kernels/integrands.cl`` selected by ``.kernel_code`` with its parameters in
``.kernel_params()``. ``.smooth``, ``.periodic`` and ``.edges`` classify it for
:mod:`clsamp.theory`.

References
----------
.. [1] A. Pilleboue, G. Singh, D. Coeurjolly, M. Kazhdan, V. Ostromoukhov, "Variance
   analysis for Monte Carlo integration", ACM TOG 34(4), 2015.
.. [2] P. Christensen, A. Kensler, C. Kilpatrick, "Progressive multi-jittered sample
   sequences", Computer Graphics Forum 37(4), 2018.
"""

import difflib
import itertools
import math
from fractions import Fraction

import numpy as np

from . import philox
from .errors import InvalidArgumentError
from .geometry.torus import ball_volume
from .validation import check_choice, check_positive_int, check_real, check_seed, plain

# Kernel codes (INTEGRAND in kernels/integrands.cl).
GAUSSIAN, DISK, HEAVISIDE, PMJ_DISK, PMJ_GAUSSIAN, PMJ_BILINEAR, PMJ_STEP, PMJ_TRIANGLE = range(8)
# the Genz families: GENZ + their index in GENZ_KINDS
GENZ = 8



def _vector(value, name, d=None):
    try:
        array = np.asarray(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise InvalidArgumentError(
            f"'{name}' must be a sequence of real numbers, got {plain(value)}") from None
    if array.size == 0 or (d is not None and array.size != d):
        want = f"{d} numbers" if d is not None else "at least one number"
        raise InvalidArgumentError(f"'{name}' must hold {want}, got {plain(value)}")
    if not np.all(np.isfinite(array)):
        raise InvalidArgumentError(f"'{name}' must be finite, got {plain(value)}")
    return array


def _points(points, d):
    """Points as a float64 array (..., n, d), checked for shape only (the hot path)."""
    x = np.asarray(points, dtype=np.float64)
    if x.ndim not in (2, 3) or x.shape[-1] != d:
        raise InvalidArgumentError(
            f"'points' must have shape (n, {d}) or (r, n, {d}), got {np.shape(points)}")
    return x


class Integrand:
    """Base: a function on [0, 1)^d with an exact integral and an OpenCL evaluation.

    Parameters
    ----------
    d : int
        Dimension (subclasses set it from their parameters).

    Attributes
    ----------
    name : str
        Short name (``"gaussian"``, ``"disk"``, ``"pmj_step"``, ...).
    d : int
        Dimension.
    integral : float
        The exact integral over [0, 1)^d (correctly rounded where the closed form
        allows, see each class).
    smooth : bool
        Whether it is infinitely differentiable on its domain (the torus if
        ``periodic``, else the open square).
    periodic : bool
        Whether it is a function on the torus (a toroidal shift creates no edge).
    edges : str
        ``"none"``, ``"curved"``, ``"straight"`` (some not parallel to an axis) or
        ``"axis"`` (all parallel to the axes): the discontinuities, as theory needs.
    """

    name = None
    kernel_code = None
    smooth = False
    periodic = False
    edges = "none"

    def __init__(self, d):
        self.d = d

    def __call__(self, points):
        """Evaluate at points (the NumPy reference).

        Parameters
        ----------
        points : array_like
            (n, d) or (r, n, d) points.

        Returns
        -------
        ndarray
            float64 of shape (n,) or (r, n).

        Raises
        ------
        InvalidArgumentError
            Points of the wrong shape.
        """
        return self._evaluate(_points(points, self.d))

    def _evaluate(self, x):
        raise NotImplementedError

    def kernel_params(self):
        """The parameters ``kernels/integrands.cl`` reads for this integrand.

        Returns
        -------
        ndarray
            float64, laid out as the kernel's case for ``kernel_code`` reads them (one
            unused zero for integrands without parameters).
        """
        return np.zeros(1)

    def edges_when_shifted(self):
        """The discontinuities of x -> f((x + u) mod 1): the square's sides join the
        integrand's own edges unless it is periodic.

        Returns
        -------
        str
            ``"none"``, ``"curved"``, ``"straight"`` or ``"axis"``.
        """
        if self.periodic:
            return self.edges
        if self.edges in ("curved", "straight"):
            return self.edges
        return "axis"

    def __repr__(self):
        return f"{type(self).__name__}({self._describe()})"

    def _describe(self):
        return f"d={self.d}"

    def describe(self):
        """A one-line description with the parameters (for reports).

        Returns
        -------
        str
        """
        return f"{self.name}: {self._describe()}, integral {float(self.integral)!r}"


class Gaussian(Integrand):
    """The wrapped Gaussian on the torus: smooth and periodic, the best case.

    f(x) = prod_j g(x_j - c_j), g(t) = sum_{k in {-1, 0, 1}} exp(-(w(t) + k)^2 / (2 sigma^2)),
    with w(t) = t - round(t) the wrapped difference in [-1/2, 1/2].

    Parameters
    ----------
    center : sequence of float, optional
        The centre c in [0, 1)^d; its length sets d. Default (0.4142, 0.7320), away from
        every dyadic and triadic grid line (about sqrt(2) - 1 and sqrt(3) - 1).
    sigma : float, optional
        Standard deviation, in (0, 0.15]; default 0.15 (wide enough that the wrap matters:
        the copy half a period away adds exp(-1/(8 sigma^2)) ~ 4e-3 of the peak).

    Notes
    -----
    Three images per axis are kept, at distances |w|, 1 - |w| and 1 + |w|, evaluated as
    exp(s w^2) (1 + B + exp(2s) / B) with s = -1/(2 sigma^2) and B = exp(s (1 - 2|w|))
    (two exponentials instead of three). The terms left out are at least 1.5 away,
    below exp(-1.125 / sigma^2) < 2e-22 of the peak, so f is smooth and periodic far
    beyond double precision. The exact integral of the function evaluated is
    (sigma sqrt(2 pi) erf(1.5 / (sigma sqrt 2)))^d. Its MSE under homogenized sampling
    does not depend on the centre (the shift is uniform).
    """

    name = "gaussian"
    kernel_code = GAUSSIAN
    smooth = True
    periodic = True
    edges = "none"
    MAX_SIGMA = 0.15

    def __init__(self, center=(0.4142, 0.7320), sigma=0.15):
        c = _vector(center, "center")
        if np.any(c < 0) or np.any(c >= 1):
            raise InvalidArgumentError(f"'center' must lie in [0, 1)^d, got {plain(center)}")
        super().__init__(c.size)
        self.center = c
        self.sigma = check_real(sigma, "sigma", minimum=0.0, maximum=self.MAX_SIGMA, open_minimum=True)
        one = self.sigma * math.sqrt(2 * math.pi) * math.erf(1.5 / (self.sigma * math.sqrt(2)))
        self.integral = one ** self.d

    def _describe(self):
        return f"center={self.center.tolist()}, sigma={self.sigma}"

    def kernel_params(self):
        """The kernel's parameters: s = -1/(2 sigma^2), the centre, exp(2s).

        Returns
        -------
        ndarray
            float64 of length d + 2.
        """
        s = -0.5 / self.sigma**2
        return np.array([s, *self.center, math.exp(2 * s)])

    def _evaluate(self, x):
        # the images at |w|, 1 - |w| and 1 + |w| as E0 (1 + B + exp(2s) / B), two exps
        # per coordinate instead of three (the kernel's formula, term for term)
        s = -0.5 / self.sigma**2
        w = x - self.center
        w = w - np.round(w)
        e0 = np.exp(s * (w * w))
        b = np.exp(s * (1.0 - 2.0 * np.abs(w)))
        with np.errstate(divide="ignore"):
            far = np.where(b > 0, math.exp(2 * s) / b, 0.0)
        g = e0 * ((1.0 + b) + far)
        out = g[..., 0]
        for j in range(1, self.d):
            out = out * g[..., j]
        return out


class Disk(Integrand):
    """The indicator of a disk (ball in d-D) on the torus: it wraps across the sides.

    f(x) = 1 if |w(x - c)| < r else 0, with w the wrapped difference in [-1/2, 1/2]^d.

    Parameters
    ----------
    center : sequence of float, optional
        Default (0.7311, 0.2243): the disk of the default radius crosses both seams of
        the torus, and the centre is on no dyadic or triadic grid line.
    radius : float, optional
        In (0, 1/2), so the ball does not overlap itself; default 0.3389 (area 0.3608).

    Notes
    -----
    Discontinuous along a curve: the worst case of Pilleboue et al. (2015). The exact
    integral is the ball's volume, pi r^2 in 2-D.
    """

    name = "disk"
    kernel_code = DISK
    smooth = False
    periodic = True
    edges = "curved"

    def __init__(self, center=(0.7311, 0.2243), radius=0.3389):
        c = _vector(center, "center")
        if np.any(c < 0) or np.any(c >= 1):
            raise InvalidArgumentError(f"'center' must lie in [0, 1)^d, got {plain(center)}")
        super().__init__(c.size)
        self.center = c
        self.radius = check_real(radius, "radius", minimum=0.0, maximum=0.5,
                                 open_minimum=True, open_maximum=True)
        self.integral = ball_volume(self.d, self.radius)

    def _describe(self):
        return f"center={self.center.tolist()}, radius={self.radius}"

    def kernel_params(self):
        """The kernel's parameters: the squared radius, then the centre.

        Returns
        -------
        ndarray
            float64 of length d + 1.
        """
        return np.array([self.radius**2, *self.center])

    def _evaluate(self, x):
        w = x - self.center
        w = w - np.round(w)
        return (np.sum(w * w, axis=-1) < self.radius**2).astype(np.float64)


def halfspace_volume(normal, offset):
    """Exact volume of {x in [0, 1]^d : normal . x < offset}, from the float inputs,
    correctly rounded.

    The inclusion-exclusion over the cube's vertices, in rational arithmetic:
    V = sum_v (-1)^|v| max(0, offset - n.v)^m / (m! prod n_j) over the m non-zero
    components (the others contribute a factor 1), after flipping negative components.
    Every float is an integer over a power of two, so the sum runs in Python integers
    scaled by one common power of two, and one division rounds it.

    Parameters
    ----------
    normal : sequence of float
        The half-space's normal, d components (zeros allowed).
    offset : float

    Returns
    -------
    float
        The volume, correctly rounded.

    Examples
    --------
    >>> from clsamp.integrands import halfspace_volume
    >>> halfspace_volume([1.0, 1.0], 1.0), halfspace_volume([1.0, -1.0], 0.0)
    (0.5, 0.5)
    """
    n = [Fraction(float(v)) for v in normal]
    b = Fraction(float(offset))
    for j, v in enumerate(n):        # x_j -> 1 - x_j makes every component non-negative
        if v < 0:
            n[j] = -v
            b -= v
    active = [v for v in n if v != 0]
    m = len(active)
    if m == 0:
        return 1.0 if b > 0 else 0.0
    scale = max(v.denominator for v in active + [b])          # a power of two
    ints = [int(v * scale) for v in active]
    top = int(b * scale)
    total = 0
    for corner in itertools.product((0, 1), repeat=m):
        t = top - sum(v for v, c in zip(ints, corner, strict=True) if c)
        if t > 0:
            total += (-1) ** sum(corner) * t**m
    return float(Fraction(total, math.factorial(m) * math.prod(ints)))


class Heaviside(Integrand):
    """A straight edge: f(x) = 1 if normal . x < offset else 0, on the unit square (cube).

    Parameters
    ----------
    normal : sequence of float, optional
        The edge's normal; its length sets d. Default (cos 0.3, sin 0.3) rounded to
        (0.9553, 0.2955): the edge is far from every axis direction and from the diagonal.
    offset : float, optional
        Default 0.6 (the edge crosses the square, cutting off 0.5306 of it).

    Notes
    -----
    Not periodic: under a toroidal shift the square's sides are edges too (axis-parallel).
    The exact integral is the polytope's volume by inclusion-exclusion in rational
    arithmetic on the float parameters (:func:`halfspace_volume`), correctly rounded.
    """

    name = "heaviside"
    kernel_code = HEAVISIDE
    smooth = False
    periodic = False

    def __init__(self, normal=(0.9553, 0.2955), offset=0.6):
        nrm = _vector(normal, "normal")
        if not np.any(nrm != 0):
            raise InvalidArgumentError(f"'normal' must not be zero, got {plain(normal)}")
        super().__init__(nrm.size)
        self.normal = nrm
        self.offset = check_real(offset, "offset")
        self.integral = halfspace_volume(self.normal, self.offset)
        self.edges = "axis" if np.count_nonzero(nrm) == 1 else "straight"

    def _describe(self):
        return f"normal={self.normal.tolist()}, offset={self.offset}"

    def kernel_params(self):
        """The kernel's parameters: the offset, then the normal.

        Returns
        -------
        ndarray
            float64 of length d + 1.
        """
        return np.array([self.offset, *self.normal])

    def _evaluate(self, x):
        # accumulate in the kernel's order so both round alike
        s = x[..., 0] * self.normal[0]
        for j in range(1, self.d):
            s = s + x[..., j] * self.normal[j]
        return (s < self.offset).astype(np.float64)


class _PMJ(Integrand):
    """One of the 2-D test integrands of Christensen et al. (2018), on the unit square."""

    periodic = False

    def __init__(self):
        super().__init__(2)


class PMJDisk(_PMJ):
    """Quarter disk: f = 1 if x^2 + y^2 < 2/pi; integral exactly 1/2."""

    name = "pmj_disk"
    kernel_code = PMJ_DISK
    edges = "curved"
    integral = 0.5

    def _evaluate(self, x):
        return (x[..., 0] * x[..., 0] + x[..., 1] * x[..., 1] < 2.0 / math.pi).astype(np.float64)


class PMJGaussian(_PMJ):
    """f = exp(-x^2 - y^2); integral (sqrt(pi)/2 erf(1))^2 = 0.557746285351034..."""

    name = "pmj_gaussian"
    kernel_code = PMJ_GAUSSIAN
    smooth = True
    integral = (math.sqrt(math.pi) / 2 * math.erf(1.0)) ** 2

    def _evaluate(self, x):
        return np.exp(-(x[..., 0] * x[..., 0]) - x[..., 1] * x[..., 1])


class PMJBilinear(_PMJ):
    """f = x y; integral exactly 1/4."""

    name = "pmj_bilinear"
    kernel_code = PMJ_BILINEAR
    smooth = True
    integral = 0.25

    def _evaluate(self, x):
        return x[..., 0] * x[..., 1]


class PMJStep(_PMJ):
    """f = 1 if x < 1/pi; integral 1/pi (the float 1/pi: the edge is at that float)."""

    name = "pmj_step"
    kernel_code = PMJ_STEP
    edges = "axis"
    integral = 1.0 / math.pi

    def _evaluate(self, x):
        return (x[..., 0] < 1.0 / math.pi).astype(np.float64)


class PMJTriangle(_PMJ):
    """f = 1 if y > x; integral exactly 1/2."""

    name = "pmj_triangle"
    kernel_code = PMJ_TRIANGLE
    edges = "straight"
    integral = 0.5

    def _evaluate(self, x):
        return (x[..., 1] > x[..., 0]).astype(np.float64)


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

    ==============  ===============================================  ====================
    kind            f(x)                                             character
    ==============  ===============================================  ====================
    oscillatory     cos(2 pi u_1 + sum a_j x_j)                      smooth
    product_peak    prod (a_j^-2 + (x_j - u_j)^2)^-1                 smooth, a peak at u
    corner_peak     (1 + sum a_j x_j)^-(d + 1)                       smooth, a corner peak
    gaussian        exp(-sum a_j^2 (x_j - u_j)^2)                    smooth
    continuous      exp(-sum a_j |x_j - u_j|)                        kinks along x_j = u_j
    discontinuous   0 if x_1 > u_1 or x_2 > u_2, else exp(sum a_j x_j)  steps along axes
    ==============  ===============================================  ====================

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


_FACTORIES = {
    "gaussian": Gaussian,
    "disk": Disk,
    "heaviside": Heaviside,
    "pmj_disk": PMJDisk,
    "pmj_gaussian": PMJGaussian,
    "pmj_bilinear": PMJBilinear,
    "pmj_step": PMJStep,
    "pmj_triangle": PMJTriangle,
}


GENZ_NAMES = {f"genz_{kind}": kind for kind in GENZ_KINDS}


def integrand_names():
    """The names :func:`make_integrand` knows.

    Returns
    -------
    list of str
    """
    return list(_FACTORIES) + list(GENZ_NAMES)


def pmj_set():
    """The five integrands of Christensen et al. (2018), in their order.

    Returns
    -------
    list of Integrand
        The quarter disk, the Gaussian, the bilinear, the step and the triangle.
    """
    return [PMJDisk(), PMJGaussian(), PMJBilinear(), PMJStep(), PMJTriangle()]


def make_integrand(spec, d=None):
    """An :class:`Integrand` from a name (default parameters) or an integrand itself.

    Parameters
    ----------
    spec : str or Integrand
        One of :func:`integrand_names`.
    d : int, optional
        For ``"gaussian"``, ``"disk"`` and ``"heaviside"`` by name: the dimension (the
        default centre or normal is repeated/cut to d; 2 when None); for the Genz
        families (``"genz_oscillatory"``, ...): :func:`genz` of seed 0 in d dimensions.

    Returns
    -------
    Integrand
        ``spec`` itself where it is one.

    Raises
    ------
    InvalidArgumentError
        An unknown name (the message suggests the nearest), or a ``d`` that a 2-D
        integrand cannot take.

    Examples
    --------
    >>> from clsamp.integrands import make_integrand
    >>> f = make_integrand("pmj_bilinear")
    >>> f.integral, float(f([[0.5, 0.5]])[0])
    (0.25, 0.25)
    """
    if isinstance(spec, Integrand):
        return spec
    if not isinstance(spec, str):
        raise InvalidArgumentError(
            f"'integrand' must be an Integrand or one of {', '.join(_FACTORIES)}; got {spec!r}")
    key = spec.strip().lower()
    if key in GENZ_NAMES:
        return genz(GENZ_NAMES[key], 2 if d is None else d)
    factory = _FACTORIES.get(key)
    if factory is None:
        close = difflib.get_close_matches(spec, integrand_names(), n=1)
        hint = f" Did you mean {close[0]!r}?" if close else ""
        raise InvalidArgumentError(
            f"unknown 'integrand' {spec!r}.{hint} Known integrands: {', '.join(integrand_names())}")
    if d is None or d == 2 or issubclass(factory, _PMJ):
        made = factory()
        if d is not None and made.d != d:
            raise InvalidArgumentError(f"integrand {spec!r} is {made.d}-dimensional, got 'd'={d}")
        return made
    default = {"gaussian": (0.4142, 0.7320), "disk": (0.7311, 0.2243),
               "heaviside": (0.9553, 0.2955)}[factory.name]
    first = "center" if factory is not Heaviside else "normal"
    values = [default[j % 2] * (1 + 0.01 * (j // 2)) for j in range(d)]
    return factory(**{first: values})
