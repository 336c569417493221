"""Dither masks (threshold arrays): void and cluster, in 1 to 4 dimensions, and its
spatiotemporal variant, with the power spectrum of their ranks.

A dither mask of side ``size`` in d dimensions holds each rank 0 .. size^d - 1 once;
thresholding it at any level k gives a blue-noise binary pattern of k ones, and every
such pattern holds the patterns of the lower levels (the ranks are progressive).
"""

import math

import numpy as np

from .. import philox, runtime
from ..errors import InvalidArgumentError, NoDeviceError
from ..validation import check_choice, check_int, check_real, check_seed

__all__ = ["dither_mask", "mask_spectrum", "SIGMA", "INITIAL_DENSITY"]

SIGMA = 1.9                 # the Gaussian's standard deviation, in pixels (Wolfe et al.)
SIGMA_RANGE = (0.01, 1e6)   # the standard deviations accepted
INITIAL_DENSITY = 0.1       # the share of ones in the initial binary pattern (Ulichney)
ENERGY_LOSS = 0.005         # the Gaussian is cut where it has fallen to this share
MAX_PIXELS = 1 << 24        # the largest mask built (its steps are sequential)
MAX_WORK = 1 << 35          # pixels x window: the energies its steps update, at most
MAX_TWIN_PIXELS = 1 << 20   # the largest mask of the NumPy twin (an argmax over it a step)
BLOCK = 8                   # pixels a leaf of the device's tournament trees


def _offsets(sigma, side):
    """(offsets, weights) of the 1-D Gaussian window on a ring of ``side`` pixels, each
    pixel once: radius sqrt(-2 sigma^2 ln ENERGY_LOSS), at most the ring."""
    radius = int(math.sqrt(-2.0 * sigma * sigma * math.log(ENERGY_LOSS)))
    if 2 * radius + 1 <= side:
        offsets = np.arange(-radius, radius + 1)
    else:
        offsets = np.arange(-(side // 2), side - side // 2)
    return offsets, np.exp(-(offsets * offsets) / (2.0 * sigma * sigma))


class _Energy:
    """The energy of a binary pattern on a periodic grid and its two masked views: ``hi``
    (the energy at ones, -inf at zeros: the tightest cluster is its argmax) and ``lo``
    (the energy at zeros, +inf at ones: the largest void is its argmin).

    Each stencil is (axes, offsets per axis, weights over those axes): a one at p adds the
    weights around p along those axes, the other coordinates fixed at p's.
    """

    def __init__(self, shape, stencils):
        self.shape = shape
        self.stencils = stencils
        self.on = np.zeros(shape, dtype=bool)
        self.energy = np.zeros(shape)
        self.hi = np.full(shape, -np.inf)
        self.lo = np.zeros(shape)

    def _window(self, point, axes, offsets):
        index = []
        for axis, size in enumerate(self.shape):
            if axis in axes:
                k = axes.index(axis)
                view = [1] * len(axes)
                view[k] = -1
                index.append(((point[axis] + offsets[k]) % size).reshape(view))
            else:
                index.append(point[axis])
        return tuple(index)

    def splat(self, flat, sign):
        point = np.unravel_index(flat, self.shape)
        for axes, offsets, weights in self.stencils:
            window = self._window(point, axes, offsets)
            for array in (self.energy, self.hi, self.lo):
                array[window] += sign * weights

    def set(self, flat, value):
        point = np.unravel_index(flat, self.shape)
        self.on[point] = value
        self.hi[point] = self.energy[point] if value else -np.inf
        self.lo[point] = np.inf if value else self.energy[point]
        self.splat(flat, 1.0 if value else -1.0)

    def tightest_cluster(self):
        return int(np.argmax(self.hi))

    def largest_void(self):
        return int(np.argmin(self.lo))

    def copy(self):
        other = _Energy(self.shape, self.stencils)
        for name in ("on", "energy", "hi", "lo"):
            setattr(other, name, getattr(self, name).copy())
        return other


def dither_mask(size, d=2, seed=0, temporal=None, sigma=SIGMA, backend="opencl"):
    """A blue-noise dither mask by void and cluster: each rank 0 .. size^d - 1 once.

    Parameters
    ----------
    size : int
        Pixels per side, at least 2.
    d : int
        Dimensions of the mask (1 to 4; 2 for an image).
    seed : int
        Seed of the initial binary pattern (clsamp's Philox stream ``INIT``): the same
        seed gives the same mask everywhere.
    temporal : int, optional
        Frames of a spatiotemporal mask (Wolfe et al. 2022): shape (temporal, size, ...,
        size), each rank 0 .. temporal size^d - 1 once, each frame a blue-noise mask and
        each pixel's sequence over the frames blue too.
    sigma : float
        The standard deviation of the Gaussian energy, in pixels (frames along time),
        0.01 to 10^6 (default 1.9).
    backend : {"opencl", "numpy"}
        Where the steps run: the current device where it is a CPU device with double
        precision and no loop limit, else NumPy; "numpy" always NumPy. Both give the same
        ranks.

    Returns
    -------
    ndarray of int64
        Shape (size,) * d, or (temporal,) + (size,) * d.

    Raises
    ------
    InvalidArgumentError
        A bad argument, or a mask too large for the time its steps take: more than 2^24
        pixels; more than 2^35 energy updates, the pixels times the Gaussian's window
        (tens of minutes on a CPU device: 256^3 at the default sigma, or 64^4); on NumPy
        (``backend="numpy"``, or a device that does not run the steps) more than 2^20
        pixels: an argmax a step makes it O(N^2) (512 x 512 takes about a minute, each
        doubling of the side 16 times that).

    Notes
    -----
    Ulichney's void and cluster (1993) on the periodic grid, with the energy of a binary
    pattern the sum over its ones of a Gaussian of the (wrapped) distance. An initial
    pattern of 10 % ones, drawn from the seed, is made blue by moving the one in the
    tightest cluster (the largest energy among ones) into the largest void (the smallest
    energy among zeros) until the two coincide. Its ones are then ranked by removing the
    tightest cluster repeatedly (ranks below the initial count), zeros are ranked by
    filling the largest void until half the pixels are ones, and the rest by the same
    removal on the inverted pattern. Thresholding at any level gives a blue-noise pattern
    that contains all lower levels.

    The spatiotemporal variant changes only the energy (Wolfe, Morrical, Ramamoorthi
    2022): two pixels interact through the d-D Gaussian when they are in the same frame
    and through a 1-D Gaussian of their frame distance when they are the same pixel, not
    at all otherwise, so frames are blue in space and pixels blue in time. The Gaussians
    are cut where they fall to 0.5 % (sigma 1.9: 6 pixels), as the authors' code does.
    The steps are sequential, so one work-item on the device runs them all, each a local
    update of the energy and of two tournament trees over blocks of 8 pixels (the
    tightest cluster and the largest void at their roots): O(w log N) a step for a
    window of w pixels. The NumPy twin takes an argmax over the mask a step, O(N).

    References
    ----------
    .. [1] R. Ulichney, "The void-and-cluster method for dither array generation", Proc.
       SPIE 1913, Human Vision, Visual Processing, and Digital Display IV, 1993.
    .. [2] A. Wolfe, N. Morrical, R. Ramamoorthi, "Spatiotemporal blue
       noise masks", Eurographics Symposium on Rendering, 2022.

    Examples
    --------
    >>> import numpy as np, clsamp
    >>> mask = clsamp.dither_mask(16, seed=1)
    >>> mask.shape, bool(np.array_equal(np.sort(mask.ravel()), np.arange(256)))
    ((16, 16), True)
    >>> clsamp.dither_mask(8, seed=1, temporal=4).shape
    (4, 8, 8)
    """
    size = check_int(size, "size", minimum=2)
    d = check_int(d, "d")
    if not 1 <= d <= 4:
        raise InvalidArgumentError(f"'d' must be 1 to 4, got {d}")
    seed = check_seed(seed)
    if temporal is not None:
        temporal = check_int(temporal, "temporal", minimum=2)
    # beyond these the Gaussian's 2 sigma^2 underflows or its radius overflows
    sigma = check_real(sigma, "sigma", minimum=SIGMA_RANGE[0], maximum=SIGMA_RANGE[1])
    shape = (size,) * d if temporal is None else (temporal,) + (size,) * d
    total = math.prod(shape)
    if total > MAX_PIXELS:
        names = "'size' and 'd'" if temporal is None else "'size', 'd' and 'temporal'"
        raise InvalidArgumentError(f"{names} give a mask of {total} pixels ({' x '.join(map(str, shape))}); "
                                   f"at most {MAX_PIXELS}")
    backend = check_choice(backend, "backend", ("opencl", "numpy"))
    window = sum(math.prod(len(_offsets(sigma, shape[a])[0]) for a in axes)
                 for axes in _stencil_axes(shape, temporal is not None))
    if total * window > MAX_WORK:
        raise InvalidArgumentError(
            f"'size'={size}, 'd'={d}, 'sigma'={sigma:g}"
            f"{'' if temporal is None else f', temporal={temporal}'}: {total} pixels, each step "
            f"updating a window of {window}, make {total * window:.3g} energy updates, more than "
            f"2^35 (tens of minutes); give a smaller size or sigma")
    device = backend == "opencl" and _device_runs_it()
    if not device and total > MAX_TWIN_PIXELS:
        why = "backend='numpy'" if backend == "numpy" else "this device does not run the steps"
        raise InvalidArgumentError(
            f"'size'={size}: NumPy makes the mask here ({why}), an argmax over all {total} "
            f"pixels a step, and takes at most 2^20 pixels (512 x 512 takes about a minute, "
            "each doubling of the side 16 times that); give a smaller size, or a CPU OpenCL device")
    stencils = _mask_stencils(shape, temporal is not None, sigma)
    ones, initial = _initial_ones(total, seed)
    if device:
        ranks = _void_and_cluster_device(shape, stencils, initial[:ones])
    else:
        ranks = _void_and_cluster(_Energy(shape, stencils), total, ones, initial)
    return ranks.reshape(shape)


def _device_runs_it():
    """Whether the current device runs the steps: a CPU that shares the host's memory (one
    work-item's walk on a GPU is unmeasured, and an integrated GPU's watchdog may end it),
    with fp64 and no loop limit; False where there is no device at all."""
    try:
        device = runtime.current_device()
    except NoDeviceError:       # no OpenCL at all: NumPy gives the same ranks
        return False
    return (device.type == "cpu" and device.host_memory and device.fp64
            and runtime.loop_limit() is None)


def _initial_ones(total, seed):
    """The initial pattern's count of ones (``INITIAL_DENSITY`` of the pixels, 2 to half)
    and the pixels in the order they are set: the first ``ones`` of it."""
    ones = min(max(2, int(total * INITIAL_DENSITY)), total // 2)
    u = philox.uniform(seed, philox.Stream.INIT, 0, np.arange(total, dtype=np.uint32), 0)
    return ones, np.argsort(u, kind="stable")


def _stencil_axes(shape, temporal):
    """The axes of each stencil: all of them, or space and then time."""
    return [tuple(range(len(shape)))] if not temporal else [tuple(range(1, len(shape))), (0,)]


def _mask_stencils(shape, temporal, sigma):
    def gaussian(axes):
        parts = [_offsets(sigma, shape[a]) for a in axes]
        weights = np.ones([len(o) for o, _ in parts])
        for k, (_, w) in enumerate(parts):
            view = [1] * len(parts)
            view[k] = -1
            weights = weights * w.reshape(view)
        return tuple(axes), [o for o, _ in parts], weights
    return [gaussian(axes) for axes in _stencil_axes(shape, temporal)]


def _void_and_cluster(state, total, ones, initial):
    """The ranks of every pixel (flat), the three phases of Ulichney's method (the twin of
    ``void_and_cluster`` in ``kernels/dither.cl``)."""
    for flat in initial[:ones]:
        state.set(int(flat), True)
    for _ in range(10 * total):            # at most; it ends when cluster and void coincide
        cluster = state.tightest_cluster()
        state.set(cluster, False)
        void = state.largest_void()
        state.set(void, True)
        if void == cluster:
            break
    ranks = np.full(total, -1, dtype=np.int64)
    initial = state.copy()
    for left in range(ones - 1, -1, -1):  # phase 1: the initial ones, tightest first out
        cluster = state.tightest_cluster()
        ranks[cluster] = left
        state.set(cluster, False)
    state = initial
    for count in range(ones, total // 2):  # phase 2: fill the largest voids to half
        void = state.largest_void()
        ranks[void] = count
        state.set(void, True)
    inverted = _Energy(state.shape, state.stencils)
    for flat in np.flatnonzero(~state.on.ravel()):
        inverted.set(int(flat), True)
    for count in range(total // 2, total):  # phase 3: the zeros, as ones of the inverse
        cluster = inverted.tightest_cluster()
        ranks[cluster] = count
        inverted.set(cluster, False)
    return ranks


def _void_and_cluster_device(shape, stencils, initial):
    """:func:`_void_and_cluster`'s ranks by ``void_and_cluster`` (``kernels/dither.cl``)."""
    total = math.prod(shape)
    blocks = -(-total // BLOCK)
    P = 1 << max(0, (blocks - 1).bit_length())
    stride = [math.prod(shape[a + 1:]) for a in range(len(shape))]
    meta = np.zeros((len(stencils), 16), dtype=np.int32)
    offsets, weights = [], []
    for s, (axes, axis_offsets, w) in enumerate(stencils):
        meta[s, 0] = len(axes)
        for k, (axis, o) in enumerate(zip(axes, axis_offsets, strict=True)):
            meta[s, 1 + k], meta[s, 5 + k] = axis, len(o)
            meta[s, 9 + k] = sum(len(x) for x in offsets)
            offsets.append(np.asarray(o, dtype=np.int32))
        meta[s, 13] = sum(x.size for x in weights)
        meta[s, 14] = w.size
        weights.append(np.ascontiguousarray(w, dtype=np.float64).ravel())
    buf = runtime.input_buffer
    rank = runtime.Output((total,), np.int64, host=np.empty(total, dtype=np.int64))
    scratch = [runtime.Output((n,), t) for n, t in
               ((total, np.float64), (total, np.uint8), (total, np.float64), (total, np.uint8),
                (2 * P, np.uint32), (2 * P, np.uint32), (P, np.uint32),
                (1 + sum(x.size for x in weights), np.uint32))]
    runtime.kernel("dither.cl", "void_and_cluster", {"VC_BLOCK": BLOCK})(
        runtime.queue(), (1,), (1,), np.uint32(total), np.uint32(P), np.uint32(len(shape)),
        buf(np.asarray(shape, dtype=np.uint32)), buf(np.asarray(stride, dtype=np.uint32)),
        np.uint32(len(stencils)), buf(meta.ravel()), buf(np.concatenate(offsets)),
        buf(np.concatenate(weights)), buf(np.asarray(initial, dtype=np.uint32)),
        np.uint32(len(initial)), *(o.buffer for o in scratch), rank.buffer)
    runtime.wait()                  # Ctrl-C is taken while it runs
    return rank.finish()


def mask_spectrum(mask, axes=None):
    """The power spectrum of a mask's thresholds, 1 for white noise at every frequency.

    Parameters
    ----------
    mask : ndarray of int
        Ranks (:func:`dither_mask`), any shape.
    axes : tuple of int, optional
        The axes transformed (default all); the others are averaged over, e.g. ``axes=(0,)``
        of a spatiotemporal mask: each pixel's sequence over time.

    Returns
    -------
    ndarray
        |F(k)|^2 / (M var) of the thresholds over the transformed axes (M their pixels),
        zero frequency first (``numpy.fft`` order) and set to 0; white noise (a random
        permutation of the ranks) has expectation 1 at every other frequency, blue noise
        little power at low frequencies.

    Examples
    --------
    >>> import numpy as np, clsamp
    >>> from clsamp.samplers.dither import mask_spectrum
    >>> P = mask_spectrum(clsamp.dither_mask(32, seed=2))
    >>> bool(P[:3, :3].sum() < 0.5 * 8)
    True
    """
    values = np.asarray(mask, dtype=np.float64)
    axes = tuple(range(values.ndim)) if axes is None else tuple(axes)
    centred = values - values.mean(axis=axes, keepdims=True)
    count = math.prod(values.shape[a] for a in axes)
    var = np.mean(centred * centred, axis=axes, keepdims=True)
    power = np.abs(np.fft.fftn(centred, axes=axes)) ** 2 / (count * np.where(var > 0, var, 1.0))
    others = tuple(a for a in range(values.ndim) if a not in axes)
    power = power.mean(axis=others) if others else power
    power.flat[0] = 0.0
    return power
