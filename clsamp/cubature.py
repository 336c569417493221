"""Guaranteed adaptive cubature on one randomized sequence: the cone-based error bounds of
Hickernell and Jiménez Rugama, for digital nets (fast Walsh transform) and for rank-1
lattices (fast Fourier transform).

With n = 2^m points of a digital net (a lattice), the discrete Walsh (Fourier)
coefficients f~_m(κ) of the integrand's values estimate its true coefficients. For
integrands in a cone C, whose coefficients decay steadily, the sum of the true
coefficients that alias onto the mean is bounded by a multiple of a sum of the discrete
ones that the points can see:

    |I - mean| <= C(m) S~_(m-r, m)(f),   S~_(m-r, m) = sum_(κ = 2^(m-r-1))^(2^(m-r) - 1) |f~_m(κ~(κ))|,

with r = 4 (``R_LAG``) and the inflation factor C(m) = 5 2^-m (``fudge``), κ~ the
ordering of the wavenumbers that puts each coefficient before the smaller ones it aliases
with (``_order_wavenumbers``). n doubles from 2^10 until the bound meets the tolerance.
The algorithm, its constants and the wavenumber ordering are those of the authors' GAIL
``cubSobol_g`` / ``cubLattice_g`` and of qmcpy's ``CubQMCNetG`` / ``CubQMCLatticeG``.

The Walsh transform, the doubling's butterfly and the wavenumber ordering of a digital net
run on the device where it has fp64 (:mod:`clsamp.cubature_device`, the same bits as the
NumPy here); the lattice's spectrum is built on the host a doubling at a time (a real FFT,
``scipy.fft``, of the new values and the radix-2 step), its wavenumber ordering on the
device as the net's. The points come from the samplers (on the device; a lattice's first
few thousand from the sampler's NumPy twin, the same bits), or, for an integrand with a
kernel, are made in the kernel that evaluates it (:mod:`clsamp.fused`).

References
----------
.. [1] F. J. Hickernell, Ll. A. Jiménez Rugama, "Reliable adaptive cubature using digital
   sequences", in Monte Carlo and Quasi-Monte Carlo Methods, MCQMC 2014, Springer (2016),
   367-383.
.. [2] Ll. A. Jiménez Rugama, F. J. Hickernell, "Adaptive multidimensional integration
   based on rank-1 lattices", in Monte Carlo and Quasi-Monte Carlo Methods, MCQMC 2014,
   Springer (2016), 407-422.
.. [3] F. J. Hickernell, Ll. A. Jiménez Rugama, D. Li, "Adaptive quasi-Monte Carlo methods
   for cubature", in Contemporary Computational Mathematics, Springer (2018), 597-619
   (the estimate that meets a relative tolerance).
"""

import math
import warnings

import numpy as np

from . import runtime
from .cubature_device import DeviceWalsh
from .errors import InvalidArgumentError
from .samplers import make_sampler
from .transforms import sidi, tent

M_MIN = 10               # the first 2^10 points (qmcpy's n_init)
R_LAG = 4                # r: the bound sums the coefficients of wavenumbers 2^(m-r-1) .. 2^(m-r) - 1
PERIODIZATIONS = ("none", "baker", "sidi")
_ONE_BELOW = 1.0 - 2.0**-53
CHUNK = 2**22            # coordinates sampled and evaluated at a time: 2^20 points in 3-D or 4-D
# a digital net's state moves to the device at the doubling of this many points: below it
# the launches cost more than the NumPy passes (docs/performance.md, "The Walsh state on
# the device (issue 38)")
DEVICE_FROM = 2**16
# a lattice's chunks of at most this many coordinates come from the sampler's NumPy twin
# (the same bits), below the cost of a launch and a read-back (docs/performance.md)
HOST_LATTICE = 2**14

__all__ = ["fudge", "walsh_coefficients", "fourier_coefficients", "Cubature", "PERIODIZATIONS"]


def fudge(m):
    """The inflation factor C(m) = 5 2^-m of the error bound (the authors' default).

    Parameters
    ----------
    m : int
        log2 of the number of points.

    Returns
    -------
    float
    """
    return 5.0 * 2.0**-m


def walsh_coefficients(y):
    """The discrete Walsh coefficients (1/n) sum_i y_i (-1)^popcount(k & i), k = 0 .. n-1.

    Parameters
    ----------
    y : ndarray of float64
        Values at the points of a base-2 digital net in natural (radical-inverse) order,
        x_i = C i: n a power of 2.

    Returns
    -------
    ndarray of float64
        (n,); entry 0 is the mean.

    Examples
    --------
    >>> walsh_coefficients(np.array([1.0, 2.0, 3.0, 4.0])).tolist()
    [2.5, -0.5, -1.0, 0.0]
    """
    n = y.size
    out = np.array(y, dtype=np.float64)
    h = 1
    while h < n:
        if 4 * h <= n:
            # two levels of butterflies in one pass (radix 4): the additions of two radix-2
            # levels in their order, at about half the memory traffic
            a = out.reshape(-1, 4, h)
            p, q, r, s = a[:, 0], a[:, 1], a[:, 2], a[:, 3]
            s0, d0, s1, d1 = p + q, p - q, r + s, r - s
            a[:, 0], a[:, 1], a[:, 2], a[:, 3] = s0 + s1, d0 + d1, s0 - s1, d0 - d1
            h *= 4
        else:                            # butterflies over bit log2(h) of the index
            a = out.reshape(-1, 2, h)
            low = a[:, 0] - a[:, 1]
            a[:, 0] += a[:, 1]
            a[:, 1] = low
            h *= 2
    return out / n


def fourier_coefficients(y):
    """The discrete Fourier coefficients (1/n) sum_j y(x_j) e^(-2 pi i jk/n) of a rank-1
    lattice, from values in radical-inverse order.

    Parameters
    ----------
    y : ndarray of float64
        Values at the points of the sequence frac(Φ_2(i) z + Δ), i = 0 .. n-1: point i is
        the lattice's point j = Φ_2(i) n; n a power of 2.

    Returns
    -------
    ndarray of complex128
        (n,); entry 0 is the mean.
    """
    return _spectrum(_half_spectrum(y[_bit_reversal(y.size.bit_length() - 1)]))


def _spectrum(half):
    """The whole spectrum of a real sequence of n values from its half, k = 0 .. n/2, by the
    conjugate symmetry c_(n-k) = conj(c_k)."""
    n = 2 * (half.size - 1)
    return np.concatenate([half, np.conj(half[1:n - n // 2][::-1])])


def _half_spectrum(values):
    """The Fourier coefficients k = 0 .. n/2 of values in lattice order (entry j at the
    lattice's point j / n): a real FFT, scaled by 1/n."""
    import scipy.fft
    half = scipy.fft.rfft(values)
    half *= 1.0 / values.size              # exact: n is a power of 2
    return half


class _LatticeSpectrum:
    """A lattice's half spectrum, c_k for k = 0 .. n/2, kept from one doubling to the next.

    The first 2^m values: one real FFT in lattice order. A doubling: point n + k of the
    sequence is the lattice's point 2 Φ_2(k) n + 1 of 2n, so the held values are the even
    points of the 2n and the new ones the odd, and the radix-2 step of the FFT gives
    c_k = (E_k + w^k O_k) / 2 and c_(n-k) = conj(E_k - w^k O_k) / 2 for k <= n/2, with
    E the held half spectrum, O the new values' (a real FFT of n values in their lattice
    order) and w = e^(-i pi / n). The twiddles w^k are kept too: a doubling's even ones are
    the last doubling's, its odd ones those times w (:meth:`twiddles`).
    """

    def __init__(self):
        self.half = self._w = None

    def add(self, y):
        """Take the values of the next points (the first 2^m, or as many as are held)."""
        n = y.size
        new = _half_spectrum(y[_bit_reversal(n.bit_length() - 1)])
        if self.half is None:
            self.half = new
            return
        new *= self.twiddles(n)
        out = np.empty(n + 1, dtype=np.complex128)
        np.add(self.half[:n // 2], new[:n // 2], out=out[:n // 2])
        top = out[n // 2:][::-1]                        # top[k] is c_(n - k), k <= n/2
        np.subtract(self.half, new, out=top)
        np.conjugate(top, out=top)
        out *= 0.5
        self.half = out

    def twiddles(self, n):
        """e^(-i pi k / n) for k = 0 .. n/2 (n a power of 2, each call's n twice the last's)."""
        if self._w is None or 2 * (self._w.size - 1) * 2 != n:
            k = np.arange(n // 2 + 1) * (-math.pi / n)
            w = np.empty(k.size, dtype=np.complex128)
            np.cos(k, out=w.real)
            np.sin(k, out=w.imag)
        else:
            w = np.empty(n // 2 + 1, dtype=np.complex128)
            w[0::2] = self._w
            w[1::2] = self._w[:-1] * complex(math.cos(math.pi / n), -math.sin(math.pi / n))
        self._w = w
        return w


def _bit_reversal(m):
    """The permutation of 0 .. 2^m - 1 that reverses each index's m bits (int64)."""
    r = np.zeros(2**m, dtype=np.int64)
    for level in range(m):            # r_(l+1) = (2 r_l, 2 r_l + 1)
        h = 2**level
        r[:h] *= 2
        np.add(r[:h], 1, out=r[h:2 * h])
    return r


def _order_wavenumbers(kappa, size, top, bottom, m):
    """Reorder the map κ -> wavenumber so that of each pair (κ, κ + 2^l) that alias at
    level l the larger coefficient comes first, for l = top, top - 1, .., bottom + 1 (GAIL's
    ``kappanumap``)."""
    for level in range(top, bottom, -1):
        nl = 2**level
        flip = np.flatnonzero(size[kappa[nl + 1:2 * nl]] > size[kappa[1:nl]]) + 1
        if flip.size:
            # the same swaps in every block of 2 nl wavenumbers
            blocks = kappa[:2**m].reshape(-1, 2 * nl)
            held = blocks[:, flip]
            blocks[:, flip] = blocks[:, flip + nl]
            blocks[:, flip + nl] = held
    return kappa


def _periodize(values, x, periodization):
    if periodization == "none":
        return values(np.minimum(x, _ONE_BELOW))
    if periodization == "baker":
        y = tent(x)
        return values(np.minimum(y, _ONE_BELOW, out=y))
    psi, weight = sidi(x, 2)
    return values(np.minimum(psi, _ONE_BELOW)) * np.prod(weight, axis=1)


class Cubature:
    """One run of the adaptive rule: the points, the coefficients, the bound.

    Parameters
    ----------
    values : callable
        (count, d) points -> (count,) values of f (checked by the caller).
    d : int
        The dimension.
    method : {"digital", "lattice"}
        A Sobol' net (Joe-Kuo) in natural order with Matoušek's linear matrix scrambling and
        a digital shift (``make_sampler("digital_net", randomize="lms+shift")``, qmcpy's
        ``DigitalNetB2`` default; the points of ``sobol:lms+shift``, reordered) and Walsh
        coefficients, or a shifted rank-1 lattice in
        radical-inverse order (``make_sampler("lattice", randomize="shift")``, Kuo's
        vector) and Fourier coefficients.
    seed : int
        Of the shift.
    periodization : {"none", "baker", "sidi"}
        Lattice only: f is integrated as f(ψ(x)) prod ψ'(x_j) with Baker's tent or
        Sidi's sin^2 transform (:func:`clsamp.transforms.sidi`, k = 2).
    block : callable, optional
        (start, count) -> the (periodized) values at points start .. start + count - 1 in
        natural order, made without the sampler: :meth:`clsamp.fused.FusedRule.values`,
        whose kernel makes the same points. ``values`` is not called then.
    fill : callable, optional
        With ``block``, for a digital net's state on the device: (start, count, out) writes
        those values into the device array ``out`` (:meth:`clsamp.fused.FusedRule.fill`), so
        that they never cross to the host.
    device : bool, optional
        From the doubling of :data:`DEVICE_FROM` points on, keep the state on the device
        (:class:`clsamp.cubature_device.DeviceWalsh`, the same bits): a net's Walsh
        coefficients and ordering, transformed there; a lattice's ordering, reordered there
        by the magnitudes of the spectrum the host computes. None: where the current device
        has fp64.
    max_n : int, optional
        The most points the run will take (sizes the device's arrays).

    Notes
    -----
    :meth:`step` evaluates the next 2^m points (the first 2^10 on the first call) and
    returns (mean, bound). A net's Walsh coefficients are updated in O(n log n) from those
    of the points already seen (the new half's transform and the doubling's butterfly); a
    lattice's half spectrum likewise (the new half's real FFT and the radix-2 step with
    its twiddles, :class:`_LatticeSpectrum`). See the module's references.
    """

    def __init__(self, values, d, method, seed, periodization="none", block=None, device=None,
                 max_n=None, fill=None):
        if method == "digital":
            # natural order, which the transform reads: point i is L C i xor the shift
            self.sampler = make_sampler("digital_net", d=d, seed=seed, randomize="lms+shift")
        else:
            self.sampler = make_sampler("lattice", d=d, seed=seed, randomize="shift")
            self._twin = make_sampler("lattice", d=d, seed=seed, randomize="shift", backend="numpy")
        self.values, self.method, self.periodization = values, method, periodization
        self.fused, self.fill = block, fill
        self.n, self.total = 0, 0.0
        self._coefficients = self._kappa = None
        self._spectrum = _LatticeSpectrum() if method == "lattice" else None
        if device is None:
            device = runtime.current_device().fp64
        self.walsh = DeviceWalsh(max_n) if device else None

    @property
    def coefficients(self):
        """The discrete Walsh (Fourier) coefficients of the 2^m values so far, on the host."""
        if self.method == "lattice":
            return _spectrum(self._spectrum.half)
        return self._coefficients if self._coefficients is not None else self.walsh.coefficients()

    @property
    def kappa(self):
        """The wavenumber ordering (``_order_wavenumbers``), on the host."""
        return self._kappa if self._kappa is not None else self.walsh.ordering()

    @property
    def label(self):
        """The sampler and transform, as the result reports them."""
        if self.method == "lattice" and self.periodization != "none":
            return f"{self.sampler.label}, {self.periodization}"
        return self.sampler.label

    def _block(self, start, count):
        """f at the points start .. start + count - 1, in natural order for the transform,
        a power of 2 of points at a time, at most CHUNK coordinates (count and start are
        multiples of a power of 2 >= the chunk)."""
        if self.fused is not None:
            return self.fused(start, count)
        chunk = min(count, 1 << max(0, (CHUNK // self.sampler.d).bit_length() - 1))
        return np.concatenate([self._chunk(base, chunk) for base in range(start, start + count, chunk)])

    def _chunk(self, start, count):
        if self.method == "lattice":
            sampler = self._twin if count * self.sampler.d <= HOST_LATTICE else self.sampler
            return _periodize(self.values, sampler.sample(count, start=start), self.periodization)
        with warnings.catch_warnings():     # a chunk alone is no net; the 2^m points together are
            warnings.filterwarnings("ignore", "the balance properties of", UserWarning)
            return self.values(self.sampler.sample(count, start=start))

    def step(self):
        """Evaluate the next points (2^10 at first, then as many as are done) and bound the error.

        Returns
        -------
        mean, bound : float
            The sample mean of the 2^m points and C(m) S~_(m-r, m). A net's mean is its
            Walsh coefficient of wavenumber 0 (the transform's sum, on the host or the
            device alike), a lattice's the values' ``np.sum`` over n.
        """
        if self.walsh is not None and self.n >= DEVICE_FROM:
            return self._device_step()
        first = self.n == 0
        n = 2**M_MIN if first else self.n
        y = self._block(self.n, n)
        size = n if first else 2 * n
        m = size.bit_length() - 1
        if self.method == "lattice":
            self._spectrum.add(y)
            half = np.abs(self._spectrum.half)
            magnitudes = np.concatenate([half, half[1:size - size // 2][::-1]])
        else:
            new = walsh_coefficients(y)
            if not first:
                # the doubling's butterfly, (c + new, c - new) / 2, written into one new array
                both = np.empty(2 * n)
                np.add(self._coefficients, new, out=both[:n])
                np.subtract(self._coefficients, new, out=both[n:])
                both *= 0.5
                new = both
            self._coefficients = new
            magnitudes = np.abs(new)
        if first:
            self._kappa = _order_wavenumbers(np.arange(n), magnitudes, m - 1, 0, m)
        else:
            self._kappa = _order_wavenumbers(np.concatenate([self._kappa, n + self._kappa]),
                                             magnitudes, m - 1, m - R_LAG - 1, m)
        if self.method == "lattice":
            self.total += float(np.sum(y))
            mean = self.total / size
        else:
            mean = float(self._coefficients[0])
        self.n = size
        low = 2**(m - R_LAG - 1)
        bound = fudge(m) * float(np.sum(magnitudes[self._kappa[low:2 * low]]))
        return mean, bound

    def _device_step(self):
        """:meth:`step` with the coefficients (a lattice's magnitudes) and the ordering on the
        device from the doubling of :data:`DEVICE_FROM` points on: the same operations
        (kernels/walsh.cl), the same bits."""
        if self._kappa is not None:                 # the host's state moves over once
            self.walsh.load(self._coefficients, self._kappa)
            self._coefficients = self._kappa = None
        n = 2 * self.n
        m = n.bit_length() - 1
        if self.method == "lattice":        # the values come to the host, for the FFT
            y = self._block(self.n, self.n)
            self._spectrum.add(y)
            self.total += float(np.sum(y))
            self.walsh.double_lattice(np.abs(self._spectrum.half), m - R_LAG - 1)
        elif self.fill is not None:         # the values stay on the device
            self.fill(self.n, self.n, self.walsh.values_buffer())
            self.walsh.double(None, m - R_LAG - 1)
        else:
            self.walsh.double(self._block(self.n, self.n), m - R_LAG - 1)
        self.n = n
        mean, terms = self.walsh.summary(2**(m - R_LAG - 1))
        if self.method == "lattice":
            mean = self.total / n
        return mean, fudge(m) * float(np.sum(terms))


def combine(mean, bound, abs_tol, rel_tol):
    """The estimate that meets max(abs_tol, rel_tol |I|) for every I in mean +- bound, if one does.

    Parameters
    ----------
    mean, bound : float
    abs_tol, rel_tol : float
        0 for a tolerance not asked.

    Returns
    -------
    estimate, half_width : float
        The estimate and the largest distance from it to mean +- bound.
    met : bool
        Whether every I in mean +- bound is within max(abs_tol, rel_tol |I|) of it.

    Notes
    -----
    The estimate is (l + u + tol(l) - tol(u)) / 2 for the interval [l, u] (Hickernell,
    Jiménez Rugama and Li 2018, the module's [3]); with rel_tol = 0 it is the mean.
    """
    low, high = mean - bound, mean + bound

    def tol(v):
        return max(abs_tol, rel_tol * abs(v))

    estimate = 0.5 * (low + high + tol(low) - tol(high))
    met = high - low <= tol(low) + tol(high)
    return estimate, max(estimate - low, high - estimate), met


def check_periodization(periodization, method):
    """The periodization a method uses (None: Baker's tent for lattices, none for nets).

    Parameters
    ----------
    periodization : str or None
        One of :data:`PERIODIZATIONS`, or None for the method's default.
    method : str
        The integration method (a periodization other than "none" needs "lattice").

    Returns
    -------
    str
        One of :data:`PERIODIZATIONS`.

    Raises
    ------
    InvalidArgumentError
        An unknown periodization, or one given to a method other than "lattice".
    """
    if periodization is None:
        return "baker" if method == "lattice" else "none"
    if not isinstance(periodization, str) or periodization not in PERIODIZATIONS:
        raise InvalidArgumentError(
            f"'periodization' must be one of {', '.join(map(repr, PERIODIZATIONS))} or None, "
            f"got {periodization!r}")
    if method != "lattice" and periodization != "none":
        raise InvalidArgumentError(
            f"'periodization' applies to method='lattice' only, got {periodization!r} with "
            f"method={method!r}")
    return periodization
