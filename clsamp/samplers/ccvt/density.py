"""The density points of CCVT: stratified (jittered) or i.i.d. uniform on the integer torus.

OpenCL: ``ccvt_density`` and ``ccvt_density_jittered`` (``kernels/ccvt_density.cl``);
NumPy reference: :func:`density_points`, the same integers.
"""

import math

import numpy as np

from ... import philox, runtime
from ...geometry import integer_torus as it
from ...validation import check_choice
from .pairs import ccvt_defines

DENSITIES = ("jittered", "random")


def density_rows(M):
    """Rows of the jittered density: isqrt(M). Row i holds points floor(i M / k) to
    floor((i+1) M / k) - 1, so every row has isqrt(M) to isqrt(M) + 2 cells and every
    cell is within a factor (1 + 2 / isqrt(M))^2 of square.

    Parameters
    ----------
    M : int
        Density points.

    Returns
    -------
    int
    """
    return max(1, math.isqrt(M))


def density_points(seed, realizations, M, density="jittered"):
    """The density, uint32 (r, M, 2) on the integer torus.

    ``"random"``: M i.i.d. uniform points from words 4, 5 (Philox block 1) of
    (seed, Stream.INIT, r, j). ``"jittered"``: the same words place point j uniformly in
    its own stratum of an equal-area partition of the torus into exactly M cells:
    k = :func:`density_rows` rows, row i of height c_i / M cut into c_i cells of width
    1 / c_i, c_i = floor((i+1) M / k) - floor(i M / k) (Bresenham: any M, near-square
    cells, unlike a kx-by-ky grid that needs a divisor of M and degenerates into 1 x M
    strips for prime M); then the whole set is shifted by a random toroidal offset (words
    6, 7 of (seed, Stream.INIT, r, 0)), which makes the density, hence the optimized
    sites, stationary on the torus. All integer arithmetic, exact in 64 bits. The sites'
    starting positions use words 0, 1 of block 0.

    Parameters
    ----------
    seed : int
    realizations : array_like of int
    M : int
        Density points a realization.
    density : {"jittered", "random"}

    Returns
    -------
    ndarray of uint32
        (len(realizations), M, 2), integer torus coordinates.
    """
    check_choice(density, "density", DENSITIES)
    r = np.asarray(realizations, dtype=np.uint32)[:, None, None]
    j = np.arange(M, dtype=np.uint32)[None, :, None]
    w = np.arange(4, 6, dtype=np.uint32)[None, None, :]
    u = philox.random_words(seed, philox.Stream.INIT, r, j, w) >> np.uint32(32 - it.BITS)
    if density == "random":
        return u
    k = np.uint64(density_rows(M))
    M64, bits = np.uint64(M), np.uint64(it.BITS)
    j = np.arange(M, dtype=np.uint64)
    row = ((j + np.uint64(1)) * k - np.uint64(1)) // M64
    start = row * M64 // k
    c = ((row + np.uint64(1)) * M64 // k - start)[None, :]
    u = u.astype(np.uint64)
    x = (((j - start)[None, :] << bits) + u[..., 0]) // c
    y = ((start[None, :] << bits) + u[..., 1] * c) // M64
    shift = philox.random_words(seed, philox.Stream.INIT, r[:, :, 0], np.uint32(0),
                                np.arange(6, 8, dtype=np.uint32)[None, :])
    shift = (shift >> np.uint32(32 - it.BITS)).astype(np.uint64)
    mask = np.uint64(it.MASK)
    return np.stack([(x + shift[:, 0:1]) & mask, (y + shift[:, 1:2]) & mask],
                    axis=-1).astype(np.uint32)


def density_points_device(seed, realizations, M, density="jittered"):
    """:func:`density_points` made by the ``ccvt_density`` / ``ccvt_density_jittered``
    kernels (the same integers).

    Parameters
    ----------
    seed, realizations, M, density
        As :func:`density_points`; the realizations must be consecutive.

    Returns
    -------
    pyopencl.array.Array of uint32
        (len(realizations), M, 2).
    """
    import pyopencl.array as cla
    check_choice(density, "density", DENSITIES)
    realizations = np.asarray(realizations)
    r = len(realizations)
    out = cla.empty(runtime.queue(), (r, M, 2), np.uint32)
    if r and not np.array_equal(realizations, realizations[0] + np.arange(r)):
        raise ValueError("realizations must be consecutive")
    if r == 0:
        return out
    key = (*philox.seed_key(seed), np.uint32(philox.Stream.INIT))
    if density == "random":
        kernel = runtime.kernel("ccvt_density.cl", "ccvt_density", ccvt_defines())
        kernel(runtime.queue(), (M, r), None, out.data, np.uint32(M),
               np.uint32(realizations[0]), *key)
    else:
        kernel = runtime.kernel("ccvt_density.cl", "ccvt_density_jittered", ccvt_defines())
        kernel(runtime.queue(), (M, r), None, out.data, np.uint32(M),
               np.uint32(density_rows(M)), np.uint32(realizations[0]), *key)
    return out
