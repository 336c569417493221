"""The ``poisson_disk`` sampler: the round loop both backends share, the batches, and the
sampler itself."""

import dataclasses

import numpy as np

from ... import runtime
from ...errors import InvalidArgumentError, SamplingError
from ...geometry import torus
from ...validation import check_real
from ..base import PILLEBOUE, Rate, SampleInfo, Sampler, _check_realizations, info_field, register
from .coarse import (
    COARSE_MIN_D,
    COARSE_RHO,
    COARSE_ROUNDS,
    COARSE_SPARSE,
    CoarseGeometry,
    gather_coarse,
    throw_coarse,
)
from .device import DeviceCoarse, DeviceDarts
from .grid import (
    BATCH_CELLS,
    HEXAGONAL_DENSITY,
    MAX_ATTEMPTS,
    MAX_CELLS,
    MAX_LEVEL,
    MAX_RADIUS,
    MAX_ROUNDS,
    SKIP,
    Geometry,
    acceptance_threshold,
    cells_text,
    grid_cells,
    level_of,
)
from .reference import NumpyCoarse, NumpyDarts


# -- the round loop -------------------------------------------------------------------------
def _throw_darts(backend, n):
    """Run rounds until every realization is maximal or (n given) holds n points.

    Each round: one dart per active entry (``throw``), a few greedy steps among the
    valid darts (``resolve``), then the entries are refined (``refine``, ``emit``): covered ones are
    dropped, uncovered ones kept or split into their 2^d halves. With n given, the round
    that passes n keeps only its highest-priority darts, so exactly n points remain, and a
    realization that becomes maximal with fewer than n points is marked short.

    Returns
    -------
    counts : ndarray of int, points per realization
    short : ndarray of bool, realizations that became maximal below n
    stats : dict, rounds and darts thrown
    """
    B = backend.B
    trimmed = np.zeros(B, dtype=np.int64)
    counts = np.zeros(B, dtype=np.int64)
    done = np.zeros(B, dtype=np.uint8)
    short = np.zeros(B, dtype=bool)
    darts = 0
    round_ = 0
    leftover = 0
    while backend.m:
        level = level_of(round_)
        if level > MAX_LEVEL and round_ < MAX_ROUNDS:
            # What is left after MAX_LEVEL refinements are subcells 2^-31 of a grid cell wide
            # that no single disk covers but the union does, up to the point where two
            # circles cross: a gap of no measure (below 2^-60 of the torus) that no dart can
            # hit. The set is maximal; stop there.
            side = 1.0 / (backend.geo.G * 2.0 ** level)
            if backend.m * side ** backend.geo.d < 2.0 ** -60:
                leftover = int(backend.m)
                if n is not None:          # those realizations are maximal: short if below n
                    rel = np.asarray(runtime.to_host(backend.rel[:backend.m]), dtype=np.int64)
                    stuck = np.zeros(B, dtype=bool)
                    stuck[np.unique(rel)] = True
                    short |= stuck & (done == 0)
                break
        if round_ >= MAX_ROUNDS or level > MAX_LEVEL:
            raise SamplingError(
                f"poisson_disk did not finish in {MAX_ROUNDS} rounds / {MAX_LEVEL} levels "
                "(a bug: please report it with the seed and radius)")
        backend.throw(round_, level)
        darts += backend.m
        backend.resolve(round_)
        if n is not None:
            # the maximal mode reads the counts once, at the end (one sync less a round)
            counts = backend.accepted() - trimmed
            over = (counts >= n) & (done == 0)
            if over.any():
                excess = np.where(over, counts - n, 0)
                if excess.any():
                    rel, slots, prio = backend.won_entries()
                    # each realization's darts of this round, best first: higher priority,
                    # then lower entry index (dart_resolve's key); the last `excess` go
                    order = np.lexsort((np.arange(rel.size), -prio.astype(np.int64), rel))
                    rel, slots = rel[order], slots[order]
                    start = np.searchsorted(rel, np.arange(B))
                    size = np.bincount(rel, minlength=B)
                    rank = np.arange(rel.size) - start[rel]
                    backend.clear(slots[rank >= size[rel] - excess[rel]])
                    trimmed += excess
                counts[over] = n
                done[over] = 1
        split = int(level_of(round_ + 1) > level)
        entry_counts, remaining = backend.refine(level, split, done, n is not None)
        if n is not None:
            newly_short = (remaining == 0) & (done == 0)
            short |= newly_short
            done[newly_short] = 1
        entry_counts = np.asarray(entry_counts, dtype=np.int64)
        offs = np.concatenate(([0], np.cumsum(entry_counts)[:-1])).astype(np.int64)
        if len(entry_counts) and offs[-1] + entry_counts[-1] > 2**32 - 1:
            raise SamplingError("poisson_disk: more than 2^32 active cells in one batch")
        backend.emit(entry_counts, offs, split)
        round_ += 1
    counts = backend.accepted() - trimmed
    return counts, short, {"rounds": round_, "darts": darts, "leftover": leftover}


@dataclasses.dataclass(frozen=True)
class PoissonDiskInfo(SampleInfo):
    """What a call of the dart thrower did, per realization (first axis).

    Attributes
    ----------
    realizations : ndarray (r,)
        The realization indices.
    counts : ndarray (r,) of int
        Points in each set.
    radius : float
        The radius the call kept (``rho * d_max(n)`` with a fixed n).
    rho_bound : ndarray (r,) of float
        ``radius / d_max(count)``: a lower bound of each set's relative radius
        (:func:`clsamp.metrics.relative_radius` measures it).
    rounds : int
        Rounds of darts the longest batch took.
    darts : int
        Darts thrown in all.
    redraws : int
        Realizations drawn again because they became maximal below n.
    """

    counts: np.ndarray = info_field()
    radius: float = info_field("same")
    rho_bound: np.ndarray = info_field()
    rounds: int = info_field("max")
    darts: int = info_field("sum")
    redraws: int = info_field("sum")


@register("poisson_disk")
class PoissonDiskSampler(Sampler):
    """Poisson-disk points by parallel dart throwing, on the unit torus.

    Parameters
    ----------
    d : int
        Dimension, 1 to 8; maximal sets (``radius`` with n left out) 1 to 4.
    seed : int
        Seed of the darts (``Stream.CANDIDATES``).
    rho : float, optional
        Relative radius in (0, pi / sqrt(12) = 0.906899...] for a fixed n (default 0.75
        when ``radius`` is not given, 0.65 in d >= 5): the points are at least
        ``rho * d_max(n)`` apart, d_max from
        :func:`clsamp.metrics.max_min_distance` (2-D: sqrt(2 / (sqrt(3) n))).
        Saturated (maximal) dart throwing reaches about 0.77 in 2-D (0.80 in 3-D and 4-D,
        0.75 in 1-D), so values close to that may need redraws and values above it fail:
        the error says so.
    radius : float, optional
        Absolute radius in (0, 0.5]. With ``sample()`` (n left out) the set is maximal:
        no point of the torus is r or more from every point. With ``sample(n)`` exactly n
        points at least r apart. Not together with ``rho``.
    backend : {"opencl", "numpy"}
        ``"numpy"`` runs the NumPy reference, which gives the same points.

    Notes
    -----
    A background grid of G^d cells of side 1/G < r / sqrt(d) holds at most one point per
    cell (Wei 2008; Ebeida et al. 2011). Uncovered space is tracked as a list of active
    cells: all grid cells at first, then their 2^d-fold subdivisions (the flat quadtree of
    Ebeida et al. 2011, 2012), one level deeper every round after the first two. In every
    round each active cell receives one dart, uniform in the cell (so darts land uniformly
    in the uncovered area's cover); a dart is valid when no accepted point is within r.
    Valid darts closer than r to each other are settled by a few parallel steps of the
    greedy independent set in the order of a random Philox priority (Luby 1986): a dart is
    accepted when no higher conflicting dart is still in play, which is what throwing them
    one at a time in that order would accept; darts still undecided after
    :func:`resolve_steps` steps are dropped for the round (their cells stay active). Every
    rule asks only whether some neighbour exists, so the outcome is a function of the seed
    alone: the same on every device and in the NumPy reference. An active cell is dropped
    as soon as it lies inside one disk (its farthest corner closer than r to a point); when
    none is left, no point of the torus is r or more from the set: the set is maximal --
    exactly, not after a count of failures.

    Fixed n runs the same process at r = rho * d_max(n) and stops a realization in the
    round its count passes n, keeping that round's n - (earlier points) highest-priority
    darts (any subset of a valid set is valid). A realization that becomes maximal below n
    (small n fluctuates) is drawn again from the next of ``MAX_ATTEMPTS`` independent Philox
    streams, so realization k still depends on k alone; if all fail, n points cannot be
    placed at that rho and ``InvalidArgumentError`` says so. Saturated dart throwing reaches
    rho of about 0.75 in 1-D (Renyi's parking constant 0.7476), 0.77 in 2-D and 0.80 in 3-D
    and 4-D (random sequential addition saturates at a density of about 0.256 in 4-D by the
    fit (0.202 + 0.974 d) / 2^d of Torquato et al. 2006, of the D4 lattice's 0.6169:
    rho = 0.80; maximal sets here reach 0.804-0.806), so at the default 0.75 large 1-D sets
    fail: use a smaller rho there.

    In d = 5..8 the grid of side r / sqrt(d) would hold about 100 (5-D) to 5600 (8-D) cells
    a point at rho = 0.75, a dart searching thousands to hundreds of thousands of them, so
    there (fixed n only) the darts go into the whole torus, ``n`` a round into each
    unfinished set, as plain dart throwing (Cook 1986), settled by the same greedy steps, and
    the points near a dart are found through cells of side >= r (3^d of them around it, or
    one cell holding every point when fewer than 3 fit an axis): memory linear in n.
    Without voids no set is known to be maximal; one still short of n after
    ``COARSE_ROUNDS`` (64) rounds is drawn again, as a maximal one is. Dart throwing's slow
    approach to saturation (the uncovered space shrinks as a power of the darts thrown,
    Torquato et al. 2006) makes 0.75 out of reach in 64 rounds; 0.7 takes 11-36 rounds and the
    default 0.65 takes 4-6 (docs/performance.md). The points of a set come in the order
    they were accepted (each round's in cell order). A fixed n in d <= 4 is thrown the same
    way where the fine grid would hold more than 256 cells a point (``COARSE_SPARSE``: a
    radius far below the points' spacing, rho below about 0.08 in 2-D, 0.24 in 3-D and 0.42
    in 4-D), so a radius too small for a grid still gives n points; only maximal sets need
    the grid.

    The kernels hold every double as its IEEE-754 bit pattern and compute each operation
    (the darts' coordinates, the cells' corners, differences, squares and sums of the
    distances) through ``kernels/f64bits.h``: by the hardware where the device has fp64,
    else by integer arithmetic with the same round-to-nearest-even, and they compare the
    non-negative doubles as integers. The sampler therefore runs on devices without fp64
    (most laptop GPUs) and gives the same bits there; a device that ends long loops
    (llvmpipe) refuses it with ``NoDeviceError``.

    In radius mode the count differs between realizations, so ``sample()`` accepts
    ``realizations`` of None (shape (m, d)) or 1 (shape (1, m, d)) only;
    :meth:`sample_sets` returns a list of k maximal sets (made in one batch). ``start``
    must be 0 (a set, not a sequence).

    Points are returned in grid-cell order (row-major), not in the order of acceptance,
    where the fine grid makes them (d <= 4, but a sparse fixed n).

    References
    ----------
    M. S. Ebeida, A. A. Davidson, A. Patney, P. M. Knupp, S. A. Mitchell, J. D. Owens,
    "Efficient maximal Poisson-disk sampling", ACM Trans. Graph. 30(4), 2011.
    M. S. Ebeida, S. A. Mitchell, A. Patney, A. A. Davidson, J. D. Owens, "A simple
    algorithm for maximal Poisson-disk sampling in high dimensions", Comput. Graph.
    Forum 31(2), 2012.
    L.-Y. Wei, "Parallel Poisson disk sampling", ACM Trans. Graph. 27(3), 2008.
    R. L. Cook, "Stochastic sampling in computer graphics", ACM Trans. Graph. 5(1), 1986.
    M. Luby, "A simple parallel algorithm for the maximal independent set problem",
    SIAM J. Comput. 15(4), 1986.
    A. Lagae, P. Dutre, "A comparison of methods for generating Poisson disk
    distributions", Comput. Graph. Forum 27(1), 2008.
    S. Torquato, O. U. Uche, F. H. Stillinger, "Random sequential addition of hard spheres
    in high Euclidean dimensions", Phys. Rev. E 74, 061308, 2006.

    Examples
    --------
    >>> import clsamp
    >>> from clsamp.metrics import relative_radius
    >>> pts = clsamp.make_sampler("poisson_disk", seed=1).sample(256, realizations=2)
    >>> pts.shape, bool(relative_radius(pts).min() >= 0.75)
    ((2, 256, 2), True)
    >>> s = clsamp.make_sampler("poisson_disk", radius=0.1, seed=1)
    >>> pts, info = s.sample(return_info=True)
    >>> pts.shape == (info.counts[0], 2)
    True
    """

    dimensions = tuple(range(1, 9))
    accepts_start = False
    expensive = True
    needs_fp64 = False
    info = PoissonDiskInfo
    rates = {"best": Rate(-1.0, PILLEBOUE), "worst": Rate(-1.0, PILLEBOUE)}

    def __init__(self, d=2, seed=0, rho=None, radius=None, backend="opencl"):
        super().__init__(d=d, seed=seed, backend=backend)
        if rho is not None and radius is not None:
            raise InvalidArgumentError(
                "give 'radius' (absolute) or 'rho' (relative to d_max(n)), not both; "
                f"got radius={radius!r}, rho={rho!r}")
        if radius is not None:
            self.radius = check_real(radius, "radius", minimum=0.0, open_minimum=True)
            if self.radius > MAX_RADIUS:
                raise InvalidArgumentError(
                    f"'radius' must be <= {MAX_RADIUS} on the unit torus, got {self.radius}: a "
                    "wider disk around a point overlaps its own periodic image, so it is no "
                    "longer a disk on the torus")
            if self.d == 1 and self.radius >= MAX_RADIUS:
                raise InvalidArgumentError(
                    f"'radius' must be below {MAX_RADIUS} in 1-D, got {self.radius}: a point's "
                    "disk then leaves only its antipode uncovered, which no dart hits")
            self.rho = None
            # maximal sets for d <= 4 only, and where their grid fits
            self.needs_n = self.d >= COARSE_MIN_D or grid_cells(self.radius, self.d) > MAX_CELLS
        else:
            self.radius = None
            default = 0.75 if self.d < COARSE_MIN_D else COARSE_RHO
            self.rho = default if rho is None else check_real(rho, "rho", minimum=0.0,
                                                           open_minimum=True)
            if self.rho > HEXAGONAL_DENSITY:
                raise InvalidArgumentError(
                    f"'rho' must be <= {HEXAGONAL_DENSITY!r} (pi / sqrt(12), beyond "
                    f"hexagonal packing), got {self.rho}; maximal dart throwing reaches "
                    "about 0.77 in 2-D")

    def __repr__(self):
        what = f"radius={self.radius}" if self.radius is not None else f"rho={self.rho}"
        return f"{type(self).__name__}(d={self.d}, seed={self.seed}, {what})"

    @property
    def variable_size(self):
        """Maximal sets (radius mode) differ in size: read them with :meth:`sample_sets`."""
        return self.radius is not None

    def sample_sets(self, realizations, n=None, return_info=False):
        """Sets as a list of (m_k, d) arrays, one per realization: maximal sets in radius
        mode (n left out), else the rows of :meth:`sample`.

        Parameters
        ----------
        realizations : int or range
            r for the realizations 0..r-1, or a range for exactly those. Set k is the one
            ``sample(realizations=range(k, k + 1))`` gives and does not depend on which
            others are asked for; all sets are made in one batch.
        n : int, optional
            Exactly n points a set instead of maximal ones.
        return_info : bool
            Also return the :class:`PoissonDiskInfo` of the call.

        Returns
        -------
        list of ndarray, or (list of ndarray, PoissonDiskInfo)
            One (m_k, d) array per realization.

        Raises
        ------
        InvalidArgumentError
            ``realizations`` is not a count or a non-empty range of step 1.
        """
        if self.radius is None or n is not None:
            return super().sample_sets(realizations, n=n, return_info=return_info)
        self._check_maximal()
        if isinstance(realizations, range) and (len(realizations) == 0 or realizations.step != 1):
            raise InvalidArgumentError(
                f"'realizations' must be a count or a non-empty range of step 1, got "
                f"{realizations!r}")
        # the bounds sample() takes: 32-bit counters (2^32 + k would be realization k)
        (reals,), _ = _check_realizations(realizations)
        sets, info = self._run(None, reals, device=self.backend == "opencl", as_list=True)
        return (sets, info) if return_info else sets

    def convergence_rate(self, case):
        """The published rate of the MSE for ``case`` (:meth:`Sampler.convergence_rate`).

        Parameters
        ----------
        case : {"best", "worst", "axis"}
            The integrand as the estimator sees it (:func:`clsamp.theory.case_of`).

        Returns
        -------
        Rate or None
            The 2-D rates for sets of a given n (``rho`` mode); None in other
            dimensions and for maximal sets (``radius`` mode), whose n is not chosen.
        """
        return self.rates.get(case) if self.d == 2 and self.radius is None else None

    # -- what the base calls ------------------------------------------------------------
    def _check_call(self, n, realizations, start, return_info=False):
        if n is None and self.radius is not None:
            self._check_maximal()
        checked = super()._check_call(n, realizations, start, return_info)
        runs = checked[1]
        if checked[0] is None and sum(len(run) for run in runs) != 1:
            raise InvalidArgumentError(
                f"'realizations'={realizations!r}: maximal sets (radius mode, n left out) have "
                "different sizes, so they do not fit one (r, n, d) array; use "
                "sample_sets(realizations) for a list, or give n for exactly n points each")
        return checked

    def _reference(self, n, realizations, start):
        return self._run(n, realizations, device=False)

    def _device(self, n, realizations, start):
        return self._run(n, realizations, device=True)

    def _check_maximal(self):
        """Refuse a maximal set beyond d = 4 (naming 'd') or whose grid does not fit (naming
        'radius')."""
        if self.d >= COARSE_MIN_D:
            raise InvalidArgumentError(
                f"'d'={self.d}: maximal sets (radius mode, n left out) are made for d <= "
                f"{COARSE_MIN_D - 1} (their grid of side r / sqrt(d) grows as (sqrt(d) / r)^d); "
                "give n for exactly n points at least 'radius' apart")
        self._check_grid(self.radius, f"'radius'={self.radius} is too small for a maximal set "
                         f"in d={self.d}", "give n for exactly n points at least 'radius' apart")

    def _check_grid(self, radius, what, advice):
        """Refuse a fine grid of more than MAX_CELLS cells at ``radius``, saying ``what``."""
        cells = grid_cells(radius, self.d)
        if cells > MAX_CELLS:
            raise InvalidArgumentError(
                f"{what}: the background grid of radius {radius:.3g} would have "
                f"{cells_text(cells)} cells, more than {MAX_CELLS}; {advice}")

    # -- the work -------------------------------------------------------------------------
    def _coarse(self, radius, n):
        """Whether n points at ``radius`` are thrown into the whole torus (:mod:`.coarse`):
        from 5-D on, and in any d where the fine grid would hold more than ``COARSE_SPARSE``
        cells a point."""
        return n is not None and (self.d >= COARSE_MIN_D
                                  or grid_cells(radius, self.d) > COARSE_SPARSE * n)

    def _geometry(self, n):
        if self.radius is not None:
            radius, r2, given = self.radius, acceptance_threshold(self.radius), "radius"
        else:
            d_max = torus.max_min_distance(n, self.d)
            radius, given = self.rho * d_max, "rho"
            r2 = acceptance_threshold(radius, d_max, self.rho)
        if self._coarse(radius, n):
            return CoarseGeometry(self.d, radius, r2, n)
        if n is not None:           # a maximal set's grid was checked with its call
            self._check_grid(radius, f"'n'={n} with '{given}'={getattr(self, given)} is too much "
                             f"for d={self.d}", f"give fewer points or a larger {given}")
        return Geometry(self.d, radius, r2)

    def _run(self, n, realizations, device, as_list=False):
        geo = self._geometry(n)
        ids = np.arange(realizations.start, realizations.stop, dtype=np.int64)
        if self.radius is not None:
            what = f"'radius'={self.radius:.6g}"
        else:
            what = f"'rho'={self.rho:.6g} (radius {geo.radius:.6g})"
        parts, counts, stats = _draw(geo, ids, n, self.seed, device, what)
        sizes, where = np.unique(counts, return_inverse=True)
        rho_bound = np.array([geo.radius / torus.max_min_distance(int(c), self.d)
                              for c in sizes])[where]
        info = PoissonDiskInfo(realizations=ids, counts=counts, radius=geo.radius,
                               rho_bound=rho_bound, rounds=stats["rounds"], darts=stats["darts"],
                               redraws=stats["redraws"])
        if as_list:
            sets = []
            for out, c in parts:
                host = out.get() if device else out
                sets.extend(np.split(host[:int(c.sum())], np.cumsum(c)[:-1]))
            return sets, info
        (out, c), = parts if n is None else ((parts, counts),)
        m = int(c[0])
        shape = (len(ids), m, self.d)
        if m * len(ids) < out.shape[0]:  # a maximal set's buffer is one row long when empty
            out = out[:m * len(ids)]
        return out.reshape(shape), info


def _draw(geo, ids, n, seed, device, what):
    """Draw realizations ``ids`` in batches of at most BATCH_CELLS grid cells.

    Fixed n: returns ``(out, counts, stats)`` with out of shape (len(ids) * n, d) (device or
    host), realization after realization. A realization that becomes maximal below n is
    drawn again with the next ``attempt`` (the Philox counters' grid-cell word carries it
    in bits 26-31), up to MAX_ATTEMPTS times; so realization k still depends on k alone, and
    its points follow the process conditioned on reaching n.

    Maximal (n None): returns ``([(out, counts) per batch], counts, stats)``.
    """
    coarse = isinstance(geo, CoarseGeometry)
    if coarse:
        make = DeviceCoarse if device else NumpyCoarse
    else:
        make = DeviceDarts if device else NumpyDarts
    per_batch = max(1, BATCH_CELLS // geo.footprint)
    if device:  # the point grid, the largest buffer, within one launch's budget
        per_batch = min(per_batch, runtime.fit(8 * geo.d * geo.footprint))
    stats = {"rounds": 0, "darts": 0, "redraws": 0}

    def alloc(rows):
        if device:
            import pyopencl.array as cla
            return cla.empty(runtime.queue(), (max(rows, 1), geo.d), np.float64)
        return np.empty((max(rows, 1), geo.d), dtype=np.float64)

    def account(st):
        stats["rounds"] = max(stats["rounds"], st["rounds"])
        stats["darts"] += st["darts"]

    if n is None:
        parts, all_counts = [], []
        for lo in range(0, len(ids), per_batch):
            backend = make(geo, ids[lo:lo + per_batch], 0, seed)
            counts, _, st = _throw_darts(backend, None)
            account(st)
            out = alloc(int(counts.sum()))
            backend.gather(np.concatenate(([0], np.cumsum(counts)[:-1])).astype(np.int64), out)
            parts.append((out, counts))
            all_counts.append(counts)
        return parts, np.concatenate(all_counts), stats

    out = alloc(len(ids) * n)
    pending = np.arange(len(ids))
    best = 0
    for attempt in range(MAX_ATTEMPTS):
        if not pending.size:
            break
        if attempt:
            stats["redraws"] += int(pending.size)
        still = []
        for lo in range(0, pending.size, per_batch):
            batch = pending[lo:lo + per_batch]
            backend = make(geo, ids[batch], attempt, seed)
            counts, short, st = (throw_coarse if coarse else _throw_darts)(backend, n)
            account(st)
            dst = np.where(short, SKIP, batch * n).astype(np.int64)
            if coarse:
                gather_coarse(backend.points, dst, out, SKIP)
            else:
                backend.gather(dst, out)
            if short.any():
                best = max(best, int(counts[short].max()))
            still.append(batch[short])
        pending = np.concatenate(still)
    if pending.size and coarse:
        raise InvalidArgumentError(
            f"n={n} points cannot be placed at {what} in d={geo.d}: realization "
            f"{int(ids[pending[0]])} stayed below n after {COARSE_ROUNDS} rounds of n darts in "
            f"{MAX_ATTEMPTS} attempts (at most {best} points). Use a smaller 'rho' (dart "
            f"throwing in d >= {COARSE_MIN_D} reaches about 0.7 in that many rounds) or a "
            "smaller 'radius'")
    if pending.size:
        raise InvalidArgumentError(
            f"n={n} points cannot be placed at {what} in d={geo.d}: realization "
            f"{int(ids[pending[0]])} became maximal below n in {MAX_ATTEMPTS} attempts (at most "
            f"{best} points). Use a smaller 'rho' (saturated dart throwing reaches about 0.75 "
            "in 1-D, 0.77 in 2-D, 0.80 in 3-D and 4-D) or a smaller 'radius'")
    return out, np.full(len(ids), n, dtype=np.int64), stats
