"""Argument checking at the public boundary.

Public functions call these once; the code behind them trusts its inputs. Every
failure is an :class:`~clsamp.errors.InvalidArgumentError` whose message names
the argument and what was expected, e.g. ``'n' must be a positive integer, got -1``.
"""

import numbers

import numpy as np

from .errors import InvalidArgumentError

MAX_UINT32 = 2**32 - 1
MAX_ITERATIONS = 10**6    # an optimizer's cap on its iterations (each set keeps their history)


def plain(value):
    """``value`` as a message shows it: NumPy scalars as the Python numbers they hold
    (``0.25``, not ``np.float64(0.25)``), arrays as lists, anything else as ``repr``.

    Parameters
    ----------
    value : object

    Returns
    -------
    str

    Examples
    --------
    >>> plain(np.float64(0.25)), plain(np.arange(3)), plain("x")
    ('0.25', '[0, 1, 2]', "'x'")
    """
    if isinstance(value, np.generic):
        value = value.item()
    elif isinstance(value, np.ndarray):
        value = value.tolist()
    return repr(value)


def check_int(value, name, minimum=None, maximum=None):
    """Return ``value`` as a Python int, or raise naming ``name``.

    Booleans and floats are refused even when integral (``n=4.0`` is a bug in
    the caller more often than a request for four points).

    Parameters
    ----------
    value : object
    name : str
        The argument's name, for the message.
    minimum, maximum : int, optional
        Inclusive bounds.

    Returns
    -------
    int

    Raises
    ------
    InvalidArgumentError
        Not an integer, or out of bounds.

    Examples
    --------
    >>> check_int(np.int64(3), "n")
    3
    >>> check_int(-1, "n", minimum=1)
    Traceback (most recent call last):
    ...
    clsamp.errors.InvalidArgumentError: 'n' must be an integer >= 1, got -1
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        raise InvalidArgumentError(f"'{name}' must be an integer, got {plain(value)}")
    value = int(value)
    if minimum is not None and value < minimum:
        raise InvalidArgumentError(f"'{name}' must be an integer >= {minimum}, got {value}")
    if maximum is not None and value > maximum:
        raise InvalidArgumentError(f"'{name}' must be an integer <= {maximum}, got {value}")
    return value


def check_positive_int(value, name, maximum=None):
    """An integer >= 1 (:func:`check_int` with ``minimum=1``).

    Parameters
    ----------
    value : object
    name : str
    maximum : int, optional

    Returns
    -------
    int

    Raises
    ------
    InvalidArgumentError
    """
    return check_int(value, name, minimum=1, maximum=maximum)


def check_image_size(resolution, name="resolution"):
    """(width, height) of an image from ``resolution``: an int r (an r x r image) or a pair
    (width, height), each in [1, 65535], as pbrt's film takes it.

    Parameters
    ----------
    resolution : int or (int, int)
    name : str
        The argument's name, for the message.

    Returns
    -------
    (int, int)

    Raises
    ------
    InvalidArgumentError

    Examples
    --------
    >>> check_image_size(64), check_image_size((320, 180))
    ((64, 64), (320, 180))
    """
    if isinstance(resolution, (tuple, list)) or (isinstance(resolution, np.ndarray)
                                                 and resolution.ndim == 1):
        if len(resolution) != 2:
            raise InvalidArgumentError(
                f"'{name}' must be an int or a pair (width, height), got {resolution!r}")
        width = check_positive_int(resolution[0], f"{name}[0] (width)", maximum=65535)
        height = check_positive_int(resolution[1], f"{name}[1] (height)", maximum=65535)
        return width, height
    side = check_positive_int(resolution, name, maximum=65535)
    return side, side


def check_seed(seed):
    """A seed is an integer in [0, 2^64): the two 32-bit words of the Philox key.

    Parameters
    ----------
    seed : object

    Returns
    -------
    int

    Raises
    ------
    InvalidArgumentError
        Not an integer in that range.
    """
    return check_int(seed, "seed", minimum=0, maximum=2**64 - 1)


def check_real(value, name, minimum=None, maximum=None, open_minimum=False, open_maximum=False):
    """Return ``value`` as a finite float within the given bounds, or raise naming ``name``.

    Parameters
    ----------
    value : object
        A real number (bool refused).
    name : str
        The argument's name, for the message.
    minimum, maximum : float, optional
        Bounds, inclusive unless ``open_minimum`` / ``open_maximum``.
    open_minimum, open_maximum : bool

    Returns
    -------
    float

    Raises
    ------
    InvalidArgumentError
        Not a finite real number, or out of bounds.

    Examples
    --------
    >>> check_real(1, "sigma", minimum=0.0, open_minimum=True)
    1.0
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise InvalidArgumentError(f"'{name}' must be a real number, got {plain(value)}")
    value = float(value)
    if not np.isfinite(value):
        raise InvalidArgumentError(f"'{name}' must be finite, got {value}")
    if minimum is not None and (value <= minimum if open_minimum else value < minimum):
        relation = ">" if open_minimum else ">="
        raise InvalidArgumentError(f"'{name}' must be {relation} {minimum}, got {value}")
    if maximum is not None and (value >= maximum if open_maximum else value > maximum):
        relation = "<" if open_maximum else "<="
        raise InvalidArgumentError(f"'{name}' must be {relation} {maximum}, got {value}")
    return value


def check_choice(value, name, choices):
    """``value`` must be one of ``choices``; the message lists them.

    Parameters
    ----------
    value : object
    name : str
        The argument's name, for the message.
    choices : sequence

    Returns
    -------
    object
        ``value`` itself.

    Raises
    ------
    InvalidArgumentError
    """
    if value not in choices:
        listed = ", ".join(repr(c) for c in choices)
        raise InvalidArgumentError(f"'{name}' must be one of {listed}; got {plain(value)}")
    return value


def check_bool(value, name):
    """``value`` must be True or False (a NumPy bool too).

    Parameters
    ----------
    value : object
    name : str
        The argument's name, for the message.

    Returns
    -------
    bool

    Raises
    ------
    InvalidArgumentError
    """
    if not isinstance(value, (bool, np.bool_)):
        raise InvalidArgumentError(f"'{name}' must be True or False, got {value!r}")
    return bool(value)


def check_curve(x, y, names=("x", "y")):
    """Two 1-D arrays of real numbers of one length, at least one value: a curve to draw.

    Parameters
    ----------
    x, y : array_like
    names : (str, str)
        Their names in an error.

    Returns
    -------
    (ndarray, ndarray)
        float64 copies (NaN and infinities stay: matplotlib leaves a gap).

    Raises
    ------
    InvalidArgumentError
        Not 1-D, empty, not real numbers, or of different lengths.
    """
    arrays = []
    for value, name in zip((x, y), names, strict=True):
        try:
            array = np.asarray(value)
        except ValueError:    # ragged
            array = np.empty((0, 0))
        if array.ndim != 1 or array.size == 0 or array.dtype.kind not in "buif":
            raise InvalidArgumentError(
                f"{name} must be a non-empty 1-D array of real numbers, got shape "
                f"{array.shape} of {array.dtype}")
        arrays.append(array.astype(np.float64))
    if len(arrays[0]) != len(arrays[1]):
        raise InvalidArgumentError(
            f"{names[0]} and {names[1]} must have the same length, got {len(arrays[0])} and "
            f"{len(arrays[1])}")
    return tuple(arrays)


def check_curves(curves, name, what=("x", "y")):
    """``{label: (x, y)}`` with each pair a :func:`check_curve` curve.

    Parameters
    ----------
    curves : dict
    name : str
        The argument's name in an error.
    what : (str, str)
        What x and y are, for the error.

    Returns
    -------
    dict
        ``{label: (x, y)}``, float64 arrays.

    Raises
    ------
    InvalidArgumentError
        Not a dict, or a value not a pair of one length.
    """
    if not isinstance(curves, dict):
        raise InvalidArgumentError(
            f"'{name}' must be a dict {{label: ({what[0]}, {what[1]})}}, got {type(curves).__name__}")
    checked = {}
    for label, pair in curves.items():
        if not isinstance(pair, (tuple, list)) or len(pair) != 2:
            raise InvalidArgumentError(
                f"'{name}'[{label!r}] must be a pair ({what[0]}, {what[1]}), got "
                f"{type(pair).__name__}")
        checked[label] = check_curve(*pair, names=(f"'{name}'[{label!r}]'s {what[0]}",
                                                   f"'{name}'[{label!r}]'s {what[1]}"))
    return checked


def point_sets(points, name="points", d=None):
    """The sets of a list of point arrays of different sizes, or None for anything else.

    ``[a_0, a_1, ...]`` with each ``a_k`` an (n_k, d) array (``sample_sets`` output: maximal
    Poisson-disk sets) gives the list of the validated (n_k, d) float64 arrays, all of one
    d. A nested list of numbers (one set written out) is not such a list.

    Parameters
    ----------
    points : object
    name : str
        The argument's name, for messages.
    d : int or tuple of int, optional
        The dimension(s) accepted.

    Returns
    -------
    list of ndarray or None

    Raises
    ------
    InvalidArgumentError
        A set that :func:`check_points` refuses, or sets of different dimensions.
    """
    if not (isinstance(points, (list, tuple)) and points
            and all(isinstance(p, np.ndarray) or _is_device_array(p) for p in points)
            and all(p.ndim == 2 for p in points)):
        return None
    sets = [check_points(p, f"{name}[{k}]", d=d, allow_batch=False)[0][0]
            for k, p in enumerate(points)]
    dims = {s.shape[1] for s in sets}
    if len(dims) > 1:
        raise InvalidArgumentError(f"'{name}' sets must share one dimension, got {sorted(dims)}")
    return sets


def _is_device_array(value):
    return type(value).__module__.startswith("pyopencl") and hasattr(value, "shape")


def check_points(points, name="points", d=None, allow_batch=True, keep_device=False):
    """Validate a point set and return it as a float64 array of shape (r, n, d).

    Parameters
    ----------
    points : array_like or pyopencl.array.Array
        Shape (n, d) for one set or (r, n, d) for r realizations, float64
        (float32 is accepted and widened exactly), every coordinate in [0, 1). A device
        array (``Sampler.sample_device``) is checked on the device.
    name : str
        The argument's name, used in error messages.
    d : int or tuple of int, optional
        The dimension(s) accepted.
    allow_batch : bool
        Whether the (r, n, d) form is accepted.
    keep_device : bool
        Return a device array as a device array (for kernels that read it there); else
        it is read back.

    Returns
    -------
    batch : ndarray (or device array), shape (r, n, d), float64, C-contiguous
    single : bool
        True when the input was one (n, d) set.
    """
    device = _is_device_array(points)
    if isinstance(points, (list, tuple)):
        try:
            points = np.asarray(points)
        except (TypeError, ValueError):
            raise InvalidArgumentError(
                f"'{name}' must be a NumPy array of shape (n, d) or (r, n, d), got a list "
                "whose rows differ in length") from None
    if not (device or isinstance(points, np.ndarray)):
        raise InvalidArgumentError(
            f"'{name}' must be a NumPy array of shape (n, d) or (r, n, d), "
            f"got {type(points).__name__}")
    # float64 or float32 in either byte order on the host (copied to float64 below)
    if not (points.dtype == np.float64 if device else
            points.dtype.kind == "f" and points.dtype.itemsize in (4, 8)):
        allowed = "float64" if device else "float64 (or float32)"
        raise InvalidArgumentError(f"'{name}' must have dtype {allowed}, got {points.dtype}")
    shapes = "(n, d) or (r, n, d)" if allow_batch else "(n, d)"
    if points.ndim == 2:
        single = True
        batch = points.reshape((1,) + points.shape) if device else points[None]
    elif points.ndim == 3 and allow_batch:
        single = False
        batch = points
    else:
        raise InvalidArgumentError(f"'{name}' must have shape {shapes}, got {points.shape}")
    if batch.shape[1] < 1 or batch.shape[2] < 1 or batch.shape[0] < 1:
        raise InvalidArgumentError(f"'{name}' must hold at least one point, got shape {points.shape}")
    if d is not None:
        allowed = (d,) if isinstance(d, int) else tuple(d)
        if batch.shape[2] not in allowed:
            want = " or ".join(str(a) for a in allowed)
            raise InvalidArgumentError(
                f"'{name}' must have {want} dimensions (last axis), got {batch.shape[2]}")
    if device:
        from . import runtime
        batch = runtime.device_block(batch, 0, batch.shape[0])    # contiguous, offset 0
        lo, hi, bad = runtime.bounds(batch)
    else:
        batch = np.ascontiguousarray(batch, dtype=np.float64)
        bad = 0 if np.all(np.isfinite(batch)) else 1
        lo, hi = (float(batch.min()), float(batch.max())) if not bad else (0.0, 0.0)
    if bad:
        raise InvalidArgumentError(f"'{name}' contains NaN or infinite values")
    if lo < 0.0 or hi >= 1.0:
        raise InvalidArgumentError(
            f"'{name}' must lie in [0, 1) in every coordinate, got values in [{lo!r}, {hi!r}]")
    if device and not keep_device:
        batch = batch.get()
    return batch, single
