"""Generating matrices of digital nets, and their linear matrix scrambling (LMS).

A digital net in base b is given by one generating matrix C_j per dimension: point i,
dimension j has the digits y = C_j a (mod b), a the base-b digits of i (least significant
first) and y the digits of the coordinate (most significant first), x_ij = Σ_r y_r b^-(r+1).
This module holds the matrices of the constructions clsamp ships (Faure's Pascal
matrices, Niederreiter's base-2 matrices as Bratley, Fox and Niederreiter compute them),
Matoušek's random linear scrambling of them, and the NumPy twins of the kernels that
make the points (``kernels/lowdiscrepancy.cl`` in base 2, ``kernels/digital_net.cl``).

In base 2 a matrix is held as its columns, one uint32 word each: column k (the image
of index digit k) has output digit r at bit 31 - r, so that the point is the xor of the
columns of the set digits of i, times 2^-32 (as :func:`clsamp.number_theory.sobol_matrices`).
"""

import numpy as np

from . import number_theory as nt
from . import philox
from .errors import InvalidArgumentError

_U32 = np.uint32
_U64 = np.uint64
BITS = 32
LMS_WORD0 = 4      # row k of L_(r,j) is word 4 + k of (Stream.SCRAMBLE, r, j): blocks 1..8
MAX_DIGITS = 64    # index digits of a base-b matrix that the kernel takes


# -- Matoušek's linear matrix scrambling (base 2) -----------------------------------
def lms_row_masks(seed, realizations, d):
    """The random non-singular lower-triangular matrices L_(r,j) of LMS, row by row.

    Row k of L (output digit k) has a one on the diagonal and independent uniform bits
    left of it; as a word, bit 31 - l holds entry (k, l), so the row is word 4 + k of
    Philox (``Stream.SCRAMBLE``, counter (j, realization, block 1 + k // 4)) masked to
    bits 31 - k and above, with bit 31 - k set. Words 0..3 (block 0) stay the seeds of
    ``"xor"`` and ``"owen"``, so the digital shift of ``"lms+shift"`` is ``"xor"``'s.

    Parameters
    ----------
    seed : int
        The sampler's seed (the Philox key).
    realizations : array_like of int
        Realization numbers, each its own matrices.
    d : int
        Dimensions, each its own matrix.

    Returns
    -------
    ndarray of uint32
        (len(realizations), d, 32): row k of each matrix.

    Examples
    --------
    >>> rows = lms_row_masks(1, [0], 1)[0, 0]
    >>> [hex(int(rows[0])), int(rows[31]) & 1]
    ['0x80000000', 1]
    """
    r = np.asarray(realizations, dtype=_U32)[:, None, None]
    j = np.arange(d, dtype=_U32)[None, :, None]
    k = np.arange(BITS, dtype=_U64)[None, None, :]
    words = philox.random_words(seed, philox.Stream.SCRAMBLE, r, j, LMS_WORD0 + k.astype(_U32))
    diagonal = _U64(1) << (_U64(BITS - 1) - k)
    above = (_U64(0xFFFFFFFF) ^ (2 * diagonal - _U64(1))) & _U64(0xFFFFFFFF)
    return ((words.astype(_U64) & above) | diagonal).astype(_U32)


def lms_apply(rows, columns):
    """L C over GF(2): each column word mapped through the rows of L.

    Parameters
    ----------
    rows : ndarray of uint32
        (..., 32): the rows of L (:func:`lms_row_masks`).
    columns : ndarray of uint32
        (..., k): the columns of C, broadcast against ``rows[..., None, :]``'s leading axes.

    Returns
    -------
    ndarray of uint32
        (..., k): output digit r of column c is the parity of rows[r] & columns[c].

    Examples
    --------
    >>> identity = (1 << (31 - np.arange(32))).astype(np.uint32)
    >>> int(lms_apply(identity, np.array([0x12345678], dtype=np.uint32))[0]) == 0x12345678
    True
    """
    rows = np.asarray(rows, dtype=_U32)
    columns = np.asarray(columns, dtype=_U32)
    out = np.zeros(np.broadcast_shapes(rows.shape[:-1] + (1,), columns.shape), dtype=_U32)
    for k in range(BITS):
        parity = np.bitwise_count(rows[..., k, None] & columns).astype(_U32) & _U32(1)
        out |= parity << _U32(BITS - 1 - k)
    return out


def lms_digits(seed, realizations, matrices, base):
    """Matoušek's scrambling in base b: L C_j mod b per realization and dimension.

    L is lower triangular: entry (q, l), l <= q, is word 4 + q R + l (R the rows) of
    Philox (``Stream.SCRAMBLE``, counter (j, realization, ...)) made a digit, uniform in
    [1, b) on the diagonal (so L is non-singular) and in [0, b) below it
    (:func:`clsamp.number_theory.digit_shift`, bias below b / 2^32).

    Parameters
    ----------
    seed : int
        Philox's key.
    realizations : array_like of int
        One L per realization (and dimension).
    matrices : ndarray
        (d, R, m) digits.
    base : int

    Returns
    -------
    ndarray of int64
        (len(realizations), d, R, m).
    """
    matrices = np.asarray(matrices, dtype=np.int64)
    d, rows, _ = matrices.shape
    q = np.arange(rows)[:, None]
    col = np.arange(rows)[None, :]
    r = np.asarray(realizations, dtype=_U32)[:, None, None, None]
    j = np.arange(d, dtype=_U32)[None, :, None, None]
    words = philox.random_words(seed, philox.Stream.SCRAMBLE, r, j,
                                (LMS_WORD0 + q * rows + col).astype(_U32)[None, None])
    below = nt.digit_shift(words, base).astype(np.int64)
    diagonal = 1 + nt.digit_shift(words, base - 1).astype(np.int64)
    lower = np.where(q == col, diagonal, np.where(col < q, below, 0))
    return np.einsum("rjql,jlk->rjqk", lower, matrices) % base


# -- Base-2 matrices from digit arrays -------------------------------------------------
def columns_base2(matrices):
    """Digit matrices (d, rows, m) of zeros and ones as column words (d, 32).

    Parameters
    ----------
    matrices : ndarray
        (d, rows, m) with rows, m <= 32; entry (j, r, k) is output digit r of index digit k.

    Returns
    -------
    ndarray of uint32
        (d, 32), columns past m zero.
    """
    matrices = np.asarray(matrices)
    d, rows, m = matrices.shape
    out = np.zeros((d, BITS), dtype=_U32)
    for r in range(min(rows, BITS)):
        out[:, :m] |= matrices[:, r, :].astype(_U32) << _U32(BITS - 1 - r)
    return out


def natural_to_gray(columns):
    """Columns whose Gray-code net is the natural-order net of ``columns``.

    C i = D g(i) with g(i) = i ^ (i >> 1) the Gray code and D_c = C_0 ^ ... ^ C_c (bit k of
    i is the xor of the Gray code's bits k and above), so the Gray-code kernel makes
    point i of the natural order from D.

    Parameters
    ----------
    columns : ndarray of uint32
        (d, 32).

    Returns
    -------
    ndarray of uint32
        (d, 32): the running xors.
    """
    return np.bitwise_xor.accumulate(np.asarray(columns, dtype=_U32), axis=-1)


def interlace_columns(columns, order):
    """Digit interlacing (Dick 2008): the column words of the order-``order`` net whose
    dimension j interlaces the digits of base dimensions order j, ..., order j + order - 1.

    Output digit order r + v of dimension j is digit r of base dimension order j + v, for
    r < ceil((32 - v) / order): as matrices, row order r + v of C'_j is row r of
    C_(order j + v), so the interlaced net is again a digital net (with 32 output digits; the
    base digits past them are dropped). A base net of m digit columns keeps all its digits
    while order m <= 32.

    Parameters
    ----------
    columns : ndarray of uint32
        (order d, k) column words (output digit r at bit 31 - r), the base net's.
    order : int
        The interlacing factor alpha >= 1 (1 returns the columns).

    Returns
    -------
    ndarray of uint32
        (d, k).

    References
    ----------
    .. [1] J. Dick, "Walsh spaces containing smooth functions and quasi-Monte Carlo rules of
       arbitrary high order", SIAM J. Numer. Anal. 46(3) (2008), 1519-1553.

    Examples
    --------
    >>> [hex(int(w)) for w in interlace_columns(np.array([[0xC0000000], [0x80000000]]), 2)[0]]
    ['0xe0000000']
    """
    columns = np.asarray(columns, dtype=_U32)
    if order == 1:
        return columns.copy()
    d = columns.shape[0] // order
    base = columns[:d * order].reshape(d, order, *columns.shape[1:])
    out = np.zeros((d, *columns.shape[1:]), dtype=_U32)
    for v in range(order):
        for r in range(-(-(BITS - v) // order)):
            bit = (base[:, v] >> _U32(BITS - 1 - r)) & _U32(1)
            out |= bit << _U32(BITS - 1 - (order * r + v))
    return out


# -- Faure -----------------------------------------------------------------------------
def faure_base(d):
    """Faure's base for d dimensions: the smallest prime b >= d (and >= 2).

    Parameters
    ----------
    d : int
        Dimensions of the net.

    Returns
    -------
    int
        Prime.

    Examples
    --------
    >>> [faure_base(d) for d in (1, 2, 3, 4, 6, 8)]
    [2, 2, 3, 5, 7, 11]
    """
    b = max(2, int(d))
    while any(b % p == 0 for p in range(2, int(b**0.5) + 1)):
        b += 1
    return b


def faure_matrices(d, base, m):
    """Faure's generating matrices: the powers P^j of the Pascal matrix mod b.

    Entry (r, k) of C_j is binom(k, r) j^(k - r) mod b (zero for r > k; C_0 the identity).

    Parameters
    ----------
    d : int
        Dimensions, at most ``base``.
    base : int
        A prime.
    m : int
        Index digits (the matrices are m x m).

    Returns
    -------
    ndarray of int64
        (d, m, m).

    Examples
    --------
    >>> faure_matrices(2, 3, 3)[1].tolist()
    [[1, 1, 1], [0, 1, 2], [0, 0, 1]]
    """
    out = np.zeros((d, m, m), dtype=np.int64)
    binom = np.zeros((m, m), dtype=np.int64)          # binom[r, k] = C(k, r) mod b
    for k in range(m):
        binom[0, k] = 1
        for r in range(1, k + 1):
            binom[r, k] = (binom[r - 1, k - 1] + binom[r, k - 1]) % base
    for j in range(d):
        for r in range(m):
            for k in range(r, m):
                out[j, r, k] = binom[r, k] * pow(j, k - r, base) % base
    return out


# -- Niederreiter (base 2) -------------------------------------------------------------
def _gf2_multiply(a, b):
    out = 0
    while b:
        if b & 1:
            out ^= a
        a <<= 1
        b >>= 1
    return out


def irreducible_polynomials_gf2(count):
    """The first ``count`` irreducible polynomials over GF(2), by increasing value.

    A polynomial is an int whose bit k is the coefficient of x^k: x (2), 1 + x (3),
    1 + x + x^2 (7), 1 + x + x^3 (11), 1 + x^2 + x^3 (13), ...; Bratley, Fox and
    Niederreiter (1992) give dimension j the j-th.

    Parameters
    ----------
    count : int

    Returns
    -------
    list of int

    Examples
    --------
    >>> irreducible_polynomials_gf2(8)
    [2, 3, 7, 11, 13, 19, 25, 31]
    """
    found = []
    p = 2
    while len(found) < count:
        degree = p.bit_length() - 1
        if all(_gf2_mod(p, q) for q in found if 2 * (q.bit_length() - 1) <= degree):
            found.append(p)
        p += 1
    return found


def _gf2_mod(a, b):
    db = b.bit_length()
    while a.bit_length() >= db:
        a ^= b << (a.bit_length() - db)
    return a


NIEDERREITER_MAX_DIMENSION = 1111   # polynomials of degree <= 13: t stays below 32 bits' reach


def niederreiter_matrices(d, bits=BITS):
    """Niederreiter's base-2 generating matrices as Bratley, Fox and Niederreiter compute them.

    Dimension j takes the j-th irreducible polynomial p (degree e). Output digit
    r = q e + u (0 <= u < e) of index digit k is v_(k+u), v the sequence of BFN's section
    3.3 for p^(q+1) (degree M = e (q + 1)): v_s = 0 below M - e, v_s = 1 from M - e to
    M - 1 (BFN set each K_q to its largest value, which makes the free values one), and
    v_(s+M) = Σ_(l<M) c_l v_(s+l) past them, c_l the coefficients of p^(q+1). The first
    2^m points in Gray-code order form a (t, m, d)-net with t = Σ_j (e_j - 1).

    Parameters
    ----------
    d : int
        1 to NIEDERREITER_MAX_DIMENSION.
    bits : int
        Output digits (rows) and index digits (columns).

    Returns
    -------
    ndarray of uint8
        (d, bits, bits): entry (j, r, k).

    References
    ----------
    .. [1] P. Bratley, B. L. Fox, H. Niederreiter, "Implementation and tests of
       low-discrepancy sequences", ACM TOMACS 2(3) (1992), 195-213.
    .. [2] H. Niederreiter, "Low-discrepancy and low-dispersion sequences", J. Number
       Theory 30 (1988).

    Examples
    --------
    >>> niederreiter_matrices(2, 4)[1].tolist()
    [[1, 1, 1, 1], [0, 1, 0, 1], [0, 0, 1, 1], [0, 0, 0, 1]]
    """
    if not 1 <= d <= NIEDERREITER_MAX_DIMENSION:
        raise InvalidArgumentError(
            f"'d' must be in [1, {NIEDERREITER_MAX_DIMENSION}] for Niederreiter, got {d}")
    out = np.zeros((d, bits, bits), dtype=np.uint8)
    for j, p in enumerate(irreducible_polynomials_gf2(d)):
        e = p.bit_length() - 1
        power = 1                     # p^q
        v = None
        for r in range(bits):
            q, u = divmod(r, e)
            if u == 0:
                previous = power.bit_length() - 1       # BFN's "bigm": the degree of p^q
                power = _gf2_multiply(power, p)
                big = power.bit_length() - 1           # M, the degree of p^(q+1)
                length = bits + big + bits
                v = [0] * length
                v[previous] = 1
                for s in range(previous + 1, big):
                    v[s] = 1
                for s in range(length - big):
                    term = 0
                    for bit in range(big):
                        if (power >> bit) & 1:
                            term ^= v[s + bit]
                    v[s + big] = term
            out[j, r, :] = v[u:u + bits]
    return out


def niederreiter_t(d):
    """The t of Niederreiter's base-2 sequence in d dimensions: Σ_j (e_j - 1).

    Parameters
    ----------
    d : int
        Dimensions (the first d polynomials).

    Returns
    -------
    int
        t >= 0: the first 2^m points form a (t, m, d)-net for every m >= t.

    Examples
    --------
    >>> [niederreiter_t(d) for d in (1, 2, 3, 4, 5)]
    [0, 0, 1, 3, 5]
    """
    return sum(p.bit_length() - 2 for p in irreducible_polynomials_gf2(d))


# -- Base-b digital nets ---------------------------------------------------------------
def running_sums(matrices, base):
    """D_c = C_0 + ... + C_c (mod b), column by column: the increment of the digits when
    index i + 1 carries c digits (c trailing digits b - 1 of i become 0, digit c grows).

    Parameters
    ----------
    matrices : ndarray
        (d, rows, m).
    base : int

    Returns
    -------
    ndarray of uint32
        (d, rows, m).
    """
    return (np.cumsum(np.asarray(matrices, dtype=np.int64), axis=-1) % base).astype(_U32)


def digital_net_digits(index, matrices, base):
    """The output digits of points of a base-b digital net: y = C a mod b.

    Parameters
    ----------
    index : array_like of int
        Point indices (< b^m).
    matrices : ndarray
        (d, rows, m) digits in [0, b).
    base : int

    Returns
    -------
    ndarray of int64
        (len(index), d, rows).
    """
    matrices = np.asarray(matrices, dtype=np.int64)
    m = matrices.shape[-1]
    a = nt.index_digits(np.asarray(index, dtype=_U64), base, m).astype(np.int64)   # (n, m)
    return np.einsum("jrk,nk->njr", matrices, a) % base


def digital_net_numerators(digits, base):
    """Σ_r y_r b^(R-1-r): the coordinate times b^R, exact (b^R <= 2^53).

    Parameters
    ----------
    digits : ndarray of int
        (..., R).
    base : int

    Returns
    -------
    ndarray of uint64
    """
    out = np.zeros(digits.shape[:-1], dtype=_U64)
    for r in range(digits.shape[-1]):
        out = out * _U64(base) + digits[..., r].astype(_U64)
    return out
