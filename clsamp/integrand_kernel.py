"""Integrands on the device: the program of ``kernels/integrands.cl`` for one integrand and
the double-double partial sums of f - integral it returns, added on the host in order.

Any object with ``d``, ``kernel_code``, ``kernel_params()`` and ``integral`` (a
:class:`clsamp.integrands.Integrand`) runs here.
"""

import numpy as np

from . import philox, runtime

SLICE = 4096            # points one work-group sums (fixed: the summation order depends on n only)


class IntegrandKernel:
    """The integrand's program and parameters on the current device, built once
    (``kernels/integrands.cl``; ``homogenize`` shifts realization k by its own vector)."""

    def __init__(self, f, homogenize, seed):
        import pyopencl.array as cla
        runtime.require_fp64()
        self.f = f
        self.seed = seed
        self.kernel = runtime.kernel("integrands.cl", "integrand_error_sums",
                                     defines={"DIM": f.d, "INTEGRAND": f.kernel_code,
                                              "HOMOGENIZE": int(bool(homogenize))},
                                     appendix=f.opencl_source)
        self.params = cla.to_device(runtime.queue(), np.ascontiguousarray(f.kernel_params(),
                                                                          dtype=np.float64))

    def error_sums(self, points, n, realization0):
        """The partial sums of f - integral over each set's points, computed on the device in
        slices of :data:`SLICE` points (a summation order that depends on n only), each in
        double-double.

        Parameters
        ----------
        points : pyopencl.array.Array, shape (r, n, d)
            The sets on the current device.
        n : int
            Points per set.
        realization0 : int
            The realization of the first set, which picks its homogenizing shift.

        Returns
        -------
        ndarray, shape (r, groups, 2)
            On the host: per set and slice the (high, low) parts of the sum; :func:`combine_sums`
            adds them.
        """
        import pyopencl as cl
        import pyopencl.array as cla
        queue = runtime.queue()
        r = points.shape[0]
        if points.shape != (r, n, self.f.d) or not points.flags.c_contiguous:
            points = cla.to_device(queue, np.ascontiguousarray(points.get()).reshape(r, n, self.f.d))
        groups = -(-n // SLICE)
        # a quad of points per work-item step: no more work-items than quads in a slice
        quads = -(-min(n, SLICE) // 4)
        local = min(runtime.local_size(64), 1 << max(0, (quads - 1).bit_length()))
        out = cla.empty(queue, (r, groups, 2), np.float64)
        self.kernel(queue, (groups * local, r), (local, 1), points.data, np.uint32(n),
                    np.uint32(SLICE), np.uint32(realization0), *philox.seed_key(self.seed),
                    np.uint32(philox.Stream.EXPERIMENT), self.params.data,
                    np.float64(offset(self.f)), out.data, cl.LocalMemory(16 * local))
        return out.get()


def offset(f):
    """What the kernels subtract from every value: the exact integral, or 0 where it is
    not known (an integrand from ``Integrand.from_opencl`` without one).

    Parameters
    ----------
    f : Integrand

    Returns
    -------
    float
    """
    return 0.0 if f.integral is None else float(f.integral)


def _two_sum(a, b):
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


def combine_sums(parts):
    """Double-double partial sums added in order to one double per row (Knuth's two-sum).

    Parameters
    ----------
    parts : ndarray, shape (..., groups, 2)
        (high, low) pairs, as :meth:`IntegrandKernel.error_sums` gives them.

    Returns
    -------
    ndarray, shape (...)
    """
    hi = np.zeros(parts.shape[:-2])
    lo = np.zeros(parts.shape[:-2])
    for g in range(parts.shape[-2]):
        hi, e = _two_sum(hi, parts[..., g, 0])
        lo = lo + e + parts[..., g, 1]
    return hi + lo
