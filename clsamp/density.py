"""A target density on [0, 1)^d for adaptive sampling: a callable or an array (an image in
2-D), checked once, evaluated with its gradient, and sampled.

Samplers that place points by a density take it through :func:`as_density`, which refuses
a bad one in one line before any work, and use the :class:`Density` it returns: values
normalized to mean 1 over the domain, their gradient, and starting points drawn from it.
"""

import numpy as np

from . import philox
from .errors import InvalidArgumentError
from .validation import plain

PROBE = 4096          # points a callable is checked and normalized on
FD_STEP = 2.0 ** -20  # central differences of a callable's gradient
MARGIN = 1.25         # a callable's rejection bound over the largest value probed
BATCH = 4             # candidates drawn per point and pass of the rejection sampler


def _probe_points(d):
    """The midpoints of a g^d grid, g^d about :data:`PROBE`; from d = 14 on, where even
    2 a side is more than twice that, :data:`PROBE` fixed uniform points (Philox)."""
    g = int(round(PROBE ** (1.0 / d)))
    if g < 2 or g ** d > 2 * PROBE:
        index = np.arange(PROBE, dtype=np.uint32)[:, None]
        return philox.uniform(0, philox.Stream.INIT, np.uint32(2**32 - 1), index,
                              np.arange(d, dtype=np.uint32)[None, :])
    axis = (np.arange(g) + 0.5) / g
    return np.stack(np.meshgrid(*([axis] * d), indexing="ij"), axis=-1).reshape(-1, d)


class Density:
    """A density on [0, 1)^d, normalized to mean 1 (use :func:`as_density` to make one).

    Attributes
    ----------
    d : int
    image : ndarray or None
        The array (normalized) when the density is one: multilinear between the cell
        centres, constant beyond the outer centres, so its mean is the array's mean.
    bound : float
        An upper bound of the normalized density, for rejection sampling (exact for an
        array; for a callable, :data:`MARGIN` times the largest value probed).
    """

    def __init__(self, d, function=None, image=None, scale=1.0, bound=1.0, name="density"):
        self.d, self._function, self.image = d, function, image
        self._scale, self.bound, self._name = scale, bound, name

    def __call__(self, x):
        """The normalized density at points.

        Parameters
        ----------
        x : ndarray (m, d)

        Returns
        -------
        ndarray (m,)

        Raises
        ------
        InvalidArgumentError
            A callable that returns the wrong shape, a negative or a non-finite value.
        """
        x = np.asarray(x, dtype=np.float64)
        if self.image is not None:
            return self._interpolate(x)[0]
        return _call(self._function, x, self._name) * self._scale

    def gradient(self, x):
        """The gradient of the normalized density at points: exact for an array (the
        multilinear pieces'), central differences of step 2^-20 (one-sided at the faces)
        for a callable.

        Parameters
        ----------
        x : ndarray (m, d)

        Returns
        -------
        ndarray (m, d)
        """
        x = np.asarray(x, dtype=np.float64)
        if self.image is not None:
            return self._interpolate(x, gradient=True)[1]
        grad = np.empty_like(x)
        for k in range(self.d):
            hi, lo = x.copy(), x.copy()
            hi[:, k] = np.minimum(x[:, k] + FD_STEP, np.nextafter(1.0, 0.0))
            lo[:, k] = np.maximum(x[:, k] - FD_STEP, 0.0)
            grad[:, k] = (self(hi) - self(lo)) / (hi[:, k] - lo[:, k])
        return grad

    def _interpolate(self, x, gradient=False):
        """Multilinear interpolation of the array between cell centres, and its gradient."""
        shape = np.array(self.image.shape)
        u = np.clip(x * shape - 0.5, 0.0, shape - 1.0)
        lo = np.minimum(np.floor(u).astype(np.int64), shape - 2).clip(0)
        frac = np.where(shape > 1, u - lo, 0.0)
        hi = np.minimum(lo + 1, shape - 1)
        m, d = x.shape
        value = np.zeros(m)
        grad = np.zeros((m, d)) if gradient else None
        inside = (x * shape > 0.5) & (x * shape < shape - 0.5)   # the slope is 0 beyond
        for corner in range(1 << d):
            bits = [(corner >> k) & 1 for k in range(d)]
            index = tuple(np.where(b, hi[:, k], lo[:, k]) for k, b in enumerate(bits))
            weights = [np.where(b, frac[:, k], 1.0 - frac[:, k]) for k, b in enumerate(bits)]
            v = self.image[index]
            value = value + v * np.prod(weights, axis=0)
            if gradient:
                for k in range(d):
                    others = np.prod([w for j, w in enumerate(weights) if j != k], axis=0)
                    slope = (1.0 if bits[k] else -1.0) * shape[k] * inside[:, k]
                    grad[:, k] = grad[:, k] + v * slope * others
        return value, grad

    def sample(self, seed, realizations, n):
        """Points drawn from the density by rejection.

        Candidate k of realization r is Philox's uniform point (seed, Stream.INIT, r, k)
        in dimensions 0..d-1 and is kept when its dimension d, times :attr:`bound`, falls
        below the density there; the first n kept in candidate order are the set, so a
        realization does not depend on which others are drawn.

        Parameters
        ----------
        seed : int
        realizations : iterable of int
        n : int
            Points a set.

        Returns
        -------
        ndarray (len(realizations), n, d)
        """
        sets = []
        for r in realizations:
            kept, first = [], 0
            while sum(len(k) for k in kept) < n:
                count = BATCH * n + 64
                index = np.arange(first, first + count, dtype=np.uint64).astype(np.uint32)
                u = philox.uniform(seed, philox.Stream.INIT, np.uint32(r), index[:, None],
                                   np.arange(self.d + 1, dtype=np.uint32)[None, :])
                keep = u[:, self.d] * self.bound < self(u[:, :self.d])
                kept.append(u[keep, :self.d])
                first += count
            sets.append(np.concatenate(kept)[:n])
        return np.stack(sets) if sets else np.empty((0, n, self.d))


def _call(function, x, name):
    """function(x) as (m,) float64, refused in one line when it is not a density's values."""
    try:
        value = np.asarray(function(x), dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InvalidArgumentError(
            f"'{name}' must be a callable taking points (m, d) and returning (m,) "
            f"values; it raised {type(error).__name__}: {error}") from None
    if value.shape != (len(x),):
        raise InvalidArgumentError(
            f"'{name}' must return one value a point, shape ({len(x)},); got shape "
            f"{value.shape}")
    if not np.all(np.isfinite(value)) or np.any(value < 0):
        bad = value[~(np.isfinite(value) & (value >= 0))][0]
        raise InvalidArgumentError(
            f"'{name}' must be finite and non-negative, got {bad} at some point")
    return value


def as_density(density, d, name="density"):
    """Check a density and return it as a :class:`Density` normalized to mean 1.

    Parameters
    ----------
    density : callable or array_like
        A callable on points (m, d) in [0, 1)^d returning m non-negative values, or an
        array with d axes (an image in 2-D), non-negative: entry [i, j] is the density at
        the cell centre ((i + 1/2) / shape[0], (j + 1/2) / shape[1]) -- the first axis is
        x, so an image shown with rows going down the screen is ``image[::-1].T``.
        Either needs a positive integral; its scale does not matter.
    d : int
        The dimension of the points.
    name : str
        The argument's name, for messages.

    Returns
    -------
    Density

    Raises
    ------
    InvalidArgumentError
        Not a callable or an array with d axes of at least 1 entry; a negative or
        non-finite value; a zero integral (for a callable: zero on every probe point, the
        midpoints of a grid of about 4096 cells, or 4096 uniform points from d = 14 on).

    Examples
    --------
    >>> import numpy as np
    >>> ramp = as_density(lambda x: 0.2 + 1.6 * x[:, 0], d=2)
    >>> [round(float(v), 6) for v in ramp(np.array([[0.0, 0.5], [1.0, 0.5]]))]
    [0.2, 1.8]
    >>> float(as_density(np.ones((4, 4)), d=2).image.mean())
    1.0
    """
    if callable(density):
        values = _call(density, _probe_points(d), name)
        mean = float(values.mean())
        if not mean > 0:
            raise InvalidArgumentError(f"'{name}' must have a positive integral; it is 0 on "
                                       f"all {len(values)} probe points")
        return Density(d, function=density, scale=1.0 / mean,
                       bound=MARGIN * float(values.max()) / mean, name=name)
    if isinstance(density, (str, bytes, dict)) or density is None:
        raise InvalidArgumentError(
            f"'{name}' must be a callable or an array with {d} axes, got {plain(density)}")
    try:
        image = np.array(density, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidArgumentError(
            f"'{name}' must be a callable or an array with {d} axes, got {plain(density)}") from None
    if image.ndim != d or image.size == 0:
        raise InvalidArgumentError(
            f"'{name}' must be an array with {d} axes (one a dimension), got shape {image.shape}")
    if not np.all(np.isfinite(image)) or np.any(image < 0):
        raise InvalidArgumentError(f"'{name}' must be finite and non-negative, got "
                                   f"{image[~(np.isfinite(image) & (image >= 0))][0]}")
    mean = float(image.mean())
    if not mean > 0:
        raise InvalidArgumentError(f"'{name}' must have a positive integral, got all zeros")
    image = image / mean
    return Density(d, image=image, bound=float(image.max()), name=name)
