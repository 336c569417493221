"""Philox4x32-10 counter-based random numbers: the NumPy reference.

Salmon, Moraes, Dror, Shaw, "Parallel random numbers: as easy as 1, 2, 3"
(SC 2011). The OpenCL twin is ``kernels/philox.h``; both produce bit-identical
words for the same key and counter, and tests hold them together with the
Random123 known-answer vectors.

clsamp's convention (docs/design.md, "Conventions"): the key is the 64-bit ``seed``
split into two 32-bit words (low, high); the counter is ``(index, realization, block,
stream)`` where ``block`` numbers the groups of four 32-bit words (two doubles) drawn for
one point. So point ``index`` of realization ``r`` gets the same numbers however
many points or realizations were asked for, and different purposes inside one
sampler (point coordinates, permutations, shifts) use different values of ``stream``.
"""

import numpy as np

M0 = np.uint64(0xD2511F53)
M1 = np.uint64(0xCD9E8D57)
W0 = np.uint32(0x9E3779B9)
W1 = np.uint32(0xBB67AE85)
_LOW32 = np.uint64(0xFFFFFFFF)
_SHIFT32 = np.uint64(32)


class Stream:
    """Stream numbers: one per purpose, so purposes never share random words.

    Kernels receive the stream as an argument; these names keep Python and the
    NumPy references in agreement.
    """

    POINTS = 0          # coordinates of random, jittered, ... points
    PERMUTATION = 1     # shuffles (LHS, MJ, CMJ, padding)
    SCRAMBLE = 2        # Owen / xor / digit permutation seeds
    SHIFT = 3           # Cranley-Patterson rotations and homogenization shifts
    CANDIDATES = 4      # dart-throwing candidates
    PIXEL = 5           # per-pixel decorrelation in the renderer
    INIT = 6            # initial sites of optimizing samplers
    EXPERIMENT = 7      # convergence experiments
    FAMILY = 8          # the members of integrand families
    DIRECTIONS = 9      # the directions of sliced optimal transport (sot)


def seed_key(seed):
    """The Philox key words (low, high) of a 64-bit seed.

    Parameters
    ----------
    seed : int
        0 to 2^64 - 1.

    Returns
    -------
    (numpy.uint32, numpy.uint32)

    Examples
    --------
    >>> [int(w) for w in seed_key(2**32 + 7)]
    [7, 1]
    """
    seed = int(seed)
    return np.uint32(seed & 0xFFFFFFFF), np.uint32((seed >> 32) & 0xFFFFFFFF)


def philox4x32(counter, key):
    """Philox4x32 with 10 rounds.

    Parameters
    ----------
    counter : array_like of uint32, shape (..., 4)
    key : array_like of uint32, shape (..., 2)

    Returns
    -------
    ndarray of uint32, shape (..., 4) (the broadcast of counter and key)

    Examples
    --------
    >>> [hex(w) for w in philox4x32([0, 0, 0, 0], [0, 0]).tolist()]   # Random123's answer
    ['0x6627e8d5', '0xe169c58d', '0xbc57ac4c', '0x9b00dbd8']
    """
    counter = np.asarray(counter, dtype=np.uint32)
    key = np.asarray(key, dtype=np.uint32)
    c0, c1, c2, c3 = (counter[..., i] for i in range(4))
    k0, k1 = key[..., 0], key[..., 1]
    with np.errstate(over="ignore"):
        for round_ in range(10):
            if round_:
                k0 = k0 + W0
                k1 = k1 + W1
            p0 = M0 * c0.astype(np.uint64)
            p1 = M1 * c2.astype(np.uint64)
            hi0 = (p0 >> _SHIFT32).astype(np.uint32)
            lo0 = (p0 & _LOW32).astype(np.uint32)
            hi1 = (p1 >> _SHIFT32).astype(np.uint32)
            lo1 = (p1 & _LOW32).astype(np.uint32)
            c0, c1, c2, c3 = hi1 ^ c1 ^ k0, lo1, hi0 ^ c3 ^ k1, lo0
    return np.stack(np.broadcast_arrays(c0, c1, c2, c3), axis=-1)


def _counter(stream, realization, index, block):
    parts = np.broadcast_arrays(
        np.asarray(index, dtype=np.uint32),
        np.asarray(realization, dtype=np.uint32),
        np.asarray(block, dtype=np.uint32),
        np.asarray(stream, dtype=np.uint32))
    return np.stack(parts, axis=-1)


def random_words(seed, stream, realization, index, word):
    """32-bit random words: word ``w`` of (seed, stream, realization, index).

    Arguments broadcast. Words 4b..4b+3 come from one Philox call with block b,
    exactly as ``clsamp_bits`` in ``kernels/philox.h``.

    Parameters
    ----------
    seed : int
        64-bit seed (the key).
    stream : int or array_like of int
        The purpose (:class:`Stream`).
    realization, index, word : int or array_like of int

    Returns
    -------
    ndarray of uint32
        The broadcast shape.
    """
    word = np.asarray(word, dtype=np.uint32)
    out = philox4x32(_counter(stream, realization, index, word >> np.uint32(2)),
                     np.stack(seed_key(seed)))
    return np.take_along_axis(out, (word & np.uint32(3)).astype(np.intp)[..., None]
                              * np.ones(out.shape[:-1] + (1,), dtype=np.intp), axis=-1)[..., 0]


def words_to_unit(hi, lo):
    """A double in [0, 1) with 53 random bits from two 32-bit words (genrand_res53).

    Parameters
    ----------
    hi, lo : int or array_like of int
        32-bit words: the top 27 bits of ``hi`` and of ``lo`` the top 26 are used.

    Returns
    -------
    ndarray of float64
        (hi >> 5) 2^-27 + (lo >> 6) 2^-53.

    Examples
    --------
    >>> float(words_to_unit(2**31, 0)), float(words_to_unit(2**32 - 1, 2**32 - 1)) == 1 - 2**-53
    (0.5, True)
    """
    hi = np.asarray(hi, dtype=np.uint32) >> np.uint32(5)
    lo = np.asarray(lo, dtype=np.uint32) >> np.uint32(6)
    return (hi.astype(np.float64) * 67108864.0 + lo.astype(np.float64)) * (1.0 / 9007199254740992.0)


def uniform(seed, stream, realization, index, dim):
    """Uniform doubles in [0, 1): coordinate ``dim`` of point ``index``.

    Dimension pair (2b, 2b+1) comes from Philox block b: words (0, 1) make the
    even dimension and words (2, 3) the odd one. Arguments broadcast.

    Parameters
    ----------
    seed : int
        64-bit seed.
    stream : int
        The purpose (:class:`Stream`).
    realization, index, dim : int or array_like of int

    Returns
    -------
    ndarray of float64
        The broadcast shape.
    """
    dim = np.asarray(dim, dtype=np.uint32)
    out = philox4x32(_counter(stream, realization, index, dim >> np.uint32(1)),
                     np.stack(seed_key(seed)))
    odd = (dim & np.uint32(1)).astype(bool)
    hi = np.where(odd, out[..., 2], out[..., 0])
    lo = np.where(odd, out[..., 3], out[..., 1])
    return words_to_unit(hi, lo)


def uniform_pair(seed, stream, realization, index, block):
    """Coordinates 2 ``block`` and 2 ``block`` + 1 of point ``index``, from one Philox call:
    ``uniform(..., 2 block)`` and ``uniform(..., 2 block + 1)``, the same bits at half the
    work. Arguments broadcast.

    Parameters
    ----------
    seed : int
    stream : int
        The purpose (:class:`Stream`).
    realization, index, block : int or array_like of int

    Returns
    -------
    even, odd : ndarray of float64
        The broadcast shape.

    Examples
    --------
    >>> even, odd = uniform_pair(7, Stream.POINTS, 0, 3, 1)
    >>> bool(even == uniform(7, Stream.POINTS, 0, 3, 2)), bool(odd == uniform(7, Stream.POINTS, 0, 3, 3))
    (True, True)
    """
    out = philox4x32(_counter(stream, realization, index, block), np.stack(seed_key(seed)))
    return words_to_unit(out[..., 0], out[..., 1]), words_to_unit(out[..., 2], out[..., 3])


def uniform_block(seed, stream, realizations, n, d, start=0):
    """Uniform points: the NumPy reference of the ``random`` sampler.

    Parameters
    ----------
    seed : int
    stream : int
        The purpose (:class:`Stream`); the sampler uses ``Stream.POINTS``.
    realizations : array_like of int
    n, d : int
        Points a set and their dimension.
    start : int
        The index of the first point.

    Returns
    -------
    ndarray of float64
        (len(realizations), n, d).

    Examples
    --------
    >>> uniform_block(1, Stream.POINTS, [0, 3], 4, 2).shape
    (2, 4, 2)
    """
    r = np.asarray(realizations, dtype=np.uint32)[:, None, None]
    i = (np.uint64(start) + np.arange(n, dtype=np.uint64)).astype(np.uint32)[None, :, None]
    j = np.arange(d, dtype=np.uint32)[None, None, :]
    return uniform(seed, stream, r, i, j)
