"""Float-float (double-single) numbers on the host: the twin of ``kernels/float_float.h``.

A float-float value is the unevaluated sum hi + lo of two float32 numbers, about 48
significant bits: what the analyses compute in on devices without fp64 (and, by choice, on
GPUs, whose fp64 runs at 1/32 to 1/64 of their float rate). The host splits float64 inputs
into pairs and joins results back; the arithmetic is the header's (its error bounds, from
Joldes, Muller & Popescu 2017, are stated there). :func:`check_precision` is the one place
the ``precision=`` argument is read.
"""

import math

import numpy as np

from . import runtime
from .errors import NoDeviceError
from .validation import check_choice

__all__ = ["PRECISIONS", "U2", "check_precision", "split", "join", "exp_coefficients", "argument"]

PRECISIONS = ("double", "float-float")
U2 = 2.0**-48          # u^2 with u = 2^-24: the unit in which float-float error bounds count
_FLOAT2 = np.dtype([("hi", np.float32), ("lo", np.float32)])


def check_precision(precision, backend="opencl"):
    """The precision an analysis computes in on the current device.

    Parameters
    ----------
    precision : {"double", "float-float"} or None
        None: ``"double"`` where the current device has fp64, ``"float-float"`` where it
        has not.
    backend : {"opencl", "numpy"}
        With ``"numpy"`` the NumPy reference computes in float64 whatever ``precision`` says
        (it is still checked).

    Returns
    -------
    str
        ``"double"`` or ``"float-float"``.

    Raises
    ------
    InvalidArgumentError
        ``precision`` is none of the above.
    NoDeviceError
        ``"double"`` on a device without fp64.

    Examples
    --------
    >>> from clsamp import runtime
    >>> with runtime.without_fp64():
    ...     check_precision(None)
    'float-float'
    """
    if precision is not None:
        check_choice(precision, "precision", PRECISIONS)
    if backend == "numpy":
        return precision or "double"
    device = runtime.current_device()
    if precision is None:
        return "double" if device.fp64 else "float-float"
    if precision == "double" and not device.fp64:
        raise NoDeviceError(
            f"'precision' 'double' needs fp64 (cl_khr_fp64), which device {device.name} lacks; "
            "use precision='float-float' (the default there), or choose another device with "
            "clsamp.use_device or CLSAMP_DEVICE")
    return precision


def split(x):
    """float64 values as float-float pairs, the nearest pair to within 2^-48 relative.

    Parameters
    ----------
    x : array_like of float64

    Returns
    -------
    ndarray of float32, shape x.shape + (2,)
        ``[..., 0]`` the float nearest to x, ``[..., 1]`` the float nearest to the rest.
    """
    x = np.asarray(x, dtype=np.float64)
    hi = x.astype(np.float32)
    lo = (x - hi).astype(np.float32)          # x - hi is exact in float64
    return np.stack([hi, lo], axis=-1)


def join(pairs):
    """Float-float pairs (last axis of length 2) as float64, hi + lo rounded once.

    Parameters
    ----------
    pairs : array_like of float32, shape (..., 2)

    Returns
    -------
    ndarray of float64

    Examples
    --------
    >>> abs(float(join(split(0.1))) - 0.1) <= 0.1 * 2.0**-48
    True
    """
    pairs = np.asarray(pairs)
    return pairs[..., 0].astype(np.float64) + pairs[..., 1].astype(np.float64)


def exp_coefficients():
    """What ``ff2_exp`` in ``kernels/float_float.h`` reads: 1/i! for i = 0..12, then ln 2, as
    float-float pairs.

    Returns
    -------
    ndarray of float32, shape (14, 2)
    """
    return split(np.append(1.0 / np.array([math.factorial(i) for i in range(13)], dtype=np.float64),
                           math.log(2.0)))


def argument(value):
    """A float64 number as a ``float2`` kernel argument (hi, lo).

    Parameters
    ----------
    value : float

    Returns
    -------
    numpy.void
        A scalar of a (hi, lo) float32 record, which pyopencl passes as a float2.
    """
    return split(np.float64(value)).view(_FLOAT2)[()]
