"""The errors of a sampler's integral estimates at one n: for one integrand, or for every
member of a family of integrands with the same points.

For realization k the estimate is (1/n) sum_i f(x_ki), x_k the sampler's k-th point set
shifted, when ``homogenize``, by its own random toroidal vector u_k =
``philox.uniform(seed, Stream.EXPERIMENT, k, 0, j)`` (Pilleboue et al. 2015: the shift
makes every point uniform, so the estimator is unbiased). The OpenCL path makes the
points on the device and shifts, evaluates and sums them in one kernel per chunk
(``kernels/integrands.cl``, ``kernels/families.cl``), reading back only the errors; the
NumPy path (``backend="numpy"``) does the same in NumPy.

An estimator (:class:`IntegrandErrors`, :class:`FamilyErrors`) answers one question,
:meth:`~IntegrandErrors.block`: the errors of realizations lo .. hi - 1 at n, which do not
depend on the block. :func:`clsamp.convergence` asks it for every n, in-process or in
tasks on a cluster (:func:`errors_block`).

References
----------
.. [1] A. Pilleboue et al., "Variance analysis for Monte Carlo integration", ACM TOG
   34(4), 2015.
"""

import copy

import numpy as np

from . import runtime
from .experiments_ff import FamilyKernelFF, IntegrandKernelFF
from .families import FamilyKernel, errors_numpy
from .geometry import torus
from .integrand_kernel import IntegrandKernel, combine_sums

HOST_CHUNK = 2**22      # doubles per chunk of the NumPy path (32 MB)
# Doubles of points generated per launch: the device's shape's chunk (runtime.shape): on a
# CPU 16 MB, so the points the sampler just wrote are still in the caches when the
# integrand kernel reads them (which matters most when the integrand is cheap;
# docs/performance.md); on a GPU larger launches keep more items in flight.

__all__ = ["IntegrandErrors", "FamilyErrors", "errors_block"]


class _Estimator:
    """What both estimators share: the sampler, the experiment's flags, and the kernel,
    built on first use and never pickled (a task carries the estimator to a worker)."""

    def __init__(self, sampler, target, homogenize, seed, backend, precision="double"):
        self.sampler = sampler
        self.target = target
        self.homogenize = bool(homogenize)
        self.seed = seed
        self.backend = backend
        self.precision = precision
        self._kernel = None

    def __getstate__(self):
        return {**self.__dict__, "_kernel": None}

    def __copy__(self):
        other = type(self).__new__(type(self))
        other.__dict__.update(self.__getstate__())
        return other

    @property
    def name(self):
        """The integrand's or the family's name."""
        return self.target.name

    @property
    def kernel(self):
        """The target's kernel on the current device (None for the NumPy path)."""
        if self._kernel is None and self.backend == "opencl":
            self._kernel = self._make_kernel()
        return self._kernel

    def warm_up(self, n):
        """Build every program the sweep uses (the sampler's and the target's), so that
        no timing includes a build."""
        if self.backend == "opencl":
            self.block(n, 0, 1)


class IntegrandErrors(_Estimator):
    """The errors (1/n) sum_i f(x_ki) - integral of one integrand ``target``.

    Parameters
    ----------
    sampler : Sampler
    target : Integrand
        Of the sampler's dimension.
    homogenize : bool
    seed : int
        Seed of the homogenizing shifts.
    backend : {"opencl", "numpy"}
    precision : {"double", "float-float"}
        What the OpenCL path computes in (:mod:`clsamp.experiments_ff` for float-float,
        within :func:`clsamp.experiments_ff.error_bound` of the fp64 errors).
    """

    width = 1            # errors per realization
    cost = 1             # work of a point, in units of one point's generation

    def _make_kernel(self):
        make = IntegrandKernelFF if self.precision == "float-float" else IntegrandKernel
        return make(self.target, self.homogenize, self.seed)

    def block(self, n, lo, hi):
        """The errors of realizations lo .. hi - 1 at n, which do not depend on the block.

        Parameters
        ----------
        n : int
            Points per set.
        lo, hi : int
            The realizations lo .. hi - 1.

        Returns
        -------
        ndarray, shape (hi - lo,)
        """
        if self.backend == "opencl":
            return _errors_opencl(self.kernel, self.sampler, n, hi - lo, lo)
        return _errors_numpy(self.sampler, self.target, n, hi - lo, self.homogenize, self.seed, lo)


class FamilyErrors(_Estimator):
    """Every member's errors (1/n) sum_i f_m(x_ki) - integral_m of a family ``target``,
    one point set a realization for all members.

    Parameters are those of :class:`IntegrandErrors`, with ``target`` a
    :class:`~clsamp.families.Family`.
    """

    @property
    def width(self):
        """Errors per realization: one a member."""
        return self.target.members

    @property
    def cost(self):
        """A point costs about as much to make as 100 member evaluations (docs/performance.md)."""
        return 1 + self.target.members / 100

    def _make_kernel(self):
        make = FamilyKernelFF if self.precision == "float-float" else FamilyKernel
        return make(self.target, self.homogenize, self.seed)

    def block(self, n, lo, hi):
        """Every member's errors, shape (hi - lo, members); see :meth:`IntegrandErrors.block`."""
        return _family_errors(self.kernel, self.sampler, self.target, n, lo, hi, self.homogenize,
                              self.seed)


def errors_block(estimator, n, lo, hi):
    """One task of a sweep (:mod:`clsamp.parallel`), with kernels of the task's own (a task
    may run in any thread or process).

    Parameters
    ----------
    estimator : IntegrandErrors or FamilyErrors
    n, lo, hi : int
        As :meth:`IntegrandErrors.block` takes them.

    Returns
    -------
    ndarray
        ``estimator.block(n, lo, hi)``.
    """
    return copy.copy(estimator).block(n, lo, hi)


# -- one integrand ---------------------------------------------------------------------
def _errors_numpy(sampler, f, n, r, homogenize, seed, r0=0):
    """The NumPy reference of one n: the errors (1/n) sum_i (f(x_ki) - integral) of
    realizations r0 .. r0 + r - 1."""
    step = max(1, HOST_CHUNK // (n * f.d))
    out = np.empty(r)
    for lo in range(r0, r0 + r, step):
        hi = min(r0 + r, lo + step)
        x = sampler.sample(n, realizations=range(lo, hi))
        if homogenize:
            x = torus.shift(x, torus.homogenization_shifts(seed, np.arange(lo, hi), f.d)[:, None, :])
        # numpy sums a contiguous row pairwise: error ~ eps log2(n) of sum |f - I|
        out[lo - r0:hi - r0] = np.sum(f._evaluate(x) - f.integral, axis=1) / n
    return out


def _errors_opencl(kernel, sampler, n, r, r0=0):
    limit = 8 * runtime.shape().chunk
    out = np.empty(r)
    for lo, hi in runtime.chunk_ranges(r, 8 * n * sampler.d, limit):
        points = sampler.sample_device(n, realizations=range(r0 + lo, r0 + hi))
        out[lo:hi] = combine_sums(kernel.error_sums(points, n, r0 + lo)) / n
    return out



# -- a family ---------------------------------------------------------------------------
def _family_errors(kernel, sampler, fam, n, lo, hi, homogenize, seed):
    """The (hi - lo, members) errors of realizations lo .. hi - 1 at n (kernel None: NumPy)."""
    out = np.empty((hi - lo, fam.members))
    # a chunk's points and its (realizations x members) sums stay modest
    per_realization = 8 * max(n * fam.d, 4 * fam.members)
    for a, b in runtime.chunk_ranges(hi - lo, per_realization, 2**24):
        run = range(lo + a, lo + b)
        if kernel is not None:
            out[a:b] = kernel.errors(sampler.sample_device(n, realizations=run), n, lo + a)
        else:
            x = sampler.sample(n, realizations=run)
            if homogenize:
                u = torus.homogenization_shifts(seed, np.arange(run.start, run.stop), fam.d)
                x = torus.shift(x, u[:, None, :])
            out[a:b] = errors_numpy(fam, x)
    return out
