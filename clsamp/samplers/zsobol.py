"""``zsobol``: Owen-scrambled Sobol' indexed by the pixel's Morton code (Ahmed and Wonka 2020).

A renderer sampler: each pixel's samples are one aligned block of a single Owen-scrambled
(0, 2)-sequence, and the blocks are handed to pixels along a Z (Morton) curve with random
base-4 digit permutations, so neighbouring pixels get complementary parts of one
low-discrepancy sequence and their errors are negatively correlated: the error is pushed to
high screen-space frequencies (blue noise). As a point-set sampler, realization k is pixel k
(row-major) of an image of ``resolution``.
"""

import numpy as np

from .. import number_theory as nt
from .. import philox, runtime
from ..errors import InvalidArgumentError
from ..validation import check_image_size
from .base import Rate, Sampler, register

_U32, _U64 = np.uint32, np.uint64
# The 24 permutations of four base-4 digits, in lexicographic order (pbrt-v4's table).
PERMUTATIONS = np.array([[a, b, c, d] for a in range(4) for b in range(4) for c in range(4)
                         for d in range(4) if len({a, b, c, d}) == 4], dtype=np.uint32)
DEFAULT_RESOLUTION = 256


def morton2(x, y):
    """The Morton (Z-order) code of pixel (x, y): the bits of x and y interleaved, x in the
    even bits (pbrt-v4's EncodeMorton2).

    Parameters
    ----------
    x, y : int or array_like of int
        Coordinates below 2^16.

    Returns
    -------
    ndarray of uint64

    Examples
    --------
    >>> morton2([1, 0, 3], [0, 1, 3]).tolist()
    [1, 2, 15]
    """
    def spread(v):
        v = np.asarray(v, dtype=_U64) & _U64(0xFFFF)
        v = (v | (v << _U64(8))) & _U64(0x00FF00FF)
        v = (v | (v << _U64(4))) & _U64(0x0F0F0F0F)
        v = (v | (v << _U64(2))) & _U64(0x33333333)
        return (v | (v << _U64(1))) & _U64(0x55555555)
    return spread(x) | (spread(y) << _U64(1))


def _sobol1_bytes():
    """(4 x 256,) uint32: entry 256 k + b is the xor of Sobol' dimension 1's direction numbers
    of the set bits of byte b at bit 8 k (the kernel's table)."""
    v1 = nt.sobol_matrices(2)[1]
    out = np.zeros((4, 256), dtype=_U32)
    for k in range(4):
        for b in range(256):
            for c in range(8):
                if b >> c & 1:
                    out[k, b] ^= v1[8 * k + c]
    return out.ravel()


@register("zsobol")
class ZSobolSampler(Sampler):
    """Z-ordered Owen-scrambled Sobol' (Ahmed and Wonka 2020; pbrt-v4's ZSobolSampler).

    Pixel (x, y) with n = 2^m samples takes the Sobol' indices of its Morton code: sample
    s's index is ``(morton(x, y) << m) | s`` with every base-4 digit (from the top) replaced
    by one of the 24 permutations of {0, 1, 2, 3}, chosen by a 64-bit hash of the digits
    above it and a per-pair seed (an odd m leaves one last binary digit, flipped by a hash
    bit). The permutation of the digits above the sample bits picks which aligned block of
    2^m indices the pixel gets, the lower ones only reorder the pixel's samples; the first
    two Sobol' dimensions of the index (natural order), Owen-scrambled with the per-pair
    seed (as ``sobol:owen``), are the point. So each pixel's samples are a (0, m, 2)-net,
    no two pixels share an index, and the 4^k pixels of an aligned Morton square take
    disjoint blocks that together form a larger net: their errors cancel, which pushes the
    image's error to high frequencies.

    Dimensions come in pairs: pair p (coordinates 2p, 2p + 1; a last odd coordinate is the
    first of its pair) has its own digit permutations and scrambles, drawn from Philox
    with counter ``(seed, SCRAMBLE, realization 0, index p)`` (the same for every pixel,
    as the sequence is one). The digit hash is pbrt's MixBits of ``digits ^ seed64``
    instead of pbrt's ``digits ^ 0x55555555 * dimension``, so seeds differ; the algorithm is
    pbrt's, the bits are not.

    Parameters
    ----------
    d : int
        Dimension (any; pairs as above).
    seed : int
    resolution : int or (int, int)
        The image whose pixels the realizations are: realization k is pixel
        (k mod width, k // width). Morton codes cover the square of side the power of two
        at or above max(width, height); that side squared times n must stay within 2^32
        Sobol' indices (256 x 256 pixels: up to 65536 samples each). Default 256.
    backend : {"opencl", "numpy"}

    Notes
    -----
    n must be a power of two; ``start`` must be 0 (the permutations depend on n, so a pixel's
    set is made whole, as pbrt's sampler fixes its samples per pixel). The renderer
    (:func:`clsamp.render.render`) calls it with each pixel's number and the image's size,
    and does not pad it with permutations.

    References
    ----------
    .. [1] A. G. M. Ahmed, P. Wonka, "Screen-space blue-noise diffusion of Monte Carlo
       sampling error via hierarchical ordering of pixels", ACM TOG 39(6) (SIGGRAPH Asia 2020).
    .. [2] M. Pharr, W. Jakob, G. Humphreys, *Physically Based Rendering*, 4th ed., 8.7.7.
    .. [3] B. Burley, "Practical hash-based Owen scrambling", JCGT 9(4) (2020).

    Examples
    --------
    >>> import clsamp
    >>> s = clsamp.make_sampler("zsobol", d=2, seed=3, resolution=(64, 32))
    >>> s.sample(16, realizations=range(64, 66)).shape     # pixels (0, 1) and (1, 1)
    (2, 16, 2)
    """

    accepts_start = False
    host_output = True
    pixel_indexed = True

    def __init__(self, d=2, seed=0, backend="opencl", resolution=DEFAULT_RESOLUTION):
        super().__init__(d=d, seed=seed, backend=backend)
        self._set_resolution(resolution)

    def _set_resolution(self, resolution):
        self.width, self.height = check_image_size(resolution)
        self.log2_side = (max(self.width, self.height) - 1).bit_length()

    @property
    def max_n(self):
        """The most samples a pixel takes: the Morton code's bits leave 32 - 2 log2(side)."""
        return 1 << (32 - 2 * self.log2_side)

    def for_image(self, width, height):
        """A copy of this sampler for a (width, height) image, realization k being pixel k
        (row-major): what a renderer asks of a pixel-indexed sampler.

        Parameters
        ----------
        width, height : int
            The image's size in pixels.

        Returns
        -------
        ZSobolSampler
            The same seed and dimension.
        """
        other = self.with_seed(self.seed)
        other._set_resolution((width, height))
        return other

    def __repr__(self):
        return (f"ZSobolSampler(name='zsobol', d={self.d}, seed={self.seed}, "
                f"resolution=({self.width}, {self.height}))")

    def valid_n(self, n):
        """The valid point count nearest to ``n``: a power of two (the smaller on a tie),
        at most ``max_n`` (which the resolution sets).

        Parameters
        ----------
        n : int

        Returns
        -------
        int
        """
        if n <= 1:
            return 1
        low = 1 << (n.bit_length() - 1)
        best = low if n - low <= 2 * low - n else 2 * low
        return min(best, self.max_n)

    def convergence_rate(self, case):
        """The published rate of the MSE for ``case`` (:meth:`Sampler.convergence_rate`).

        Each pixel's set is a nested-scrambled (0, m, 2)-net: N^-3 for smooth integrands
        (Owen 1997), N^-1.5 for discontinuous ones (He and Wang 2015).

        Parameters
        ----------
        case : {"best", "worst", "axis"}
            The integrand as the estimator sees it (:func:`clsamp.theory.case_of`).

        Returns
        -------
        Rate or None
            None for d other than 2.
        """
        if self.d != 2:
            return None
        return {"best": Rate(-3.0, "Owen 1997"), "worst": Rate(-1.5, "He and Wang 2015")}.get(case)

    # -- shared by both paths -------------------------------------------------------------
    def _check_pixels(self, realizations):
        if realizations.stop > self.width * self.height:
            raise InvalidArgumentError(
                f"'realizations' are pixels of the {self.width} x {self.height} image (0 to "
                f"{self.width * self.height - 1}), got {realizations!r}; pass a larger 'resolution'")

    def _pair_words(self):
        """(pairs, 4) uint32: Owen seeds of x and y, and the 64-bit digit-permutation seed."""
        pairs = -(-self.d // 2)
        return philox.random_words(self.seed, philox.Stream.SCRAMBLE, 0,
                                   np.arange(pairs, dtype=_U32)[:, None],
                                   np.arange(4, dtype=_U32)[None, :])

    # -- NumPy reference --------------------------------------------------------------------
    def sample_indices(self, n, pixels, pair_seed):
        """The Sobol' indices of the samples of ``pixels`` (the NumPy reference).

        Parameters
        ----------
        n : int
            Samples a pixel, a power of two.
        pixels : array_like of int
            Pixel numbers, row-major in the image.
        pair_seed : int
            The 64-bit seed of the digit permutations.

        Returns
        -------
        ndarray
            uint64 of shape (len(pixels), n).
        """
        m = n.bit_length() - 1
        odd = m & 1
        pixels = np.asarray(pixels, dtype=_U64)
        code = morton2(pixels % _U64(self.width), pixels // _U64(self.width))
        index = (code[:, None] << _U64(m)) | np.arange(n, dtype=_U64)[None, :]
        digits = self.log2_side + (m + 1) // 2
        out = np.zeros_like(index)
        seed = _U64(pair_seed)
        for i in range(digits - 1, odd - 1, -1):
            shift = _U64(2 * i - odd)
            digit = (index >> shift) & _U64(3)
            higher = index >> (shift + _U64(2))
            p = (nt.mix64(higher ^ seed) >> _U64(24)) % _U64(24)
            out |= PERMUTATIONS[p, digit].astype(_U64) << shift
        if odd:
            flip = nt.mix64((index >> _U64(1)) ^ seed) & _U64(1)
            out |= (index & _U64(1)) ^ flip
        return out

    def _reference(self, n, realizations, start):
        self._check_pixels(realizations)
        pixels = np.arange(realizations.start, realizations.stop)
        words = self._pair_words()
        v1 = nt.sobol_matrices(2)[1]
        out = np.empty((len(pixels), n, self.d))
        for p in range(words.shape[0]):
            seed64 = int(words[p, 2]) | (int(words[p, 3]) << 32)
            index = self.sample_indices(n, pixels, seed64).astype(_U32)
            x = nt.reverse_bits32(index)                       # Sobol' dimension 0, natural order
            y = np.zeros_like(index)
            for c in range(32):
                y ^= np.where((index >> _U32(c)) & _U32(1), v1[c], _U32(0))
            out[:, :, 2 * p] = nt.owen_scramble_base2(x, words[p, 0]) * 2.0**-32
            if 2 * p + 1 < self.d:
                out[:, :, 2 * p + 1] = nt.owen_scramble_base2(y, words[p, 1]) * 2.0**-32
        return out

    # -- OpenCL ---------------------------------------------------------------------------------
    def _device(self, n, realizations, start, out=None):
        self._check_pixels(realizations)
        words = self._pair_words()
        table = runtime.to_device(words)
        perms = runtime.table(("zsobol", "perms"), lambda: PERMUTATIONS)
        v1 = runtime.table(("zsobol", "bytes"), _sobol1_bytes)
        r = len(realizations)
        target = runtime.Output((r, n, self.d), host=out)
        local = runtime.local_size()
        kernel = runtime.kernel("zsobol.cl", "zsobol_points")
        items = -(-n // 16)                                 # ZS_BLOCK samples a work-item
        kernel(runtime.queue(), (-(-items // local) * local, r), (local, 1), target.buffer, table.data,
               perms.data, v1.data, np.uint32(n), np.uint32(n.bit_length() - 1), np.uint32(self.d),
               np.uint32(realizations.start), np.uint32(self.width), np.uint32(self.log2_side))
        return target.finish()
