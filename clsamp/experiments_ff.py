"""The convergence experiments in float-float, for devices without fp64: the twins of
:class:`~clsamp.integrand_kernel.IntegrandKernel` and :class:`~clsamp.families.FamilyKernel`
(``kernels/experiments_ff.cl``), and the bound that holds their errors to the fp64 ones.

:func:`clsamp.convergence` runs these with ``precision="float-float"`` (the default on a
device without fp64). Every integrand of :mod:`clsamp.integrands` but one written in OpenCL
C (whose source computes in double) and every family of :mod:`clsamp.families` has a
float-float form; an integrand whose values pass float's range (2^126: Genz's
discontinuous or product peak with large ``a``) is refused by name (:func:`check_target`).
The shifted coordinates are the fp64 kernels' bits, each rounded to a float-float pair;
values and sums are float-float (Joldes, Muller & Popescu 2017); the host adds the
per-group sums in double-double.

Error bound (u = 2^-24, u² = 2^-48 ≈ 3.6e-15). For realization k the float-float error
e_k = (1/n) Σ_i (f(x_i) - I) differs from the fp64 one by at most

    |Δe_k| <= u² · S_f · (K_f + K_sum),

where S_f >= sup |f - I| is the integrand's scale (sup |f| + |I|), K_f the relative error of
one value in units of u²·S_f and K_sum the summation's. K_f counts each float-float
operation (3u² an addition, 5u² a product, 15u² a division, about 10u² an exponential or
cosine after its argument's error) and the coordinates' rounding to pairs (2^-48 relative)
times the integrand's slope: it grows with the difficulty parameters (Σ a_j of Genz's
families, 1/σ of the Gaussians; :func:`value_bound` states each). Recursive float-float
sums of m terms of size <= T err by at most 1.5 (m + 1) u² T a term: an integrand kernel
sums at most 64 points a work-item, then a tree of log2(local) <= 8 levels (3u² each), so
K_sum = 1.5·65 + 24 + 3; a family kernel sums chunks of c = min(n, 2^16) points in blocks
of 64, 64 blocks a superblock and then the ⌈c/4096⌉ superblocks, K_sum = 1.5 (65 + 65 +
⌈c/4096⌉ + 1) + 3 (the host adds the groups and chunks in double-double, whose error is
negligible). Devices that stop long loops (llvmpipe) sum fewer points a work-item, within
the same bound. Integrands with
edges (disks, half-planes, boxes, steps) have exact values, K_f = 0, except where a point
lies within about 1e-14 of an edge, where the two paths may disagree by jump/n (none in
the tests' sets).

So errors are resolved down to about 1e-12·S_f (:func:`error_bound` at n = 4096: 4.4e-13
to 7.1e-13·S_f for an indicator or a family of them, 5e-13 to 1.2e-11·S_f for the smooth
integrands and families up to 8-D, Keister's 9e-12·S_f in 2-D to 2.7e-10·S_f in 64-D;
docs/performance.md, "Convergence experiments in float-float (issue 39)", sets these
beside the measured errors). The float-float MSE, a
mean of e_k², is within 2·B·sqrt(MSE) + B² of the fp64 one (B the bound), so an MSE of
1e-12·S_f² (a good sampler at large n) keeps about six correct digits; where the rms
error falls to 10·B (an MSE near 1e-22·S_f²) one digit is left, and below B none.

References
----------
.. [1] M. Joldes, J.-M. Muller, V. Popescu, "Tight and rigorous error bounds for basic
   building blocks of double-word arithmetic", ACM TOMS 44(2), 2017.
.. [2] M. J. Wichura, "Algorithm AS 241: the percentage points of the normal
   distribution", Applied Statistics 37(3), 1988.
"""

import math

import numpy as np

from . import families, philox, runtime
from .errors import InvalidArgumentError
from .float_float import U2, argument, exp_coefficients, split
from .integrand_kernel import combine_sums, offset
from .integrands import base
from .integrands.device import USER_SOURCE
from .integrands.qmc import GENZ_KINDS
from .transforms import _A, _B, _C, _D, _E, _F

__all__ = ["IntegrandKernelFF", "FamilyKernelFF", "constants", "value_bound", "error_bound", "check_target"]

BLOCK = 64             # points a work-item of integrand_error_sums_ff sums (at most)
CHUNK = 2**16          # points a work-item of family_error_sums_ff sums (at most)
MAX_SCALE = 2.0**126   # the largest integrand scale float-float evaluates (float's range)


def constants():
    """The table every float-float experiment kernel reads (its layout: C_* in
    ``kernels/experiments_ff.cl``).

    Returns
    -------
    ndarray of float32, shape (88, 2)
        ff2_exp's 14 pairs, (-1)^i/(2i)! for i = 9 .. 0, (-1)^i/(2i+1)! for i = 8 .. 0 (the
        highest degree first, as Horner's rule reads them), π/2 in three
        parts, 1/π, 2/π, 0.180625, 1.6, 0.425 and the coefficients of AS 241's six
        polynomials, each split into a float-float pair.
    """
    cos = [(-1) ** i / math.factorial(2 * i) for i in reversed(range(10))]
    sin = [(-1) ** i / math.factorial(2 * i + 1) for i in reversed(range(9))]
    half_pi = split(math.pi / 2)
    rest = float(np.float32(math.pi / 2 - float(half_pi[0]) - float(half_pi[1])))
    # the third part of pi/2: the rest of float64's pi/2 (within 2^-54 of it)
    head = split(np.array(cos + sin, dtype=np.float64))
    tail = split(np.array([1 / math.pi, 2 / math.pi, 0.180625, 1.6, 0.425,
                           *_A, *_B, *_C, *_D, *_E, *_F], dtype=np.float64))
    return np.concatenate([exp_coefficients(), head, half_pi[None], [[rest, 0.0]], tail]).astype(np.float32)


def check_target(target):
    """Refuse, in one line naming it, an integrand with no float-float form.

    Parameters
    ----------
    target : Integrand or Family

    Raises
    ------
    InvalidArgumentError
        An integrand written in OpenCL C (``Integrand.from_opencl``): its source computes
        in double; or one whose values reach beyond float's range (:data:`MAX_SCALE`: Genz's
        discontinuous or product-peak integrands with large ``a``).
    """
    if getattr(target, "kernel_code", None) == USER_SOURCE:
        raise InvalidArgumentError(
            f"'precision' 'float-float' cannot evaluate integrand {target.name!r}: its OpenCL C "
            "source computes in double; use precision='double' on a device with fp64")
    scale = value_bound(target)[1]
    if not scale <= MAX_SCALE:
        raise InvalidArgumentError(
            f"'precision' 'float-float' cannot evaluate integrand {target.name!r}: its values reach "
            f"{scale:.3g}, beyond float's range (2^126); use precision='double' on a device with fp64")


def _pairs(values):
    return np.ascontiguousarray(split(np.atleast_1d(np.asarray(values, dtype=np.float64))))


def _constant_table():
    return runtime.table("experiments_ff constants", constants, np.float32)


class IntegrandKernelFF:
    """``integrand_error_sums_ff`` for one integrand on the current device, built once: the
    float-float twin of :class:`~clsamp.integrand_kernel.IntegrandKernel` (the same
    ``error_sums``).

    Parameters
    ----------
    f : Integrand
    homogenize : bool
    seed : int

    Raises
    ------
    InvalidArgumentError
        An integrand written in OpenCL C (:func:`check_target`).
    """

    def __init__(self, f, homogenize, seed):
        check_target(f)
        self.f = f
        self.seed = seed
        self.kernel = runtime.kernel("experiments_ff.cl", "integrand_error_sums_ff",
                                     defines={"DIM": f.d, "INTEGRAND": f.kernel_code,
                                              "HOMOGENIZE": int(bool(homogenize))})
        params = f.kernel_params() if len(f.kernel_params()) else [0.0]
        self.params = runtime.to_device(_pairs(params))
        self.consts = _constant_table()

    def error_sums(self, points, n, realization0):
        """The partial sums of f - integral over each set's points, in float-float.

        Parameters
        ----------
        points : pyopencl.array.Array, shape (r, n, d)
        n : int
        realization0 : int

        Returns
        -------
        ndarray, shape (r, groups, 2)
            Per set and group of 64·local points the float-float sum as (hi, lo) float64;
            :func:`~clsamp.integrand_kernel.combine_sums` adds them.
        """
        import pyopencl as cl
        import pyopencl.array as cla
        queue = runtime.queue()
        r = points.shape[0]
        if points.shape != (r, n, self.f.d) or not points.flags.c_contiguous:
            points = cla.to_device(queue, np.ascontiguousarray(points.get()).reshape(r, n, self.f.d))
        per_item = _per_item(BLOCK, 16 + 80 * self.f.d, 1)
        items = -(-n // per_item)
        local = min(runtime.local_size(64), 1 << max(0, (items - 1).bit_length()))
        slice_ = per_item * local
        groups = -(-n // slice_)
        out = cla.empty(queue, (r, groups, 2), np.float32)
        self.kernel(queue, (groups * local, r), (local, 1), points.data, np.uint32(n),
                    np.uint32(slice_), np.uint32(realization0), *philox.seed_key(self.seed),
                    np.uint32(philox.Stream.EXPERIMENT), self.params.data,
                    argument(offset(self.f)), self.consts.data, out.data, cl.LocalMemory(8 * local))
        return out.get().astype(np.float64)


class FamilyKernelFF:
    """``family_error_sums_ff`` for one family on the current device, built once: the
    float-float twin of :class:`~clsamp.families.FamilyKernel` (the same ``errors``).

    Parameters
    ----------
    family : Family
    homogenize : bool
    seed : int
    """

    def __init__(self, family, homogenize, seed):
        self.family = family
        self.seed = seed
        self.kernel = runtime.kernel("experiments_ff.cl", "family_error_sums_ff",
                                     defines={"DIM": family.d, "FAMILY": family.code,
                                              "HOMOGENIZE": int(bool(homogenize))})
        self.params = runtime.to_device(_pairs(family.params.T))
        self.integrals = runtime.to_device(_pairs(family.integrals))
        self.consts = _constant_table()

    def errors(self, points, n, realization0):
        """Every member's error of every set, in float-float (see
        :meth:`~clsamp.families.FamilyKernel.errors`).

        Parameters
        ----------
        points : pyopencl.array.Array or ndarray
            (r, n, d) points.
        n, realization0 : int

        Returns
        -------
        ndarray
            (r, members) float64.
        """
        import pyopencl.array as cla
        r, m, d = points.shape[0], self.family.members, self.family.d
        chunk = _per_item(CHUNK, 24 + 4 * d + 2 * d * d, 64)
        chunks = -(-n // chunk)
        out = cla.empty(runtime.queue(), (r, chunks, m, 2), np.float32)
        self.kernel(runtime.queue(), (m, r, chunks), None, runtime.to_device(points).data, np.uint32(n),
                    np.uint32(chunk), np.uint32(realization0), *philox.seed_key(self.seed),
                    np.uint32(philox.Stream.EXPERIMENT), self.params.data, np.uint32(m),
                    self.integrals.data, self.consts.data, out.data)
        sums = np.swapaxes(out.get().astype(np.float64), 1, 2)
        return combine_sums(sums) / n


def _per_item(most, loops_a_point, multiple):
    """Points a work-item sums: ``most``, or on a device that stops long loops
    (:func:`clsamp.runtime.loop_limit`) what half its limit allows at ``loops_a_point``
    iterations a point, a multiple of ``multiple``."""
    limit = runtime.loop_limit()
    if limit is None:
        return most
    return max(multiple, min(most, limit // 2 // loops_a_point) // multiple * multiple)


def value_bound(target):
    """(K_f, S_f): one value's float-float error is at most K_f·u²·S_f, S_f >= sup |f - I|
    (the module's docstring; per integrand from its operation counts and slope).

    Parameters
    ----------
    target : Integrand or Family

    Returns
    -------
    tuple of float
    """
    d = target.d
    if isinstance(target, families.Family):
        scale = 1.0 + float(np.max(np.abs(target.integrals)))
        if target.code == families.GAUSSIANS:        # sqrt(lambda_max) <= 1 / 0.025
            return 10.0 + 3.6 * d * (2 * d + 5) + 110.0 * math.sqrt(d), scale
        if target.code == families.CLIPPED:          # sqrt(h) <= 1 / (0.05 sqrt 2)
            return 20.0 + 33.0 * d, scale
        return 0.0, scale
    if target.kernel_code == USER_SOURCE:
        check_target(target)
    code, p, integral = target.kernel_code, target.kernel_params(), abs(float(target.integral or 0.0))
    a = np.asarray(p[:d]) if code >= base.GENZ else None
    if code == base.GAUSSIAN:
        s = abs(p[0])
        return d * (55.0 + 4.0 * math.sqrt(s)), (1.0 + 2.0 * math.exp(-s)) ** d + integral
    if code in (base.DISK, base.HEAVISIDE, base.PMJ_DISK, base.PMJ_STEP, base.PMJ_TRIANGLE):
        return 0.0, 1.0 + integral
    if code in (base.PMJ_GAUSSIAN, base.PMJ_BILINEAR):
        return (30.0 if code == base.PMJ_GAUSSIAN else 10.0), 1.0 + integral
    kind = GENZ_KINDS[code - base.GENZ] if code < base.GENZ + len(GENZ_KINDS) else "keister"
    if kind == "oscillatory":
        return 40.0 + (3 * d + 8) * (a.sum() + abs(p[2 * d])), 1.0 + integral
    if kind == "product_peak":
        return float(np.sum(50.0 + 2.0 * a)), float(np.prod(a * a)) + integral
    if kind == "corner_peak":
        return (d + 1) * (7.0 * a.sum() + 3 * d + 15), 1.0 + integral
    if kind in ("gaussian", "continuous"):
        return 20.0 + 3 * d + 2.0 * a.sum(), 1.0 + integral
    if kind == "discontinuous":
        u = np.asarray(p[d:2 * d])
        top = float(np.sum(a[:2] * u[:2]) + np.sum(a[2:]))         # the sup: x_j <= u_j for j < 2
        return 10.0 + (7 + 3 * d) * a.sum(), math.exp(min(top, 700.0)) + integral
    # Keister: |y_j| <= 6 for coordinates in [2^-53, 1 - 2^-53], AS 241's rational
    # functions within 200u² relative, cos(sqrt s) changing by at most half of s's error
    return 60.0 + 1200.0 * d, p[0] + integral


def error_bound(target, n):
    """The largest difference between the float-float and the fp64 error e_k of one
    realization (each member of a family) at n points.

    Parameters
    ----------
    target : Integrand or Family
    n : int

    Returns
    -------
    float
        u²·S_f·(K_f + K_sum) (the module's docstring).

    Examples
    --------
    >>> from clsamp.integrands import make_integrand
    >>> f"{error_bound(make_integrand('disk'), 4096):.1e}"
    '6.0e-13'
    """
    k, scale = value_bound(target)
    if isinstance(target, families.Family):
        k_sum = 1.5 * (65 + 65 + -(-min(n, CHUNK) // 4096) + 1) + 3.0
    else:
        k_sum = 1.5 * 65 + 24.0 + 3.0
    return U2 * scale * (k + k_sum)
