"""Digital nets from generating matrices: ``digital_net`` (the user's matrices), ``faure``
(Pascal matrices in a prime base) and ``niederreiter`` (base 2, Bratley-Fox-Niederreiter).

A base-2 net runs on Sobol's kernel (``sobol_points``, :class:`DigitalNetB2`) with every
base-2 randomization; a net in base b >= 3 on ``digital_points`` (``kernels/lowdiscrepancy.cl``),
unrandomized, with a Cranley-Patterson ``"shift"``, a digital shift ``"xor"`` (a random
digit added mod b to each output digit, the same for every point), or Matoušek's linear
matrix scrambling in GF(b) (``"lms"``, ``"lms+shift"``: L C_j mod b, L random non-singular
lower triangular, made per realization by the kernel ``lms_digits``). The
matrices come from :mod:`clsamp.generating_matrices`, which also holds the NumPy twins.
"""

import functools
import hashlib

import numpy as np

from .. import generating_matrices as gm
from .. import number_theory as nt
from .. import philox, runtime
from ..errors import InvalidArgumentError
from ..validation import check_int
from .base import register
from .lowdiscrepancy import LMS, DigitalNetB2

BASE_B_RANDOMIZATIONS = (None, "shift", "xor", "lms", "lms+shift")


class _DigitalNet(DigitalNetB2):
    """A digital net in base b from digit matrices (d, rows, m), in natural order: point i
    is C_j a mod b, a the digits of i. Base 2 takes Sobol's kernel (Gray-code columns
    D_c = C_0 ⊕ ... ⊕ C_c give the natural order, :func:`gm.natural_to_gray`); base b >= 3
    ``digital_points``."""

    net_name = "digital net"

    def _set_matrices(self, matrices, base):
        """Keep the digit matrices this sampler uses: their first d, 32 rows and columns in
        base 2 (32-bit points and indices), and in base b the rows whose b^rows stays within
        2^53 and the columns of 32-bit indices."""
        self.base = base
        if base == 2:
            rows, cols = 32, 32
        else:
            rows = 0
            while base ** (rows + 1) <= 2**53:
                rows += 1
            cols = nt.digit_count(base)
        self.matrices = np.ascontiguousarray(matrices[:self.order * self.d, :rows, :cols],
                                             dtype=np.uint8 if base < 256 else np.uint32)
        self._points = base ** self.matrices.shape[2]        # b^m: the points the columns index
        self._digest = hashlib.sha1(self.matrices.tobytes()).hexdigest()

    def _last_index(self):
        return min(self.max_n, self._points - 1)

    def _table_key(self):
        return (type(self).__name__, self.base, self.matrices.shape, self._digest, self.order)

    def base_columns(self):
        """The Gray-code columns of a base-2 net (:meth:`DigitalNetB2.base_columns`).

        Returns
        -------
        ndarray of uint32
            (order d, 32).
        """
        return gm.natural_to_gray(gm.columns_base2(self.matrices))

    def _reference(self, n, realizations, start):
        if self.base == 2:
            return super()._reference(n, realizations, start)
        b = self.base
        rs = np.arange(realizations.start, realizations.stop)
        index = np.uint64(start) + np.arange(n, dtype=np.uint64)
        lms = self.randomize in LMS
        tables = gm.lms_digits(self.seed, rs, self.matrices, b) if lms else [self.matrices]
        rows = np.arange(self.matrices.shape[1], dtype=np.uint64)
        denominator = float(b ** len(rows))
        seed64 = self._seed64(realizations)
        out = np.empty((len(rs), n, self.d))
        digits = None
        for k in range(len(rs)):
            if digits is None or lms:
                digits = gm.digital_net_digits(index, tables[k if lms else 0], b)   # (n, d, rows)
            y = digits
            if self.randomize in ("xor", "lms+shift"):
                y = (y + nt.digit_shift(nt.digit_hash(seed64[k][:, None], rows[None, :]), b)) % b
            out[k] = gm.digital_net_numerators(y, b) / denominator
        return self._rotated(out, rs)

    def _device(self, n, realizations, start, out=None):
        if self.base == 2:
            return super()._device(n, realizations, start, out)
        b = self.base
        d, rows, cols = self.matrices.shape
        key = self._table_key()
        columns = runtime.table((key, "columns"), lambda: self.matrices.transpose(0, 2, 1).ravel())
        sums = runtime.table((key, "sums"),
                             lambda: gm.running_sums(self.matrices, b).transpose(0, 2, 1).ravel())
        defines = {"DN_ROWS": rows, "DN_COLS": cols}
        lms = self.randomize in LMS
        if lms:
            columns, sums = self._lms_digit_tables(columns, defines, realizations)
        return self._launch("digital_points", columns, n, realizations, start,
                            {**defines, "LD_LMS": int(lms)}, out,
                            (sums.data, np.uint32(b), np.uint64(b**rows)))

    def _lms_digit_tables(self, columns, defines, realizations):
        """Each realization's scrambled matrices and running sums (kernel ``lms_digits``)."""
        import pyopencl.array as cla
        queue = runtime.queue()
        size = len(realizations) * self.matrices.size
        tables = cla.empty(queue, (size,), np.uint32), cla.empty(queue, (size,), np.uint32)
        kernel = runtime.kernel("lowdiscrepancy.cl", "lms_digits", defines=defines)
        local = runtime.local_size()
        kernel(queue, (-(-self.d // local) * local, len(realizations)), (local, 1), tables[0].data,
               tables[1].data, columns.data, np.uint32(self.d), np.uint32(self.base),
               np.uint32(realizations.start), *philox.seed_key(self.seed),
               np.uint32(philox.Stream.SCRAMBLE))
        return tables


@register("digital_net")
class DigitalNetSampler(_DigitalNet):
    """A digital net in base b from the user's generating matrices, in natural order.

    Point i, dimension j has the base-b digits y = C_j a (mod b), a the digits of i
    (least significant first), and the coordinate x_ij = Σ_r y_r b^-(r+1) [1]_. The
    first b^m points form a (t, m, d)-net, t given by the matrices (Niederreiter 1992,
    Thm. 4.28). Matrices from LatNet Builder, qmcpy or a paper are entered here.

    Parameters
    ----------
    d : int
        Dimensions: the first d matrices (at most as many as given).
    seed : int
    randomize : {None, "shift", "xor", "owen", "lms", "lms+shift"}
        In base 2 every randomization of :class:`clsamp.samplers.lowdiscrepancy.SobolSampler`;
        in base b >= 3 ``"shift"`` (Cranley-Patterson), ``"xor"`` (a digital shift:
        output digit r plus a random digit mod b), ``"lms"`` (L C_j mod b with L a random
        lower-triangular matrix over GF(b), non-zero on its diagonal; Matoušek 1998) and
        ``"lms+shift"`` (both, qmcpy's "LMS DS"). All but ``"shift"`` keep the nets.
    matrices : array_like of int, optional
        (d, rows, m): entry (j, r, k) in [0, b) is output digit r of index digit k of
        dimension j. Base 2 uses the first 32 rows and columns (32-bit points and
        indices); base b the rows with b^rows <= 2^53 and the columns of 32-bit indices.
        Default: the Joe-Kuo Sobol' matrices (base 2), as qmcpy's ``DigitalNetB2``.
    base : int
        A prime, 2 to 2^20.
    order : {1, 2, 3}
        In base 2, alpha >= 2 interlaces the digits of matrices alpha j .. alpha j + alpha - 1
        into dimension j (a higher-order net, Dick 2008; as qmcpy's
        ``DigitalNetB2(alpha=...)``), so d alpha matrices are needed; randomizations None,
        ``"xor"``, ``"lms"``, ``"lms+shift"`` (see
        :class:`clsamp.samplers.lowdiscrepancy.DigitalNetB2`).
    backend : {"opencl", "numpy"}

    Notes
    -----
    ``sample(n, start=k)`` continues ``sample(k)``; start + n may not pass b^m, the
    points the m columns index. In base 2 the points equal ``sobol``'s kernel's with
    the columns D_c = C_0 ⊕ ... ⊕ C_c in Gray-code order (C i = D g(i)).

    References
    ----------
    .. [1] H. Niederreiter, *Random Number Generation and Quasi-Monte Carlo Methods*,
       SIAM (1992), ch. 4.
    .. [2] J. Dick, F. Pillichshammer, *Digital Nets and Sequences*, Cambridge (2010).

    Examples
    --------
    >>> import clsamp, numpy as np
    >>> eye = np.eye(3, dtype=int)[None]
    >>> clsamp.make_sampler("digital_net", d=1, matrices=eye, base=3).sample(4)[:, 0].tolist()
    [0.0, 0.3333333333333333, 0.6666666666666666, 0.1111111111111111]
    """

    def __init__(self, d=2, seed=0, backend="opencl", randomize=None, matrices=None, base=2,
                 order=1):
        base = check_int(base, "base", minimum=2, maximum=nt.MAX_BASE)
        if any(base % p == 0 for p in range(2, int(base**0.5) + 1)):
            raise InvalidArgumentError(f"'base' must be a prime (digits form a field), got {base}")
        if matrices is None:
            if base != 2:
                raise InvalidArgumentError(
                    f"'matrices' must be given in base {base} (the default is Sobol's, base 2)")
            alpha = check_int(order, "order", minimum=1)
            matrices = _sobol_digits(check_int(d, "d", minimum=1,
                                               maximum=nt.sobol_max_dimension() // alpha) * alpha)
        matrices = _check_matrices(matrices, base)
        if not 1 <= check_int(d, "d") <= len(matrices):
            raise InvalidArgumentError(
                f"'d' must be in [1, {len(matrices)}] for the {len(matrices)} matrices given, got {d}")
        super().__init__(d=d, seed=seed, backend=backend,
                         randomize=_base_b_choice(randomize, base))
        if base != 2 and order != 1:
            raise InvalidArgumentError(f"'order' must be 1 in base {base} (interlacing is "
                                       f"implemented in base 2), got {order!r}")
        self._set_order(order, len(matrices), "the matrices given")
        self._set_matrices(matrices, base)


@register("faure")
class FaureSampler(_DigitalNet):
    """Faure's sequence: the digital net in the smallest prime base b >= d whose matrices
    are the powers of the Pascal matrix, C_j = P^j mod b, P_rk = binom(k, r).

    Dimension 0 is the van der Corput sequence in base b; the first b^m points form a
    (0, m, d)-net in base b for every m (Faure 1982). Natural order, as qmcpy's ``Faure``.

    Parameters
    ----------
    d : int
        Dimension, 1 to 21201 (base up to 21211).
    seed : int
    randomize : {None, "shift", "xor", "lms", "lms+shift"}
        ``"shift"``: Cranley-Patterson; ``"xor"``: a digital shift in base b; ``"lms"``,
        ``"lms+shift"``: Matoušek's linear matrix scrambling in base b, without and with
        the digital shift (see :class:`DigitalNetSampler`). All but ``"shift"`` keep the
        nets.
    backend : {"opencl", "numpy"}

    Notes
    -----
    Points carry m = the digits of 32-bit indices in base b (x = v / b^m, exact to the
    last bit); start + n may not pass b^m when that is below 2^32 - 1.

    References
    ----------
    .. [1] H. Faure, "Discrépance de suites associées à un système de numération (en
       dimension s)", Acta Arith. 41 (1982), 337-351.

    Examples
    --------
    >>> import clsamp
    >>> clsamp.make_sampler("faure", d=3).sample(4).tolist()[3]
    [0.1111111111111111, 0.4444444444444444, 0.7777777777777778]
    """

    max_d = 21201
    randomizations = BASE_B_RANDOMIZATIONS
    net_name = "Faure"

    def __init__(self, d=2, seed=0, backend="opencl", randomize=None):
        super().__init__(d=d, seed=seed, backend=backend, randomize=randomize)
        base = gm.faure_base(self.d)
        m = nt.digit_count(base)
        self._set_matrices(gm.faure_matrices(self.d, base, m), base)


@register("niederreiter")
class NiederreiterSampler(DigitalNetB2):
    """Niederreiter's base-2 sequence with Bratley, Fox and Niederreiter's matrices, in
    Gray-code order (as their Fortran and GSL's ``gsl_qrng_niederreiter_2``).

    Dimension j uses the j-th irreducible polynomial over GF(2) (x, 1 + x, 1 + x + x^2,
    ...); the first 2^m points form a (t, m, d)-net with t = Σ_j (deg p_j - 1)
    (:func:`clsamp.generating_matrices.niederreiter_t`): 0 for d <= 2, 1 for 3, 3 for 4.

    Parameters
    ----------
    d : int
        Dimension, 1 to 1111.
    seed : int
    randomize : {None, "shift", "xor", "owen", "lms", "lms+shift"}
        As for :class:`clsamp.samplers.lowdiscrepancy.SobolSampler`.
    backend : {"opencl", "numpy"}

    Notes
    -----
    32-bit points and indices; GSL keeps 31 bits, so its points are these with the last
    bit cleared.

    References
    ----------
    .. [1] P. Bratley, B. L. Fox, H. Niederreiter, "Implementation and tests of
       low-discrepancy sequences", ACM TOMACS 2(3) (1992), 195-213.
    .. [2] H. Niederreiter, "Low-discrepancy and low-dispersion sequences", J. Number
       Theory 30 (1988), 51-70.

    Examples
    --------
    >>> import clsamp
    >>> clsamp.make_sampler("niederreiter", d=3).sample(4).tolist()[2:]
    [[0.75, 0.25, 0.3125], [0.25, 0.75, 0.5625]]
    """

    max_d = gm.NIEDERREITER_MAX_DIMENSION
    max_d_source = "the construction's cost"
    net_name = "Niederreiter"

    def base_columns(self):
        """The columns of :func:`clsamp.generating_matrices.niederreiter_matrices`.

        Returns
        -------
        ndarray of uint32
            (d, 32).
        """
        return _niederreiter_columns(self.d)


@functools.lru_cache(maxsize=8)
def _niederreiter_columns(d):
    return gm.columns_base2(gm.niederreiter_matrices(d))


def _sobol_digits(d):
    columns = nt.sobol_matrices(d)
    shifts = (31 - np.arange(32, dtype=np.uint32))[None, :, None]
    return ((columns[:, None, :] >> shifts) & 1).astype(np.uint8)


def _base_b_choice(randomize, base):
    if base != 2 and randomize not in BASE_B_RANDOMIZATIONS:
        raise InvalidArgumentError(
            f"'randomize' must be one of {BASE_B_RANDOMIZATIONS} in base {base} (Owen "
            f"scrambling runs in base 2), got {randomize!r}")
    return randomize


def _check_matrices(matrices, base):
    try:
        array = np.asarray(matrices)
    except (TypeError, ValueError):
        array = None
    if array is None or array.ndim != 3 or 0 in array.shape or array.dtype.kind not in "iub":
        raise InvalidArgumentError(
            "'matrices' must be an integer array (d, rows, m) of generating-matrix digits, got "
            f"{getattr(array, 'shape', type(matrices).__name__)}")
    if array.min() < 0 or array.max() >= base:
        raise InvalidArgumentError(
            f"'matrices' must hold digits in [0, {base}) for base {base}, got values in "
            f"[{array.min()}, {array.max()}]")
    return array
