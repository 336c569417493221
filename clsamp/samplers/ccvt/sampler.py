"""The ``ccvt`` sampler and :func:`ccvt_optimize`: capacity-constrained Voronoi
tessellation (Balzer et al. 2009) from random or given starting sites."""

import dataclasses

import numpy as np

from ... import runtime
from ...errors import InvalidArgumentError
from ...geometry import integer_torus as it
from ...validation import MAX_ITERATIONS, check_bool, check_choice, check_int, check_positive_int
from ..base import PILLEBOUE, Rate, SampleInfo, info_field, register
from ..optimizer import OptimizerSampler, check_sites
from .density import DENSITIES, density_points, density_points_device
from .device import ccvt_device
from .pairs import CCVT_META, MAX_POINTS_PER_SITE
from .reference import ccvt_reference
from .start import MAX_RELAX, start_partition, start_sites


@dataclasses.dataclass(frozen=True)
class CCVTInfo(SampleInfo):
    """What a CCVT optimization did, per realization (first axis).

    Attributes
    ----------
    realizations : ndarray (r,)
        The realization indices.
    energy_history : ndarray (r, iterations)
        The capacity-constrained energy: the mean squared toroidal distance of the density
        points to the site that owns them, after each iteration (exchanges, then sites to
        centroids). Never rising; a realization that converged before the others repeats
        its final value. n times its last entry is the set's capacity N*E: never below the
        energy of the same density points at their nearest sites, but, a sum over a
        sample of the torus, not bounded by :func:`clsamp.metrics.normalized_energy` of
        the returned sites (every point of the torus at its nearest site): 2-3 % below it
        at 8 points a site, measured.
    capacities : ndarray (r, n)
        Density points owned by each site at the end, counted from the ownership: all
        equal to ``points_per_site``.
    iterations : ndarray (r,)
        Iterations each realization ran (the last one made no exchange if it converged).
    converged : ndarray (r,) of bool
        Whether an iteration made no exchange (a local optimum) within the cap.
    """

    energy_history: np.ndarray = info_field("pad")
    capacities: np.ndarray = info_field()
    iterations: np.ndarray = info_field()
    converged: np.ndarray = info_field()


def ccvt_optimize(sites, points_per_site=1024, iterations=1000, seed=0, backend="opencl",
                  callback=None, density="jittered", relax=0):
    """CCVT from given starting sites on the unit torus.

    Parameters
    ----------
    sites : ndarray (n, 2) or (r, n, 2)
        Starting sites in [0, 1) (duplicates and clusters are fine).
    points_per_site : int
        Capacity: density points per site (M = n * points_per_site in all).
    iterations : int
        Cap on the iterations; the optimization stops earlier when an iteration makes
        no exchange.
    seed : int
        Seeds the density points (realization k uses (seed, Stream.INIT, k)).
    backend : {"opencl", "numpy"}
    callback : callable, optional
        ``callback(members, sites)`` with the ownership (r, n, p) and the integer sites
        after every iteration (OpenCL) or at the end (NumPy); for tests.
    density : {"jittered", "random"}
        The density points: one per cell of an equal-area stratification (default) or
        i.i.d. uniform (:func:`density_points`; see :class:`CCVTSampler`).
    relax : int
        Relaxation steps of the starting sites before the partition (:func:`start_sites`;
        see :class:`CCVTSampler`), default 0.

    Returns
    -------
    points : ndarray (r, n, 2)
        The optimized sites, float64 in [0, 1) (batch-shaped even for one set).
    info : CCVTInfo
        Realizations 0..r-1 standing for the given sets.
    """
    batch, _ = check_sites(sites)
    points_per_site = check_points_per_site(points_per_site, batch.shape[1])
    iterations = check_positive_int(iterations, "iterations", maximum=MAX_ITERATIONS)
    check_choice(density, "density", DENSITIES)
    relax = check_int(relax, "relax", minimum=0, maximum=MAX_RELAX)
    return _run(batch, np.arange(batch.shape[0]), points_per_site, iterations, seed,
                backend, callback, density, relax)


def check_points_per_site(points_per_site, n):
    """``points_per_site`` checked for n sites: a positive integer, and n times it below
    2^32 density points (CCVT's and ``bnot``'s counts are 32-bit).

    Parameters
    ----------
    points_per_site : int
    n : int

    Returns
    -------
    int

    Raises
    ------
    InvalidArgumentError
        Not a positive integer up to ``MAX_POINTS_PER_SITE``, or too many density points.
    """
    p = check_positive_int(points_per_site, "points_per_site", maximum=MAX_POINTS_PER_SITE)
    if n * p > 2**32 - 1:
        raise InvalidArgumentError(
            f"'points_per_site' * n must stay below 2^32 density points, got {p} * {n}")
    return p


def _run(sites, realizations, p, iterations, seed, backend, callback=None, density="jittered",
         relax=0, progress=False):
    r, n, _ = sites.shape
    M = n * p
    results = []
    for lo, hi in runtime.chunk_ranges(r, 32 * M + (64 + 8 * CCVT_META) * n):
        start, weight = start_sites(sites[lo:hi], p, backend, relax)
        if backend == "numpy":
            points = density_points(seed, realizations[lo:hi], M, density)
            members = start_partition(start, points, p, backend, weight)
            run = ccvt_reference(start, points, members, iterations, callback)
        else:
            on_device = density_points_device(seed, realizations[lo:hi], M, density)
            runtime.wait()                  # Ctrl-C is taken while the density is drawn
            points = on_device.get()
            members = start_partition(start, points, p, backend, weight, on_device)
            run = ccvt_device(start, on_device, members, iterations, callback, progress=progress)
        results.append(run)
    length = max(len(e) for part in results for e in part[1])
    history, capacities, counts = [], [], []
    for _, energies, members, _ in results:
        for k, e in enumerate(energies):
            counts.append(len(e))
            history.append([float(v) for v in e] + [float(e[-1])] * (length - len(e)))
            # counted from the ownership itself: a point listed twice would leave another unowned
            owner = np.full(M, n, dtype=np.int64)
            owner[members[k].ravel().astype(np.int64)] = np.repeat(np.arange(n), p)
            capacities.append(np.bincount(owner, minlength=n + 1)[:n])
    scale = float(M) * float(it.SIZE) ** 2
    info = CCVTInfo(realizations=np.asarray(realizations, dtype=np.int64),
                    energy_history=np.asarray(history) / scale,
                    capacities=np.asarray(capacities), iterations=np.asarray(counts),
                    converged=np.concatenate([part[3] for part in results]))
    return it.to_unit(np.concatenate([part[0] for part in results])), info


@register("ccvt")
class CCVTSampler(OptimizerSampler):
    """Capacity-constrained Voronoi tessellation: blue noise with exactly equal cells.

    Parameters
    ----------
    d : int
        Must be 2 (the unit torus [0, 1)^2; distances wrap).
    seed : int
        Seeds the starting sites and the density points (Philox, ``Stream.INIT``;
        realization k does not depend on how many realizations are drawn).
    points_per_site : int
        Capacity of every site, default 1024: M = n * points_per_site density points are
        drawn and each site owns exactly that many at every moment.
    iterations : int
        Cap on the iterations (default 1000); each realization stops at the first
        iteration in which no exchange lowers the energy.
    backend : {"opencl", "numpy"}
    density : {"jittered", "random"}
        How the M density points are drawn. ``"jittered"`` (default): one uniform point
        in each cell of an equal-area partition of the torus into exactly M near-square
        cells, the whole set shifted by a random toroidal offset per realization.
        ``"random"``: M i.i.d. uniform points, as in Balzer et al. (see Notes).
    relax : int
        Steps of a capacity-constrained Lloyd relaxation of the random starting sites on
        a coarse lattice proxy of the density before the optimization
        (:func:`~clsamp.samplers.ccvt.start.start_sites`), default 0: Balzer et al.'s
        random start. Relaxed sites leave the optimization less to do and end at a lower
        energy, but more regular: rows of hexagonal order appear, the structure CCVT
        exists to avoid. At most 64.

    Notes
    -----
    Balzer, Schloemer and Deussen minimize the energy E = mean over density points of
    the squared toroidal distance to the site owning them, under the constraint that
    every site owns the same number of points.

    *Start* (:mod:`clsamp.samplers.ccvt.start`). Every density point goes to its nearest
    site in the power distance |x - s_i|^2 - w_i, the weights balancing the cells' areas
    (a smooth correction solved by FFT for the large-scale crowding of random sites, and
    a damped Newton step per site); the excess of overfull sites is then passed along
    neighbouring sites to the nearest ones with room. The partition is exact in capacity,
    compact and, unlike a partition of the unit square, without seams on the axes.

    *Iterations.* (1) Neighbouring sites i, j exchange points: each side's candidates
    are ordered by the gain of moving to the other site, and pairs are exchanged in order
    while the two gains sum to more than zero (the paper's heap-based swap, here in
    rounds of the 16 best candidates a side); a pair that exchanged moves both its sites
    to the periodic centroids of their points at once, as Balzer et al.'s code does.
    (2) Every site whose points changed moves to its periodic centroid. Both steps lower
    E, and an exchange is one point for one point, so the energy never rises and the
    capacities are equal at every moment. The run stops at the first iteration without an
    exchange (a local optimum), or at ``iterations``.

    Neighbours are sites closer than 2 / sqrt(n), found through an even grid of cells at
    least that wide, never all n^2 pairs. The gain of a point x of i is
    ``2 u.D - |D|^2`` (u: x relative to s_i, D: s_j relative to s_i), its exact change of
    squared distance unless the torus brings another image of s_j nearer, in which case
    the true change is larger. In OpenCL the pairs of one launch are disjoint (nine
    phases: inside each cell, then each cell with its neighbour along (1,0), (0,1),
    (1,1), (1,-1), one parity at a time), so no site is in two pairs at once. Each site
    keeps its points in 64 buckets (16 sectors times 4 radial bands) with their largest
    radii, which bound the gains of a bucket toward any neighbour, so a pair reads only
    the buckets that can hold a candidate; pairs that cannot have changed since they last
    met are skipped. Every skip is exact: the NumPy reference, which reads everything,
    gives the same bits. Positions are integers on the 2^22 torus of
    :mod:`clsamp.geometry.integer_torus`, and so is everything computed on them, the
    bounds that skip included (integer upper bounds: radii rounded up by an exact integer
    square root), so a device without fp64 gives the same bits; the device needs 64-bit
    integer atomics (the energy totals) instead.

    *Density.* A site owns exactly p density points, so its cell's true area is the area
    those p points cover. With i.i.d. points that is a random count (relative spread
    about 1 / sqrt(p)), which puts an N^-1 floor under the Monte Carlo MSE; one point per
    equal-area stratum makes the covered area nearly exact and restores the published
    rates. The strata are rows of equal-area cells (isqrt(M) rows of isqrt(M) to
    isqrt(M) + 2 cells), so any M works; the per-realization shift makes the process
    stationary. ``density="random"`` keeps Balzer et al.'s i.i.d. density (and has no
    published rate).

    ``sample(..., return_info=True)`` also returns a :class:`CCVTInfo`: the energy
    after every iteration, the capacities, the iterations run and whether each
    realization converged. The N*E of the returned set on the scale of every other
    sampler is :func:`clsamp.metrics.normalized_energy` (0.160375 for the
    hexagonal lattice, about 1/pi for white noise). Timings and iteration counts are in
    docs/performance.md.

    References
    ----------
    .. [1] M. Balzer, T. Schloemer, O. Deussen, "Capacity-constrained point distributions:
       a variant of Lloyd's method", ACM Trans. Graph. 28(3) (SIGGRAPH), 2009.
    .. [2] A. Pilleboue, G. Singh, D. Coeurjolly, M. Kazhdan, V. Ostromoukhov, "Variance
       analysis for Monte Carlo integration", ACM Trans. Graph. 34(4) (SIGGRAPH), 2015.

    Examples
    --------
    >>> import clsamp
    >>> s = clsamp.make_sampler("ccvt", seed=3, points_per_site=32)
    >>> pts, info = s.sample(64, return_info=True)
    >>> int(info.capacities.min()), int(info.capacities.max())
    (32, 32)
    >>> bool(64 * info.energy_history[0, -1] < 0.2)
    True
    """

    info = CCVTInfo
    rates = {"best": Rate(-3.0, PILLEBOUE), "worst": Rate(-1.5, PILLEBOUE)}
    # exact integers on the torus, the pruning bounds too (kernels/ccvt.h): 64-bit atomics,
    # no double
    needs_fp64 = False

    def __init__(self, d=2, seed=0, points_per_site=1024, iterations=1000, backend="opencl",
                 density="jittered", relax=0, progress=True):
        super().__init__(d=d, seed=seed, backend=backend)
        self.progress = check_bool(progress, "progress")
        self.points_per_site = check_positive_int(points_per_site, "points_per_site",
                                                  maximum=MAX_POINTS_PER_SITE)
        self.iterations = check_positive_int(iterations, "iterations", maximum=MAX_ITERATIONS)
        self.density = check_choice(density, "density", DENSITIES)
        self.relax = check_int(relax, "relax", minimum=0, maximum=MAX_RELAX)

    def convergence_rate(self, case):
        """The published rate of the MSE for ``case`` (:meth:`Sampler.convergence_rate`).

        Parameters
        ----------
        case : {"best", "worst", "axis"}
            The integrand as the estimator sees it (:func:`clsamp.theory.case_of`).

        Returns
        -------
        Rate or None
            None with ``density="random"``: i.i.d. density points leave an N^-1 floor
            under the MSE (see Notes), whatever the published rate.
        """
        if self.density != "jittered":
            return None   # i.i.d. density points leave an N^-1 floor (see Notes)
        return super().convergence_rate(case)

    def _most_sites(self):
        return (2**32 - 1) // self.points_per_site

    def _check_n(self, n):
        check_points_per_site(self.points_per_site, n)     # its message, before the sites
        return super()._check_n(n)

    def _optimize(self, sites, realizations, backend):
        p = check_points_per_site(self.points_per_site, sites.shape[1])
        return _run(sites, np.arange(realizations.start, realizations.stop, dtype=np.int64), p,
                    self.iterations, self.seed, backend, density=self.density, relax=self.relax,
                    progress=self.progress)
