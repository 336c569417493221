"""Random permutations, on the device and in NumPy, for samplers and the renderer.

Two kinds, with different guarantees:

``random_permutations(seed, stream, realizations, length, perms)``
    **Exactly uniform** permutations: Fisher–Yates (Durstenfeld's in-place form)
    driven by Philox4x32-10, with Lemire's multiply-and-reject for unbiased bounded
    integers. Returns uint32 ndarray of shape ``(len(realizations), len(perms),
    length)``; row ``[k, q]`` is permutation ``perms[q]`` of realization
    ``realizations[k]`` and never depends on which other realizations or perms were
    asked for. ``realizations`` and ``perms`` are a ``range`` (or an int ``c`` for
    ``range(c)``); ``perms`` numbers must be below 2^22. Every one of the
    ``length!`` permutations has the same probability (up to Philox being a
    good generator, and a retry cap whose failure probability is below 2^-500).
    Used by ``latin_hypercube``, ``multijittered`` and ``uncorrelated_jitter``; for
    pbrt-style padding, pass pixel numbers as ``realizations`` and dimension pairs as
    ``perms`` (with a stream of its own, e.g. ``Stream.PIXEL``).

``random_permutations_device(seed, stream, realizations, length, perms)``
    The same permutations, bit for bit, made by the OpenCL kernel
    ``fisher_yates`` in ``kernels/permutation.cl``; returns a
    ``pyopencl.array.Array`` (uint32, same shape) on ``runtime.queue()``. One
    work-item shuffles one permutation, so the work is parallel over
    realizations × perms but sequential within one permutation.

``permute(i, length, p)``
    Kensler's hash permutation with cycle walking (Kensler 2013, listing
    "permute"): element ``i`` of a pseudo-random permutation of ``[0, length)``
    selected by the 32-bit pattern ``p``, computed alone without a table (the
    right tool when a kernel needs one point of one permutation). Arguments
    broadcast; ``i < length`` and ``1 <= length < 2^32``. This is Kensler's
    **approximation** of a random permutation, not an exactly uniform one: only
    2^32 patterns exist (far fewer than ``length!``) and the hash is a heuristic
    mixer. Used by ``correlated_multijittered``.

``permute_device(i, length, p)``
    :func:`permute` evaluated on the device by ``clsamp_permute`` (for checks;
    kernels call ``clsamp_permute`` directly).

``bounded_integers(seed, stream, realization, step, perm, range_)`` and ``bounded_integers_device``
    Exactly uniform integers in ``[0, range_)`` (Lemire's rejection) from the Philox
    words of (realization, step, perm): Fisher–Yates step ``t`` uses ``range_ = t + 1``.
    ``fisher_yates_draws`` returns all the draws of a batch at once.

OpenCL (``#include "permutation.h"``, which includes ``philox.h``)::

    uint clsamp_permute(uint i, uint length, uint p);            /* == permute */
    uint clsamp_bounded(uint2 key, uint stream, uint realization,
                        uint step, uint perm, uint range);       /* uniform in [0, range) */
    void clsamp_fisher_yates(__global uint *a, uint length, uint2 key, uint stream,
                             uint realization, uint perm);       /* one row of random_permutations */

where ``key`` is the seed as (low, high) words (:func:`clsamp.philox.seed_key`).

Philox counters: step ``t`` of permutation ``perm`` first draws lane ``t % 4`` of
block ``perm << 8`` at index ``t // 4`` (one Philox call serves four steps); its
retries (rare: probability below ``range / 2^32``) use index ``t`` and blocks
``(perm << 8) | 128 | a // 4``. Give each purpose its own ``stream``
(:class:`clsamp.philox.Stream`) or its own ``perm`` numbers.

References
----------
.. [1] R. Durstenfeld, "Algorithm 235: Random permutation", CACM 7(7), 1964.
.. [2] D. Lemire, "Fast random integer generation in an interval", ACM TOMACS 29(1), 2019.
.. [3] A. Kensler, "Correlated Multi-Jittered Sampling", Pixar Technical Memo 13-01, 2013.

Examples
--------
>>> from clsamp import permutation
>>> from clsamp.philox import Stream
>>> p = permutation.random_permutations(seed=1, stream=Stream.PERMUTATION, realizations=2,
...                                     length=5, perms=3)
>>> p.shape, sorted(p[1, 2].tolist())
((2, 3, 5), [0, 1, 2, 3, 4])
>>> sorted(int(v) for v in permutation.permute(range(6), 6, 0x1234))
[0, 1, 2, 3, 4, 5]
"""

import numpy as np

from . import philox, runtime
from .errors import InvalidArgumentError
from .validation import MAX_UINT32, check_int

FY_RETRIES = 512        # retries per step before accepting (probability < 2^-500)
MAX_PERM = 2**22        # perm numbers live in bits 8.. of the Philox block word

_MASK32 = np.uint64(0xFFFFFFFF)


def _u32(x):
    return np.asarray(x, dtype=np.uint64) & _MASK32


def permute(i, length, p):
    """Kensler's hash permutation: element ``i`` of the permutation of [0, length) named by ``p``.

    Parameters
    ----------
    i : array_like of int
        Indices in [0, length).
    length : int
        Length of the permutation, 1 <= length < 2^32.
    p : array_like of int
        32-bit pattern selecting the permutation (broadcasts against ``i``).

    Returns
    -------
    ndarray of uint32
        ``permute(i, length, p)``: a bijection of [0, length) for each fixed ``p``,
        identical to ``clsamp_permute`` in ``kernels/permutation.h``.

    Notes
    -----
    The hash is an invertible sequence of xor-shifts and odd multiplications on the
    bits below the next power of two ``w + 1 >= length``; values that land in
    [length, w] are hashed again (cycle walking), which keeps the map a bijection of
    [0, length). A final rotation by ``p`` modulo ``length`` removes the fixed point
    at zero. It approximates a random permutation; it is not exactly uniform.

    One deliberate difference from the listing: its final ``(i + p) % l`` is computed
    in 32 bits and is not a bijection when ``i + p`` wraps past 2^32 (for l = 3 and
    p = 0xffffffff it maps 0 and 1 both to 0); here the rotation is by ``p % l``,
    which equals the listing wherever the listing's sum does not wrap.

    References
    ----------
    .. [1] A. Kensler, "Correlated Multi-Jittered Sampling", Pixar Technical Memo 13-01, 2013.
    """
    length = check_int(length, "length", minimum=1, maximum=MAX_UINT32)
    i, p = np.broadcast_arrays(_u32(i), _u32(p))
    i = i.copy()
    if length == 1:
        return np.zeros(i.shape, dtype=np.uint32)
    w = length - 1
    for shift in (1, 2, 4, 8, 16):
        w |= w >> shift
    w = np.uint64(w)
    ln = np.uint64(length)
    todo = np.ones(i.shape, dtype=bool)
    with np.errstate(over="ignore"):
        while todo.any():
            x, q = i[todo], p[todo]
            x ^= q
            x = (x * np.uint64(0xE170893D)) & _MASK32
            x ^= q >> np.uint64(16)
            x ^= (x & w) >> np.uint64(4)
            x ^= q >> np.uint64(8)
            x = (x * np.uint64(0x0929EB3F)) & _MASK32
            x ^= q >> np.uint64(23)
            x ^= (x & w) >> np.uint64(1)
            x = (x * (np.uint64(1) | (q >> np.uint64(27)))) & _MASK32
            x = (x * np.uint64(0x6935FA69)) & _MASK32
            x ^= (x & w) >> np.uint64(11)
            x = (x * np.uint64(0x74DCB303)) & _MASK32
            x ^= (x & w) >> np.uint64(2)
            x = (x * np.uint64(0x9E501CC3)) & _MASK32
            x ^= (x & w) >> np.uint64(2)
            x = (x * np.uint64(0xC860A3DF)) & _MASK32
            x &= w
            x ^= x >> np.uint64(5)
            i[todo] = x
            todo[todo] = x >= ln
    # Kensler's (i + p) % l wraps in 32 bits and is then no bijection; rotate by p % l.
    return ((i + p % ln) % ln).astype(np.uint32)


def _as_range(value, name):
    if isinstance(value, range):
        if value.step != 1 or value.start < 0 or len(value) < 1:
            raise InvalidArgumentError(
                f"'{name}' must be a non-empty range with step 1 starting at >= 0, got {value!r}")
        return value
    return range(check_int(value, name, minimum=1))


def _check(realizations, length, perms):
    realizations = _as_range(realizations, "realizations")
    perms = _as_range(perms, "perms")
    length = check_int(length, "length", minimum=1, maximum=MAX_UINT32)
    if realizations.stop - 1 > MAX_UINT32:
        raise InvalidArgumentError(
            f"'realizations' must stay below 2^32, got {realizations!r}")
    if perms.stop > MAX_PERM:
        raise InvalidArgumentError(f"'perms' numbers must be below 2^22, got {perms!r}")
    return realizations, length, perms


def _retry(seed, stream, realization, step, perm, rng, m):
    """Lemire's rejection loop for the entries of ``m = first_word * rng`` that need it."""
    threshold = (np.uint64(2**32) - rng) % rng
    rejected = (m & _MASK32) < threshold
    for attempt in range(FY_RETRIES):
        if not rejected.any():
            break
        idx = np.nonzero(rejected)
        word = (perm[idx] << np.uint32(10)) | np.uint32(512 + attempt)
        retry = philox.random_words(seed, stream, realization[idx], step[idx], word)
        m[idx] = retry.astype(np.uint64) * rng[idx]
        rejected[idx] = (m[idx] & _MASK32) < threshold[idx]
    return (m >> np.uint64(32)).astype(np.uint32)


def bounded_integers(seed, stream, realization, step, perm, range_):
    """Uniform integers in ``[0, range_)`` from the Philox words of (realization, step, perm).

    The NumPy twin of ``clsamp_bounded`` in ``kernels/permutation.h`` (arguments
    broadcast; ``1 <= range_ < 2^32``): Lemire's multiply-and-reject, so each value is
    exactly uniform. Fisher–Yates step ``t`` of permutation ``perm`` uses
    ``range_ = t + 1``.

    Parameters
    ----------
    seed : int
        Seed in [0, 2^64): the Philox key.
    stream : int
        Philox stream (a :class:`clsamp.philox.Stream` number).
    realization, step, perm : int or array_like of int
        Which draw: together they name the Philox words it comes from.
    range_ : int or array_like of int
        Exclusive upper bounds, 1 to 2^32 - 1.

    Returns
    -------
    ndarray of uint32
        The broadcast shape.

    Raises
    ------
    InvalidArgumentError
        A ``range_`` of 0.
    """
    realization, step, perm, range_ = (np.array(a, dtype=np.uint32) for a in np.broadcast_arrays(
        np.asarray(realization), np.asarray(step), np.asarray(perm), np.asarray(range_)))
    if np.any(range_ == 0):
        raise InvalidArgumentError("'range_' must be >= 1 everywhere")
    first = philox.random_words(seed, stream, realization, step >> np.uint32(2),
                                (perm << np.uint32(10)) | (step & np.uint32(3)))
    rng = range_.astype(np.uint64)
    return _retry(seed, stream, realization, step, perm, rng, first.astype(np.uint64) * rng)


def fisher_yates_draws(seed, stream, realizations, length, perms):
    """The bounded integers Fisher–Yates uses: ``j[k, q, t]`` uniform in [0, t].

    Step ``t`` swaps positions ``t`` and ``j[..., t]``, for t = length-1 down to 1.
    Equal to ``bounded_integers(seed, stream, k, t, q, t + 1)``, computed with one
    Philox call per four steps.

    Parameters
    ----------
    seed, stream, realizations, length, perms
        As :func:`random_permutations`.

    Returns
    -------
    ndarray of uint32
        (len(realizations), len(perms), length); ``j[..., 0]`` is 0 (unused).
    """
    realizations, length, perms = _check(realizations, length, perms)
    shape = (len(realizations), len(perms), length)
    r = np.arange(realizations.start, realizations.stop, dtype=np.uint32)[:, None, None]
    q = np.arange(perms.start, perms.stop, dtype=np.uint32)[None, :, None]
    quads = (length + 3) // 4
    index = np.arange(quads, dtype=np.uint32)[None, None, :]
    counter = philox._counter(stream, r, index, q << np.uint32(8))
    words = philox.philox4x32(counter, np.stack(philox.seed_key(seed)))
    x = words.reshape(len(realizations), len(perms), 4 * quads)[..., :length].astype(np.uint64)
    step = np.broadcast_to(np.arange(length, dtype=np.uint32), shape)
    rng = step.astype(np.uint64) + np.uint64(1)
    draws = _retry(seed, stream, np.broadcast_to(r, shape), step, np.broadcast_to(q, shape),
                   rng, x * rng)
    draws[..., 0] = 0
    return draws


SLOW_SWAPS = 2**21      # Python swaps beyond which the NumPy reference shows a progress bar


def random_permutations(seed, stream, realizations, length, perms, progress=True):
    """Exactly uniform random permutations of [0, length) (NumPy reference).

    Parameters
    ----------
    seed : int
        Seed in [0, 2^64): the Philox key.
    stream : int
        Philox stream (a :class:`clsamp.philox.Stream` number) of this purpose.
    realizations : range or int
        Realization numbers (an int ``c`` means ``range(c)``).
    length : int
        Length of each permutation.
    perms : range or int
        Permutation numbers within a realization (an int ``c`` means ``range(c)``).
    progress : bool
        Show a progress bar when the swaps are many (more than ``SLOW_SWAPS``: they run
        as a Python loop).

    Returns
    -------
    ndarray of uint32, shape (len(realizations), len(perms), length)

    Notes
    -----
    Durstenfeld's Fisher–Yates: for t = length-1, ..., 1 swap ``a[t]`` with ``a[j_t]``,
    ``j_t`` uniform in [0, t]; with exactly uniform ``j_t`` (Lemire's rejection) every
    permutation has probability 1/length!. Bit-identical to
    :func:`random_permutations_device`.
    """
    draws = fisher_yates_draws(seed, stream, realizations, length, perms)
    out = np.empty(draws.shape, dtype=np.uint32)
    rows, perms_per_row, length = draws.shape
    bar = None
    if progress and rows * perms_per_row * length > SLOW_SWAPS:
        from tqdm import tqdm
        bar = tqdm(total=rows * perms_per_row, desc="permutations (NumPy)", unit="perm")
    for k in range(rows):
        for q in range(perms_per_row):
            a = list(range(length))
            j = draws[k, q].tolist()
            for t in range(length - 1, 0, -1):
                s = j[t]
                a[t], a[s] = a[s], a[t]
            out[k, q] = a
            if bar is not None:
                bar.update()
    if bar is not None:
        bar.close()
    return out


def random_permutations_device(seed, stream, realizations, length, perms):
    """:func:`random_permutations` made by the OpenCL kernel, as a device array.

    Parameters
    ----------
    seed, stream, realizations, length, perms
        As :func:`random_permutations`.

    Returns
    -------
    pyopencl.array.Array of uint32, shape (len(realizations), len(perms), length),
    on ``runtime.queue()``; bit-identical to :func:`random_permutations`.
    """
    import pyopencl.array as cla
    realizations, length, perms = _check(realizations, length, perms)
    rows = len(realizations) * len(perms)
    queue = runtime.queue()
    shape = (len(realizations), len(perms), length)
    draws = cla.empty(queue, shape, np.uint32)
    out = cla.empty(queue, shape, np.uint32)
    local = runtime.local_size()
    items = -(-length // 16)                                  # sixteen steps a work-item
    runtime.kernel("permutation.cl", "fisher_yates_draws")(
        queue, (-(-items // local) * local, rows), (local, 1), draws.data, np.uint32(length),
        np.uint32(len(perms)), np.uint32(perms.start), np.uint32(realizations.start),
        *philox.seed_key(seed), np.uint32(stream))
    # Few, long work-items: small work-groups let a CPU device spread them over its cores.
    compute_units = max(1, runtime.current_device().compute_units)
    local = runtime.local_size(max(1, rows // (4 * compute_units)))
    grid = (-(-rows // local) * local,)
    limit = runtime.loop_limit()
    if limit is None:
        runtime.kernel("permutation.cl", "fisher_yates_apply")(
            queue, grid, (local,), out.data, draws.data, np.uint32(length), np.uint32(rows))
        return out
    # a device that stops long loops: the identity in parallel, the swaps in pieces
    fill = runtime.local_size()
    runtime.kernel("permutation.cl", "fisher_yates_identity")(
        queue, (-(-length // fill) * fill, rows), (fill, 1), out.data, np.uint32(length),
        np.uint32(rows))
    swaps = runtime.kernel("permutation.cl", "fisher_yates_swaps")
    step = limit // 2
    high = length - 1
    while high > 0:
        low = max(0, high - step)
        swaps(queue, grid, (local,), out.data, draws.data, np.uint32(length), np.uint32(rows),
              np.uint32(high), np.uint32(low))
        high = low
    return out


def _device_args(*arrays):
    import pyopencl.array as cla
    return [cla.to_device(runtime.queue(), np.ascontiguousarray(a, dtype=np.uint32)) for a in arrays]


def permute_device(i, length, p):
    """:func:`permute` evaluated by ``clsamp_permute`` on the device (same values).

    Parameters
    ----------
    i, length, p
        As :func:`permute`.

    Returns
    -------
    ndarray of uint32
        The broadcast shape of ``i`` and ``p``, on the host.

    Raises
    ------
    InvalidArgumentError
        ``length`` out of range, or an ``i`` not below it.
    """
    length = check_int(length, "length", minimum=1, maximum=MAX_UINT32)
    i, p = np.broadcast_arrays(_u32(i), _u32(p))
    if i.size and int(i.max()) >= length:
        raise InvalidArgumentError(f"'i' must lie in [0, length={length}), got max {int(i.max())}")
    shape = i.shape
    i_d, p_d = _device_args(i.ravel(), p.ravel())
    import pyopencl.array as cla
    out = cla.empty(runtime.queue(), (max(1, i.size),), np.uint32)
    local = runtime.local_size()
    runtime.kernel("permutation.cl", "kensler_permute")(
        runtime.queue(), (-(-max(1, i.size) // local) * local,), (local,), out.data, i_d.data,
        p_d.data, np.uint32(length), np.uint32(i.size))
    return out.get()[:i.size].reshape(shape)


def bounded_integers_device(seed, stream, realization, step, perm, range_):
    """:func:`bounded_integers` evaluated by ``clsamp_bounded`` on the device.

    Parameters
    ----------
    seed, stream
        As :func:`bounded_integers`.
    realization, perm : int
        One realization and permutation number.
    step, range_ : int or array_like of int
        Broadcast against each other.

    Returns
    -------
    ndarray of uint32
        The broadcast shape of ``step`` and ``range_``, on the host.

    Raises
    ------
    InvalidArgumentError
        A ``range_`` of 0.
    """
    step, range_ = np.broadcast_arrays(_u32(step), _u32(range_))
    if np.any(range_ == 0):
        raise InvalidArgumentError("'range_' must be >= 1 everywhere")
    shape = step.shape
    s_d, r_d = _device_args(step.ravel(), range_.ravel())
    import pyopencl.array as cla
    count = max(1, step.size)
    out = cla.empty(runtime.queue(), (count,), np.uint32)
    local = runtime.local_size()
    runtime.kernel("permutation.cl", "bounded_integers")(
        runtime.queue(), (-(-count // local) * local,), (local,), out.data, s_d.data, r_d.data,
        np.uint32(step.size), np.uint32(perm), np.uint32(realization), *philox.seed_key(seed),
        np.uint32(stream))
    return out.get()[:step.size].reshape(shape)
