"""What the Voronoi optimizers (``lloyd``, ``ccvt``) share: their starting sites and the
sampler base that runs an optimization per realization.

Both work on the exact integer torus of :mod:`clsamp.geometry.integer_torus`; the
starting sites of realization k are Philox words of (seed, ``Stream.INIT``, k), so
realization k never depends on how many are drawn.
"""

import numpy as np

from .. import philox
from ..geometry import integer_torus as it
from ..validation import check_points, check_positive_int
from .base import Sampler


def initial_sites(seed, realizations, n, start=0, d=2):
    """Initial sites: words 0 .. d - 1 of Philox (seed, Stream.INIT, r, start + i), top BITS
    bits each. The optimizers' density points use other words of the stream.

    Parameters
    ----------
    seed : int
    realizations : array_like of int
    n : int
        Sites.
    start : int
        The index of the first site.
    d : int
        Coordinates a site, 1 .. 4 (the words of one Philox block).

    Returns
    -------
    ndarray of uint32
        (len(realizations), n, d), integer torus coordinates.
    """
    r = np.asarray(realizations, dtype=np.uint32)[:, None, None]
    i = (np.uint64(start) + np.arange(n, dtype=np.uint64)).astype(np.uint32)[None, :, None]
    w = np.arange(d, dtype=np.uint32)[None, None, :]
    return philox.random_words(seed, philox.Stream.INIT, r, i, w) >> np.uint32(32 - it.BITS)


def check_sites(sites, name="sites", d=2):
    """Starting sites given by a user, as integer torus coordinates.

    Parameters
    ----------
    sites : array_like
        (n, d) or (r, n, d) points in [0, 1).
    name : str
        The argument's name, for messages.
    d : int or tuple of int
        The dimensions accepted.

    Returns
    -------
    sites : ndarray of uint32
        (r, n, d).
    single : bool
        Whether one (n, 2) set was given.

    Raises
    ------
    InvalidArgumentError
        Points :func:`clsamp.validation.check_points` refuses.
    """
    batch, single = check_points(sites, name, d=d)
    return it.to_torus(batch), single


class OptimizerSampler(Sampler):
    """Base of the optimizers: each realization is an optimization from its own random
    sites; ``_optimize(sites, realizations, backend)`` returns ``(points, info)``."""

    dimensions = (2,)
    max_n = 2**31
    expensive = True
    needs_fp64 = True
    # the density points are keyed by realization only: an offset start would move the
    # starting sites but not the density, a set that belongs to no realization
    accepts_start = False

    def _sites(self, n, realizations):
        return initial_sites(self.seed, np.arange(realizations.start, realizations.stop), n,
                             d=self.d)

    def _reference(self, n, realizations, start):
        return self._optimize(self._sites(n, realizations), realizations, "numpy")

    def _device(self, n, realizations, start):
        return self._optimize(self._sites(n, realizations), realizations, "opencl")

    def valid_n(self, n):
        """``n``, or the most sites whose density points the sampler counts in 32 bits,
        where n's are too many (``points_per_site`` or ``density`` times n).

        Parameters
        ----------
        n : int

        Returns
        -------
        int
            At most ``max_n``.
        """
        return min(check_positive_int(n, "n"), self._most_sites(), self.max_n)

    def _most_sites(self):
        return self.max_n

    def _optimize(self, sites, realizations, backend):
        raise NotImplementedError
