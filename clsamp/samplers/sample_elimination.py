"""The ``sample_elimination`` sampler: weighted sample elimination (Yuksel 2015), from M
uniform candidates down to n, in any dimension up to 8, on the unit torus or in the unit
cube, optionally in progressive order.

The neighbour search and the weights are the O(M k) part: ``se_count`` and ``se_pairs``
in ``kernels/sample_elimination.cl`` on the device, :func:`neighbour_weights_reference`
here in NumPy, the same bits, over the grid of cells of :mod:`clsamp.geometry.cells`. The
elimination -- take the heaviest candidate, lower its neighbours' weights, again -- walks
one candidate at a time: ``se_eliminate`` on a device that shares the host's cores, one
work-item a set, where the pair lists already are (:func:`eliminate_device`, a tournament
tree), and :func:`eliminate` in Python's heapq (the twin's, and on discrete GPUs), the
same removals in the same order.
"""

import dataclasses
import heapq
import math

import numpy as np

from .. import runtime
from ..geometry.cells import cells_for, neighbour_cells, sorted_by_cell
from ..geometry.torus import PACKING_DENSITY, ball_volume, max_min_distance
from ..validation import check_bool, check_positive_int, check_real
from .base import SampleInfo, Sampler, info_field, make_sampler, register

RATIO = 5.0     # candidates per output point
ALPHA = 8       # the weight's exponent
BETA = 0.65     # weight limiting: d_min = d_max (1 - (n / M)^GAMMA) BETA
GAMMA = 1.5


@dataclasses.dataclass(frozen=True)
class Weighting:
    """The weight function of one elimination, w(d) = (1 - max(d, d_min) / d_max)^alpha
    for d < d_max, 0 beyond.

    Attributes
    ----------
    d_max : float
        The neighbourhood's radius: 2 r_max, r_max the largest Poisson-disk radius of the
        output's count (:func:`clsamp.geometry.torus.max_min_distance` gives 2 r_max).
    d_min : float
        Where weight limiting clamps distances from below (2 r_min).
    alpha : int
    periodic : bool
    """

    d_max: float
    d_min: float
    alpha: int
    periodic: bool

    @classmethod
    def for_counts(cls, candidates, n, d, alpha=ALPHA, beta=BETA, gamma=GAMMA, periodic=True):
        """The paper's weighting for eliminating ``candidates`` points down to ``n``:
        d_max = 2 r_max(n), d_min = d_max (1 - (n / M)^gamma) beta.

        Parameters
        ----------
        candidates, n, d : int
        alpha : int
        beta, gamma : float
        periodic : bool

        Returns
        -------
        Weighting
        """
        d_max = max_min_distance(n, d)
        d_min = d_max * (1.0 - (n / candidates) ** gamma) * beta
        return cls(d_max=d_max, d_min=d_min, alpha=alpha, periodic=periodic)

    def cells(self, points_per_set, d):
        """Cells per axis of the neighbour grid: at least d_max wide, at most about one
        point a cell (narrower cells only add empty ones to the stencil).

        Parameters
        ----------
        points_per_set : int
        d : int

        Returns
        -------
        int
            At least 3, or 1 (one cell holding every pair).
        """
        return cells_for(self.d_max, points_per_set, d)


def _power(t, alpha):
    """t^alpha by squaring, low bits first (``se_power``)."""
    p = np.ones_like(t)
    e = alpha
    while e:
        if e & 1:
            p = p * t
        t = t * t
        e >>= 1
    return p


def neighbour_weights_reference(pts, start, m, cells, weighting):
    """NumPy twin of ``se_count`` and ``se_pairs``: each sorted candidate's neighbours
    within d_max, their weights, and the sum of those, in the kernel's order.

    Parameters
    ----------
    pts : ndarray (total, d)
        Candidates sorted by (set, cell) (:func:`clsamp.geometry.cells.sorted_by_cell`).
    start : ndarray of uint32 (sets cells^d + 1,)
    m : int
        Candidates per set.
    cells : int
        Cells per axis.
    weighting : Weighting

    Returns
    -------
    offset : ndarray of int64 (total + 1,)
        Candidate i's neighbours are ``nbr[offset[i]:offset[i + 1]]``.
    nbr : ndarray of uint32
        Their sorted indices, in stencil order, then sorted order.
    w : ndarray of float64
        The pair weights, in that order (symmetric to the bit: w_ij = w_ji).
    weight : ndarray of float64 (total,)
        The sum of each candidate's pair weights, added in that order.
    """
    total, d = pts.shape
    own = np.arange(total, dtype=np.int64)
    cell = np.zeros(total, dtype=np.int64)
    for k in range(d):       # the cell again from the coordinates, as the kernel finds it
        cell = cell * cells + np.minimum((pts[:, k] * cells).astype(np.int64), cells - 1)
    slot_base = (own // m) * cells ** d
    start = start.astype(np.int64)
    stencil = 3 ** d if cells > 1 else 1
    R2 = weighting.d_max * weighting.d_max
    weight = np.zeros(total)
    found_i, found_j, found_w, found_key = [], [], [], []
    step = 0
    for o in range(stencil):
        slot = slot_base + neighbour_cells(cell, o, cells, d)
        first, stop = start[slot], start[slot + 1]
        for k in range(int((stop - first).max(initial=0))):
            j = first + k
            live = np.flatnonzero((j < stop) & (j != own))
            step += 1
            if live.size == 0:
                continue
            i, jj = live, j[live]
            r2 = None
            for a in range(d):
                v = pts[i, a] - pts[jj, a]
                if weighting.periodic:
                    v = np.where(v > 0.5, v - 1.0, v)
                    v = np.where(v < -0.5, v + 1.0, v)
                r2 = v * v if r2 is None else r2 + v * v
            near = r2 < R2
            i, jj, r2 = i[near], jj[near], r2[near]
            dist = np.sqrt(r2)
            e = _power(1.0 - np.where(dist > weighting.d_min, dist, weighting.d_min)
                       / weighting.d_max, weighting.alpha)
            weight[i] = weight[i] + e
            found_i.append(i)
            found_j.append(jj)
            found_w.append(e)
            found_key.append(np.full(i.size, step, dtype=np.int64))
    i = np.concatenate(found_i) if found_i else np.empty(0, dtype=np.int64)
    key = np.concatenate(found_key) if found_key else np.empty(0, dtype=np.int64)
    order = np.lexsort((key, i))
    nbr = (np.concatenate(found_j) if found_j else np.empty(0, np.int64))[order].astype(np.uint32)
    w = (np.concatenate(found_w) if found_w else np.empty(0))[order]
    offset = np.concatenate(([0], np.cumsum(np.bincount(i, minlength=total)))).astype(np.int64)
    return offset, nbr, w, weight


def _loop_bound(d, cells, start):
    """The most loop iterations one work-item of ``se_pairs`` can run."""
    most = int(np.diff(start.astype(np.int64)).max(initial=0))
    stencil = 3 ** d if cells > 1 else 1
    return stencil * (2 * d + 8) * (most + 1)


def slab_width(m, d, weighting):
    """Slots a candidate for the one-pass neighbour lists of :func:`eliminate_device`: the
    expected neighbours of a uniform candidate, lambda = (m - 1) V_d d_max^d, plus
    6 sqrt(lambda) + 8, at most m - 1 (a set whose list overflows takes the two-pass path).

    Parameters
    ----------
    m, d : int
        Candidates per set, dimensions.
    weighting : Weighting

    Returns
    -------
    int
    """
    lam = (m - 1) * min(1.0, ball_volume(d, weighting.d_max))
    return max(1, min(m - 1, math.ceil(lam + 6.0 * math.sqrt(lam) + 8.0)))


def _pairs_on_device(pts, start, m, cells, weighting, host, cap=0, wait=True):
    """Launch the neighbour passes: ``se_pairs`` into ``cap`` slots a candidate where
    ``cap`` > 0 and no list overflows, else ``se_count``, the offsets on the host and
    ``se_pairs`` into them. Returns each list's first slot (uint64, total) and length
    (uint32), the outputs ``nbr``, ``w``, ``weight`` (:class:`clsamp.runtime.Output`: over
    host arrays where ``host``, else on the device, ``weight`` read-write for
    ``se_eliminate``) and the kernels' defines. With ``cap`` > 0 and not ``wait``, the one
    pass only, not waited for: its lengths are then the :class:`~clsamp.runtime.Output`
    ``count`` (read-write where not ``host``, for ``se_eliminate``) and its first slots
    None."""
    runtime.require_fp64()
    total, d = pts.shape
    limit = runtime.loop_limit()
    if limit is not None and _loop_bound(d, cells, start) > limit:
        runtime.require_short_loops("sample elimination's neighbour search")
    defines = {"D": d, "PERIODIC": int(weighting.periodic), "ALPHA": int(weighting.alpha),
               "LANES": runtime.shape().pair_lanes}
    queue = runtime.queue()
    local = runtime.local_size(64)
    grid = (-(-total // local) * local,)
    geometry = (runtime.input_buffer(pts), runtime.input_buffer(start), np.uint32(m),
                np.uint32(total), np.int32(cells), np.uint32(3 ** d if cells > 1 else 1),
                np.float64(weighting.d_max * weighting.d_max))
    weight = runtime.Output((total,), np.float64, host=np.empty(total), read_write=not host)
    count = runtime.Output((total,), np.uint32, host=np.empty(total, dtype=np.uint32),
                           read_write=not host)

    def pairs(offset, cap, slots):
        nbr = runtime.Output((slots,), np.uint32,
                             host=np.empty(slots, dtype=np.uint32) if host else None)
        w = runtime.Output((slots,), np.float64, host=np.empty(slots) if host else None)
        runtime.kernel("sample_elimination.cl", "se_pairs", defines)(
            queue, grid, (local,), *geometry, np.float64(weighting.d_min),
            np.float64(weighting.d_max), runtime.input_buffer(offset), np.uint32(cap),
            nbr.buffer, w.buffer, weight.buffer, count.buffer)
        return nbr, w

    if cap > 0:
        nbr, w = pairs(np.zeros(1, dtype=np.uint64), cap, total * cap)
        if not wait:
            return None, count, nbr, w, weight, defines
        found = count.finish()
        if int(found.max(initial=0)) <= cap:
            return np.arange(total, dtype=np.uint64) * np.uint64(cap), found, nbr, w, weight, defines
    else:
        runtime.kernel("sample_elimination.cl", "se_count", defines)(
            queue, grid, (local,), *geometry, count.buffer)
        found = count.finish()
    offset = np.zeros(total + 1, dtype=np.uint64)
    np.cumsum(found, dtype=np.uint64, out=offset[1:])
    nbr, w = pairs(offset, 0, max(int(offset[-1]), 1))
    return offset[:-1], found.copy(), nbr, w, weight, defines


def neighbour_weights_device(pts, start, m, cells, weighting):
    """``se_count`` and ``se_pairs`` on the current device: the result of
    :func:`neighbour_weights_reference`, the same bits.

    Parameters
    ----------
    pts, start, m, cells, weighting
        As :func:`neighbour_weights_reference` takes them.

    Returns
    -------
    offset, nbr, w, weight
        As :func:`neighbour_weights_reference` returns them.

    Raises
    ------
    NoDeviceError
        A device without fp64, or one that stops long loops where a work-item's loops
        would pass its limit.
    """
    first, found, nbr, w, weight, _ = _pairs_on_device(pts, start, m, cells, weighting, host=True)
    offset = np.concatenate((first.astype(np.int64), [int(first[-1]) + int(found[-1])]))
    size = int(offset[-1])
    return offset, nbr.finish()[:size], w.finish()[:size], weight.finish()


def _tree_slots(m):
    """The slots of ``se_eliminate``'s 8-ary tournament tree for m candidates (its key and
    winner arrays, a set each): the leaves, m rounded up to a multiple of 8, then each level
    above, an eighth of the one below rounded up to a multiple of 8, up to the one root."""
    size, slots = -(-int(m) // 8) * 8, 0
    while size > 1:
        slots += size
        size = -(-size // 8)
        size = -(-size // 8) * 8 if size > 1 else 1
    return slots + 1


def eliminate_device(pts, start, m, cells, weighting, keep):
    """The neighbours, their weights and the elimination of every set on the current
    device (``se_pairs`` into :func:`slab_width` slots a candidate, then ``se_eliminate``,
    one work-item a set): what :func:`neighbour_weights_reference` and :func:`eliminate`
    give, the same bits, without the pair lists leaving the device.

    Parameters
    ----------
    pts, start, m, cells, weighting
        As :func:`neighbour_weights_reference` takes them: the sets of m candidates, sorted
        by (set, cell).
    keep : int
        Candidates left in each set, 1..m.

    Returns
    -------
    gone : ndarray of uint32 (sets, m - keep)
        Each set's removed candidates (sorted indices within the set) in the order they
        went.
    weight : ndarray of float64 (sets, m)
        The weights at the end (those of the removed candidates included).

    Raises
    ------
    NoDeviceError
        As :func:`neighbour_weights_device`.
    """
    total, d = pts.shape
    sets = total // m
    removals = m - keep
    cap = slab_width(m, d, weighting)
    limit = runtime.loop_limit()
    if limit is None:
        # the elimination right after the one pass, with no wait between: it reads the
        # lists' lengths from the pass's counts and leaves every set alone where a list
        # overflowed its slots, which the passes with offsets below then redo
        _, count, nbr, w, weight, defines = _pairs_on_device(
            pts, start, m, cells, weighting, host=False, cap=cap, wait=False)
        done = _eliminate_lists(None, count.buffer, cap, nbr, w, weight, m, sets, removals,
                                defines)
        if done is not None:
            return done
        cap = 0
    first, found, nbr, w, weight, defines = _pairs_on_device(
        pts, start, m, cells, weighting, host=False, cap=cap)
    if limit is not None and (removals + int(found.sum())) * (int(m).bit_length() + 1) > limit:
        runtime.require_short_loops("sample elimination's tournament tree")
    return _eliminate_lists(runtime.input_buffer(first), runtime.input_buffer(found), 0, nbr, w,
                            weight, m, sets, removals, defines)


def _eliminate_lists(first, count, cap, nbr, w, weight, m, sets, removals, defines):
    """``se_eliminate`` over the lists: list i from slot ``first[i]`` (a buffer), or with
    ``cap`` > 0 from slot i cap, its length in ``count`` (a buffer). Returns
    :func:`eliminate_device`'s (gone, weight), or None where ``cap`` > 0 and a list
    overflowed its slots (then nothing was eliminated)."""
    gone = runtime.Output((sets * max(removals, 1),), np.uint32,
                          host=np.empty(sets * max(removals, 1), dtype=np.uint32))
    overflow = runtime.Output((sets,), np.uint32, host=np.empty(sets, dtype=np.uint32))
    slots = sets * _tree_slots(m)
    key, idx = runtime.Output((slots,), np.float64), runtime.Output((slots,), np.uint32)
    local = min(runtime.local_size(64), sets)
    runtime.kernel("sample_elimination.cl", "se_eliminate", defines)(
        runtime.queue(), (-(-sets // local) * local,), (local,),
        first if first is not None else runtime.input_buffer(np.zeros(1, dtype=np.uint64)),
        count, np.uint32(cap), nbr.buffer, w.buffer, weight.buffer, np.uint32(m),
        np.uint32(sets), np.uint32(removals), key.buffer, idx.buffer, gone.buffer,
        overflow.buffer)
    if cap > 0 and overflow.finish().any():
        return None
    gone = gone.finish()[:sets * removals].reshape(sets, removals)
    return gone, weight.finish().reshape(sets, m)


def eliminate(weight, offset, nbr, w, keep):
    """Weighted sample elimination of one set, given its neighbours: remove the candidate
    of the largest weight (the lowest index among equal ones), subtract its pair weights
    from its remaining neighbours, and again, until ``keep`` remain.

    Parameters
    ----------
    weight : ndarray (m,)
        The initial weights.
    offset : ndarray of int (m + 1,)
        Candidate i's neighbours are ``nbr[offset[i]:offset[i + 1]]``.
    nbr : ndarray of int
        Neighbour indices, 0..m-1.
    w : ndarray of float64
        The pair weights.
    keep : int

    Returns
    -------
    survivors : ndarray of int64 (keep,)
        Ascending.
    eliminated : ndarray of int64 (m - keep,)
        In the order they were removed.
    last : float
        The largest weight left among the survivors (0: no two within d_max).

    Examples
    --------
    >>> import numpy as np
    >>> from clsamp.samplers.sample_elimination import eliminate
    >>> # three points on a line: the middle one has two neighbours, so it goes first
    >>> s, e, last = eliminate(np.array([0.5, 1.0, 0.5]), np.array([0, 1, 3, 4]),
    ...                        np.array([1, 0, 2, 1]), np.array([0.5, 0.5, 0.5, 0.5]), 2)
    >>> s.tolist(), e.tolist(), last
    ([0, 2], [1], 0.0)
    """
    m = len(weight)
    current = np.array(weight, dtype=np.float64)
    starts = np.asarray(offset).tolist()
    nbr = np.asarray(nbr, dtype=np.intp)
    alive = np.ones(m, dtype=bool)
    heap = [(-v, i) for i, v in enumerate(current.tolist())]
    heapq.heapify(heap)
    gone = []
    pop, push = heapq.heappop, heapq.heappush
    # Weights only fall, so each remaining candidate keeps one entry whose key is at least
    # its weight, refreshed when it surfaces: an entry that surfaces with its exact weight
    # is the heaviest candidate (and the lowest index among equal ones), as an eagerly
    # updated heap would give, with one push per surfacing instead of per update. The
    # removed candidate's terms leave all its neighbours at once (the removed ones' too:
    # they have no entry left).
    while len(gone) < m - keep:
        negative, i = pop(heap)
        weight_i = current[i]
        if -negative != weight_i:
            push(heap, (-float(weight_i), i))
            continue
        alive[i] = False
        gone.append(i)
        a, b = starts[i], starts[i + 1]
        current[nbr[a:b]] -= w[a:b]
    survivors = np.flatnonzero(alive)
    last = current[survivors].max(initial=0.0)
    return survivors, np.array(gone, dtype=np.int64), float(last)


def _eliminate_sets(points, keep, weighting, backend):
    """One elimination of every set of ``points`` (sets, m, d) down to ``keep``: per set,
    the survivors (ascending candidate indices), the eliminated (in order) and the last
    weight."""
    sets, m, d = points.shape
    if backend != "numpy" and sets > 1:
        # the device holds the candidates and their pair lists: a realization's neighbours
        # are about M V_d d_max^d (here with a margin of 4)
        pairs = max(min(m, math.ceil(4 * m * ball_volume(d, weighting.d_max))),
                    slab_width(m, d, weighting))
        ranges = runtime.chunk_ranges(
            sets, m * (8 * d + 64) + 12 * _tree_slots(m) + 12 * m * pairs)
        if len(ranges) > 1:
            return [result for lo, hi in ranges
                    for result in _eliminate_sets(points[lo:hi], keep, weighting, backend)]
    cells = weighting.cells(m, d)
    pts, _, start, order = sorted_by_cell(points, cells)
    original = order.reshape(sets, m) - (np.arange(sets) * m)[:, None]   # sorted -> set index
    if backend != "numpy" and runtime.current_device().host_memory:
        # a device on the host's cores: the heap beside the lists (on a discrete GPU one
        # work-item's heap walk is unmeasured; the lists come to the host's heapq there)
        gone, weight = eliminate_device(pts, start, m, cells, weighting, keep)
        per_set = []
        for s in range(sets):
            alive = np.ones(m, dtype=bool)
            alive[gone[s]] = False
            survivors = np.flatnonzero(alive)
            per_set.append((survivors, gone[s], float(weight[s, survivors].max(initial=0.0))))
    else:
        run = neighbour_weights_reference if backend == "numpy" else neighbour_weights_device
        offset, nbr, w, weight = run(pts, start, m, cells, weighting)
        per_set = []
        for s in range(sets):
            lo, hi = s * m, (s + 1) * m
            a, b = offset[lo], offset[hi]
            per_set.append(eliminate(weight[lo:hi], offset[lo:hi + 1] - a,
                                     nbr[a:b].astype(np.int64) - lo, w[a:b], keep))
    return [(np.sort(original[s, survivors]), original[s, gone], last)
            for s, (survivors, gone, last) in enumerate(per_set)]


@dataclasses.dataclass(frozen=True)
class SampleEliminationInfo(SampleInfo):
    """What a sample elimination did, per realization (first axis).

    Attributes
    ----------
    realizations : ndarray (r,)
        The realization indices.
    candidates : int
        M, the uniform candidates each set started from.
    d_max, d_min : float
        The weighting's radius and its limit (2 r_max and 2 r_min of the paper) for the
        elimination to n.
    stages : int
        Eliminations run: 1, plus the halvings of progressive ordering.
    max_weight : ndarray (r,)
        The largest weight left among the n survivors of the first elimination: 0 where
        no two are closer than d_max, up to the rounding of the subtractions that took
        the eliminated candidates' terms out (about 1e-19 at n = 1).
    """

    candidates: int = info_field("same")
    d_max: float = info_field("same")
    d_min: float = info_field("same")
    stages: int = info_field("same")
    max_weight: np.ndarray = info_field()


@register("sample_elimination")
class SampleEliminationSampler(Sampler):
    """Weighted sample elimination: a Poisson-disk-like subset of n points chosen from
    M = ratio n uniform candidates by removing the most crowded one at a time.

    Parameters
    ----------
    d : int
        Dimension, 1 to 8 (where the densest sphere packing, and so r_max, is known).
    seed : int
        Seeds the candidates (the ``random`` sampler's realization k with this seed).
    ratio : float
        Candidates per output point, > 1 (default 5): M = round(ratio n), at least n + 1.
    periodic : bool
        True (default): distances on the unit torus. False: the unit cube, distances not
        wrapped (as the paper's algorithm without tiling).
    progressive : bool
        Order the points so that every prefix of size n // 2^k is itself an eliminated
        set (default False: the survivors in the candidates' order).
    alpha : int
        The weight's exponent (default 8).
    beta, gamma : float
        Weight limiting (defaults 0.65 and 1.5; beta = 0 turns it off).
    backend : {"opencl", "numpy"}

    Notes
    -----
    Each candidate i has the weight w_i = sum_j (1 - d_ij / d_max)^alpha over the other
    candidates j within d_max = 2 r_max, r_max the largest Poisson-disk radius n points
    can have (half the maximal minimum distance of
    :func:`clsamp.geometry.torus.max_min_distance`, from the densest known packing in d
    dimensions). Weight limiting clamps d_ij below at d_min = 2 r_min,
    r_min = r_max (1 - (n / M)^gamma) beta. The candidate of the largest weight is
    removed, its neighbours' weights lose its terms, and a max-heap gives the next,
    until n remain (Yuksel 2015).

    Progressive ordering (the paper's progressive sampling, as the author's cySampleElim
    does it): the n survivors are eliminated again to n // 2 with d_max for n // 2 points (d_min
    kept), those to n // 4, and so on while 3 or more remain; the output lists the last
    survivors, then each stage's eliminated points from the last stage to the first,
    each in reverse order of removal, so the first n // 2^k points are the survivors of
    stage k.

    The neighbours and weights run on the device (``kernels/sample_elimination.cl``,
    over :mod:`clsamp.geometry.cells`' grid); its NumPy twin gives the same bits. The
    elimination is sequential -- each removal changes the next choice -- and runs as a
    heap, on a CPU device one work-item a realization beside the pair lists, on a GPU
    on the host; ties go to the lower index, so every device and the NumPy twin give
    the same points.

    References
    ----------
    .. [1] C. Yuksel, "Sample Elimination for Generating Poisson Disk Sample Sets",
       Computer Graphics Forum 34(2), 2015 (Eurographics).

    Examples
    --------
    >>> import clsamp
    >>> s = clsamp.make_sampler("sample_elimination", d=2, seed=1)
    >>> pts, info = s.sample(256, return_info=True)
    >>> pts.shape, info.candidates
    ((256, 2), 1280)
    >>> bool(clsamp.metrics.relative_radius(pts) > 0.6)
    True
    """

    dimensions = tuple(sorted(PACKING_DENSITY))
    max_d = max(PACKING_DENSITY)
    max_d_source = "r_max needs the densest known sphere packing (geometry.torus.PACKING_DENSITY)"
    expensive = True
    accepts_start = False
    needs_fp64 = True
    info = SampleEliminationInfo

    def __init__(self, d=2, seed=0, ratio=RATIO, periodic=True, progressive=False, alpha=ALPHA,
                 beta=BETA, gamma=GAMMA, backend="opencl"):
        super().__init__(d=d, seed=seed, backend=backend)
        self.ratio = check_real(ratio, "ratio", minimum=1.0, open_minimum=True, maximum=1024.0)
        self.periodic = check_bool(periodic, "periodic")
        self.progressive = check_bool(progressive, "progressive")
        self.alpha = check_positive_int(alpha, "alpha", maximum=64)
        self.beta = check_real(beta, "beta", minimum=0.0, maximum=1.0)
        self.gamma = check_real(gamma, "gamma", minimum=0.0, open_minimum=True, maximum=64.0)

    def candidates(self, n):
        """M, the candidates for n points: round(ratio n), at least n + 1.

        Parameters
        ----------
        n : int

        Returns
        -------
        int
        """
        return max(n + 1, int(round(self.ratio * n)))

    def _run(self, n, realizations, backend):
        m = self.candidates(n)
        cand = make_sampler("random", d=self.d, seed=self.seed, backend=backend).sample(
            m, realizations=realizations)
        weighting = Weighting.for_counts(m, n, self.d, self.alpha, self.beta, self.gamma,
                                         self.periodic)
        first = _eliminate_sets(cand, n, weighting, backend)
        index = np.stack([survivors for survivors, _, _ in first])
        stages = 1
        if self.progressive:
            index, stages = self._progressive(cand, index, weighting, backend)
        pts = np.take_along_axis(cand, index[..., None], axis=1)
        info = SampleEliminationInfo(
            realizations=np.arange(realizations.start, realizations.stop, dtype=np.int64),
            candidates=m, d_max=weighting.d_max, d_min=weighting.d_min, stages=stages,
            max_weight=np.array([last for _, _, last in first]))
        return pts, info

    def _progressive(self, cand, index, weighting, backend):
        """Reorder the survivors ``index`` (sets, n) by halving stages (see Notes)."""
        sets = len(cand)
        size = index.shape[1]
        tails = []
        stages = 1
        while size >= 3:
            keep = size // 2
            stage = dataclasses.replace(weighting, d_max=max_min_distance(keep, self.d))
            results = _eliminate_sets(np.take_along_axis(cand, index[..., None], axis=1), keep,
                                      stage, backend)
            tails.append(np.stack([index[s, gone[::-1]] for s, (_, gone, _) in enumerate(results)]))
            index = np.stack([index[s, survivors] for s, (survivors, _, _) in enumerate(results)])
            size = keep
            stages += 1
        return np.concatenate([index, *tails[::-1]], axis=1).reshape(sets, -1), stages

    def _work_bytes(self, n):
        # measured: 697 and 1316 bytes a candidate in 2-D and 4-D (5 candidates a point)
        return (80 + 310 * self.d) * self.candidates(n)

    def _reference(self, n, realizations, start):
        return self._run(n, realizations, "numpy")

    def _device(self, n, realizations, start, out=None):
        return self._run(n, realizations, "opencl")

