"""Float geometry of the unit torus [0, 1)^d.

Distances wrap: the difference of two coordinates is ``min(|a - b|, 1 - |a - b|)`` and a
squared distance sums those differences' squares from the first coordinate to the last.
These are the operations (and the order) of the Poisson-disk kernels'
acceptance test (``kernels/dart_throwing.cl``), so a promise such as "minimum distance
>= r" checks out bit for bit.
"""

import math

import numpy as np

from .. import philox
from ..errors import InvalidArgumentError
from ..validation import check_positive_int

# Densest known sphere packings (fraction of space covered) in dimensions 1..8:
# integers, hexagonal, FCC, D4, D5, E6, E7, E8 (Conway & Sloane, "Sphere Packings,
# Lattices and Groups", table 1.2); proven optimal in 1, 2, 3 and 8.
PACKING_DENSITY = {
    1: 1.0,
    2: math.pi / math.sqrt(12.0),
    3: math.pi / math.sqrt(18.0),
    4: math.pi ** 2 / 16.0,
    5: math.pi ** 2 / (15.0 * math.sqrt(2.0)),
    6: math.pi ** 3 / (48.0 * math.sqrt(3.0)),
    7: math.pi ** 3 / 105.0,
    8: math.pi ** 4 / 384.0,
}


def shift(points, offsets):
    """The Cranley-Patterson rotation ``(x + u) mod 1``, with a single rounding.

    Parameters
    ----------
    points : ndarray
        Coordinates in [0, 1).
    offsets : ndarray
        Shifts in [0, 1), broadcast against ``points`` (one vector per realization:
        shape (r, 1, d) against points (r, n, d)).

    Returns
    -------
    ndarray
        ``x + u``, less 1 where that reaches 1: in [0, 1), as the kernels compute it
        (``ld_shift``), and exact wherever ``x + u`` is.

    References
    ----------
    R. Cranley, T. N. L. Patterson, "Randomization of number theoretic methods for
    multiple integration", SIAM J. Numer. Anal. 13(6), 1976.

    Examples
    --------
    >>> import numpy as np
    >>> from clsamp.geometry.torus import shift
    >>> shift(np.array([0.25, 0.75]), np.array([0.5, 0.5])).tolist()
    [0.75, 0.25]
    """
    y = points + offsets
    return np.where(y >= 1.0, y - 1.0, y)



def homogenization_shifts(seed, realizations, d):
    """The toroidal shift of each realization of an experiment.

    Parameters
    ----------
    seed : int
        The experiment's seed.
    realizations : array_like of int
    d : int

    Returns
    -------
    ndarray of float64
        (len(realizations), d) in [0, 1): component j of realization k is
        ``philox.uniform(seed, Stream.EXPERIMENT, k, 0, j)``, as the integrand kernels
        draw it.
    """
    k = np.asarray(realizations, dtype=np.uint32)[:, None]
    return philox.uniform(seed, philox.Stream.EXPERIMENT, k, 0, np.arange(d, dtype=np.uint32)[None, :])

def wrapped_delta(a, b):
    """``min(|a - b|, 1 - |a - b|)``: the toroidal distance of coordinates, broadcast.

    Parameters
    ----------
    a, b : array_like of float
        Coordinates in [0, 1).

    Returns
    -------
    ndarray of float64
        In [0, 1/2].
    """
    t = np.abs(a - b)
    return np.minimum(t, 1.0 - t)


def distance2(a, b, periodic=True):
    """Squared toroidal distances between points ``a`` and ``b`` (broadcast, last axis d).

    The operations and their order are those of ``kernels/torus.h`` (``torus_distance2``,
    ``cube_distance2``), so the results agree with the kernels bit for bit.

    Parameters
    ----------
    a, b : ndarray
        Points in [0, 1)^d, (..., d), broadcast against each other.
    periodic : bool
        False: the plain Euclidean distance in the unit cube, no wrapping.

    Returns
    -------
    ndarray of float64
        The broadcast shape without the last axis.

    Examples
    --------
    >>> import numpy as np
    >>> from clsamp.geometry.torus import distance2
    >>> round(float(distance2(np.array([0.05, 0.5]), np.array([0.95, 0.5]))), 12)
    0.01
    """
    delta = wrapped_delta(a, b) if periodic else np.abs(a - b)
    total = delta[..., 0] * delta[..., 0]
    for k in range(1, delta.shape[-1]):
        total = total + delta[..., k] * delta[..., k]
    return total


def ball_volume(d, radius=1.0):
    """Volume of the d-ball of ``radius``: pi^(d/2) r^d / Gamma(d/2 + 1).

    Parameters
    ----------
    d : int
    radius : float

    Returns
    -------
    float

    Examples
    --------
    >>> round(ball_volume(3), 6)       # 4 pi / 3
    4.18879
    """
    return math.pi ** (d / 2) * radius**d / math.gamma(d / 2 + 1)


def max_min_distance(n, d=2):
    """The largest minimum distance n points can have in the unit d-torus, d_max.

    Parameters
    ----------
    n : int
        Number of points (>= 1).
    d : int
        Dimension, 1 to 8.

    Returns
    -------
    float

    Notes
    -----
    n disjoint balls of radius d_max/2 fill at most the packing density Delta_d of
    the torus, ``n V_d (d_max / 2)^d = Delta_d``, so
    ``d_max = 2 (Delta_d / (n V_d))^(1/d)``. In 2-D (hexagonal packing) this is
    ``sqrt(2 / (sqrt(3) n))``; in 3-D (FCC) ``(sqrt(2) / n)^(1/3)``; in 1-D ``1/n``.

    References
    ----------
    A. Lagae, P. Dutre, "A comparison of methods for generating Poisson disk
    distributions", Computer Graphics Forum 27(1), 2008.

    Examples
    --------
    >>> from clsamp.geometry.torus import max_min_distance
    >>> round(max_min_distance(1000), 5)
    0.03398
    """
    n = check_positive_int(n, "n")
    d = check_positive_int(d, "d")
    if d not in PACKING_DENSITY:
        raise InvalidArgumentError(
            f"'d' must be in 1..8 (dimensions with a known densest packing), got {d}")
    if d == 2:
        return math.sqrt(2.0 / (math.sqrt(3.0) * n))
    return 2.0 * (PACKING_DENSITY[d] / (n * ball_volume(d))) ** (1.0 / d)
