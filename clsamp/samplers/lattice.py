"""Rank-1 lattices and Kronecker sequences: ``lattice`` and ``kronecker``.

Both are integer arithmetic to the last bit (no floating-point product), so the kernels in
``kernels/lattice.cl`` and the NumPy references below give the same bits on every device.
Their randomization is the Cranley-Patterson shift of the low-discrepancy samplers
(``randomize="shift"``: ``philox.uniform(seed, SHIFT, realization k, 0, j)``).
"""

from decimal import Decimal, getcontext
from functools import cache
from importlib import resources

import numpy as np

from .. import number_theory as nt
from .. import runtime
from ..errors import InvalidArgumentError
from ..geometry import torus
from ..validation import check_choice, check_positive_int
from .base import register
from .lowdiscrepancy import LowDiscrepancySampler, shift_vectors

LATTICE_TABLE = "lattice_kuo_33002.npz"
ORDERS = ("radical_inverse", "gray", "natural")
_U32, _U64 = np.uint32, np.uint64


@cache
def _kuo():
    with resources.files("clsamp.data").joinpath(LATTICE_TABLE).open("rb") as f:
        table = np.load(f)
        return table["z"].astype(_U32), str(table["source"])


def kuo_vector(d):
    """The first ``d`` entries of the shipped generating vector (Cools, Kuo, Nuyens 2006).

    Parameters
    ----------
    d : int
        1 to the table's length.

    Returns
    -------
    ndarray of uint32
        A copy.

    Raises
    ------
    InvalidArgumentError
        ``d`` beyond the table.
    """
    z, _ = _kuo()
    if not 1 <= d <= len(z):
        raise InvalidArgumentError(f"'d' must be in [1, {len(z)}] for the shipped lattice, got {d}")
    return z[:d].copy()


def korobov(a, d, modulus=2**32):
    """Korobov's generating vector (1, a, a^2, ..., a^(d-1)) mod ``modulus``.

    Parameters
    ----------
    a : int
        The generator, 1 <= a < modulus.
    d : int
        Dimensions.
    modulus : int
        The lattice size it is meant for (2^32: the extensible base-2 lattice; n for a
        lattice of n points in ``order="natural"``).

    Returns
    -------
    ndarray of uint64

    References
    ----------
    .. [1] N. M. Korobov, "The approximate computation of multiple integrals", Dokl.
       Akad. Nauk SSSR 124 (1959).

    Examples
    --------
    >>> korobov(3, 4, 101).tolist()
    [1, 3, 9, 27]
    """
    modulus = check_positive_int(modulus, "modulus", maximum=2**32)
    a = check_positive_int(a, "a")
    if a >= modulus:
        raise InvalidArgumentError(f"'a' must be below the modulus {modulus}, got {a}")
    d = check_positive_int(d, "d")
    return np.array([pow(a, j, modulus) for j in range(d)], dtype=_U64)


def check_generating_vector(vector, d):
    """A user's generating vector: 1-D positive integers below 2^32, its first ``d``.

    Parameters
    ----------
    vector : array_like of int
    d : int
        The dimension asked for, at most the vector's length.

    Returns
    -------
    ndarray of uint32
        (d,).

    Raises
    ------
    InvalidArgumentError
        Anything else.
    """
    try:
        z = np.asarray(vector)
    except (TypeError, ValueError):
        z = np.asarray([None])
    if z.ndim != 1 or z.size < 1 or z.dtype.kind not in "iu":
        raise InvalidArgumentError(
            f"'generating_vector' must be a 1-D array of positive integers, got {vector!r}"[:200])
    if np.any(z < 1) or np.any(z.astype(object) >= 2**32):
        raise InvalidArgumentError("'generating_vector' entries must be in [1, 2^32)")
    if not isinstance(d, (int, np.integer)) or not 1 <= d <= z.size:
        raise InvalidArgumentError(
            f"'d' must be in [1, {z.size}] for the {z.size} entries of 'generating_vector', got {d!r}")
    return z[:d].astype(_U32)


def fibonacci(count):
    """The Fibonacci numbers F_1 .. F_count (1, 1, 2, 3, 5, ...).

    Parameters
    ----------
    count : int
        At least 2.

    Returns
    -------
    list of int

    Examples
    --------
    >>> fibonacci(7)
    [1, 1, 2, 3, 5, 8, 13]
    """
    out = [1, 1]
    while len(out) < count:
        out.append(out[-1] + out[-2])
    return out[:count]


class _Shifted(LowDiscrepancySampler):
    """Sequences whose one randomization is the Cranley-Patterson shift."""

    randomizations = (None, "shift")

    def _shift(self, points, realizations):
        if self.randomize is None:
            return np.broadcast_to(points, (len(realizations), *points.shape)).copy()
        u = shift_vectors(self.seed, np.arange(realizations.start, realizations.stop), self.d)
        return torus.shift(points[None], u[:, None, :])

    def _run(self, kernel_name, table, n, realizations, start, scalars, out, defines=None):
        r = len(realizations)
        target = runtime.Output((r, n, self.d), host=out)
        shifts = (shift_vectors(self.seed, np.arange(realizations.start, realizations.stop), self.d)
                  if self.randomize else np.zeros((1, self.d)))
        local = runtime.local_size()
        kernel = runtime.kernel("lattice.cl", kernel_name,
                                defines={"SHIFT": int(bool(self.randomize)), **(defines or {})})
        kernel(runtime.queue(), (-(-n // local) * local, r), (local, 1), target.buffer, table.data,
               runtime.to_device(np.ascontiguousarray(shifts, dtype=np.float64)).data,
               np.uint32(n), np.uint32(self.d), np.uint32(start), *scalars)
        return target.finish()


@register("lattice", "rank1_lattice")
class LatticeSampler(_Shifted):
    """Rank-1 lattice: point i is frac(i z / n) for a generating vector z.

    ``generator="kuo"`` (default) is an *extensible* lattice sequence in base 2: point i is
    frac(Φ_2(i) z), Φ_2 the van der Corput radical inverse, with the generating vector of
    Cools, Kuo and Nuyens (2006) for 2^10 to 2^20 points in up to 9125 dimensions (shipped
    in clsamp/data; qmcpy's default). Computed exactly as ((reverse32(i) z) mod 2^32) 2^-32,
    so the first 2^m points are exactly the lattice {k z / 2^m mod 1} and ``start=``
    continues the sequence (the radical-inverse order of Hickernell et al. 2000). Points
    equal qmcpy's ``Lattice(order="natural", randomize=False)``.

    ``generator="fibonacci"`` (d = 2) is the Fibonacci lattice, n = F_m points
    (i / F_m, frac(i F_(m-1) / F_m)), the best 2-D lattice (Niederreiter 1992; Sloan and
    Joe 1994): a point set, so ``start`` must be 0 and n a Fibonacci number; each
    coordinate is the integer ``i F_(m-1) mod F_m`` divided by F_m with one correctly
    rounded division.

    A ``generating_vector`` of one's own (a search's result, LatNet Builder's, or
    :func:`korobov`'s) replaces Kuo's, in any of the three orders:

    * ``"radical_inverse"`` (the default): point i is frac(Φ_2(i) z), the extensible
      sequence above (qmcpy's ``order="RADICAL INVERSE"``);
    * ``"gray"``: point i is frac(Φ_2(g(i)) z) with g(i) = i xor (i >> 1), the Gray code:
      the same first 2^m points in an order where consecutive indices differ in one bit
      (qmcpy's ``"GRAY"``);
    * ``"natural"``: the rank-1 lattice rule of n points, point i = frac(i z / n), for any
      n (qmcpy's ``"LINEAR"`` for n = 2^m): a point set, so ``start`` must be 0; each
      coordinate is the integer ``i z mod n`` over n, one correctly rounded division.
      The Fibonacci lattice is this order with z = (1, F_(m-1)).

    Parameters
    ----------
    d : int
        Dimension (1 to 9125 for ``"kuo"``, 2 for ``"fibonacci"``, at most the length of a
        ``generating_vector``, whose first d entries are used, as qmcpy's).
    seed : int
    randomize : {None, "shift"}
        ``"shift"``: x + u mod 1, u uniform per realization and dimension (Cranley-Patterson
        1976): every point uniform, the lattice structure kept on the torus.
    generator : {"kuo", "fibonacci"}
    generating_vector : array_like of int, optional
        Positive integers below 2^32, one per dimension (with ``generator="kuo"``).
    order : {"radical_inverse", "gray", "natural"}, optional
        As above; ``"natural"`` for the Fibonacci lattice (its only order).
    backend : {"opencl", "numpy"}

    Notes
    -----
    For smooth periodic integrands in a Korobov space of smoothness α, shifted lattice rules
    reach MSE O(N^(-2α+ε)) (Sloan and Joe 1994; Dick, Kuo, Sloan 2013); clsamp's integrands
    have no finite α of that kind (the wrapped Gaussian is analytic, the disk is not
    periodic-smooth), so no rate is claimed (``convergence_rate`` is None).

    References
    ----------
    .. [1] R. Cools, F. Y. Kuo, D. Nuyens, "Constructing embedded lattice rules for
       multivariate integration", SIAM J. Sci. Comput. 28 (2006).
    .. [2] F. J. Hickernell, H. S. Hong, P. L'Ecuyer, C. Lemieux, "Extensible lattice
       sequences for quasi-Monte Carlo quadrature", SIAM J. Sci. Comput. 22 (2000).
    .. [3] I. H. Sloan, S. Joe, *Lattice Methods for Multiple Integration*, Oxford (1994).

    Examples
    --------
    >>> import clsamp
    >>> clsamp.make_sampler("lattice", d=2, generator="fibonacci").sample(8).tolist()[:3]
    [[0.0, 0.0], [0.125, 0.625], [0.25, 0.25]]
    >>> clsamp.make_sampler("lattice", d=3).sample(4)[:, 1].tolist()
    [0.0, 0.5, 0.75, 0.25]
    >>> from clsamp.samplers.lattice import korobov
    >>> z = korobov(3, 2, 8)
    >>> clsamp.make_sampler("lattice", generating_vector=z, order="natural").sample(8)[:3].tolist()
    [[0.0, 0.0], [0.125, 0.375], [0.25, 0.75]]
    >>> clsamp.make_sampler("lattice", d=2, order="gray").sample(4)[:, 0].tolist()
    [0.0, 0.5, 0.75, 0.25]
    """

    max_d = len(_kuo()[0])
    max_d_source = "the shipped generating vector"

    def __init__(self, d=2, seed=0, backend="opencl", randomize=None, generator="kuo",
                 generating_vector=None, order=None):
        generator = check_choice(generator, "generator", ("kuo", "fibonacci"))
        order = check_choice(order, "order", (None,) + ORDERS)
        z = None
        if generating_vector is not None:
            if generator != "kuo":
                raise InvalidArgumentError("'generating_vector' replaces the Kuo vector; the "
                                           "Fibonacci lattice has its own")
            z = check_generating_vector(generating_vector, d)
        super().__init__(d=d, seed=seed, backend=backend, randomize=randomize)
        self.generator = generator
        if self.generator == "fibonacci":
            if self.d != 2:
                raise InvalidArgumentError(f"'d' must be 2 for the Fibonacci lattice, got {self.d}")
            if order not in (None, "natural"):
                raise InvalidArgumentError(f"the Fibonacci lattice has one order, 'natural'; got {order!r}")
            self._fib = fibonacci(47)                       # F_47 < 2^32 <= F_48
            order = "natural"
        self.order = order or "radical_inverse"
        self.generating_vector = kuo_vector(self.d) if z is None and generator == "kuo" else z

    @property
    def sequence(self):
        """The radical-inverse and Gray orders are extensible sequences; the natural order
        (and the Fibonacci lattice) a point set."""
        return self.order != "natural"

    @property
    def accepts_start(self):
        """``start`` continues a sequence; a point set takes only 0."""
        return self.sequence

    def valid_n(self, n):
        """The valid point count nearest to ``n``.

        Parameters
        ----------
        n : int

        Returns
        -------
        int
            ``n`` itself for the Kuo lattice (an extensible sequence); the nearest
            Fibonacci number for ``generator="fibonacci"`` (the smaller on a tie).
        """
        if self.generator == "kuo":
            return n
        return min(self._fib, key=lambda f: (abs(f - n), f))

    def _vector(self, n):
        """The generating vector for n points: Fibonacci's (1, F_(m-1)) for n = F_m."""
        if self.generator == "kuo":
            return self.generating_vector
        m = self._fib.index(n, 1) if n > 1 else 1
        return np.array([1, self._fib[m - 1]], dtype=_U32)

    def _reference(self, n, realizations, start):
        index = _U64(start) + np.arange(n, dtype=_U64)
        z = self._vector(n).astype(_U64)
        if self.order == "natural":
            x = ((index[:, None] * z[None, :]) % _U64(n)).astype(np.float64) / float(n)
        else:
            if self.order == "gray":
                index = index ^ (index >> _U64(1))
            radical = nt.reverse_bits32(index.astype(_U32)).astype(_U64)
            x = ((radical[:, None] * z[None, :]) & _U64(0xFFFFFFFF)).astype(np.float64) * 2.0**-32
        return self._shift(x, realizations)

    def _device(self, n, realizations, start, out=None):
        z = self._vector(n)
        key = ("lattice", self.generator, self.d, z.tobytes() if self.generator == "kuo" else n)
        table = runtime.table(key, lambda: z)
        if self.order == "natural":
            return self._run("natural_points", table, n, realizations, start, (), out)
        return self._run("lattice_points", table, n, realizations, start, (), out,
                         {"GRAY": int(self.order == "gray")})


@cache
def kronecker_alphas(d):
    """Roberts' R_d generators as 64-bit fractions: round(2^64 / φ_d^(j+1)), j < d, where
    φ_d is the positive root of x^(d+1) = x + 1 (the golden ratio for d = 1), computed in
    60-digit decimal arithmetic.

    Parameters
    ----------
    d : int

    Returns
    -------
    ndarray of uint64
        (d,): α_j 2^64, so that x_ij = frac(i α_j) is (i * alphas[j]) mod 2^64 times 2^-64.

    References
    ----------
    .. [1] M. Roberts, "The unreasonable effectiveness of quasirandom sequences" (2018).
    """
    getcontext().prec = 60
    phi = Decimal(2)
    for _ in range(200):                                # Newton on x^(d+1) - x - 1
        phi = phi - (phi ** (d + 1) - phi - 1) / ((d + 1) * phi ** d - 1)
    scale = Decimal(2) ** 64
    return np.array([int((scale / phi ** (j + 1)).to_integral_value()) % 2**64 for j in range(d)],
                    dtype=_U64)


@register("kronecker", "r_sequence")
class KroneckerSampler(_Shifted):
    """Kronecker (additive recurrence) sequence R_d of Roberts (2018): x_i = frac(i α).

    α_j = φ_d^-(j+1) with φ_d the positive root of x^(d+1) = x + 1 (the "generalized golden
    ratio"; d = 1 is the golden-ratio sequence). α_j is held as a 64-bit fraction
    A_j = round(2^64 α_j) (exact to 2^-65), and x_ij = ((i A_j) mod 2^64) 2^-64 rounded down
    to 53 bits: integer arithmetic, the same bits everywhere, and no drift for large i.
    Unlike Roberts' listing the first point is the origin (as clsamp's other sequences);
    ``randomize="shift"`` adds a uniform Cranley-Patterson shift (Roberts' 0.5 offset is
    one fixed shift).

    Parameters
    ----------
    d : int
        Dimension, 1 to 256.
    seed : int
    randomize : {None, "shift"}
    backend : {"opencl", "numpy"}

    Notes
    -----
    An open sequence: any n, and ``start=`` continues it. Its discrepancy is
    O((log N)^d / N) only for badly approximable α (d = 1 exactly; numerically good for
    small d); no MSE rate is published for the integrands here (``convergence_rate`` None).

    References
    ----------
    .. [1] M. Roberts, "The unreasonable effectiveness of quasirandom sequences" (2018),
       extremelearning.com.au.
    .. [2] H. Niederreiter, *Random Number Generation and Quasi-Monte Carlo Methods*,
       SIAM (1992), ch. 5 (Kronecker sequences).

    Examples
    --------
    >>> import clsamp
    >>> x = clsamp.make_sampler("kronecker", d=1).sample(3)[:, 0]
    >>> [round(float(v), 6) for v in x]
    [0.0, 0.618034, 0.236068]
    """

    max_d = 256

    def _reference(self, n, realizations, start):
        index = _U64(start) + np.arange(n, dtype=_U64)
        with np.errstate(over="ignore"):
            fixed = index[:, None] * kronecker_alphas(self.d)[None, :]
        x = (fixed >> _U64(11)).astype(np.float64) * 2.0**-53
        return self._shift(x, realizations)

    def _device(self, n, realizations, start, out=None):
        alphas = kronecker_alphas(self.d)
        table = runtime.table(("kronecker", self.d), lambda: alphas.view(_U32))
        return self._run("kronecker_points", table, n, realizations, start, (), out)
