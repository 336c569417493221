"""Low-discrepancy samplers: ``van_der_corput``, ``halton``, ``hammersley`` and ``sobol``.

Each takes ``randomize=`` one of ``None`` (the textbook points; the first point of each
sequence is the origin, as in scipy.stats.qmc), ``"shift"`` (Cranley-Patterson
rotation), ``"xor"`` (random digit scramble: an xor in base 2, a random digit shift
mod b in base b), ``"owen"`` (nested uniform scrambling), for ``van_der_corput`` and
``halton`` also ``"permute"`` (random digit permutations, pbrt's PermuteDigits; not
offered by ``hammersley`` and ``sobol``), and for ``sobol`` (every base-2 digital net,
:class:`DigitalNetB2`) also ``"lms"`` and ``"lms+shift"`` (Matoušek's linear matrix
scrambling, without and with the digital shift of ``"xor"``).

Realization k's randomization (shift vector, scramble seeds) is drawn from Philox with
counter realization k: for dimension j the words of
``(seed, Stream.SCRAMBLE, realization k, index j, block 0)`` seed the scrambles and
``philox.uniform(seed, Stream.SHIFT, k, 0, j)`` is the shift. So realization k does not
depend on how many realizations were asked for, and the OpenCL kernels
(``kernels/lowdiscrepancy.cl``) and the NumPy references below (on
:mod:`clsamp.number_theory`) give bit-identical points.
"""

import functools
import warnings

import numpy as np

from .. import generating_matrices as gm
from .. import number_theory as nt
from .. import philox, runtime
from ..errors import InvalidArgumentError, NoDeviceError
from ..geometry import torus
from ..validation import check_choice, check_int
from . import higher_order
from .base import Rate, Sampler, register

# RANDOMIZE in the kernel: LMS scrambles the matrices (lms_matrices), then plain or xor points
_CODES = {None: 0, "shift": 1, "xor": 2, "owen": 3, "permute": 4, "lms": 0, "lms+shift": 2}
LMS = ("lms", "lms+shift")
_SCALE32 = 2.0**-32
MAX_HALTON_DIMENSION = 21201


def scramble_words(seed, realizations, d):
    """The four Philox words seeding dimension j's scramble in each realization.

    Parameters
    ----------
    seed : int
    realizations : array_like of int
    d : int

    Returns
    -------
    ndarray of uint32
        (len(realizations), d, 4): words (0, 1) are the 64-bit seed of the digit
        randomizations (``Stream.SCRAMBLE``, counter (j, realization, 0, stream)).
    """
    r = np.asarray(realizations, dtype=np.uint32)[:, None, None]
    j = np.arange(d, dtype=np.uint32)[None, :, None]
    w = np.arange(4, dtype=np.uint32)[None, None, :]
    return philox.random_words(seed, philox.Stream.SCRAMBLE, r, j, w)


def shift_vectors(seed, realizations, d):
    """Cranley-Patterson shifts: one uniform vector in [0, 1)^d per realization.

    Parameters
    ----------
    seed : int
    realizations : array_like of int
    d : int

    Returns
    -------
    ndarray of float64
        (len(realizations), d), from ``Stream.SHIFT`` (remembered for up to 64 realizations).
    """
    r = tuple(np.asarray(realizations, dtype=np.uint32).tolist())
    return (_few_shifts if len(r) <= 64 else _few_shifts.__wrapped__)(int(seed), r, int(d)).copy()


@functools.lru_cache(maxsize=64)
def _few_shifts(seed, r, d):
    return philox.uniform(seed, philox.Stream.SHIFT, np.array(r, dtype=np.uint32)[:, None], 0,
                          np.arange(d, dtype=np.uint32)[None, :])


OWEN_TABLE_ENTRIES_PER_DIGIT = 2**15   # a depth's table: at most this times b entries
OWEN_TABLE_BYTES = 64 * 2**20          # all tables of one launch
OWEN_LOOP_BASE = 2048                  # largest owen base where runtime.loop_limit() applies


def owen_table_layout(bases, n, realizations=1):
    """Which nodes of the Owen digit trees the kernel tabulates before a launch of n points.

    Nodes near the root are shared by many points: the root (depth 0, b entries) of
    every base b >= 3, and depth k >= 1 while its b^(k+1) entries are at most
    min(4 n, OWEN_TABLE_ENTRIES_PER_DIGIT b) (a point's shuffle costs about b/2 steps,
    so a large base gains the most from a table). While the tables of ``realizations``
    realizations pass OWEN_TABLE_BYTES, the largest deepest table goes. A choice of
    speed only: a table holds the same permutations the kernel computes without it.

    Parameters
    ----------
    bases : sequence of int
        Each dimension's base (0 or 2: no table).
    n : int
        Points of the launch.
    realizations : int
        Realizations of the launch (each has its own tables).

    Returns
    -------
    layout : ndarray of uint32
        The ``owen_layout`` of ``kernels/lowdiscrepancy.cl``: per dimension, its first
        segment and its tabulated depths; then per segment, dimension, depth, first node
        and offset.
    segments, nodes, entries : int
        Per realization: the tables, the nodes they hold and their entries.
    """
    bases = [int(b) for b in bases]
    depths = []
    for b in bases:
        k = 0
        if b >= 3:
            limit = min(4 * max(1, int(n)), OWEN_TABLE_ENTRIES_PER_DIGIT * b)
            m, power = nt.digit_count(b), b
            k = 1
            while k < m and power * b <= limit:
                power *= b
                k += 1
        depths.append(k)
    budget = OWEN_TABLE_BYTES // (4 * max(1, realizations))
    total = sum(sum(b**(k + 1) for k in range(kk)) for b, kk in zip(bases, depths, strict=True))
    while total > budget:
        j = max(range(len(bases)), key=lambda j: bases[j]**depths[j] if depths[j] else 0)
        total -= bases[j]**depths[j]
        depths[j] -= 1
    dims, segs = [], []
    node = offset = 0
    for j, (b, kk) in enumerate(zip(bases, depths, strict=True)):
        dims += [len(segs) // 4, kk]
        for k in range(kk):
            segs += [j, k, node, offset]
            node += b**k
            offset += b**(k + 1)
    layout = np.array(dims + segs, dtype=np.uint32)
    return layout, len(segs) // 4, node, offset


class LowDiscrepancySampler(Sampler):
    """What the low-discrepancy samplers share (also lattice.py's): ``randomize=``, the launch and
    the Philox draws.

    Parameters
    ----------
    d : int
        Dimension.
    seed : int
        Seeds the randomization; without one the points do not depend on it.
    backend : {"opencl", "numpy"}
    randomize : str or None
        One of the subclass's ``randomizations``.
    """

    sequence = True
    host_output = True
    randomizations = (None, "shift", "xor", "owen")

    def __init__(self, d=2, seed=0, backend="opencl", randomize=None):
        super().__init__(d=d, seed=seed, backend=backend)
        self.randomize = check_choice(randomize, "randomize", self.randomizations)

    @property
    def randomized(self):
        """Whether the seed changes the points: with a randomization only."""
        return self.randomize is not None

    def __repr__(self):
        return (f"{type(self).__name__}(name={self.name!r}, d={self.d}, seed={self.seed}, "
                f"randomize={self.randomize!r})")

    def _rotated(self, points, realizations):
        """``points`` (r, n, d), Cranley-Patterson rotated by each realization's shift vector
        where ``randomize`` is ``"shift"``; else themselves."""
        if self.randomize != "shift":
            return points
        return torus.shift(points, shift_vectors(self.seed, realizations, self.d)[:, None, :])

    def _seed64(self, realizations):
        words = scramble_words(self.seed, np.arange(realizations.start, realizations.stop), self.d)
        return words[..., 0].astype(np.uint64) | (words[..., 1].astype(np.uint64) << np.uint64(32))

    @staticmethod
    def _block():
        # A work-item makes `block` consecutive points by cheap increments, after a start that costs about as
        # much as a few dozen of them (the index's digits: m dependent divisions per dimension); on a CPU 256
        # points of 16 dimensions still fit its L1 while the item fills them column by column; on a GPU one
        # point an item keeps the most items in flight (runtime.shape). At most 4 where the device stops long
        # loops (runtime.loop_limit). The bits do not depend on it.
        block = runtime.shape().block
        return block if runtime.loop_limit() is None else min(block, 4)

    def _launch(self, kernel_name, table, n, realizations, start, defines, out=None, extra=()):
        """Run a kernel into a new device array, or into the host array ``out`` (returned);
        ``extra`` are kernel arguments after the common ones."""
        r = len(realizations)
        queue = runtime.queue()
        target = runtime.Output((r, n, self.d), host=out)
        block = self._block()
        local = runtime.local_size()
        items = -(-n // block)
        split, grid, group = runtime.dimension_split(
            self.d, 256 if kernel_name == "sobol_points" else 4, (-(-items // local) * local, r),
            (local, 1))
        kernel = runtime.kernel("lowdiscrepancy.cl", kernel_name,
                                defines={"RANDOMIZE": _CODES[self.randomize], "LD_BLOCK": block,
                                         **defines, **split})
        kernel(queue, grid, group, target.buffer, table.data,
               np.uint32(n), np.uint32(self.d),
               start if isinstance(start, np.uint64) else np.uint32(start),   # sobol_points64's
               np.uint32(realizations.start),
               *philox.seed_key(self.seed), np.uint32(philox.Stream.SCRAMBLE),
               np.uint32(philox.Stream.SHIFT), *extra)
        return target.finish()


class DigitalNetB2(LowDiscrepancySampler):
    """A digital net in base 2 from its generating matrices, in Gray-code order: what
    ``sobol``, ``niederreiter`` and base-2 ``digital_net`` share (one kernel,
    ``sobol_points``, and its NumPy twin).

    Point i, dimension j is 2^-32 ⊕_c g_c(i) V_jc, g(i) = i ⊕ (i >> 1), V_jc the column
    words of :meth:`gray_columns`. Randomizations: ``"shift"``, ``"xor"``, ``"owen"`` as
    for Sobol'; ``"lms"`` replaces every matrix by L V with L a random non-singular
    lower-triangular binary matrix (Matoušek 1998), one per realization and dimension,
    made on the device (kernel ``lms_matrices``; :func:`clsamp.generating_matrices.lms_row_masks`);
    ``"lms+shift"`` then xors ``"xor"``'s digit vector. Every randomization but
    ``"shift"`` keeps each prefix of 2^m points a (t, m, d)-net.

    ``order`` alpha >= 2 (``sobol``, base-2 ``digital_net``): the higher-order net that
    interlaces the digits of base dimensions alpha j .. alpha j + alpha - 1 into dimension j
    (:mod:`clsamp.samplers.higher_order`, Dick 2008), with None, ``"xor"``, ``"lms"`` and
    ``"lms+shift"`` (L per base dimension, interlaced).

    Parameters
    ----------
    d : int
    seed : int
    backend : {"opencl", "numpy"}
    randomize : {None, "shift", "xor", "owen", "lms", "lms+shift"}
    """

    randomizations = (None, "shift", "xor", "owen", "lms", "lms+shift")
    net_name = "digital net"
    base = 2
    order = 1

    def base_columns(self):
        """The base net's column words, before interlacing.

        Returns
        -------
        ndarray of uint32
            (order d, 32).
        """
        raise NotImplementedError

    def gray_columns(self):
        """The column words the Gray-code kernel xors: :meth:`base_columns`, interlaced
        for a higher-order net.

        Returns
        -------
        ndarray of uint32
            (d, 32).
        """
        return gm.interlace_columns(self.base_columns(), self.order)

    def __repr__(self):
        text = super().__repr__()
        return text if self.order == 1 else text[:-1] + f", order={self.order})"

    def _set_order(self, order, base_dimensions, source):
        """Keep ``order`` (:func:`clsamp.samplers.higher_order.check_order`)."""
        self.order = higher_order.check_order(order, self.d, self.randomize, base_dimensions, source)

    def convergence_rate(self, case):
        """The published rate of the MSE (:meth:`Sampler.convergence_rate`; with ``order``
        >= 2, :func:`clsamp.samplers.higher_order.rate`).

        Parameters
        ----------
        case : {"best", "worst", "axis"}

        Returns
        -------
        Rate or None
        """
        if self.order == 1:
            return super().convergence_rate(case)
        return higher_order.rate(self.order, self.randomize, case)

    def _table_key(self):
        return (type(self).__name__, self.d, self.order)

    def _warn_weaker(self, n, start):
        total = power = start + (n or 0)
        while power > 1 and power % self.base == 0:
            power //= self.base
        if power != 1:
            what = "two" if self.base == 2 else f"{self.base}"
            warnings.warn(f"the balance properties of {self.net_name} points need a power of {what} "
                          f"points: {self.label!r} asked for start + n = {total}, which is not, so "
                          "the set is not a net", UserWarning, stacklevel=3)

    def _reference(self, n, realizations, start):
        index = (np.uint64(start) + np.arange(n, dtype=np.uint64)).astype(np.uint32)
        rs = np.arange(realizations.start, realizations.stop)
        columns = self.gray_columns()
        out = np.empty((len(realizations), n, self.d))
        if self.randomize in LMS:
            # a higher-order net: scramble the base net, then interlace (as qmcpy)
            base = self.base_columns() if self.order > 1 else columns
            scrambled = gm.lms_apply(gm.lms_row_masks(self.seed, rs, len(base)), base[None])
            scrambled = gm.interlace_columns(scrambled.reshape(-1, nt.SOBOL_BITS), self.order)
            scrambled = scrambled.reshape(len(rs), self.d, nt.SOBOL_BITS)
            seeds = scramble_words(self.seed, rs, self.d)[..., 0]
            for k in range(len(rs)):
                x = nt.sobol_integers(index, scrambled[k])
                out[k] = (x ^ seeds[k][None, :] if self.randomize == "lms+shift" else x) * _SCALE32
            return out
        x = nt.sobol_integers(index, columns)         # (n, d) uint32
        if self.randomize is None:
            out[:] = x * _SCALE32
        elif self.randomize == "shift":
            out[:] = torus.shift(x[None] * _SCALE32, shift_vectors(self.seed, rs, self.d)[:, None, :])
        else:
            seeds = scramble_words(self.seed, rs, self.d)[..., 0]
            for k in range(len(rs)):
                if self.randomize == "xor":
                    out[k] = (x ^ seeds[k][None, :]) * _SCALE32
                else:
                    out[k] = nt.owen_scramble_base2(x, seeds[k][None, :]) * _SCALE32
        return out

    def _width(self):
        """Dimensions the kernel makes at once (its SIMD width): 2 or 4."""
        return 2 if self.d <= 2 else 4

    def _kernel_matrices(self):
        # (32, d padded to the width): row c holds direction number c of every dimension,
        # so the kernel loads a vector of dimensions at once; bit-reversed for Owen.
        width = self._width()
        table = np.zeros((nt.SOBOL_BITS, -(-self.d // width) * width), dtype=np.uint32)
        matrices = self.gray_columns()
        if self.randomize == "owen":
            matrices = nt.reverse_bits32(matrices)
        table[:, :self.d] = matrices.T
        return table

    def _device(self, n, realizations, start, out=None):
        table = runtime.table((self._table_key(), self.randomize == "owen"), self._kernel_matrices)
        lms = self.randomize in LMS
        if lms:
            table = self._lms_tables(table, realizations)
        return self._launch("sobol_points", table, n, realizations, start,
                            {"LD_WIDTH": self._width(), "LD_LMS": int(lms)}, out)

    def _lms_tables(self, table, realizations):
        """Each realization's scrambled table (kernel ``lms_matrices``), one after another."""
        import pyopencl.array as cla
        queue = runtime.queue()
        stride = -(-self.d // self._width()) * self._width()
        tables = cla.empty(queue, (len(realizations) * nt.SOBOL_BITS * stride,), np.uint32)
        kernel = runtime.kernel("lowdiscrepancy.cl", "lms_matrices",
                                defines={"LD_LMS": 1, "LD_INTERLACE": self.order})
        local = runtime.local_size()
        kernel(queue, (-(-stride // local) * local, len(realizations)), (local, 1), tables.data,
               table.data, np.uint32(self.d), np.uint32(stride), np.uint32(realizations.start),
               *philox.seed_key(self.seed), np.uint32(philox.Stream.SCRAMBLE))
        return tables


@register("sobol")
class SobolSampler(DigitalNetB2):
    """Sobol' sequence with Joe-Kuo direction numbers, 32-bit, up to 21201 dimensions.

    Point i, dimension j is x_ij = 2^-32 ⊕_c g_c(i) V_jc, where g(i) = i ⊕ (i >> 1) is
    the Gray code of i and V_jc = m_jc 2^(31-c) are the direction numbers
    (:func:`clsamp.number_theory.sobol_matrices`). Gray-code order is scipy's, so with
    ``randomize=None`` the points equal ``scipy.stats.qmc.Sobol(d, scramble=False)``
    bit for bit (for the 2^30 indices scipy's 30 bits cover). The first n = 2^m points
    form a (t, m, d)-net in base 2; dimensions 0 and 1 form a (0, m, 2)-net: every
    elementary interval of area 2^-m holds exactly one point.

    Parameters
    ----------
    d : int
        Dimension, 1 to 21201.
    seed : int
        Seed of the randomization.
    randomize : {None, "shift", "xor", "owen", "lms", "lms+shift"}
        ``"shift"``: x + u mod 1 with u uniform per realization and dimension
        (Cranley-Patterson); breaks the net property. ``"xor"``: x ⊕ s (random
        binary digit scramble, keeps the nets). ``"owen"``: nested uniform scrambling,
        each binary digit flipped by a hash of the digits above it and a per-dimension
        seed (Laine-Karras with Vegdahl's hash, as Burley 2020); keeps the nets, and
        each point is uniform over realizations. ``"lms"``: linear matrix scrambling
        [5]_, each generating matrix C_j replaced by L C_j with L a uniformly random
        non-singular lower-triangular binary matrix per realization and dimension
        (keeps the nets); ``"lms+shift"``: then xor a random digit vector, as
        ``scipy.stats.qmc.Sobol(scramble=True)`` and qmcpy's default do.
    backend : {"opencl", "numpy"}
    bits : {32, 64}
        Index bits. With 64, 64 direction numbers of 64 bits (the same recurrence), so
        ``start + n`` may reach 2^64; the points are the top 53 bits of the 64-bit
        state, ``(x >> 11) 2^-53``, which below index 2^32 are exactly the 32-bit
        points. ``randomize`` then one of None, ``"shift"`` and ``"xor"`` (whose
        64-bit digit vector begins with the 32-bit one).
    order : {1, 2, 3}
        2 or 3: the higher-order net of that order [6]_, interlacing the alpha d-dimensional
        Sobol' net (:mod:`clsamp.samplers.higher_order`); randomize None, ``"xor"``,
        ``"lms"`` or ``"lms+shift"``.

    Notes
    -----
    Points are integers times 2^-32 (32 bits of resolution after scrambling too; with
    ``bits=64`` past index 2^32, times 2^-53).
    ``sample(n, start=k)`` continues ``sample(k)``. A prefix whose length (start + n) is not
    a power of two warns (``UserWarning``: not a net, its balance lost), on any draw, where
    scipy warns on a first draw only.

    References
    ----------
    .. [1] I. M. Sobol', "On the distribution of points in a cube and the approximate
       evaluation of integrals", USSR Comput. Math. Math. Phys. 7 (1967).
    .. [2] S. Joe, F. Y. Kuo, "Constructing Sobol sequences with better two-dimensional
       projections", SIAM J. Sci. Comput. 30 (2008).
    .. [3] B. Burley, "Practical hash-based Owen scrambling", JCGT 9(4) (2020).
    .. [4] A. B. Owen, "Randomly permuted (t,m,s)-nets and (t,s)-sequences" (1995).
    .. [5] J. Matoušek, "On the L2-discrepancy for anchored boxes", J. Complexity 14
       (1998).
    .. [6] J. Dick, "Walsh spaces containing smooth functions and quasi-Monte Carlo rules
       of arbitrary high order", SIAM J. Numer. Anal. 46(3) (2008).

    Examples
    --------
    >>> import clsamp
    >>> clsamp.make_sampler("sobol", d=2).sample(4).tolist()
    [[0.0, 0.0], [0.5, 0.5], [0.75, 0.25], [0.25, 0.75]]
    >>> clsamp.make_sampler("sobol:owen", d=3, seed=1).sample(256, realizations=8).shape
    (8, 256, 3)
    >>> clsamp.make_sampler("sobol", d=16, randomize="lms+shift").sample(1024).shape
    (1024, 16)
    >>> clsamp.make_sampler("sobol", d=2, bits=64).sample(2, start=2**32).tolist()
    [[3.4924596548080444e-10, 0.4999999998835847], [0.500000000349246, 0.9999999998835847]]
    """

    max_d = nt.sobol_max_dimension()
    max_d_source = "the Joe-Kuo direction-number table"
    net_name = "Sobol'"

    def __init__(self, d=2, seed=0, backend="opencl", randomize=None, bits=32, order=1):
        self.bits = check_choice(bits, "bits", (32, 64))
        super().__init__(d=d, seed=seed, backend=backend, randomize=randomize)
        if self.bits == 64 and self.randomize not in (None, "shift", "xor"):
            raise InvalidArgumentError(
                f"'randomize' must be None, 'shift' or 'xor' with bits=64, got {self.randomize!r}")
        self._set_order(order, self.max_d, "the Joe-Kuo table")
        if self.order > 1 and self.bits == 64:
            raise InvalidArgumentError(f"'order' must be 1 with bits=64 (interlaced nets are "
                                       f"32-bit), got {self.order}")

    def __repr__(self):
        wide = ", bits=64" if self.bits == 64 else ""
        return super().__repr__()[:-1] + wide + ")"

    def _last_index(self):
        return 2**64 - 1 if self.bits == 64 else self.max_n

    def _table_key(self):
        return (type(self).__name__, self.d, self.bits, self.order)

    def _matrices64(self):
        """(d, 64) uint64: V_jc = m_jc 2^(63-c), whose top halves are the 32-bit V_jc for c < 32."""
        v = nt.sobol_direction_integers(64)[:self.d]
        return v << (np.uint64(63) - np.arange(64, dtype=np.uint64))[None, :]

    def _reference(self, n, realizations, start):
        if self.bits == 32:
            return super()._reference(n, realizations, start)
        rs = np.arange(realizations.start, realizations.stop)
        x = nt.sobol_integers(np.uint64(start) + np.arange(n, dtype=np.uint64), self._matrices64())
        out = np.empty((len(rs), n, self.d))
        if self.randomize == "xor":
            words = scramble_words(self.seed, rs, self.d).astype(np.uint64)
            seeds = (words[..., 0] << np.uint64(32)) | words[..., 1]
            for k in range(len(rs)):
                out[k] = ((x ^ seeds[k][None, :]) >> np.uint64(11)).astype(np.float64) * 2.0**-53
            return out
        out[:] = (x >> np.uint64(11)).astype(np.float64) * 2.0**-53
        return self._rotated(out, rs)

    def _device(self, n, realizations, start, out=None):
        if self.bits == 32:
            return super()._device(n, realizations, start, out)
        table = runtime.table(self._table_key(), lambda: self._matrices64().T.copy(), dtype=np.uint64)
        return self._launch("sobol_points64", table, n, realizations, np.uint64(start), {}, out)

    def base_columns(self):
        """The Joe-Kuo direction numbers (:func:`clsamp.number_theory.sobol_matrices`).

        Returns
        -------
        ndarray of uint32
            (order d, 32).
        """
        return nt.sobol_matrices(self.order * self.d)

    def convergence_rate(self, case):
        """The published rate of the MSE for ``case`` (:meth:`Sampler.convergence_rate`).

        Owen-scrambled Sobol' points in 2-D are a nested-scrambled (0, m, 2)-net in base 2
        for N a power of two: N^-3 for smooth integrands (Owen 1997), N^-1.5 for
        discontinuous ones (He and Wang 2015).

        Parameters
        ----------
        case : {"best", "worst", "axis"}
            The integrand as the estimator sees it (:func:`clsamp.theory.case_of`).

        Returns
        -------
        Rate or None
            None for other randomizations or dimensions; with ``order`` >= 2,
            :meth:`DigitalNetB2.convergence_rate`.
        """
        if self.order > 1:
            return super().convergence_rate(case)
        if self.randomize != "owen" or self.d != 2:
            return None
        return {"best": Rate(-3.0, "Owen 1997"), "worst": Rate(-1.5, "He and Wang 2015")}.get(case)


class _RadicalInverse(LowDiscrepancySampler):
    """Samplers whose coordinates are radical inverses in per-dimension bases."""

    randomizations = (None, "shift", "xor", "owen", "permute")
    hammersley = False

    def bases(self):
        """The base of each dimension (dimension 0 of Hammersley, i/n, has none: 0).

        Returns
        -------
        ndarray
            uint32 of shape (d,).
        """
        raise NotImplementedError

    def _reference(self, n, realizations, start):
        rs = np.arange(realizations.start, realizations.stop)
        index = np.uint64(start) + np.arange(n, dtype=np.uint64)
        out = np.empty((len(rs), n, self.d))
        seed64 = self._seed64(realizations) if self.randomize not in (None, "shift") else None
        for j, base in enumerate(self.bases()):
            if self.hammersley and j == 0:
                if self.randomize in (None, "shift"):
                    out[:, :, 0] = index.astype(np.float64) / float(n)
                else:
                    fixed = ((index << np.uint64(32)) // np.uint64(n)).astype(np.uint32)
                    for k in range(len(rs)):
                        s = np.uint32(int(seed64[k, 0]) & 0xFFFFFFFF)
                        scrambled = nt.owen_scramble_base2(fixed, s) if self.randomize == "owen" \
                            else fixed ^ s
                        out[k, :, 0] = scrambled * _SCALE32
                continue
            denominator = float(int(base) ** nt.digit_count(base))
            if self.randomize in (None, "shift"):
                out[:, :, j] = nt.radical_inverse_numerator(index, base).astype(np.float64) / denominator
            else:
                for k in range(len(rs)):
                    v = nt.scrambled_radical_inverse_numerator(index, base, self.randomize, seed64[k, j])
                    out[k, :, j] = v.astype(np.float64) / denominator
        if self.randomize == "shift":
            out = torus.shift(out, shift_vectors(self.seed, rs, self.d)[:, None, :])
        return out

    def _device(self, n, realizations, start, out=None):
        bases = np.maximum(self.bases(), 2)
        table = runtime.table(("radical bases", bases.tobytes()), lambda: bases)
        extra = ()
        limit = runtime.loop_limit()
        if self.randomize == "owen" and limit is not None and bases.max() > OWEN_LOOP_BASE:
            # a node's shuffle loops about twice its base, a point's up to m times its base
            device = runtime.current_device()
            raise NoDeviceError(
                f"{self.name}:owen with base {int(bases.max())} (d={self.d}) does not run on "
                f"{device.name}: it ends a work-item's loops after {limit} iterations, and "
                f"bases above {OWEN_LOOP_BASE} (Halton's d > 309) need more; use another device "
                "(clsamp.use_device, CLSAMP_DEVICE) or backend='numpy'")
        if self.randomize == "owen":
            extra = self._owen_tables(table, bases, n, realizations)
        return self._launch("radical_points", table, n, realizations, start,
                            {"HAMMERSLEY": self.hammersley}, out, extra)

    def _owen_tables(self, bases_table, bases, n, realizations):
        """The shallow nodes' permutations for ``"owen"`` (kernel ``owen_tables``): the kernel
        arguments (table, layout, entries per realization) of ``radical_points``."""
        import pyopencl.array as cla
        layout, segments, nodes, entries = owen_table_layout(bases, n, len(realizations))
        queue = runtime.queue()
        layout_dev = runtime.table(("owen layout", bases.tobytes(), layout.tobytes()), lambda: layout)
        tables = cla.empty(queue, (max(1, entries * len(realizations)),), np.uint32)
        if nodes:
            # the defines of radical_points: one program holds both kernels
            kernel = runtime.kernel("lowdiscrepancy.cl", "owen_tables",
                                    defines={"RANDOMIZE": _CODES["owen"], "LD_BLOCK": self._block(),
                                             "HAMMERSLEY": self.hammersley})
            local = runtime.local_size()
            kernel(queue, (-(-nodes // local) * local, len(realizations)), (local, 1), tables.data,
                   layout_dev.data, bases_table.data, np.uint32(self.d), np.uint32(segments),
                   np.uint32(nodes), np.uint32(entries), np.uint32(realizations.start),
                   *philox.seed_key(self.seed), np.uint32(philox.Stream.SCRAMBLE))
        return tables.data, layout_dev.data, np.uint32(entries)


@register("van_der_corput")
class VanDerCorputSampler(_RadicalInverse):
    """Van der Corput sequence in any base b: x_i = Φ_b(i) = Σ_k d_k b^-(k+1) for i = Σ_k d_k b^k.

    Computed from the integer digits of the 32-bit index, x_i = v / b^m (v the digits
    reversed, m the digit count of 32-bit indices): one correctly rounded division, so
    every x_i is the double nearest the exact rational (index 2^32 - 1 included).

    Parameters
    ----------
    d : int
        Must be 1.
    base : int
        Base b in [2, 2^20] (default 2).
    seed : int
    randomize : {None, "shift", "xor", "owen", "permute"}
        ``"xor"``: each digit shifted by a random s_k mod b (an xor in base 2);
        ``"permute"``: each digit position k permuted by its own random permutation;
        ``"owen"``: nested uniform scrambling [3]_, each digit permuted by a permutation
        of its own for every value of the digits before it (see Notes). All m digit
        positions are randomized, the leading zeros of small indices included.
    backend : {"opencl", "numpy"}

    Notes
    -----
    Nested uniform scrambling (``"owen"``) treats the digits d_0, d_1, ... of the index
    (least significant first, the order in which Φ_b reads them) as a path in a b-ary
    tree: digit k is replaced by π_node(d_k), where the node is (k, i mod b^k), the depth
    and the digits already read. Every node's π is a uniformly random permutation of
    [0, b), independent of every other node's, as in Owen's definition [3]_: each point
    is uniform in [0, 1) over seeds, and the points keep the stratification of the
    sequence (those sharing i mod b^k share their first k scrambled digits; those that
    differ there differ). In base b >= 3 a node's permutation is a Fisher-Yates shuffle
    whose draws come from a hash of the seed and the node, made exactly uniform by
    rejection (:func:`clsamp.number_theory.owen_permutation_element`); in base 2 it is the
    Laine-Karras hash with Vegdahl's constants (Burley 2020), a hash-based approximation
    of independent random flips. A node's permutation depends on nothing but the seed and the
    node, so ``sample(n, start=k)`` continues ``sample(k)`` and realization r is the same
    however many are drawn.

    References
    ----------
    .. [1] J. G. van der Corput, "Verteilungsfunktionen", Proc. Akad. Amsterdam 38 (1935).
    .. [2] M. Pharr, W. Jakob, G. Humphreys, *Physically Based Rendering*, 4th ed., 8.6.
    .. [3] A. B. Owen, "Randomly permuted (t,m,s)-nets and (t,s)-sequences", Monte Carlo
       and Quasi-Monte Carlo Methods in Scientific Computing, Springer (1995).

    Examples
    --------
    >>> import clsamp
    >>> clsamp.make_sampler("van_der_corput", d=1, base=3).sample(4)[:, 0].tolist()
    [0.0, 0.3333333333333333, 0.6666666666666666, 0.1111111111111111]
    """

    dimensions = (1,)

    def __init__(self, d=1, seed=0, backend="opencl", randomize=None, base=2):
        self.base = check_int(base, "base", minimum=2, maximum=nt.MAX_BASE)
        super().__init__(d=d, seed=seed, backend=backend, randomize=randomize)

    def bases(self):
        """The base of the one dimension.

        Returns
        -------
        ndarray
            uint32 of shape (1,).
        """
        return np.array([self.base], dtype=np.uint32)


@register("halton")
class HaltonSampler(_RadicalInverse):
    """Halton sequence: dimension j is the radical inverse in the j-th prime (2, 3, 5, ...).

    x_ij = Φ_(p_j)(i), each exact to the last bit (see :class:`VanDerCorputSampler`).
    With ``randomize=None`` the points equal ``scipy.stats.qmc.Halton(d, scramble=False)``
    up to scipy's own rounding: scipy sums the digit terms in floating point, rounding at
    every term, while clsamp divides exact integers once. Measured, scipy's values are
    within 4 ulps of clsamp's over the first 2^22 points in 2 and 16 dimensions, and
    within 3 ulps over the first 2^16 in 2, 5, 16 and 50 (the command is in
    docs/performance.md).

    Parameters
    ----------
    d : int
        Dimension, 1 to 21201.
    seed : int
    randomize : {None, "shift", "xor", "owen", "permute"}
        See :class:`VanDerCorputSampler`; ``"permute"`` is pbrt's PermuteDigits
        (Kensler's hash permutations). ``"owen"`` is nested uniform scrambling of every
        dimension's digits in its own base, the randomized Halton sequence of Owen
        2017 [2]_: in dimension j each node of the digit tree of base p_j (the depth k and
        the index's digits below it, i mod p_j^k) gets a uniformly random permutation of
        [0, p_j), independent across nodes, dimensions and realizations (the method is
        in the Notes of :class:`VanDerCorputSampler`). All keep the stratification of
        dimension j in base p_j; ``"shift"`` does not.
    backend : {"opencl", "numpy"}

    References
    ----------
    .. [1] J. H. Halton, "On the efficiency of certain quasi-random sequences of points
       in evaluating multi-dimensional integrals", Numer. Math. 2 (1960).
    .. [2] A. B. Owen, "A randomized Halton algorithm in R" (2017), arXiv:1706.02808.
    .. [3] M. Pharr, W. Jakob, G. Humphreys, *Physically Based Rendering*, 4th ed., 8.6.
    .. [4] A. B. Owen, "Randomly permuted (t,m,s)-nets and (t,s)-sequences", Monte Carlo
       and Quasi-Monte Carlo Methods in Scientific Computing, Springer (1995).

    Examples
    --------
    >>> import clsamp
    >>> clsamp.make_sampler("halton", d=2).sample(3).tolist()
    [[0.0, 0.0], [0.5, 0.3333333333333333], [0.25, 0.6666666666666666]]
    """

    max_d = MAX_HALTON_DIMENSION

    def bases(self):
        """The base of each dimension: the first d primes.

        Returns
        -------
        ndarray
            uint32 of shape (d,).
        """
        return nt.first_primes(self.d)


@register("hammersley")
class HammersleySampler(_RadicalInverse):
    """Hammersley set: point i of n is (i/n, Φ_2(i), Φ_3(i), ..., Φ_(p_(d-1))(i)).

    n is fixed in advance, so ``start`` must be 0. With n = 2^m the first two
    dimensions form a (0, m, 2)-net in base 2 (one point in every elementary interval
    of area 2^-m), kept by ``"xor"`` and ``"owen"``, which act on the 32-bit binary
    digits of i/n (floor(i 2^32 / n)) and on the digits of the radical inverses.

    Parameters
    ----------
    d : int
        Dimension, 1 to 21201 (d = 1 gives the regular grid i/n).
    seed : int
    randomize : {None, "shift", "xor", "owen"}
    backend : {"opencl", "numpy"}

    References
    ----------
    .. [1] J. M. Hammersley, "Monte Carlo methods for solving multivariable problems",
       Ann. New York Acad. Sci. 86 (1960).

    Examples
    --------
    >>> import clsamp
    >>> clsamp.make_sampler("hammersley", d=2).sample(4).tolist()
    [[0.0, 0.0], [0.25, 0.5], [0.5, 0.25], [0.75, 0.75]]
    """

    sequence = False
    accepts_start = False
    hammersley = True
    max_d = MAX_HALTON_DIMENSION
    randomizations = (None, "shift", "xor", "owen")

    def bases(self):
        """The base of each dimension: 0 for the first (i/n, no base), then the first
        d - 1 primes.

        Returns
        -------
        ndarray
            uint32 of shape (d,).
        """
        return np.concatenate([[0], nt.first_primes(self.d - 1)]).astype(np.uint32)
