"""The ``scipy.stats.qmc`` face of a sampler: :func:`as_qmc_engine`."""

import functools

import numpy as np

from ..errors import InvalidArgumentError
from ..validation import check_int
from .base import Sampler


@functools.cache
def _engine_class():
    # The class derives from scipy's, and importing scipy.stats costs more than all of
    # `import clsamp`: it is made when the first engine is asked for.
    from scipy.stats import qmc

    class ClsampEngine(qmc.QMCEngine):
        """A clsamp sampler as a ``scipy.stats.qmc.QMCEngine`` (see :func:`as_qmc_engine`)."""

        def __init__(self, sampler, realization=0):
            super().__init__(d=sampler.d, rng=np.random.default_rng(sampler.seed))
            self.sampler = sampler
            self.realization = realization
            self.draws = 0          # sets drawn so far (samplers that are not sequences)

        def _random(self, n=1, *, workers=1):
            n = check_int(n, "n", minimum=0)
            if n == 0:
                return np.empty((0, self.d))
            if self.sampler.sequence:
                k = range(self.realization, self.realization + 1)
                return self.sampler.sample(n, realizations=k, start=self.num_generated)[0]
            k = self.realization + self.draws
            self.draws += 1
            return self.sampler.sample(n, realizations=range(k, k + 1))[0]

        def reset(self):
            """Go back to the first point (a sequence) or the first set (a point set).

            Returns
            -------
            ClsampEngine
                This engine.
            """
            self.num_generated = 0
            self.draws = 0
            return self

        def fast_forward(self, n):
            """Skip ``n`` points of a sequence, or one set of a point-set sampler.

            Parameters
            ----------
            n : int
                Points to skip, at least 0.

            Returns
            -------
            ClsampEngine
                This engine.
            """
            n = check_int(n, "n", minimum=0)
            self.num_generated += n
            if not self.sampler.sequence and n:
                self.draws += 1
            return self

        def __repr__(self):
            return f"ClsampEngine({self.sampler!r}, realization={self.realization})"

    return ClsampEngine


def as_qmc_engine(sampler, realization=0):
    """A ``scipy.stats.qmc.QMCEngine`` that draws from a clsamp sampler.

    Every tool that takes a scipy engine (``qmc.scale``, ``qmc.discrepancy`` of its
    draws, libraries built on the QMCEngine contract) then takes clsamp's samplers.

    Parameters
    ----------
    sampler : Sampler
        Any registered sampler, with its own seed and parameters.
    realization : int
        The realization the engine starts from.

    Returns
    -------
    scipy.stats.qmc.QMCEngine
        ``random(n)``, ``reset()``, ``fast_forward(n)``, ``d``, ``num_generated``.

    Notes
    -----
    For sequences (``sampler.sequence``: random, Van der Corput, Halton, Sobol) the
    engine walks realization ``realization`` of the sequence: ``random(n)`` continues
    where the last call stopped (``start=num_generated``), ``fast_forward(n)`` skips n
    points and ``reset()`` goes back to the first, as scipy's Sobol and Halton do. For
    point sets (jittered, Latin hypercube, Poisson disk, CCVT, ...), as for scipy's
    LatinHypercube, each ``random(n)`` is a fresh set of n points: realization
    ``realization``, then the next one, and so on; ``fast_forward`` skips one set and
    ``reset()`` starts again from the first. The draws are the sampler's own, bit for bit.

    Examples
    --------
    >>> import clsamp, numpy as np
    >>> from scipy.stats import qmc
    >>> engine = clsamp.as_qmc_engine(clsamp.make_sampler("sobol:owen", d=2, seed=3))
    >>> x = engine.random(64)
    >>> engine.num_generated
    64
    >>> bool(qmc.discrepancy(x) < qmc.discrepancy(np.random.default_rng(1).random((64, 2))))
    True
    >>> qmc.scale(engine.random(64), [0, 0], [10, 5]).shape     # points 64..127
    (64, 2)
    """
    if not isinstance(sampler, Sampler):
        raise InvalidArgumentError(f"'sampler' must be a clsamp Sampler, got {sampler!r}")
    realization = check_int(realization, "realization", minimum=0, maximum=2**32 - 1)
    return _engine_class()(sampler, realization)
