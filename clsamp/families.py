"""Integrand families: seeded collections of random integrands with exact integrals.

One integrand hides a sampler's weak directions (a grid looks fine on a disk and fails on a
half-plane along its rows), so variance analyses average over a family of integrands drawn
at random (Pilleboue et al. 2015; UTK's integration tests). Each family here is a
reproducible collection of ``members`` integrands in d dimensions, drawn from its own
Philox stream (``Stream.FAMILY`` of ``seed``), each member with its exact integral, and
evaluated for all members at once: in NumPy (:meth:`Family.__call__`, the reference) and
in OpenCL (``kernels/families.cl``, four members a vector lane each).

Families (d = 1 .. 8):

* ``random_gaussians``: anisotropic Gaussians exp(-w^T A w / 2) on the torus (w the
  wrapped difference to a uniform centre), A = Sigma^-1 with a uniformly random rotation
  and principal standard deviations log-uniform in [0.025, 0.055]. Smooth and periodic
  (the best case). Integral (2 pi)^(d/2) sqrt(det Sigma): keeping only the nearest image
  leaves out the mass beyond half a period, below 2 d Phi(-0.5 / 0.055) < 1e-17 of the
  integral.
* ``random_heavisides``: half-spaces n . x < b on the unit cube, n uniform on the sphere
  except a quarter of the members (axis-aligned or within about 1 degree of an axis, the
  hard case for grids), b uniform over the offsets that cut the cube. Exact volume by
  inclusion-exclusion in rational arithmetic (:func:`clsamp.integrands.halfspace_volume`).
* ``random_disks``: balls on the torus, uniform centre, radius uniform in [0.1, 0.45];
  volume pi^(d/2) r^d / Gamma(d/2 + 1).
* ``random_boxes``: axis-aligned boxes on the torus (they wrap), uniform corner, side
  lengths uniform in [0.1, 0.9]; volume the product of the sides (exact rationals).
* ``random_clipped_gaussians``: a smooth function times a discontinuous one, exp(-sum_j
  h_j (x_j - c_j)^2) on an axis-aligned box [lo, hi) inside the unit cube, c in the box,
  1 / sqrt(2 h_j) in [0.05, 0.3]: integral prod_j sqrt(pi / h_j) (erf((hi_j - c_j)
  sqrt(h_j)) - erf((lo_j - c_j) sqrt(h_j))) / 2, from ``math.erf`` (a few ulps).

References
----------
.. [1] A. Pilleboue, G. Singh, D. Coeurjolly, M. Kazhdan, V. Ostromoukhov, "Variance
   analysis for Monte Carlo integration", ACM TOG 34(4), 2015.
"""

import difflib
import math
from fractions import Fraction

import numpy as np

from . import philox, runtime
from .errors import InvalidArgumentError
from .geometry.torus import ball_volume
from .integrands import halfspace_volume
from .validation import check_int, check_seed

# Kernel codes (FAMILY in kernels/families.cl).
GAUSSIANS, HEAVISIDES, DISKS, BOXES, CLIPPED = range(5)
MAX_D = 8
MAX_MEMBERS = 1 << 16

__all__ = ["Family", "RandomGaussians", "RandomHeavisides", "RandomDisks", "RandomBoxes",
           "RandomClippedGaussians", "family_names", "is_family", "make_family"]


def _uniforms(seed, members, slots):
    """(members, slots) uniforms in [0, 1): slot k of member m is
    ``philox.uniform(seed, Stream.FAMILY, m, k, 0)``."""
    m = np.arange(members, dtype=np.uint32)[:, None]
    k = np.arange(slots, dtype=np.uint32)[None, :]
    return philox.uniform(seed, philox.Stream.FAMILY, m, k, np.uint32(0))


def _normals(u1, u2):
    """Standard normal variates from pairs of uniforms (Box-Muller)."""
    return np.sqrt(-2.0 * np.log1p(-u1)) * np.cos(2.0 * math.pi * u2)


def _wrapped(x, c):
    """x - c wrapped into [-1/2, 1/2] by comparisons, as the kernel does."""
    w = x - c
    w = np.where(w > 0.5, w - 1.0, w)
    return np.where(w < -0.5, w + 1.0, w)


def _range(value, name, top, top_included=True):
    """A range (lo, hi) of floats with 0 < lo <= hi <= top (< top when not included)."""
    try:
        lo, hi = (float(v) for v in value)
    except (TypeError, ValueError):
        lo = hi = math.nan
    ok = 0 < lo <= hi and (hi <= top if top_included else hi < top)
    if not ok:
        bound = "<=" if top_included else "<"
        raise InvalidArgumentError(
            f"'{name}' must be a range (lo, hi) with 0 < lo <= hi {bound} {top:g}, got {value!r}")
    return lo, hi


class Family:
    """Base: ``members`` random integrands in ``d`` dimensions with exact integrals.

    Parameters
    ----------
    d : int
        The dimension, 1 to 8.
    members : int
        How many integrands, 1 to 2^16.
    seed : int
        Member m is drawn from Philox stream ``Stream.FAMILY`` of this seed, realization
        m: the first members of a larger family are the same.

    Attributes
    ----------
    name : str
        The family's name (``"random_heavisides"``, ...).
    d, members, seed : int
    params : ndarray (members, P)
        Each member's parameters, in the order the kernel reads them.
    integrals : ndarray (members,)
        The exact integral of each member over [0, 1)^d.
    smooth, periodic : bool
    edges : str
        ``"none"``, ``"curved"``, ``"straight"`` or ``"axis"``: the discontinuities, as
        :mod:`clsamp.theory` needs them.
    """

    name = None
    code = None
    smooth = False
    periodic = False
    edges = "none"

    def __init__(self, d=2, members=256, seed=0):
        self.d = check_int(d, "d", minimum=1, maximum=MAX_D)
        self.members = check_int(members, "members", minimum=1, maximum=MAX_MEMBERS)
        self.seed = check_seed(seed)
        self.params, self.integrals = self._draw()
        self.params = np.ascontiguousarray(self.params, dtype=np.float64)
        self.integrals = np.asarray(self.integrals, dtype=np.float64)

    def __repr__(self):
        return f"{type(self).__name__}(d={self.d}, members={self.members}, seed={self.seed})"

    def describe(self):
        """A one-line description (for reports).

        Returns
        -------
        str
        """
        return f"{self.name}: {self.members} members in {self.d}-D, seed {self.seed}"

    def edges_when_shifted(self):
        """The discontinuities under a toroidal shift: the cube's sides join the
        members' own edges unless the family is periodic.

        Returns
        -------
        str
            ``"none"``, ``"curved"``, ``"straight"`` or ``"axis"`` (:mod:`clsamp.theory`'s
            cases).
        """
        if self.periodic or self.edges in ("curved", "straight"):
            return self.edges
        return "axis"

    def __call__(self, points, members=None):
        """Every member at every point (the NumPy reference).

        Parameters
        ----------
        points : array_like
            (n, d) or (r, n, d) points in [0, 1)^d.
        members : slice or array of int, optional
            The members to evaluate; all by default.

        Returns
        -------
        ndarray
            float64 of shape (n, M) or (r, n, M) for M members.

        Raises
        ------
        InvalidArgumentError
            Points of the wrong shape.
        """
        x = np.asarray(points, dtype=np.float64)
        if x.ndim not in (2, 3) or x.shape[-1] != self.d:
            raise InvalidArgumentError(
                f"'points' must have shape (n, {self.d}) or (r, n, {self.d}), got {np.shape(points)}")
        p = self.params if members is None else self.params[members]
        return self._evaluate(x[..., None, :], p)     # x (..., n, 1, d) against members (M, P)

    def _draw(self):
        raise NotImplementedError

    def _evaluate(self, x, p):
        raise NotImplementedError

    def kernel_params(self):
        """The members' parameters as ``kernels/families.cl`` reads them.

        Returns
        -------
        ndarray
            (P, members rounded up to 4) float64, parameter-major, so that four members'
            values of one parameter are one double4; the padding repeats the last member
            (its sums are dropped).
        """
        quads = -(-self.members // 4)
        padded = np.empty((quads * 4, self.params.shape[1]))
        padded[:self.members] = self.params
        padded[self.members:] = self.params[-1]
        return np.ascontiguousarray(padded.T)


class RandomGaussians(Family):
    """Anisotropic Gaussians on the torus: random centre, rotation and spreads (the best case).

    Parameters
    ----------
    d, members, seed : int
    sigma : (float, float)
        The range of the principal standard deviations, log-uniform; at most 0.055, so
        that the nearest image alone holds the integral to 1e-17.
    """

    name = "random_gaussians"
    code = GAUSSIANS
    smooth = True
    periodic = True
    MAX_SIGMA = 0.055

    def __init__(self, d=2, members=256, seed=0, sigma=(0.025, 0.055)):
        self.sigma = _range(sigma, "sigma", self.MAX_SIGMA)
        super().__init__(d, members, seed)

    def _draw(self):
        d, m = self.d, self.members
        u = _uniforms(self.seed, m, d + d + 2 * d * d)
        centre = u[:, :d]
        spreads = self.sigma[0] * (self.sigma[1] / self.sigma[0]) ** u[:, d:2 * d]
        z = _normals(u[:, 2 * d:2 * d + d * d], u[:, 2 * d + d * d:]).reshape(m, d, d)
        params = np.empty((m, d + d * d))
        integrals = np.empty(m)
        for k in range(m):
            q = _rotation(z[k])
            inv = [1.0 / (s * s) for s in spreads[k]]
            a = np.empty((d, d))
            for i in range(d):
                for j in range(i + 1):
                    a[i, j] = a[j, i] = math.fsum(q[i][t] * inv[t] * q[j][t] for t in range(d))
            params[k, :d] = centre[k]
            params[k, d:] = a.reshape(-1)
            integrals[k] = (2.0 * math.pi) ** (d / 2) * math.prod(float(s) for s in spreads[k])
        return params, integrals

    def _evaluate(self, x, p):
        d = self.d
        w = _wrapped(x, p[:, :d])                                   # (..., n, M, d)
        a = p[:, d:].reshape(-1, d, d)
        q = None
        for i in range(d):
            u = a[:, i, 0] * w[..., 0]
            for j in range(1, d):
                u = u + a[:, i, j] * w[..., j]
            term = w[..., i] * u
            q = term if q is None else q + term
        return np.exp(q * -0.5)


def _rotation(z):
    """A uniformly random rotation from a matrix of normals: Gram-Schmidt on its columns
    in plain float arithmetic (the same bits on every machine, unlike a LAPACK QR)."""
    d = len(z)
    cols = []
    for j in range(d):
        v = [float(z[i][j]) for i in range(d)]
        for c in cols:
            dot = math.fsum(v[i] * c[i] for i in range(d))
            v = [v[i] - dot * c[i] for i in range(d)]
        norm = math.sqrt(math.fsum(t * t for t in v))
        cols.append([t / norm for t in v])
    return [[cols[j][i] for j in range(d)] for i in range(d)]       # q[i][j]: row i, column j


class RandomHeavisides(Family):
    """Half-spaces n . x < b on the unit cube: straight edges in random directions.

    Parameters
    ----------
    d, members, seed : int
    aligned : float
        The fraction of members whose normal is an axis (half of them) or within about
        a degree of one (the other half): the members a grid gets wrong.
    """

    name = "random_heavisides"
    code = HEAVISIDES
    edges = "straight"

    def __init__(self, d=2, members=256, seed=0, aligned=0.25):
        if not (isinstance(aligned, (int, float)) and 0.0 <= aligned <= 1.0):
            raise InvalidArgumentError(f"'aligned' must be a fraction in [0, 1], got {aligned!r}")
        self.aligned = float(aligned)
        super().__init__(d, members, seed)

    def _draw(self):
        d, m = self.d, self.members
        u = _uniforms(self.seed, m, 2 * d + 3)
        z = _normals(u[:, :d], u[:, d:2 * d])
        kind, axis_u, offset_u = u[:, 2 * d], u[:, 2 * d + 1], u[:, 2 * d + 2]
        params = np.empty((m, d + 1))
        integrals = np.empty(m)
        for k in range(m):
            if kind[k] < self.aligned:
                axis = min(d - 1, int(axis_u[k] * d))
                e = np.zeros(d)
                e[axis] = 1.0 if z[k, axis] >= 0 else -1.0
                near = kind[k] >= self.aligned / 2 and d > 1
                v = e + 0.02 * z[k] * (np.arange(d) != axis) if near else e
            else:
                v = z[k]
            v = v / math.sqrt(math.fsum(t * t for t in v))
            lo = math.fsum(min(t, 0.0) for t in v)
            hi = math.fsum(max(t, 0.0) for t in v)
            offset = lo + (hi - lo) * float(offset_u[k])
            params[k, :d] = v
            params[k, d] = offset
            integrals[k] = halfspace_volume(v, offset)
        return params, integrals

    def _evaluate(self, x, p):
        d = self.d
        s = x[..., 0] * p[:, 0]
        for j in range(1, d):
            s = s + x[..., j] * p[:, j]
        return (s < p[:, d]).astype(np.float64)


class RandomDisks(Family):
    """Balls on the torus (they wrap): curved edges.

    Parameters
    ----------
    d, members, seed : int
    radius : (float, float)
        The range of the radii, uniform, inside (0, 1/2).
    """

    name = "random_disks"
    code = DISKS
    periodic = True
    edges = "curved"

    def __init__(self, d=2, members=256, seed=0, radius=(0.1, 0.45)):
        self.radius = _range(radius, "radius", 0.5, top_included=False)
        super().__init__(d, members, seed)

    def _draw(self):
        d, m = self.d, self.members
        u = _uniforms(self.seed, m, d + 1)
        r = self.radius[0] + (self.radius[1] - self.radius[0]) * u[:, d]
        params = np.concatenate([u[:, :d], (r * r)[:, None]], axis=1)
        return params, np.array([ball_volume(d, float(v)) for v in r])

    def _evaluate(self, x, p):
        d = self.d
        w = _wrapped(x, p[:, :d])
        q = w[..., 0] * w[..., 0]
        for j in range(1, d):
            q = q + w[..., j] * w[..., j]
        return (q < p[:, d]).astype(np.float64)


class RandomBoxes(Family):
    """Axis-aligned boxes on the torus (they wrap): edges along the axes only.

    Parameters
    ----------
    d, members, seed : int
    length : (float, float)
        The range of the side lengths, uniform, inside (0, 1].
    """

    name = "random_boxes"
    code = BOXES
    periodic = True
    edges = "axis"

    def __init__(self, d=2, members=256, seed=0, length=(0.1, 0.9)):
        self.length = _range(length, "length", 1.0)
        super().__init__(d, members, seed)

    def _draw(self):
        d, m = self.d, self.members
        u = _uniforms(self.seed, m, 2 * d)
        sides = self.length[0] + (self.length[1] - self.length[0]) * u[:, d:]
        params = np.concatenate([u[:, :d], sides], axis=1)
        integrals = [float(math.prod((Fraction(float(s)) for s in row), start=Fraction(1))) for row in sides]
        return params, np.array(integrals)

    def _evaluate(self, x, p):
        d = self.d
        t = x - p[:, :d]
        t = np.where(t < 0.0, t + 1.0, t)
        return np.all(t < p[:, d:], axis=-1).astype(np.float64)


class RandomClippedGaussians(Family):
    """Gaussians cut to an axis-aligned box inside the unit cube: smooth times a step.

    Parameters
    ----------
    d, members, seed : int
    """

    name = "random_clipped_gaussians"
    code = CLIPPED
    edges = "axis"

    def _draw(self):
        d, m = self.d, self.members
        u = _uniforms(self.seed, m, 4 * d)
        length = 0.2 + 0.8 * u[:, :d]
        lo = (1.0 - length) * u[:, d:2 * d]
        hi = np.minimum(lo + length, 1.0)
        c = lo + (hi - lo) * u[:, 2 * d:3 * d]
        spread = 0.05 + 0.25 * u[:, 3 * d:]
        h = 1.0 / (2.0 * spread * spread)
        params = np.concatenate([c, h, lo, hi], axis=1)
        integrals = np.empty(m)
        for k in range(m):
            total = 1.0
            for j in range(d):
                root = math.sqrt(h[k, j])
                total *= 0.5 * math.sqrt(math.pi / h[k, j]) * (
                    math.erf((hi[k, j] - c[k, j]) * root) - math.erf((lo[k, j] - c[k, j]) * root))
            integrals[k] = total
        return params, integrals

    def _evaluate(self, x, p):
        d = self.d
        t = x[..., 0] - p[:, 0]
        q = (t * t) * p[:, d]
        for j in range(1, d):
            t = x[..., j] - p[:, j]
            q = q + (t * t) * p[:, d + j]
        inside = np.all((x >= p[:, 2 * d:3 * d]) & (x < p[:, 3 * d:]), axis=-1)
        return np.where(inside, np.exp(-q), 0.0)


_FAMILIES = {cls.name: cls for cls in (RandomGaussians, RandomHeavisides, RandomDisks,
                                       RandomBoxes, RandomClippedGaussians)}
# short names (not "heaviside", "disk" or "gaussian": those are single integrands)
_SHORT = {"gaussians": "random_gaussians", "heavisides": "random_heavisides",
          "disks": "random_disks", "boxes": "random_boxes",
          "clipped_gaussians": "random_clipped_gaussians"}


def family_names():
    """The names :func:`make_family` knows.

    Returns
    -------
    list of str

    Examples
    --------
    >>> from clsamp.families import family_names
    >>> family_names()[:2]
    ['random_gaussians', 'random_heavisides']
    """
    return list(_FAMILIES)


def is_family(spec):
    """Whether ``spec`` is a :class:`Family` or the name of one.

    Parameters
    ----------
    spec : object
        A family, a name (full or short, any case), or anything else.

    Returns
    -------
    bool

    Examples
    --------
    >>> from clsamp.families import is_family
    >>> is_family("heavisides"), is_family("heaviside")     # the second is one integrand
    (True, False)
    """
    if isinstance(spec, Family):
        return True
    return isinstance(spec, str) and (spec.strip().lower() in _FAMILIES or spec.strip().lower() in _SHORT)


def make_family(spec, d=2, members=256, seed=0):
    """A :class:`Family` from its name, or a family itself.

    Parameters
    ----------
    spec : str or Family
        A name of :func:`family_names` (``"random_heavisides"``), or its short form
        (``"heavisides"``, ``"gaussians"``, ``"disks"``, ``"boxes"``,
        ``"clipped_gaussians"``), in any case; a family is returned as it is, and then
        ``d``, ``members`` and ``seed`` are not used.
    d : int
        The dimension, 1 to 8.
    members : int
        How many integrands, 1 to 2^16.
    seed : int
        The seed of the members' draws.

    Returns
    -------
    Family

    Raises
    ------
    InvalidArgumentError
        An unknown name (the message suggests the nearest known one), or a bad ``d``,
        ``members`` or ``seed``.

    Examples
    --------
    >>> from clsamp.families import make_family
    >>> fam = make_family("random_boxes", d=3, members=8, seed=1)
    >>> fam.integrals.shape, fam(fam.params[:, :3]).shape
    ((8,), (8, 8))
    """
    if isinstance(spec, Family):
        return spec
    if not isinstance(spec, str):
        raise InvalidArgumentError(
            f"'family' must be a Family or one of {', '.join(_FAMILIES)}; got {spec!r}")
    key = spec.strip().lower()
    key = _SHORT.get(key, key)
    cls = _FAMILIES.get(key)
    if cls is None:
        close = difflib.get_close_matches(key, list(_FAMILIES) + list(_SHORT), n=1)
        hint = f" Did you mean {close[0]!r}?" if close else ""
        raise InvalidArgumentError(f"unknown 'family' {spec!r}.{hint} Known families: {', '.join(_FAMILIES)}")
    return cls(d=d, members=members, seed=seed)


# -- the errors of estimates, for every member -------------------------------------------
HOST_CHUNK = 2**22      # values per chunk of the NumPy path (32 MB)


def errors_numpy(family, points):
    """Every member's integration error of every point set (the NumPy reference of
    :class:`FamilyKernel`).

    Parameters
    ----------
    family : Family
    points : ndarray
        (r, n, d) points, already shifted where the experiment homogenizes.

    Returns
    -------
    ndarray
        (r, members) float64: (1/n) sum_i (f_m(x_ki) - integral_m) for set k, member m.
    """
    r, n, _ = points.shape
    out = np.empty((r, family.members))
    step = max(1, HOST_CHUNK // max(1, n * family.members))
    block = max(1, HOST_CHUNK // max(1, n))
    for lo in range(0, r, step):
        hi = min(r, lo + step)
        for m0 in range(0, family.members, block):
            m1 = min(family.members, m0 + block)
            values = family(points[lo:hi], members=slice(m0, m1))
            out[lo:hi, m0:m1] = np.sum(values - family.integrals[m0:m1], axis=1) / n
    return out


class FamilyKernel:
    """``kernels/families.cl`` for one family on the current device, built once.

    Parameters
    ----------
    family : Family
    homogenize : bool
        Whether the kernel shifts each realization's points by its own random toroidal
        vector (Philox stream ``Stream.EXPERIMENT`` of ``seed``) before evaluating.
    seed : int
        The experiment's seed, for those shifts.

    Raises
    ------
    NoDeviceError
        The current device has no fp64.
    """

    def __init__(self, family, homogenize, seed):
        runtime.require_fp64()
        self.family = family
        self.seed = seed
        self.quads = -(-family.members // 4)
        self.kernel = runtime.kernel("families.cl", "family_error_sums",
                                     defines={"DIM": family.d, "FAMILY": family.code,
                                              "HOMOGENIZE": int(bool(homogenize))})
        self.params = runtime.to_device(family.kernel_params())
        integrals = np.empty(self.quads * 4)
        integrals[:family.members] = family.integrals
        integrals[family.members:] = family.integrals[-1]
        self.integrals = runtime.to_device(integrals)

    def errors(self, points, n, realization0):
        """Every member's integration error of every point set, on the device.

        Parameters
        ----------
        points : pyopencl.array.Array or ndarray
            (r, n, d) points.
        n : int
            Points per set.
        realization0 : int
            The realization number of the first set (it selects the sets' shifts).

        Returns
        -------
        ndarray
            (r, members) float64, as :func:`errors_numpy` gives them.
        """
        r = points.shape[0]
        mp = self.quads * 4
        out = runtime.Output((r, 2, mp), np.float64, host=np.empty((r, 2, mp)))
        self.kernel(runtime.queue(), (self.quads, r), None, runtime.to_device(points).data,
                    np.uint32(n), np.uint32(realization0), *philox.seed_key(self.seed),
                    np.uint32(philox.Stream.EXPERIMENT), self.params.data, np.uint32(mp),
                    self.integrals.data, out.buffer)
        sums = out.finish()
        return (sums[:, 0, :self.family.members] + sums[:, 1, :self.family.members]) / n
