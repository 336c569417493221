"""Number theory of the low-discrepancy samplers, as small pure NumPy functions.

Primes, radical inverses computed from integer digits, Sobol generator matrices, and the
randomizations (random digit shift / xor, random digit permutations, nested uniform
"Owen" scrambling) with the hashes they use. These are the NumPy references of
``kernels/lowdiscrepancy.cl``, which computes the same integers with the same formulas,
so both give bit-identical points; :mod:`clsamp.samplers.lowdiscrepancy` composes them.

Exactness. A point index is a 32-bit integer. In base b every index has at most
``m = digit_count(b)`` digits (the smallest m with b^m >= 2^32), so a radical inverse,
plain or scrambled, is an integer numerator v < b^m over b^m. Both fit in 53 bits for
b <= 2^20, so the float64 result ``v / b^m`` is the correctly rounded value of the exact
rational (one IEEE division). Sobol points are 32-bit integers times 2^-32 (exact).

Integer arithmetic wraps modulo 2^32 (``uint32``) or 2^64 (``uint64``) exactly as C's
unsigned types do in the kernel.

References
----------
.. [1] M. Pharr, W. Jakob, G. Humphreys, *Physically Based Rendering*, 4th ed. (2023),
   ch. 8.6-8.7 (radical inverse, digit permutations, Owen scrambling, Sobol matrices).
.. [2] S. Joe, F. Y. Kuo, "Constructing Sobol sequences with better two-dimensional
   projections", SIAM J. Sci. Comput. 30 (2008).
.. [3] A. B. Owen, "Randomly permuted (t,m,s)-nets and (t,s)-sequences", Monte Carlo and
   Quasi-Monte Carlo Methods in Scientific Computing (1995).
.. [4] S. Laine, T. Karras, "Stratified sampling for stochastic transparency", EGSR 2011.
.. [5] B. Burley, "Practical hash-based Owen scrambling", JCGT 9(4) (2020).
.. [6] N. Vegdahl, "Building a better LK hash" (2021),
   https://psychopath.io/post/2021_01_30_building_a_better_lk_hash
.. [7] A. Kensler, "Correlated multi-jittered sampling", Pixar Technical Memo 13-01 (2013).
.. [8] A. B. Owen, "A randomized Halton algorithm in R" (2017), arXiv:1706.02808.
.. [9] N. Brackett-Rozinsky, D. Lemire, "Batched ranged random integer generation",
   Software: Practice and Experience (2025), doi:10.1002/spe.3369.
"""

import functools
from importlib import resources

import numpy as np

from .errors import InvalidArgumentError

MAX_BASE = 2**20          # keeps b^m (and the Owen node numbers 2 b^m) within 53 bits
INDEX_BITS = 32
SOBOL_BITS = 32
SOBOL_TABLE = "sobol_joe_kuo_6_21201.npz"

_U32 = np.uint32
_U64 = np.uint64


# -- primes --------------------------------------------------------------------------
@functools.lru_cache(maxsize=8)
def _sieve(limit):
    is_prime = np.ones(limit + 1, dtype=bool)
    is_prime[:2] = False
    for p in range(2, int(limit**0.5) + 1):
        if is_prime[p]:
            is_prime[p * p::p] = False
    return np.flatnonzero(is_prime)


def first_primes(count):
    """The first ``count`` primes (2, 3, 5, ...) as uint32: the Halton bases.

    Parameters
    ----------
    count : int
        How many; 0 or less gives an empty array.

    Returns
    -------
    ndarray of uint32

    Examples
    --------
    >>> first_primes(5).tolist()
    [2, 3, 5, 7, 11]
    """
    if count <= 0:
        return np.zeros(0, dtype=_U32)
    limit = 16
    # p_k < k (ln k + ln ln k) for k >= 6 (Rosser's theorem)
    if count >= 6:
        limit = int(count * (np.log(count) + np.log(np.log(count)))) + 1
    return _sieve(limit)[:count].astype(_U32)


# -- radical inverse -----------------------------------------------------------------
def digit_count(base):
    """m, the number of base-``base`` digits of every 32-bit index: the least m with b^m >= 2^32.

    Parameters
    ----------
    base : int
        At least 2.

    Returns
    -------
    int
        32 in base 2, 21 in base 3.
    """
    m, power = 0, 1
    while power < 2**INDEX_BITS:
        power *= int(base)
        m += 1
    return m


def index_digits(index, base, m=None):
    """Base-``base`` digits of ``index``, least significant first.

    Parameters
    ----------
    index : int or array_like of int
        Non-negative indices.
    base : int
    m : int, optional
        Digits to return; :func:`digit_count` of the base by default.

    Returns
    -------
    ndarray of uint64
        (..., m), digit k in column k.

    Examples
    --------
    >>> index_digits(5, 3, 3).tolist()          # 5 = 2 + 1 * 3
    [2, 1, 0]
    """
    m = digit_count(base) if m is None else m
    a = np.asarray(index, dtype=_U64)
    b = _U64(base)
    digits = np.empty(a.shape + (m,), dtype=_U64)
    for k in range(m):
        digits[..., k] = a % b
        a = a // b
    return digits


def radical_inverse_numerator(index, base):
    """v such that the radical inverse of ``index`` in ``base`` is v / b^m exactly.

    Φ_b(i) = Σ_k d_k b^-(k+1) for i = Σ_k d_k b^k, so Φ_b(i) = v / b^m with
    v = Σ_{k<m} d_k b^(m-1-k) (the digits of i reversed), m = :func:`digit_count`.

    Parameters
    ----------
    index : int or array_like of int in [0, 2^32)
    base : int in [2, 2^20]

    Returns
    -------
    ndarray of uint64
        v, below b^m.
    """
    m = digit_count(base)
    digits = index_digits(index, base, m)
    v = np.zeros(digits.shape[:-1], dtype=_U64)
    for k in range(m):
        v = v * _U64(base) + digits[..., k]
    return v


def radical_inverse(index, base):
    """The radical inverse Φ_b(i) as float64, correctly rounded from the exact rational.

    Parameters
    ----------
    index : int or array_like of int in [0, 2^32)
    base : int in [2, 2^20]

    Returns
    -------
    ndarray of float64

    Examples
    --------
    >>> radical_inverse([0, 1, 2, 3], 2).tolist()
    [0.0, 0.5, 0.25, 0.75]
    >>> float(radical_inverse(3**20, 3)) == 3.0**-21
    True
    """
    m = digit_count(base)
    return radical_inverse_numerator(index, base).astype(np.float64) / float(int(base) ** m)


# -- hashes and permutations ---------------------------------------------------------
def mix64(v):
    """A 64-bit bijective finalizer (pbrt-v4's MixBits; Stafford's variant 13 constants).

    Parameters
    ----------
    v : int or array_like of int

    Returns
    -------
    ndarray of uint64
    """
    v = np.asarray(v, dtype=_U64)
    with np.errstate(over="ignore"):
        v = v ^ (v >> _U64(31))
        v = v * _U64(0x7FB5D329728EA185)
        v = v ^ (v >> _U64(27))
        v = v * _U64(0x81DADEF4BC2DD44D)
        v = v ^ (v >> _U64(33))
    return v


def digit_hash(seed64, key):
    """32 random bits for one digit: the high word of ``mix64(seed64 ^ key)``.

    ``key`` is the digit position k for the random digit shift and permutation
    (the same for every point).

    Parameters
    ----------
    seed64, key : int or array_like of int

    Returns
    -------
    ndarray of uint32
    """
    mixed = mix64(np.asarray(seed64, dtype=_U64) ^ np.asarray(key, dtype=_U64))
    return (mixed >> _U64(32)).astype(_U32)


def digit_shift(h, base):
    """A digit in [0, base) from 32 random bits: floor(h · base / 2^32) (bias below base/2^32).

    Parameters
    ----------
    h : int or array_like of int
    base : int

    Returns
    -------
    ndarray of uint32
    """
    return ((np.asarray(h, dtype=_U64) * _U64(base)) >> _U64(32)).astype(_U32)


def permutation_element(i, length, p):
    """Element ``i`` of the pseudo-random permutation of [0, length) chosen by ``p``.

    Kensler's hash-and-cycle-walk permutation [7]_ (pbrt's PermutationElement):
    a bijection on the next power of two, walked until it lands in [0, length), then
    rotated by p: ``(i + p) mod length``, the sum taken in 64 bits (pbrt's 32-bit sum
    wraps for p > 2^32 - length, and the result is then not a permutation). All
    arguments broadcast; the hash's arithmetic wraps modulo 2^32.

    Parameters
    ----------
    i : int or array_like of int
        Positions in [0, length).
    length : int or array_like of int
        The permutations' lengths, 1 to 2^32 - 1.
    p : int or array_like of int
        32-bit seeds, one per permutation.

    Returns
    -------
    ndarray of uint32
        The broadcast shape.

    Examples
    --------
    >>> sorted(permutation_element(np.arange(7), 7, 12345).tolist())
    [0, 1, 2, 3, 4, 5, 6]
    """
    i, length, p = np.broadcast_arrays(np.asarray(i, dtype=_U32), np.asarray(length, dtype=_U32),
                                       np.asarray(p, dtype=_U32))
    i, length, p = i.copy(), length.copy(), p.copy()
    w = length - _U32(1)
    for s in (1, 2, 4, 8, 16):
        w |= w >> _U32(s)
    out = np.empty_like(i)
    todo = np.ones(i.shape, dtype=bool)
    x = i
    with np.errstate(over="ignore"):
        while todo.any():
            xs, ps, ws, ls = x[todo], p[todo], w[todo], length[todo]
            xs = xs ^ ps
            xs = xs * _U32(0xE170893D)
            xs = xs ^ (ps >> _U32(16))
            xs = xs ^ ((xs & ws) >> _U32(4))
            xs = xs ^ (ps >> _U32(8))
            xs = xs * _U32(0x0929EB3F)
            xs = xs ^ (ps >> _U32(23))
            xs = xs ^ ((xs & ws) >> _U32(1))
            xs = xs * (_U32(1) | (ps >> _U32(27)))
            xs = xs * _U32(0x6935FA69)
            xs = xs ^ ((xs & ws) >> _U32(11))
            xs = xs * _U32(0x74DCB303)
            xs = xs ^ ((xs & ws) >> _U32(2))
            xs = xs * _U32(0x9E501CC3)
            xs = xs ^ ((xs & ws) >> _U32(2))
            xs = xs * _U32(0xC860A3DF)
            xs = xs & ws
            xs = xs ^ (xs >> _U32(5))
            x[todo] = xs
            done = xs < ls
            idx = np.flatnonzero(todo)
            finished = idx[done]
            # the rotation by p in 64 bits: (i + p) mod l, which 32 bits would wrap for
            # p > 2^32 - l and then miss some of [0, l)
            out.flat[finished] = ((xs[done].astype(_U64) + ps[done]) % ls[done]).astype(_U32)
            todo.flat[finished] = False
    return out


def reverse_bits32(x):
    """The 32 bits of ``x`` in reverse order (bit k goes to bit 31 - k).

    Parameters
    ----------
    x : int or array_like of int

    Returns
    -------
    ndarray of uint32
    """
    x = np.asarray(x, dtype=_U32)
    x = ((x >> _U32(1)) & _U32(0x55555555)) | ((x & _U32(0x55555555)) << _U32(1))
    x = ((x >> _U32(2)) & _U32(0x33333333)) | ((x & _U32(0x33333333)) << _U32(2))
    x = ((x >> _U32(4)) & _U32(0x0F0F0F0F)) | ((x & _U32(0x0F0F0F0F)) << _U32(4))
    x = ((x >> _U32(8)) & _U32(0x00FF00FF)) | ((x & _U32(0x00FF00FF)) << _U32(8))
    return (x >> _U32(16)) | (x << _U32(16))


def lk_hash(x, seed):
    """Vegdahl's Laine-Karras-style hash [6]_ on bit-reversed input.

    Every step (``x ^= x * even``, ``x += seed``, ``x *= odd``) changes bit k only by a
    function of bits below k, so on reversed bits each binary digit is flipped by a
    function of all digits above it: a nested (Owen) scramble [4]_ [5]_. Vegdahl's
    constants fix the original hash's poor low bits (empty buckets, XeGTAO issue 7).

    Parameters
    ----------
    x, seed : int or array_like of int
        Bit-reversed 32-bit words and 32-bit seeds, broadcast.

    Returns
    -------
    ndarray of uint32
    """
    x = np.asarray(x, dtype=_U32)
    seed = np.asarray(seed, dtype=_U32)
    with np.errstate(over="ignore"):
        x = x ^ (x * _U32(0x3D20ADEA))
        x = x + seed
        x = x * ((seed >> _U32(16)) | _U32(1))
        x = x ^ (x * _U32(0x05526C56))
        x = x ^ (x * _U32(0x53A22864))
    return x


def owen_scramble_base2(x, seed):
    """Nested uniform scramble of the 32 binary digits of the fraction x · 2^-32.

    ``reverse(lk_hash(reverse(x), seed))``: digit k (from the top) is flipped by a hash
    of the seed and the digits above it [5]_.

    Parameters
    ----------
    x, seed : int or array_like of int
        32-bit fractions and seeds.

    Returns
    -------
    ndarray of uint32
    """
    return reverse_bits32(lk_hash(reverse_bits32(x), seed))


# -- nested uniform scrambling in base b >= 3 ----------------------------------------
OWEN_ATTEMPT_STRIDE = 2**27   # word slots per rejection attempt (more than any node's chunks)


def owen_chunk_length(base):
    """g, the draws per 32-bit word of a node's Fisher-Yates shuffle: the largest g with b^g <= 2^32.

    Parameters
    ----------
    base : int

    Returns
    -------
    int
    """
    g, power = 0, 1
    while power * int(base) <= 2**32:
        power *= int(base)
        g += 1
    return g


def owen_node_key(seed64, node):
    """The 64-bit key of the digit-tree node ``node`` = b^k + (i mod b^k): mix64(seed64 ^ node).

    Parameters
    ----------
    seed64, node : int or array_like of int

    Returns
    -------
    ndarray of uint64
    """
    return mix64(np.asarray(seed64, dtype=_U64) ^ np.asarray(node, dtype=_U64))


def owen_word(key, slot):
    """32-bit word number ``slot`` of a node: a half of block slot // 2, where block 0 is the
    node key itself and block u > 0 is mix64(key ^ u); even slots take the low half.

    Parameters
    ----------
    key, slot : int or array_like of int
        Node keys (:func:`owen_node_key`) and word numbers, broadcast.

    Returns
    -------
    ndarray of uint64
        Values below 2^32.
    """
    key = np.asarray(key, dtype=_U64)
    slot = np.asarray(slot, dtype=_U64)
    u = slot >> _U64(1)
    block = np.where(u == 0, key, mix64(key ^ u))
    return np.where(slot & _U64(1), block >> _U64(32), block & _U64(0xFFFFFFFF))


def owen_chunk_draws(key, base, chunk):
    """The Fisher-Yates draws r_j, j in [c g, c g + g), of chunk c of each node: (..., g) uint64.

    Draw j is uniform on [0, b - j) (r_j = 0 for j >= b - 1). One 32-bit word x makes the
    whole chunk without division (Brackett-Rozinsky and Lemire's batched ranged draws
    [9]_): x s_0 = r_0 2^32 + x_1, x_1 s_1 = r_1 2^32 + x_2, ..., so (r_0, r_1, ...) are the
    mixed-radix digits of floor(x P / 2^32), P = prod s_t <= 2^32, and rejecting
    x_last < 2^32 mod P makes them exactly uniform and independent; a rejected word is
    replaced by word slot c + a * OWEN_ATTEMPT_STRIDE of attempt a. ``key`` and ``chunk``
    broadcast.

    Parameters
    ----------
    key : int or array_like of int
        Node keys.
    base : int
        b >= 3.
    chunk : int or array_like of int
        Chunk numbers c.

    Returns
    -------
    ndarray of uint64
        (..., g), g = :func:`owen_chunk_length` of the base.
    """
    base = int(base)
    g = owen_chunk_length(base)
    key, chunk = np.broadcast_arrays(np.asarray(key, dtype=_U64), np.asarray(chunk, dtype=np.int64))
    shape = key.shape
    key, chunk = key.ravel(), chunk.ravel()
    bounds = np.maximum(base - chunk[:, None] * g - np.arange(g)[None, :], 1).astype(_U64)
    product = np.prod(bounds, axis=1)
    threshold = (_U64(2**32) % product).astype(_U64)
    draws = np.zeros((key.size, g), dtype=_U64)
    todo = np.arange(key.size)
    attempt = 0
    low = _U64(0xFFFFFFFF)
    while todo.size:
        x = owen_word(key[todo], chunk[todo].astype(_U64) + _U64(attempt * OWEN_ATTEMPT_STRIDE))
        r = np.empty((todo.size, g), dtype=_U64)
        for t in range(g):
            x = x * bounds[todo, t]
            r[:, t] = x >> _U64(32)
            x = x & low
        ok = x >= threshold[todo]
        draws[todo[ok]] = r[ok]
        todo = todo[~ok]
        attempt += 1
    return draws.reshape(shape + (g,))


def _node_draws(key, base, last):
    """Draws r_0..r_(last) of each node ``key`` (1-D): (len(key), chunks * g) uint64."""
    g = owen_chunk_length(base)
    chunks = last // g + 1
    c = np.arange(chunks, dtype=np.int64)
    draws = owen_chunk_draws(key[:, None], base, c[None, :])
    return draws.reshape(key.size, chunks * g)


def owen_permutation_element(key, base, digit):
    """π(d) for the uniformly random permutation π of [0, b) of each node ``key``.

    π is the Fisher-Yates shuffle of the identity with the draws of
    :func:`owen_chunk_draws`: for j = 0, 1, ..., b - 1 swap positions j and j + r_j;
    π(d) is what position d holds at the end. Position d is final after step d, so π(d)
    needs only r_0..r_d: start at p = d + r_d and walk back, for j = d - 1, ..., 0,
    setting p = j where j + r_j = p (the swap that brought p's value); then π(d) = p.
    ``key`` and ``digit`` broadcast.

    Parameters
    ----------
    key : int or array_like of int
        Node keys (:func:`owen_node_key`).
    base : int
        b >= 3.
    digit : int or array_like of int
        Digits d in [0, b).

    Returns
    -------
    ndarray of uint64
        π(d), the broadcast shape.
    """
    base = int(base)
    key, digit = np.broadcast_arrays(np.asarray(key, dtype=_U64), np.asarray(digit, dtype=_U64))
    shape = digit.shape
    key, d = key.ravel(), digit.ravel().astype(np.int64)
    out = np.empty(d.shape, dtype=np.int64)
    if d.size == 0:
        return out.astype(_U64).reshape(shape)
    if base >= 256:
        # a node that many points share (the root): shuffle it whole, once
        nodes, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
        shared = np.flatnonzero(counts >= 8)
        if shared.size:
            whole = np.isin(inverse, shared)
            for u in shared:
                at = inverse == u
                out[at] = owen_permutation(nodes[u], base).astype(np.int64)[d[at]]
            rest = ~whole
            if rest.any():
                out[rest] = owen_permutation_element(key[rest], base, d[rest]).astype(np.int64)
            return out.astype(_U64).reshape(shape)
    width = int(d.max()) + 1
    batch = max(1, 2**21 // width)
    for lo in range(0, d.size, batch):
        kb, db = key[lo:lo + batch], d[lo:lo + batch]
        nodes, inverse = np.unique(kb, return_inverse=True)
        draws = _node_draws(nodes, base, int(db.max())).astype(np.int64)
        target = np.arange(draws.shape[1])[None, :] + draws     # j + r_j
        p = db + draws[inverse, db]
        bound = db.copy()
        while True:
            # the last swap j < bound that brought position p's value
            hit = (target[inverse] == p[:, None]) & (np.arange(target.shape[1])[None, :] < bound[:, None])
            found = hit.any(axis=1)
            if not found.any():
                break
            last = hit.shape[1] - 1 - np.argmax(hit[:, ::-1], axis=1)
            p = np.where(found, last, p)
            bound = np.where(found, last, 0)
        out[lo:lo + batch] = p
    return out.astype(_U64).reshape(shape)


def owen_permutation(key, base):
    """The whole permutation [π(0), ..., π(b-1)] of one node ``key`` (scalar), by Fisher-Yates.

    Parameters
    ----------
    key : int
        A node key.
    base : int
        b >= 3.

    Returns
    -------
    ndarray of uint64
        (b,); equal to :func:`owen_permutation_element` at every digit.

    Examples
    --------
    >>> sorted(owen_permutation(12345, 5).tolist())
    [0, 1, 2, 3, 4]
    """
    base = int(base)
    draws = _node_draws(np.asarray([key], dtype=_U64), base, base - 1)[0, :base].tolist()
    a = list(range(base))
    for j, r in enumerate(draws):
        a[j], a[j + r] = a[j + r], a[j]
    return np.array(a, dtype=_U64)


def scrambled_radical_inverse_numerator(index, base, randomize, seed64):
    """Numerator v of a randomized radical inverse v / b^m (m = :func:`digit_count`).

    Parameters
    ----------
    index : array_like of int in [0, 2^32)
    base : int in [2, 2^20]
    randomize : {None, "shift", "xor", "permute", "owen"}
        ``None`` and ``"shift"`` give the plain digits (a shift is applied to the
        float afterwards); ``"xor"`` adds a random digit s_k mod b at each position k
        (the base-b random digit shift, an xor in base 2); ``"permute"`` applies a
        random permutation π_k to digit k (pbrt's PermuteDigits, Kensler's hash
        permutations); ``"owen"`` is nested uniform scrambling [3]_ [8]_: digit k of index i is
        mapped by a permutation π_(k, i mod b^k) of its own for every node of the digit
        tree (the depth k and the k digits below it), each node's permutation uniformly
        random over all b! permutations and independent of the others. In base b >= 3 a
        node's permutation is a Fisher-Yates shuffle driven by the node's key
        mix64(seed64 ^ (b^k + i mod b^k)) (:func:`owen_permutation_element`); in base 2,
        ``"owen"`` is :func:`owen_scramble_base2`.
    seed64 : int
        The randomization's 64-bit seed (one per realization and dimension).
        In base 2 ``"owen"`` uses its low 32 bits.

    Returns
    -------
    ndarray of uint64
        v, below b^m.

    Raises
    ------
    InvalidArgumentError
        An unknown ``randomize``.

    Notes
    -----
    All m digits are scrambled, the index's leading zeros included, so v is uniform
    on [0, b^m) over seeds. A node's permutation depends only on the seed and the node,
    so the points do not depend on how many are drawn, nor from which start.
    """
    base = int(base)
    m = digit_count(base)
    index = np.asarray(index, dtype=_U64)
    if randomize in (None, "shift"):
        return radical_inverse_numerator(index, base)
    seed64 = _U64(seed64)
    if randomize == "owen" and base == 2:
        return reverse_bits32(lk_hash(index.astype(_U32), _U32(int(seed64) & 0xFFFFFFFF))).astype(_U64)
    if randomize not in ("xor", "permute", "owen"):
        raise InvalidArgumentError(
            f"'randomize' must be None, 'shift', 'xor', 'permute' or 'owen', got {randomize!r}")
    digits = index_digits(index, base, m)
    v = np.zeros(index.shape, dtype=_U64)
    prefix = np.zeros(index.shape, dtype=_U64)    # i mod b^k
    power = 1                                      # b^k
    for k in range(m):
        d = digits[..., k]
        if randomize == "xor":
            e = (d + digit_shift(digit_hash(seed64, k), base)) % _U64(base)
        elif randomize == "permute":
            e = permutation_element(d.astype(_U32), base, digit_hash(seed64, k)).astype(_U64)
        else:
            e = owen_permutation_element(owen_node_key(seed64, prefix + _U64(power)), base, d)
        v = v * _U64(base) + e
        prefix = prefix + d * _U64(power)
        power *= base
    return v


# -- Sobol ---------------------------------------------------------------------------
@functools.lru_cache(maxsize=1)
def sobol_table():
    """The shipped Joe-Kuo direction numbers (``clsamp/data``).

    Returns
    -------
    poly : ndarray of int64
        Each dimension's primitive polynomial, its degree s the bit length minus 1.
    vinit : ndarray of int64
        (dimensions, columns): the initial direction numbers m_1 .. m_s.
    source : str
        Where the table comes from.
    """
    with resources.files("clsamp.data").joinpath(SOBOL_TABLE).open("rb") as f:
        table = np.load(f)
        return table["poly"].astype(np.int64), table["vinit"].astype(np.int64), str(table["source"])


def sobol_max_dimension():
    """How many dimensions the shipped direction numbers cover.

    Returns
    -------
    int

    Examples
    --------
    >>> sobol_max_dimension()
    21201
    """
    return len(sobol_table()[0])


@functools.lru_cache(maxsize=2)
def sobol_direction_integers(columns=SOBOL_BITS):
    """The Joe-Kuo direction integers m_(j,c) of every shipped dimension, c < ``columns``.

    Parameters
    ----------
    columns : int
        32 or 64 (the index bits).

    Returns
    -------
    ndarray of uint64
        (dimensions, columns): m_(j,c) < 2^(c+1), odd.
    """
    poly, vinit, _ = sobol_table()
    degree = np.array([int(p).bit_length() - 1 for p in poly])
    v = np.zeros((dims := len(poly), columns), dtype=_U64)
    v[0, :] = 1
    for j in range(1, dims):
        v[j, :degree[j]] = vinit[j, :degree[j]]
    rows_all = np.arange(1, dims)
    # Bratley-Fox / Joe-Kuo, over all dimensions: m_c = 2 a_1 m_(c-1) ^ ... ^ 2^s m_(c-s) ^ m_(c-s)
    for col in range(columns):
        rows = rows_all[degree[1:] <= col]
        if rows.size == 0:
            continue
        s = degree[rows]
        p = poly[rows]
        new = v[rows, col - s]
        for k in range(int(s.max())):
            active = k < s
            bit = (p >> np.where(active, s - 1 - k, 0)) & 1
            use = active & (bit == 1)
            term = v[rows, np.maximum(col - k - 1, 0)] << _U64(k + 1)
            new = new ^ np.where(use, term, _U64(0))
        v[rows, col] = new
    return v


def sobol_matrices(d):
    """Generator matrices of the first ``d`` Sobol dimensions: uint32 array (d, 32).

    Column c of dimension j is the direction number V_(j,c) = m_(j,c) 2^(31-c), the
    image of index bit c [2]_. Point i of dimension j is the xor of V_(j,c) over the set
    bits c of the Gray code i ^ (i >> 1), times 2^-32 (scipy's order).

    Parameters
    ----------
    d : int
        1 to :func:`sobol_max_dimension`.

    Returns
    -------
    ndarray of uint32
        (d, 32), a copy.

    Raises
    ------
    InvalidArgumentError
        ``d`` out of range.
    """
    if not 1 <= d <= sobol_max_dimension():
        raise InvalidArgumentError(
            f"'d' must be in [1, {sobol_max_dimension()}] for Sobol (Joe-Kuo table), got {d}")
    v = sobol_direction_integers()[:d]
    return (v << (_U64(SOBOL_BITS - 1) - np.arange(SOBOL_BITS, dtype=_U64))[None, :]).astype(_U32)


def gray_code(index):
    """The reflected binary Gray code i ^ (i >> 1) of 32-bit indices.

    Parameters
    ----------
    index : int or array_like of int

    Returns
    -------
    ndarray of uint32
    """
    index = np.asarray(index, dtype=_U32)
    return index ^ (index >> _U32(1))


def sobol_integers(index, matrices):
    """Sobol points as 32-bit integers (point i of dimension j is ``out[i, j] * 2^-32``).

    Parameters
    ----------
    index : array_like of int
        Point indices (flattened), 32-bit (64-bit with 64 columns).
    matrices : ndarray of uint32 or uint64
        (d, 32) from :func:`sobol_matrices`, or (d, 64) of uint64 (64-bit indices).

    Returns
    -------
    ndarray of uint32 or uint64
        (len(index), d), the dtype of ``matrices``.

    Examples
    --------
    >>> (sobol_integers([0, 1, 2, 3], sobol_matrices(2)) / 2**32).tolist()
    [[0.0, 0.0], [0.5, 0.5], [0.75, 0.25], [0.25, 0.75]]
    """
    t = matrices.dtype.type                      # uint32, or uint64 for 64-bit indices
    g = np.asarray(index, dtype=t).ravel()
    g = g ^ (g >> t(1))                          # the Gray code
    out = np.zeros((g.size, matrices.shape[0]), dtype=t)
    for c in range(matrices.shape[1]):
        bit = ((g >> t(c)) & t(1)).astype(bool)
        out[bit] ^= matrices[:, c][None, :]
    return out
