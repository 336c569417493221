"""Progressive multi-jittered (0, 2) sequences: ``pmj02`` and ``pmj02bn``.

Generated with the stochastic construction of Helmer, Christensen and Kensler (2021), as in
Blender Cycles: point 0 is uniform, and for N = 2^m the points N + i (i < N) are placed in
the half of an occupied stratum that is still empty, found with one xor of the index.
Coordinates are 53-bit integers until the end, so the kernels in ``kernels/pmj.cl`` and
the NumPy references here give the same bits on every device.
"""

from functools import cache
from math import comb

import numpy as np

from .. import philox, runtime
from .base import Rate, Sampler, register

_U32, _U64 = np.uint32, np.uint64
BITS = 53                      # a coordinate is X 2^-53, X a 53-bit integer
LEVELS = 32                    # masks for N = 2^0 .. 2^31: sequences of up to 2^32 points


def _gf2_inverse(a):
    """The inverse over GF(2) of an invertible 0/1 matrix."""
    m = len(a)
    work = np.concatenate([a % 2, np.eye(m, dtype=np.uint8)], axis=1)
    for c in range(m):
        pivot = c + int(np.flatnonzero(work[c:, c])[0])
        work[[c, pivot]] = work[[pivot, c]]
        for r in np.flatnonzero(work[:, c]):
            if r != c:
                work[r] ^= work[c]
    return work[:, m:]


@cache
def generator_matrices(size=LEVELS + 1):
    """(C_x, C_y): the upper-triangular GF(2) generator matrices of the (0, 2)-sequence whose
    stochastic generation is pmj02 (row = output digit, most significant first; column =
    index bit, least significant first).

    C_x^-1 has entry binom(c - r + k, k) mod 2 at row r >= 1, column c >= r, with
    k = (r - 1) // 2 (and the unit vector in row 0); C_y = P C_x with P the Pascal matrix
    binom(c, r) mod 2, Sobol's second dimension. These are the matrices implied by the xor
    table of Helmer et al. (2021) that Cycles ships: :func:`xor_masks` reproduces its 64
    values.

    Parameters
    ----------
    size : int
        Rows and columns.

    Returns
    -------
    (ndarray, ndarray)
        C_x and C_y, uint8 (size, size) of 0 and 1.
    """
    inverse = np.zeros((size, size), dtype=np.uint8)
    inverse[0, 0] = 1
    for r in range(1, size):
        k = (r - 1) // 2
        for c in range(r, size):
            inverse[r, c] = comb(c - r + k, k) % 2
    pascal = np.array([[comb(c, r) % 2 for c in range(size)] for r in range(size)], dtype=np.uint8)
    cx = _gf2_inverse(inverse)
    cy = (pascal.astype(np.int64) @ cx) % 2
    return cx, cy.astype(np.uint8)


@cache
def xor_masks():
    """(2, 32) uint32: mask[a][m] is the xor that maps point i of the first N = 2^m to the
    point N + i shares a stratum with along axis a (x: a = 0, y: a = 1).

    For a digital sequence with upper-triangular generator C (unit diagonal), points N + i
    and i ^ a share their first m digits and differ in digit m exactly when
    C[:m, :m] a = C[:m, m] over GF(2): the new point goes in the other half of that stratum.

    Returns
    -------
    ndarray of uint32
        (2, 32); cached, do not modify.
    """
    out = np.zeros((2, LEVELS), dtype=_U32)
    for axis, c in enumerate(generator_matrices()):
        for m in range(1, LEVELS):
            bits = (_gf2_inverse(c[:m, :m]).astype(np.int64) @ c[:m, m]) % 2
            out[axis, m] = sum(int(b) << k for k, b in enumerate(bits))
    return out


def _random53(words):
    """53-bit integers from word pairs (0, 1) and (2, 3): ``philox.words_to_unit`` times 2^53."""
    w = words.astype(_U64)
    x = ((w[..., 0] >> _U64(5)) << _U64(26)) | (w[..., 1] >> _U64(6))
    y = ((w[..., 2] >> _U64(5)) << _U64(26)) | (w[..., 3] >> _U64(6))
    return np.stack([x, y], axis=-1)


def pmj02_integers(seed, realizations, total):
    """The NumPy reference of ``pmj02``: uint64 array (len(realizations), total, 2) of X with
    coordinate X 2^-53.

    Point p's 53 random bits (per axis) are Philox words 0..3 of (seed, POINTS, k, p). Point 0
    is those bits; for N = 2^m and i < min(N, total - N), axis a of point N + i keeps the
    first m + 1 bits of point i ^ mask[a][m] with the last of them flipped, and its own
    random bits below.

    Parameters
    ----------
    seed : int
    realizations : range
    total : int
        Points a realization (the first ``total`` of the sequence).

    Returns
    -------
    ndarray of uint64
        (len(realizations), total, 2).
    """
    ks = np.arange(realizations.start, realizations.stop, dtype=_U32)
    words = philox.random_words(seed, philox.Stream.POINTS, ks[:, None, None],
                                np.arange(total, dtype=_U32)[None, :, None],
                                np.arange(4, dtype=_U32)[None, None, :])
    x = _random53(words)
    masks = xor_masks()
    m, size = 0, 1
    while size < total:
        count = min(size, total - size)
        i = np.arange(count, dtype=_U32)
        low = _U64(BITS - m - 1)
        keep = _U64((1 << (BITS - m - 1)) - 1)
        for axis in range(2):
            source = x[:, i ^ masks[axis, m], axis]
            x[:, size:size + count, axis] = ((((source >> low) ^ _U64(1)) << low)
                                             | (x[:, size:size + count, axis] & keep))
        m, size = m + 1, size * 2
    return x


@register("pmj02", "progressive_multi_jittered")
class PMJ02Sampler(Sampler):
    """Progressive multi-jittered (0, 2) sequence (Christensen, Kensler, Kilpatrick 2018).

    Every prefix of 2^k points is a (0, k, 2)-net in base 2 (each elementary interval of
    area 2^-k, of every shape, holds one point) and is stratified in each coordinate, for
    every k; any other prefix is as evenly spread as the nets around it allow. Generated in
    O(N) with the stochastic method of Helmer, Christensen and Kensler (2021), Blender
    Cycles' generator: point 0 is uniform; each point N + i (N = 2^m, i < N) takes the
    x-stratum of width 1/(2N) beside the one of point i ^ a_m (the two share a stratum of
    width 1/N), likewise in y with b_m, and a uniform position inside. The masks a_m, b_m
    follow from the generator matrices of the underlying (0, 2)-sequence
    (:func:`generator_matrices`); the sequence is equivalent to an Owen-scrambled
    (0, 2)-sequence (Helmer et al. 2021), and realization k is an independent one.

    Parameters
    ----------
    d : int
        Must be 2 (renderers use one independently seeded sequence per pair of dimensions).
    seed : int
    backend : {"opencl", "numpy"}

    Notes
    -----
    Any n; ``sample(n, start=k)`` continues ``sample(k)`` (the points before ``start`` are
    generated too: the cost is that of ``start + n`` points). As for Owen-scrambled nets,
    the MSE of a smooth integrand decays as N^-3 (log N) and that of a disk as N^-1.5
    at N = 2^k (Owen 1997; He and Wang 2015).

    References
    ----------
    .. [1] P. Christensen, A. Kensler, C. Kilpatrick, "Progressive multi-jittered sample
       sequences", Computer Graphics Forum 37(4) (EGSR 2018).
    .. [2] A. Helmer, P. Christensen, A. Kensler, "Stochastic generation of (t, s) sample
       sequences", EGSR 2021 (Symposium Track).

    Examples
    --------
    >>> import clsamp
    >>> x = clsamp.make_sampler("pmj02", seed=1).sample(16)
    >>> sorted((x[:, 0] * 16).astype(int).tolist()) == list(range(16))
    True
    """

    dimensions = (2,)
    sequence = True
    host_output = True
    rates = {"best": Rate(-3.0, "Owen 1997"), "worst": Rate(-1.5, "He and Wang 2015")}
    integers = staticmethod(pmj02_integers)     # the NumPy reference, as 53-bit integers

    def _reference(self, n, realizations, start):
        x = self.integers(self.seed, realizations, start + n)[:, start:]
        return x.astype(np.float64) * 2.0**-BITS

    @staticmethod
    def _window(target, start):
        """The points from ``start`` on of the prefix the kernels made."""
        points = target.finish()
        if start == 0:
            return points
        # a copy, not np.ascontiguousarray: a window of one realization counts as
        # contiguous but keeps the prefix's stride on its length-1 axis, which
        # pyopencl's concatenate of device chunks refuses
        return runtime.to_host(points)[:, start:].copy()

    def _device(self, n, realizations, start, out=None):
        r = len(realizations)
        total = start + n
        target = runtime.Output((r, total, 2), host=out if start == 0 else None)
        masks = runtime.table(("pmj02 masks",), xor_masks)
        local = runtime.local_size()
        key = philox.seed_key(self.seed)
        first = runtime.kernel("pmj.cl", "pmj02_first")
        first(runtime.queue(), (r,), None, target.buffer, np.uint32(total),
              np.uint32(realizations.start), *key)
        level = runtime.kernel("pmj.cl", "pmj02_level")
        m, size = 0, 1
        while size < total:
            count = min(size, total - size)
            items = -(-count // 4)             # four points a work-item
            level(runtime.queue(), (-(-items // local) * local, r), (local, 1), target.buffer,
                  masks.data, np.uint32(total), np.uint32(m), np.uint32(count),
                  np.uint32(realizations.start), *key)
            m, size = m + 1, size * 2
        return self._window(target, start)


# -- pmj02bn: Christensen et al.'s construction with best-candidate sampling --------------------
CANDIDATES = 10                 # best-candidate samples per point (Christensen et al. 2018)


def _leaves(occupied, start, depth, along_x, L):
    """The valid fine strata under the elementary cell ``start`` = (x, y, shape): the leaves
    u < 2^depth (x- or y-strata of width 2^-L) none of whose cells on the way is occupied,
    ascending (Pharr 2019's recursion, flattened)."""
    x0, y0, s0 = start
    out, u = [], 0
    while u < 1 << depth:
        for t in range(depth + 1):
            head = u >> (depth - t)
            if along_x:
                x, y, s = (x0 << t) + head, y0 >> t, s0 - t
            else:
                x, y, s = x0 >> t, (y0 << t) + head, s0 + t
            if occupied[s][y * (1 << (L - s)) + x]:
                u = (head + 1) << (depth - t)
                break
        else:
            out.append(u + ((x0 if along_x else y0) << depth))
            u += 1
    return out


def _toroidal_d2(a, b):
    dx = abs(a[0] - b[0])
    dy = abs(a[1] - b[1])
    dx = min(dx, 1.0 - dx)
    dy = min(dy, 1.0 - dy)
    return dx * dx + dy * dy


class _BlueNoiseState:
    """One realization of :func:`pmj02bn_integers`: the points, the occupied elementary
    intervals of every shape at the current resolution 2^L, and a grid for the nearest
    neighbour (at most one point per cell)."""

    def __init__(self, seed, realization, total):
        self.seed, self.k, self.total = seed, realization, total
        self.x = np.zeros((total, 2), dtype=_U64)

    def subdivide(self, L, count):
        self.L, self.dim = L, 1 << ((L + 1) // 2)
        self.occupied = [bytearray(1 << L) for _ in range(L + 1)]
        self.grid = [-1] * (self.dim * self.dim)
        for p in range(count):
            self.mark(p)

    def cell(self, p):
        shift = BITS - (self.dim.bit_length() - 1)
        return int(self.x[p, 0]) >> shift, int(self.x[p, 1]) >> shift

    def mark(self, p):
        X, Y = int(self.x[p, 0]), int(self.x[p, 1])
        L = self.L
        for s in range(L + 1):
            self.occupied[s][(Y >> (BITS - s)) * (1 << (L - s)) + (X >> (BITS - L + s))] = 1
        cx, cy = self.cell(p)
        self.grid[cy * self.dim + cx] = p

    def nearest_d2(self, point):
        dim = self.dim
        cx, cy = int(point[0] * dim), int(point[1] * dim)
        best = 8.0
        for ring in range(dim):
            for gy in range(cy - ring, cy + ring + 1):
                for gx in range(cx - ring, cx + ring + 1):
                    if max(abs(gx - cx), abs(gy - cy)) != ring:
                        continue
                    q = self.grid[(gy % dim) * dim + gx % dim]
                    if q >= 0:
                        other = (float(self.x[q, 0]) * 2.0**-BITS, float(self.x[q, 1]) * 2.0**-BITS)
                        best = min(best, _toroidal_d2(point, other))
            bound = float(ring) * float(ring) / float(dim * dim)
            if best <= bound or 2 * ring + 1 >= dim:
                break
        return best

    def valid_strata(self, cx, cy):
        """The valid x- and y-strata (width 2^-L) of a point in grid cell (cx, cy)."""
        L, j = self.L, self.L // 2
        if L % 2 == 0:
            sx, sy = (cx, cy, j), (cx, cy, j)
        else:
            sx, sy = (cx, cy >> 1, j), (cx >> 1, cy, j + 1)
        return (_leaves(self.occupied, sx, sx[2], True, L),
                _leaves(self.occupied, sy, L - sy[2], False, L))

    def place(self, p, cells):
        """Point p at the best of CANDIDATES candidates, candidate c in grid cell
        cells[c % len(cells)]; returns the index in ``cells`` of the cell taken."""
        strata = [self.valid_strata(cx, cy) for cx, cy in cells]
        if not all(vx and vy for vx, vy in strata):
            raise RuntimeError(f"pmj02bn: no valid stratum for point {p}")
        words = philox.random_words(self.seed, philox.Stream.CANDIDATES, self.k, p,
                                    np.arange(8 * CANDIDATES, dtype=_U32)).astype(_U64)
        L = self.L
        keep = _U64((1 << (BITS - L)) - 1)
        best, best_d2, taken = None, -1.0, 0
        for c in range(CANDIDATES):
            valid_x, valid_y = strata[c % len(cells)]
            w = words[8 * c:8 * c + 8]
            ix = int((w[0] * _U64(len(valid_x))) >> _U64(32))
            iy = int((w[1] * _U64(len(valid_y))) >> _U64(32))
            low = _random53(w[2:6])
            X = (_U64(valid_x[ix]) << _U64(BITS - L)) | (low[0] & keep)
            Y = (_U64(valid_y[iy]) << _U64(BITS - L)) | (low[1] & keep)
            d2 = self.nearest_d2((float(X) * 2.0**-BITS, float(Y) * 2.0**-BITS))
            if d2 > best_d2:
                best, best_d2, taken = (X, Y), d2, c % len(cells)
        self.x[p] = best
        self.mark(p)
        return taken


def pmj02bn_integers(seed, realizations, total):
    """The NumPy reference of ``pmj02bn``: a sequential loop, for tests at small sizes.

    Parameters
    ----------
    seed : int
    realizations : iterable of int
    total : int
        Points a realization.

    Returns
    -------
    ndarray of uint64
        (len(realizations), total, 2), as :func:`pmj02_integers`.
    """
    out = np.zeros((len(realizations), total, 2), dtype=_U64)
    for row, k in enumerate(realizations):
        state = _BlueNoiseState(seed, k, total)
        words = philox.random_words(seed, philox.Stream.POINTS, k, 0, np.arange(4, dtype=_U32))
        state.x[0] = _random53(words)
        n, j = 1, 0
        while n < total:
            state.subdivide(2 * j + 1, n)
            for i in range(min(n, total - n)):
                cx, cy = state.cell(i)
                state.place(n + i, [(cx ^ 1, cy ^ 1)])
            if 2 * n >= total:
                break
            state.subdivide(2 * j + 2, 2 * n)
            quads = []
            for i in range(min(n, total - 2 * n)):
                cx, cy = state.cell(i)
                options = [(cx ^ 1, cy), (cx, cy ^ 1)]
                quads.append(options[state.place(2 * n + i, options)])
            for i in range(min(n, total - 3 * n)):
                state.place(3 * n + i, [(quads[i][0] ^ 1, quads[i][1] ^ 1)])
            n, j = 4 * n, j + 1
        out[row] = state.x
    return out


@register("pmj02bn", "pmj02_blue_noise")
class PMJ02BNSampler(PMJ02Sampler):
    """Progressive multi-jittered (0, 2) sequence with blue-noise candidates (pmj02bn).

    Christensen, Kensler and Kilpatrick's (2018) construction: for N = 4^j points so far,
    point N + i goes in the sub-quadrant of point i's cell diagonally opposite it, then
    2N + i in one of the two others and 3N + i opposite that one. Inside the sub-quadrant
    the point must avoid every occupied elementary interval of every shape; the valid x-
    and y-strata are found with Pharr's (2019) recursion, and of 10 candidates (uniform in
    valid strata, and for 2N + i alternating between its two sub-quadrants) the one
    farthest (toroidally) from the points so far is kept. Every prefix of 2^k points is a
    (0, k, 2)-net, as for ``pmj02``.

    The (0, 2) conditions leave one valid stratum per axis in each sub-quadrant, so the
    blue-noise choice is only the sub-quadrant of points 2N + i and the jitter inside the
    stratum: the nearest-neighbour distances grow a little over ``pmj02``'s (most at small
    N), far less than for blue noise without the net conditions.

    Parameters
    ----------
    d : int
        Must be 2.
    seed : int
    backend : {"opencl", "numpy"}

    Notes
    -----
    Sequential within a sequence (one work-item per realization); ``start=`` generates the
    points before it. The NumPy reference is a Python loop, for tests at small n.

    References
    ----------
    .. [1] P. Christensen, A. Kensler, C. Kilpatrick, "Progressive multi-jittered sample
       sequences", Computer Graphics Forum 37(4) (EGSR 2018).
    .. [2] M. Pharr, "Efficient generation of points that satisfy two-dimensional
       elementary intervals", JCGT 8(1) (2019).

    Examples
    --------
    >>> import clsamp
    >>> x = clsamp.make_sampler("pmj02bn", seed=2).sample(64)
    >>> sorted((x[:, 1] * 64).astype(int).tolist()) == list(range(64))
    True
    """

    integers = staticmethod(pmj02bn_integers)

    def _device(self, n, realizations, start, out=None):
        import pyopencl.array as cla
        runtime.require_short_loops("pmj02bn (one sequential work-item per set)")
        r = len(realizations)
        total = start + n
        levels = max(total - 1, 1).bit_length()           # the finest resolution 2^levels
        occupied_words = (((levels + 1) << levels) + 31) // 32
        grid_cells = 1 << (2 * ((levels + 1) // 2))
        target = runtime.Output((r, total, 2), host=out if start == 0 else None)
        occupied = cla.empty(runtime.queue(), (r * occupied_words,), np.uint32)
        grid = cla.empty(runtime.queue(), (r * grid_cells,), np.int32)
        status = cla.empty(runtime.queue(), (r,), np.uint32)
        kernel = runtime.kernel("pmj.cl", "pmj02bn_points")
        kernel(runtime.queue(), (r,), None, target.buffer, occupied.data, grid.data, status.data,
               np.uint32(total), np.uint64(occupied_words), np.uint64(grid_cells),
               np.uint32(realizations.start), *philox.seed_key(self.seed))
        failed = status.get()
        if failed.any():
            k = int(np.flatnonzero(failed)[0])
            raise RuntimeError(f"pmj02bn found no valid stratum for point {int(failed[k]) - 1} "
                               f"of realization {realizations.start + k}")
        return self._window(target, start)
