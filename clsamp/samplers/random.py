"""The ``random`` sampler: independent uniform points (white noise)."""

import numpy as np

from .. import philox, runtime
from .base import PILLEBOUE, Rate, Sampler, register


@register("random")
class RandomSampler(Sampler):
    """Independent uniform points in [0, 1)^d.

    Coordinate j of point i in realization k is the Philox draw
    ``uniform(seed, Stream.POINTS, k, i, j)``: every point is computed alone, so
    ``sample(n, start=k)`` continues ``sample(k)`` and any device gives the same bits.

    Notes
    -----
    The Monte Carlo error of n random points decays as n^-1/2 (MSE n^-1) for any
    square-integrable integrand (Pilleboue et al. 2015); the power spectrum is flat
    (1 at every frequency but DC).

    Examples
    --------
    >>> import clsamp
    >>> a = clsamp.make_sampler("random", d=2, seed=7).sample(4, realizations=3)
    >>> a.shape
    (3, 4, 2)
    """

    sequence = True
    host_output = True

    def convergence_rate(self, case):
        """The published rate of the MSE for ``case`` (:meth:`Sampler.convergence_rate`).

        The variance of i.i.d. sampling, sigma^2 / N, for any square-integrable integrand
        and dimension.

        Parameters
        ----------
        case : {"best", "worst", "axis"}
            The integrand as the estimator sees it (:func:`clsamp.theory.case_of`).

        Returns
        -------
        Rate or None
            N^-1 for every case.
        """
        return Rate(-1.0, PILLEBOUE) if case in ("best", "worst", "axis") else None

    def _reference(self, n, realizations, start):
        return philox.uniform_block(self.seed, philox.Stream.POINTS,
                                    np.arange(realizations.start, realizations.stop),
                                    n, self.d, start)

    def _device(self, n, realizations, start, out=None):
        r = len(realizations)
        target = runtime.Output((r, n, self.d), host=out)
        # points per work-item (runtime.shape): on a CPU 16 keep a core's multipliers busy
        # (4 overlapping Philox chains); a GPU wants the work-items. The bits do not depend on it.
        per_item = runtime.shape().points_per_item
        local = runtime.local_size()
        items = -(-n // per_item)
        items = -(-items // local) * local                     # a multiple of the group size
        defines, grid, group = runtime.dimension_split(self.d, 256, (items, r), (local, 1))
        defines = {**defines, "POINTS_PER_ITEM": per_item}
        kernel = runtime.kernel("random.cl", "random_points", defines=defines)
        kernel(runtime.queue(), grid, group, target.buffer, np.uint32(n), np.uint32(self.d),
               np.uint32(start), np.uint32(realizations.start), *philox.seed_key(self.seed),
               np.uint32(philox.Stream.POINTS))
        return target.finish()
