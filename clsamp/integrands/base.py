"""The integrands on the torus and the square (Gaussian, disk, Heaviside, the PMJ set) and
their base, :class:`Integrand` (see :mod:`clsamp.integrands`)."""

import itertools
import math
from fractions import Fraction

import numpy as np

from ..errors import InvalidArgumentError
from ..geometry.torus import ball_volume
from ..validation import check_positive_int, check_real, plain
from . import device

# Kernel codes (INTEGRAND in kernels/integrands.cl).
GAUSSIAN, DISK, HEAVISIDE, PMJ_DISK, PMJ_GAUSSIAN, PMJ_BILINEAR, PMJ_STEP, PMJ_TRIANGLE = range(8)
# the Genz families: GENZ + their index in GENZ_KINDS; then Keister's
GENZ = 8
KEISTER = 14



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
    opencl_source = None    # OpenCL C appended to the integrand kernels (from_opencl's)
    smooth = False
    periodic = False
    edges = "none"

    def __init__(self, d):
        self.d = d

    @staticmethod
    def from_opencl(source, d, integral=None, name="opencl"):
        """An integrand written in OpenCL C, evaluated on the device wherever clsamp
        integrates it (:class:`clsamp.integrands.device.OpenCLIntegrand`).

        Parameters
        ----------
        source : str
            An expression in ``x[0] .. x[d-1]`` (``"exp(-x[0] * x[1])"``), a function body
            with a ``return``, or a function ``double f(const double *x) { ... }``; it may
            call OpenCL's math built-ins and ``to_normal(u)``
            (:func:`clsamp.transforms.to_normal` on the device).
        d : int
            The dimension.
        integral : float, optional
            The exact integral where known (:func:`clsamp.convergence` needs it).
        name : str
            For reports.

        Returns
        -------
        OpenCLIntegrand

        Raises
        ------
        InvalidArgumentError
            Bad arguments, or ``source`` that does not compile (with the compiler's first
            error, its line numbered within ``source``).

        Notes
        -----
        :func:`clsamp.integrate` fuses point generation, evaluation and reduction into one
        kernel for it (:mod:`clsamp.fused`), so no point is ever stored.

        Examples
        --------
        >>> import clsamp
        >>> f = clsamp.Integrand.from_opencl("x[0] * x[1] * x[2]", 3, integral=0.125)
        >>> float(f([[0.5, 0.5, 0.5]])[0])
        0.125
        >>> res = clsamp.integrate(f, 3, abs_tol=1e-6, progress=False)
        >>> bool(abs(res.estimate - 0.125) < 1e-5), res.converged
        (True, True)
        """
        return OpenCLIntegrand(source, d, integral=integral, name=name)

    def __call__(self, points):
        """Evaluate at points (the NumPy reference; a :meth:`from_opencl` integrand runs its
        OpenCL code on the current device, the same code as every kernel runs).

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


class OpenCLIntegrand(Integrand):
    """An integrand given as OpenCL C: made by :meth:`clsamp.Integrand.from_opencl`.

    Parameters
    ----------
    source : str
        See :func:`clsamp.integrands.device.assemble`. The code may call OpenCL's math
        built-ins (in double) and ``to_normal(u)``, the standard normal quantile of
        :func:`clsamp.transforms.to_normal` (``kernels/normal.h``).
    d : int
        The dimension, 1 to 1024.
    integral : float, optional
        The exact integral, where known: :func:`clsamp.convergence` needs it (the errors
        are estimates minus it); :func:`clsamp.integrate` does not.
    name : str
        For reports.

    Attributes
    ----------
    source : str
        The code as given.
    opencl_source : str
        The code appended to the integrand kernels
        (:func:`clsamp.integrands.device.assemble`).

    Raises
    ------
    InvalidArgumentError
        ``source`` not a non-empty string, or not compiling (the message holds the
        compiler's first error, its line numbered within ``source``); a bad ``d``,
        ``integral`` or ``name``.
    NoDeviceError
        The current device has no fp64.
    """

    kernel_code = device.USER_SOURCE

    def __init__(self, source, d, integral=None, name="opencl"):
        super().__init__(check_positive_int(d, "d", maximum=device.MAX_D))
        if integral is not None:
            try:
                integral = float(integral)
            except (TypeError, ValueError):
                integral = math.nan
            if not math.isfinite(integral):
                raise InvalidArgumentError(
                    f"'integral' must be a finite real number or None, got {plain(integral)}")
        if not isinstance(name, str) or not name:
            raise InvalidArgumentError(f"'name' must be a non-empty string, got {plain(name)}")
        self.source, self.integral, self.name = source, integral, name
        self.opencl_source = device.compile_source(source, self.d)

    def _describe(self):
        text = " ".join(self.source.split())
        return f"d={self.d}, source={text if len(text) <= 60 else text[:57] + '...'!r}"

    def describe(self):
        """A one-line description (for reports).

        Returns
        -------
        str
        """
        known = "unknown" if self.integral is None else repr(float(self.integral))
        return f"{self.name}: {self._describe()}, integral {known}"

    def _evaluate(self, x):
        return device.device_values(self, x)


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
