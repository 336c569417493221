"""Geometric quality figures of point sets on the unit torus.

* :func:`min_distance` -- the smallest toroidal distance between two points of a set,
  exact, per realization, through a background grid (O(n) work, not O(n^2)).
* :func:`relative_radius` -- that distance over the largest one n points could have,
  rho = min distance / d_max (Lagae & Dutre 2008): about 0.93 for a square grid,
  1 for the hexagonal lattice, 0.7--0.8 for maximal dart throwing.
* :func:`max_min_distance` -- d_max itself (:func:`clsamp.geometry.torus.max_min_distance`).
* :func:`normalized_energy` -- N*E, n times the CVT energy of a 2-D set (mean squared
  distance from the torus to the nearest point): 0.160375 for the hexagonal lattice,
  1/6 for a square grid, about 1/pi for white noise.

Distances wrap (:mod:`clsamp.geometry.torus`): a pair's distance is computed coordinate
by coordinate as ``min(|a - b|, 1 - |a - b|)``, summed in squares from the first
coordinate to the last and square-rooted, the same operations (hence the same bits) as
the Poisson-disk kernels test acceptance with, so a sampler that promises "min distance
>= r" can be checked without tolerance.
"""

import numpy as np

from .. import runtime
from ..errors import InvalidArgumentError
from ..geometry import integer_torus, voronoi
from ..geometry.cells import sorted_by_cell
from ..geometry.torus import PACKING_DENSITY, max_min_distance
from ..geometry.torus import distance2 as toroidal_distance2
from ..validation import check_bool, check_choice, check_points, check_positive_int, point_sets

__all__ = ["min_distance", "relative_radius", "max_min_distance", "normalized_energy",
           "HEXAGONAL_NE", "WHITE_NOISE_NE"]

HEXAGONAL_NE = 5.0 / (18.0 * np.sqrt(3.0))   # N*E of the hexagonal lattice, 0.160375
WHITE_NOISE_NE = 1.0 / np.pi                 # expected N*E of independent uniform points


def _min_distance2_brute(batch, periodic=True):
    r, n, d = batch.shape
    best = np.full(r, np.inf)
    for i in range(n - 1):
        d2 = toroidal_distance2(batch[:, i:i + 1, :], batch[:, i + 1:, :], periodic)
        best = np.minimum(best, d2.min(axis=1))
    return best


def _min_distance2_grid(batch, cells, periodic=True):
    """Smallest squared distance per realization among pairs in the same or adjacent
    cells of a grid of ``cells ** d`` (cells >= 3, so the 3^d neighbours are distinct; in
    the cube a wrapped neighbour cell is farther than a cell, and never the answer)."""
    r, n, d = batch.shape
    pts, flat, start, _ = sorted_by_cell(batch, cells)
    starts = start[:-1].astype(np.int64)
    counts = np.diff(start.astype(np.int64))
    occupancy = int(counts.max())
    total_cells = cells ** d
    realization = np.repeat(np.arange(r, dtype=np.int64), n)      # sorted realization-major
    cell = np.stack(np.unravel_index(flat.astype(np.int64), (cells,) * d), axis=-1)
    own = np.arange(r * n)
    best = np.full(r * n, np.inf)
    strides = cells ** np.arange(d - 1, -1, -1)
    # Each unordered pair is met twice (once from each end); half the offsets would do,
    # but the full 3^d keeps the loop plain and its cost is small beside the sort.
    for offset in np.ndindex(*(3,) * d):
        shifted = (cell + (np.asarray(offset) - 1)) % cells
        neighbour = realization * total_cells + shifted @ strides
        first = starts[neighbour]
        count = counts[neighbour]
        for k in range(occupancy):
            valid = k < count
            if not valid.any():
                break
            j = np.where(valid, first + k, own)
            valid &= j != own
            d2 = toroidal_distance2(pts, pts[j], periodic)
            best = np.where(valid, np.minimum(best, d2), best)
    out = np.full(r, np.inf)
    np.minimum.at(out, realization, best)
    return out


def _min_distance2(batch, periodic=True):
    r, n, d = batch.shape
    if n == 1:
        return np.full(r, np.inf)
    if n <= 64:
        return _min_distance2_brute(batch, periodic)
    # Start from a cell a little wider than d_max (no set can beat it, so the grid
    # nearly always holds the closest pair); widen until the pair found is closer
    # than a cell, which proves no pair in non-adjacent cells can be closer.
    size = 1.05 * max_min_distance(n, d) if d in PACKING_DENSITY else n ** (-1.0 / d)
    best = None
    while True:
        cells = int(1.0 / size)
        if cells < 3:
            return _min_distance2_brute(batch, periodic)
        best = _min_distance2_grid(batch, cells, periodic)
        if np.all(best <= (1.0 / cells) ** 2):
            return best
        size *= 2.0


def min_distance(points, periodic=True):
    """Smallest toroidal distance between two points, per realization.

    Parameters
    ----------
    points : ndarray, shape (n, d) or (r, n, d), or a list of (n_k, d) arrays
        Points in [0, 1)^d, any d (a list: sets of different sizes, one value each).
    periodic : bool
        False: the Euclidean distance in the unit cube, without wrapping (a single point
        then has none: inf).

    Returns
    -------
    float for one set, ndarray of shape (r,) for r realizations.

    Notes
    -----
    The set is taken periodically (tiled over R^d), so the distance is

    .. math:: \\delta = \\min\\bigl(1, \\min_{i \\ne j} \\lVert x_i - x_j \\rVert_{\\mathbb{T}}\\bigr),
              \\quad \\lVert v \\rVert_{\\mathbb{T}}^2 = \\sum_k \\min(|v_k|, 1 - |v_k|)^2,

    where 1 is the distance between a point and its own nearest periodic image (so a
    single point has minimum distance 1). Points are bucketed in a grid of cells about
    d_max wide; pairs in the same or adjacent cells are compared, which is exact as
    soon as the closest pair found is closer than a cell (the grid is widened
    otherwise). Work and memory are O(n) per realization.

    Examples
    --------
    >>> import numpy as np
    >>> from clsamp.metrics import min_distance
    >>> round(min_distance(np.array([[0.05, 0.5], [0.95, 0.5]])), 12)
    0.1
    """
    periodic = check_bool(periodic, "periodic")
    sets = point_sets(points)
    if sets is not None:
        return np.array([min_distance(p, periodic) for p in sets])
    batch, single = check_points(points, "points")
    d2 = _min_distance2(batch, periodic)
    out = np.minimum(np.sqrt(d2), 1.0) if periodic else np.sqrt(d2)
    return float(out[0]) if single else out


def relative_radius(points):
    """The relative radius rho = min distance / d_max of each realization.

    Parameters
    ----------
    points : ndarray, shape (n, d) or (r, n, d), d in 1..8, or a list of (n_k, d) arrays
        Points in [0, 1)^d (a list: sets of different sizes, one value each).

    Returns
    -------
    float for one set, ndarray of shape (r,) for r realizations.

    Notes
    -----
    :math:`\\rho = \\delta / d_{max}` with :math:`\\delta` from :func:`min_distance`
    and :math:`d_{max}` from :func:`max_min_distance` (in 2-D
    :math:`\\sqrt{2 / (\\sqrt{3} n)}`). Lagae & Dutre recommend rho in [0.65, 0.85]
    for blue noise; the hexagonal lattice has rho = 1, a square grid 0.9306, white
    noise tends to 0.

    References
    ----------
    A. Lagae, P. Dutre, "A comparison of methods for generating Poisson disk
    distributions", Computer Graphics Forum 27(1), 2008.

    Examples
    --------
    >>> import numpy as np
    >>> from clsamp.metrics import relative_radius
    >>> g = (np.stack(np.meshgrid(np.arange(8), np.arange(8)), -1).reshape(-1, 2) + 0.5) / 8
    >>> round(relative_radius(g), 4)
    0.9306
    """
    sets = point_sets(points)
    if sets is not None:
        return np.array([relative_radius(p) for p in sets])
    batch, single = check_points(points, "points")
    n, d = batch.shape[1], batch.shape[2]
    if d not in PACKING_DENSITY:
        raise InvalidArgumentError(
            f"'points' must have 1 to 8 dimensions for a relative radius, got {d}")
    rho = np.minimum(np.sqrt(_min_distance2(batch)), 1.0) / max_min_distance(n, d)
    return float(rho[0]) if single else rho


def normalized_energy(points, density=4096, backend="opencl"):
    """N*E of each realization: n times the mean squared toroidal distance from the unit
    torus to the nearest point of the set (its CVT energy), a figure of the points alone.

    Parameters
    ----------
    points : ndarray or pyopencl.array.Array, shape (n, 2) or (r, n, 2), or a list of (n_k, 2)
        Points in [0, 1)^2 (a device array is read on the device; a list: sets of
        different sizes, one value each).
    density : int
        Regular g x g grid of cell centres the mean is taken over, g = ceil(sqrt(n *
        density)); the nearest point of each is found through a grid of the points, in
        OpenCL (:func:`clsamp.geometry.voronoi.cvt_energy`).
    backend : {"opencl", "numpy"}

    Returns
    -------
    float for one set, ndarray of shape (r,) for r realizations.

    Notes
    -----
    The energy Lloyd relaxation lowers, so sets of every sampler compare on one scale:
    0.160375 for the hexagonal lattice (the optimum), 1/6 for a square grid (less a term
    of order 1 / density from the discrete grid), 1/pi for the expectation over white
    noise. The points are rounded to the 2^22 integer torus first
    (:mod:`clsamp.geometry.integer_torus`), so both backends give the same bits. A
    CCVT's own energy (``energy_history`` of its info) counts each density point at the
    site that owns it, under equal capacities, and is never lower than this figure.

    Examples
    --------
    >>> import numpy as np
    >>> from clsamp.metrics import normalized_energy
    >>> g = (np.stack(np.meshgrid(np.arange(8), np.arange(8)), -1).reshape(-1, 2) + 0.5) / 8
    >>> round(normalized_energy(g), 5)
    0.16663
    """
    sets = point_sets(points)
    if sets is not None:
        return np.array([normalized_energy(p, density, backend) for p in sets])
    check_choice(backend, "backend", ("opencl", "numpy"))
    batch, single = check_points(points, "points", keep_device=backend == "opencl")
    if batch.shape[-1] != 2:
        raise InvalidArgumentError(
            f"'points' must be 2-D for normalized_energy, got d = {batch.shape[-1]}")
    backend = check_choice(backend, "backend", ("opencl", "numpy"))
    n = batch.shape[1]
    density = check_positive_int(density, "density", maximum=max(1, 2**31 // n))  # 32-bit counts
    if backend == "numpy":      # the twin's arrays: 96 B a density point (tracemalloc, 2^20 points)
        runtime.check_host_bytes(96 * n * density, f"a density grid of {n} x {density} points")
    energy = voronoi.cvt_energy(integer_torus.to_torus(batch), density, backend)
    out = batch.shape[1] * energy
    return float(out[0]) if single else out
