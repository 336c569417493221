"""Pair statistics on the unit torus or in the unit cube, in any dimension: the pair
correlation function and the distances to the nearest neighbour, in O(n) work per set
through a grid of cells.

Distances wrap by default (:mod:`clsamp.geometry.torus`): coordinate differences
``min(|a - b|, 1 - |a - b|)``, squares summed from the first coordinate to the last, the
operations of the Poisson-disk kernels, so the nearest-neighbour distances of a set that
promises "min distance >= r" check out bit for bit. ``periodic=False`` measures in the
unit cube instead (no wrapping; the PCF with the translation edge correction).
"""

import math

import numpy as np

from .. import runtime
from ..errors import InvalidArgumentError
from ..float_float import U2, argument, check_precision, exp_coefficients, split
from ..geometry.cells import cells_for, sorted_by_cell
from ..geometry.torus import distance2
from ..validation import check_bool, check_choice, check_points, check_positive_int, check_real, point_sets

BACKENDS = ("opencl", "numpy")
RADII = 100                  # default radii: 100, up to RADII_SPAN mean spacings
RADII_SPAN = 3.0
SIGMA_SPACING = 0.05         # default sigma: this many mean spacings
CUT = 5.0                    # the Gaussian is cut at CUT sigma (and so is its normalisation)
POINTS_PER_ITEM = 16         # PPI of pcf_sums
NN_CELL_SPACINGS = 1.5       # nearest neighbours: cells this many mean spacings wide


def mean_spacing(n, d):
    """The side of the cube each of n points has on the unit torus, n^(-1/d).

    Parameters
    ----------
    n, d : int
        Points and dimensions.

    Returns
    -------
    float
    """
    return float(check_positive_int(n, "n")) ** (-1.0 / check_positive_int(d, "d"))


def _check_sets(points, name="points"):
    """(a list of (n_k, d) arrays, single) with n_k >= 2: the sets a pair statistic needs."""
    sets = point_sets(points, name)
    single = False
    if sets is None:
        batch, single = check_points(points, name)
        sets = list(batch)
    small = [len(s) for s in sets if len(s) < 2]
    if small:
        raise InvalidArgumentError(
            f"'{name}' must hold at least 2 points per set (pairs are counted), got {small[0]}")
    return sets, single


# ---------------------------------------------------------------------- pair correlation


def _gauss_legendre(m=64):
    nodes, weights = np.polynomial.legendre.leggauss(m)
    return nodes, weights


def pcf_normalisation(radii, sigma, d, cut=CUT):
    """The expected kernel sum per ordered pair of uniform points on the torus, by which the
    pair sums are divided so that a Poisson (binomial) process gives exactly 1 at every
    radius (for r + cut sigma <= 1/2).

    It is the integral of the cut Gaussian K against the sphere's surface c_d s^(d-1),
    by 64-point Gauss-Legendre quadrature.

    Parameters
    ----------
    radii : ndarray
    sigma : float
        The Gaussian's standard deviation.
    d : int
    cut : float, optional
        Where the Gaussian is cut, in sigmas.

    Returns
    -------
    ndarray
        One value per radius.
    """
    surface = 2.0 * math.pi ** (d / 2) / math.gamma(d / 2)          # 2, 2 pi, 4 pi
    nodes, weights = _gauss_legendre()
    lo = np.maximum(0.0, radii - cut * sigma)
    hi = radii + cut * sigma
    half = 0.5 * (hi - lo)
    s = (lo + hi)[:, None] * 0.5 + half[:, None] * nodes[None, :]
    kernel = np.exp(-((radii[:, None] - s) ** 2) / (2.0 * sigma * sigma)) / (math.sqrt(2.0 * math.pi) * sigma)
    return surface * np.sum(weights[None, :] * kernel * s ** (d - 1), axis=1) * half


def _pcf_sums_reference(points, radii, sigma, cut, periodic=True):
    """NumPy twin of pcf_sums for one set: every unordered pair within reach, each
    radius' Gaussian evaluated directly (weighted by the translation edge correction in
    the cube)."""
    n = len(points)
    reach2 = (radii[-1] + cut * sigma) ** 2
    out = np.zeros(len(radii))
    step = max(1, (1 << 22) // max(1, n))
    for lo in range(0, n - 1, step):
        rows = np.arange(lo, min(n - 1, lo + step))
        d2 = distance2(points[rows, None, :], points[None, :, :], periodic)
        i, j = np.nonzero((np.arange(n)[None, :] > rows[:, None]) & (d2 < reach2))
        s = np.sqrt(d2[i, j])
        t = radii[None, :] - s[:, None]
        w = np.where(np.abs(t) <= cut * sigma, np.exp(-(t * t) / (2.0 * sigma * sigma)), 0.0)
        if not periodic:
            w = w / np.prod(1.0 - np.abs(points[rows[i]] - points[j]), axis=1)[:, None]
        out += w.sum(axis=0)
    return out


def _pcf_sums_device(sets, radii, sigma, cut, uniform, periodic=True, precision="double"):
    """pcf_sums for sets of one size: (r, NR) sums over each set's unordered pairs."""
    r, (n, d) = len(sets), sets[0].shape
    batch = np.stack(sets)
    reach = float(radii[-1] + cut * sigma)
    cells = cells_for(reach, n, d, cells_a_point=4.0)
    pts, cell, start, _ = sorted_by_cell(batch, cells)
    if precision == "float-float":
        return _pcf_sums_ff(pts, cell, start, r, n, d, cells, radii, sigma, cut, reach, periodic, uniform)
    items = -(-n // POINTS_PER_ITEM)
    defines = {"D": d, "NR": len(radii), "UNIFORM": int(uniform), "PPI": POINTS_PER_ITEM,
               "PERIODIC": int(periodic)}
    kernel = runtime.kernel("neighbors.cl", "pcf_sums", defines)
    q = runtime.queue()
    step = float(radii[1] - radii[0]) if len(radii) > 1 else 1.0
    inv2s2 = 1.0 / (2.0 * sigma * sigma)
    out = runtime.Output((r, items, len(radii)), np.float64,
                         host=np.empty((r, items, len(radii))))
    kernel(q, (items, r), None, *(runtime.to_device(a).data for a in (pts, cell, start)),
           np.uint32(n), np.int32(cells), np.uint32(3 ** d if cells > 1 else 1),
           np.float64(reach * reach), runtime.to_device(radii).data, np.float64(radii[0]),
           np.float64(step), np.float64(1.0 / step), np.float64(inv2s2), np.float64(cut * sigma),
           np.float64(math.exp(-2.0 * step * step * inv2s2)), np.uint32(items), out.buffer)
    return out.finish().sum(axis=1)


def pcf_float_float_bound(n, d, radii, sigma, periodic=True):
    """The relative error of a float-float pair correlation (``precision="float-float"``).

    Parameters
    ----------
    n, d : int
        Points per set and dimensions.
    radii : ndarray
    sigma : float
        As :func:`pair_correlation` used them (its returned radii; sigma defaults to 0.05
        mean spacings, ``SIGMA_SPACING * mean_spacing(n, d)``).
    periodic : bool

    Returns
    -------
    float
        ε with |g_float-float(r) - g(r)| <= ε·g(r) at every radius: u²·(T + 48(n - 1)),
        u = 2^-24, T = 5·(8√d + (4d + 36)·ρ) / σ + 190 (+ 30d + 15 in the cube), ρ the
        reach (largest radius plus 5σ); for uniform radii T·(m + 1) + 3m² instead of T,
        m = 10σ / step + 1 the radii a pair's Gaussian reaches.

    Notes
    -----
    Every term is positive, so relative errors of the terms and of their sums bound the
    result's. With the float-float errors of Joldes, Muller & Popescu 2017: a coordinate
    difference is within 8u² (the split into pairs, a subtraction, the wrap), the
    distance s within 8√d·u² + (4d + 32)u²·s (the squares, the sum, the square root),
    the kernel's argument -(r - s)²/2σ² within 5·Δ(r - s)/σ absolute for |r - s| <= 5σ,
    its exponential within about 50u² (the reduction by k ln 2 and the Horner steps);
    the edge correction's product and division add (30d + 15)u². Uniform radii take the
    Gaussian along them by the recurrence e_{k+1} = e_k·a_k, a_{k+1} = a_k·b: after m
    steps e carries m times the error of a_0 (at most T) and m² times 3u² from the
    products and b's split. A work-item adds at most
    16(n - 1) terms into a radius' sum, 3u² each, relative. Not counted: a pair whose
    distance lies within that error of the cut (5σ) or of the reach, which one path
    counts and the other not (a term of e^-12.5 ≈ 3.7e-6).
    """
    radii = np.asarray(radii, dtype=np.float64)
    reach = float(np.max(radii)) + CUT * sigma
    term = 5.0 * (8.0 * math.sqrt(d) + (4.0 * d + 36.0) * reach) / sigma + 190.0
    term += 0.0 if periodic else 30.0 * d + 15.0
    if _uniform(radii):
        m = 2.0 * CUT * sigma / float(radii[1] - radii[0]) + 1.0
        term = term * (m + 1.0) + 3.0 * m * m
    return (term + 3.0 * POINTS_PER_ITEM * (n - 1)) * U2


def _uniform(radii):
    """Whether radii are r0 + k·step (the kernels' recurrence along them)."""
    return len(radii) > 1 and bool(np.allclose(np.diff(radii), radii[1] - radii[0], rtol=1e-9, atol=0.0))


def _pcf_sums_ff(pts, cell, start, r, n, d, cells, radii, sigma, cut, reach, periodic, uniform):
    """pcf_sums_ff (kernels/neighbors_ff.cl): the pair sums in float-float, (r, NR)."""
    limit = runtime.loop_limit()
    ppi = POINTS_PER_ITEM if limit is None else 1
    if limit is not None:
        # a work-item's loops: the stencil's points, each over every radius
        stencil = (3 ** d if cells > 1 else 1) * n / cells ** d + 1
        if ppi * stencil * (len(radii) + 2) > limit // 2:
            runtime.require_short_loops("the float-float pair correlation at these radii")
    items = -(-n // ppi)
    coef = runtime.table("float_float exp", exp_coefficients, np.float32)
    out = runtime.Output((r, items, len(radii), 2), np.float32,
                         host=np.empty((r, items, len(radii), 2), np.float32))
    step = float(radii[1] - radii[0]) if len(radii) > 1 else 1.0
    inv2s2 = 1.0 / (2.0 * sigma * sigma)
    runtime.kernel("neighbors_ff.cl", "pcf_sums_ff", {"D": d, "NR": len(radii), "PPI": ppi,
                                                      "PERIODIC": int(periodic), "UNIFORM": int(uniform)})(
        runtime.queue(), (items, r), None,
        *(runtime.to_device(a).data for a in (split(pts), cell, start)), np.uint32(n), np.int32(cells),
        np.uint32(3 ** d if cells > 1 else 1), argument(reach * reach), runtime.to_device(split(radii)).data,
        argument(inv2s2), argument(cut * sigma), coef.data, argument(step), argument(step * step),
        argument(math.exp(-2.0 * step * step * inv2s2)), np.float32(1.0 / step), np.uint32(items),
        out.buffer)
    pairs = out.finish().astype(np.float64)
    return (pairs[..., 0] + pairs[..., 1]).sum(axis=1)


def _check_radii(radii, sigma, spacing, cut):
    if sigma is None:
        sigma = SIGMA_SPACING * spacing
    sigma = check_real(sigma, "sigma", minimum=0.0, open_minimum=True)
    if radii is None:
        # up to RADII_SPAN spacings, or to where the reach stays within 1/2 (few points in
        # many dimensions, whose spacing is a large part of the unit)
        span = min(RADII_SPAN * spacing, 0.5 - cut * sigma)
        while span > 0 and span + cut * sigma > 0.5:      # 0.5 - c + c may round above 1/2
            span = np.nextafter(span, 0.0)
        if span <= 0:
            raise InvalidArgumentError(
                f"'sigma' {sigma:.4g} leaves no radius within 1/2 at a cut of {cut:g} sigma")
        radii = np.minimum(span * np.arange(1, RADII + 1) / RADII, span)  # the last may round up
    else:
        try:
            radii = np.asarray(radii, dtype=np.float64)
        except (TypeError, ValueError):
            raise InvalidArgumentError(f"'radii' must be a 1-D array of radii, got {radii!r}") from None
        if radii.ndim != 1 or len(radii) < 1:
            raise InvalidArgumentError(f"'radii' must be a 1-D array of radii, got shape {radii.shape}")
        if not np.all(np.isfinite(radii)) or np.any(radii <= 0) or np.any(np.diff(radii) <= 0):
            raise InvalidArgumentError("'radii' must be positive, finite and increasing")
    if radii[-1] + cut * sigma > 0.5:
        raise InvalidArgumentError(
            f"'radii' up to {radii[-1]:.4g} plus {cut:g} sigma ({cut * sigma:.4g}) reach past "
            "1/2 (half the torus, half the cube's side), where the pair sums stop measuring "
            "the PCF; use smaller radii or sigma")
    if len(radii) > 4096:
        raise InvalidArgumentError(f"'radii' may hold at most 4096 radii, got {len(radii)}")
    if np.any(radii + cut * sigma == np.maximum(radii - cut * sigma, 0.0)):
        raise InvalidArgumentError(f"'sigma' {sigma:.4g} is too small for the radii: their kernel "
                                   "windows round to nothing")
    return radii, sigma


def pair_correlation(points, radii=None, sigma=None, backend="opencl", periodic=True, precision=None):
    """The pair correlation function g(r) of a point set, or its expectation over sets.

    Parameters
    ----------
    points : ndarray (n, d) or (r, n, d), or a list of (n_k, d) arrays
        Points in [0, 1)^d, any d >= 1, n >= 2 per set. A batch or list gives the
        expected PCF: the mean of the sets' PCFs.
    radii : array_like, optional
        Increasing positive radii (distances on the unit torus). Default: 100 radii up to
        3 mean spacings, the mean spacing being n^(-1/d), or up to 1/2 - 5 sigma where that
        is shorter (few points in many dimensions).
    sigma : float, optional
        The standard deviation of the Gaussian smoothing kernel; default 0.05 mean
        spacings. The kernel is cut at 5 sigma; radii + 5 sigma must stay below 1/2.
    backend : {"opencl", "numpy"}
    periodic : bool
        True: distances on the torus (a sampler's periodic set). False: in the unit cube,
        for sets that are not periodic, each pair weighted by the translation edge
        correction 1 / prod_k (1 - |x_k - y_k|) (Ohser 1983), the inverse of the volume
        of the cube and its translate's overlap, so that a Poisson process still gives 1.
    precision : {"double", "float-float"}, optional
        What the device computes the pair sums in; default ``"double"`` where the device
        has fp64, ``"float-float"`` where it has not, within :func:`pcf_float_float_bound`
        of the double result (each radius' Gaussian evaluated directly, no recurrence).

    Returns
    -------
    radii : ndarray (R,)
    pcf : ndarray (R,)
        1 for a Poisson process at every radius; below 1 where pairs are rarer than
        chance (the blue-noise dip at small r), above where they are more common.

    Notes
    -----
    The estimator of Oztireli and Gross (2012) on the torus,

        g(r) = sum_{i != j} K_sigma(r - |x_i - x_j|) / (n (n - 1) N(r)),

    with K_sigma the Gaussian density and N(r) = integral of K_sigma(r - s) c_d s^(d-1)
    ds (c_d s^(d-1) the sphere's surface: 2 pi s in 2-D), the expected sum for uniform
    points divided by n (n - 1). Dividing by N(r) rather than by the surface at r keeps
    g = 1 for a Poisson process even at radii below a few sigma. Pairs come from the
    neighbouring cells of a grid as wide as the largest radius plus the cut, so the work
    is O(n) per set for radii of a few mean spacings; on the device each unordered pair
    is met once (a half stencil of cells) and adds its Gaussian to the radii within the
    cut by a recurrence (two exp per pair, evaluated four pairs at a time).

    References
    ----------
    .. [1] A. C. Oztireli, M. Gross, "Analysis and synthesis of point distributions
       based on pair correlation", ACM TOG 31(6), 2012.
    .. [2] D. Heck, T. Schlomer, O. Deussen, "Blue noise sampling with controlled
       aliasing", ACM TOG 32(3), 2013.
    .. [3] J. Ohser, "On estimators for the reduced second moment measure of point
       processes", Math. Operationsforsch. Statist., Ser. Statistics 14(1), 1983.

    Examples
    --------
    >>> import clsamp
    >>> pts = clsamp.make_sampler("random", d=2, seed=3).sample(4096, realizations=8)
    >>> r, g = clsamp.pair_correlation(pts)
    >>> bool(abs(g[50:].mean() - 1) < 0.02)
    True
    """
    check_choice(backend, "backend", BACKENDS)
    periodic = check_bool(periodic, "periodic")
    precision = check_precision(precision, backend)
    sets, _ = _check_sets(points, "points")
    d = sets[0].shape[1]
    spacing = mean_spacing(min(len(s) for s in sets), d)
    radii, sigma = _check_radii(radii, sigma, spacing, CUT)
    uniform = _uniform(radii)
    sums = np.zeros((len(sets), len(radii)))
    if backend == "numpy":
        for k, s in enumerate(sets):
            sums[k] = _pcf_sums_reference(s, radii, sigma, CUT, periodic)
    else:
        sizes = sorted({len(s) for s in sets})
        for size in sizes:
            idx = [k for k, s in enumerate(sets) if len(s) == size]
            per_set = 8 * size * d + 8 * size + 8 * len(radii) * (-(-size // POINTS_PER_ITEM))
            for lo, hi in runtime.chunk_ranges(len(idx), per_set):
                part = idx[lo:hi]
                sums[part] = _pcf_sums_device([sets[k] for k in part], radii, sigma, CUT, uniform,
                                              periodic, precision)
    norm = pcf_normalisation(radii, sigma, d)
    kernel_scale = 1.0 / (math.sqrt(2.0 * math.pi) * sigma)
    counts = np.array([len(s) * (len(s) - 1) for s in sets], dtype=np.float64)
    pcf = (2.0 * kernel_scale * sums / counts[:, None]) / norm[None, :]
    return radii, pcf.mean(axis=0)


# ------------------------------------------------------------------ nearest neighbours


def nearest_neighbor_reference(points, periodic=True):
    """NumPy twin of :func:`nearest_neighbor_distances` for one set: every pair compared.

    Parameters
    ----------
    points : ndarray (n, d)
        One checked set.
    periodic : bool
        As :func:`nearest_neighbor_distances` takes it.

    Returns
    -------
    ndarray (n,)
        Each point's distance on the torus (or in the cube) to its nearest other point.
    """
    n = len(points)
    best = np.empty(n)
    step = max(1, (1 << 22) // max(1, n))
    for lo in range(0, n, step):
        d2 = distance2(points[lo:lo + step, None, :], points[None, :, :], periodic)
        d2[np.arange(len(d2)), np.arange(lo, lo + len(d2))] = np.inf
        best[lo:lo + step] = d2.min(axis=1)
    return np.sqrt(best)


def float_float_bound(distances, d):
    """How far a float-float nearest-neighbour distance may be from the double one.

    Parameters
    ----------
    distances : ndarray
        Nearest-neighbour distances s (either path's).
    d : int

    Returns
    -------
    ndarray
        2u²·(8√d + (4 + 2d)·s), u = 2^-24, per distance; 0 difference in practice.

    Notes
    -----
    The kernel chooses the nearest neighbour by float-float squared distances and the
    host computes the chosen pair's distance in float64, so the result is the double
    path's bits unless another candidate lies within the float-float error. Each
    coordinate difference is within 8u² of its value (the split of the two points into
    pairs, 2^-49 each, a subtraction and the wrap, 3u² relative each, Joldes, Muller &
    Popescu 2017), so a float-float distance is within 8√d·u² + (3 + 2d)u²·s of the
    exact one (the squares and the sum, 5u² and 3u² relative), and the chosen
    neighbour's distance within twice that of the nearest; the float64 rounding of the
    two paths adds less than u²·s.
    """
    s = np.asarray(distances, dtype=np.float64)
    return 2.0 * U2 * (8.0 * math.sqrt(d) + (4.0 + 2.0 * d) * s)


def _nearest_device(batch, periodic=True, precision="double"):
    """Squared nearest-neighbour distances (r, n) of sets of one size, in their order."""
    r, n, d = batch.shape
    cells = int(math.floor(1.0 / (NN_CELL_SPACINGS * mean_spacing(n, d))))
    cells = cells if cells >= 3 and cells ** d * r < 2**31 else 1
    pts, cell, start, order = sorted_by_cell(batch, cells)
    total = r * n
    local = runtime.local_size(64)
    grid = (np.uint32(n), np.uint32(total), np.int32(cells), np.uint32(3 ** d if cells > 1 else 1))
    defines = {"D": d, "PERIODIC": int(periodic)}
    if precision == "float-float":
        # the nearest by float-float distances, its distance in float64 here
        best = runtime.Output((total,), np.uint32, host=np.empty(total, np.uint32))
        runtime.kernel("neighbors_ff.cl", "nearest_neighbor_ff", defines)(
            runtime.queue(), (-(-total // local) * local,), (local,),
            *(runtime.to_device(a).data for a in (split(pts), cell, start)), *grid, best.buffer)
        best = best.finish().astype(np.int64)
        flat = pts.reshape(total, d)
        d2_sorted = np.full(total, np.inf)
        some = best != 0xFFFFFFFF
        d2_sorted[some] = distance2(flat[some], flat[best[some]], periodic)
    else:
        out = runtime.Output((total,), np.float64, host=np.empty(total))
        runtime.kernel("neighbors.cl", "nearest_neighbor", defines)(
            runtime.queue(), (-(-total // local) * local,), (local,),
            *(runtime.to_device(a).data for a in (pts, cell, start)), *grid, out.buffer)
        d2_sorted = out.finish()
    d2 = np.empty(total)
    d2[order] = d2_sorted
    d2 = d2.reshape(r, n)
    # a neighbour found farther than a cell may not be the nearest: those points are
    # measured against every point of their set
    if cells > 1:
        far = np.argwhere(d2 > (1.0 / cells) ** 2)
        for k, i in far:
            others = distance2(batch[k, i][None, :], batch[k], periodic)
            others[i] = np.inf
            d2[k, i] = others.min()
    return d2


def nearest_neighbor_distances(points, backend="opencl", periodic=True, precision=None):
    """The distance from each point to its nearest neighbour on the torus (or in the cube).

    Parameters
    ----------
    points : ndarray (n, d) or (r, n, d), or a list of (n_k, d) arrays
        Points in [0, 1)^d, any d >= 1, n >= 2 per set.
    backend : {"opencl", "numpy"}
    periodic : bool
        True: distances on the torus; False: in the unit cube (no wrapping).
    precision : {"double", "float-float"}, optional
        What the device compares distances in; default ``"double"`` where the device has
        fp64, ``"float-float"`` where it has not: the nearest neighbour is chosen in
        float-float and its distance computed in float64 on the host, the double path's
        bits unless two candidates lie within :func:`float_float_bound` (about 1e-13 of a
        unit) of each other.

    Returns
    -------
    ndarray (n,) for one set, (r, n) for a batch, a list of (n_k,) arrays for a list:
    the distances in the points' order. Their minimum is the set's minimum distance
    (:func:`min_distance`) where that is below 1 (on the torus from 5-D on two points
    can lie farther apart than 1, a point's distance to its own image, at which
    :func:`min_distance` stops); their distribution tells how evenly
    the points are spread (a delta at the lattice spacing, a Rayleigh law for white
    noise in 2-D: P(NN > r) = exp(-pi n r^2)).

    Notes
    -----
    Points are bucketed in cells 1.5 mean spacings wide and compared with the 3^d
    neighbouring cells; a nearest distance found there is exact when it is within one
    cell width, and the few points without such a neighbour are compared with every
    point. The distances are the bits of :func:`clsamp.geometry.torus.distance2`.

    Examples
    --------
    >>> import numpy as np, clsamp
    >>> grid = (np.stack(np.meshgrid(np.arange(8), np.arange(8)), -1).reshape(-1, 2) + 0.5) / 8
    >>> set(clsamp.nearest_neighbor_distances(grid).tolist())
    {0.125}
    """
    check_choice(backend, "backend", BACKENDS)
    periodic = check_bool(periodic, "periodic")
    precision = check_precision(precision, backend)
    listed = point_sets(points) is not None
    sets, single = _check_sets(points, "points")
    if backend == "numpy":
        out = [nearest_neighbor_reference(s, periodic) for s in sets]
    else:
        out = [None] * len(sets)
        for size in sorted({len(s) for s in sets}):
            idx = [k for k, s in enumerate(sets) if len(s) == size]
            for lo, hi in runtime.chunk_ranges(len(idx), 8 * size * (sets[0].shape[1] + 3)):
                part = idx[lo:hi]
                d2 = _nearest_device(np.stack([sets[k] for k in part]), periodic, precision)
                for row, k in enumerate(part):
                    out[k] = np.sqrt(d2[row])
    if listed:
        return out
    return out[0] if single else np.stack(out)
