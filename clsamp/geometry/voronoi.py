"""Nearest-site assignment of a regular density grid, and the CVT energy it gives, in
d = 1 .. 4 dimensions.

The density is the regular g^d grid of cell centres on the integer torus
(:mod:`clsamp.geometry.integer_torus`), ``X_m = ((2 m + 1) 2^BITS) div (2 g)`` along each
axis, made from its index (m = Σ_a m_a g^a, x fastest) and never stored. Every density
point goes to its nearest site (ties to the smaller site index, as ``numpy.argmin``), and
each site gathers the exact sums of its points' offsets from it: one pass of Lloyd's
method, and the CVT energy E = mean squared distance from the density points to their
nearest site.

OpenCL: ``voronoi_build_grid`` (``kernels/voronoi.h``) sorts each realization's sites into
a grid of power-of-two cells, and ``voronoi_assign`` (``kernels/voronoi.cl``, built for one
d) finds every density point's nearest site by searching rings of cells until no
unvisited cell can hold a nearer one (exact), accumulating with integer atomics
(order-free, so deterministic).
NumPy reference: :func:`assign_reference` (brute force). Both give the same integers.
"""

import math

import numpy as np

from .. import runtime
from . import integer_torus as it

SEGMENT = 16       # density points of one row a work-item of voronoi_assign takes
DEFINES = {**it.DEFINES, "VOR_SEGMENT": SEGMENT}
DIMENSIONS = (1, 2, 3, 4)


def defines(d=2):
    """Build options of the kernels on the integer torus for d-dimensional sites (2-D needs
    no VOR_DIM: the header's default, CCVT's).

    Parameters
    ----------
    d : int

    Returns
    -------
    dict
    """
    return DEFINES if d == 2 else {**DEFINES, "VOR_DIM": d}


def site_grid_size(n, d=2):
    """Cells per axis of the site grid: the largest power of two G with G^d <= n (1 to 2^d
    sites a cell); a power of two makes every cell exactly 2^BITS / G wide. A finer grid
    costs more in visiting the 3^d cells around a point than it saves in sites to test
    (docs/performance.md, "Lloyd in 3-D and 4-D (issue 37)").

    Parameters
    ----------
    n : int
        Sites.
    d : int
        Dimension.

    Returns
    -------
    int

    Examples
    --------
    >>> site_grid_size(3), site_grid_size(16), site_grid_size(1024), site_grid_size(1024, 4)
    (1, 4, 32, 4)
    """
    G = 1
    while (2 * G) ** d <= n:
        G *= 2
    return G


def density_side(n, density, d=2):
    """Side g of the regular g^d density grid: the smallest with g^d >= n * density.

    Parameters
    ----------
    n : int
        Sites.
    density : int
        Density points per site.
    d : int
        Dimension.

    Returns
    -------
    int

    Examples
    --------
    >>> density_side(1024, 256), density_side(10, 10), density_side(1024, 256, 4)
    (512, 10, 23)
    """
    target = n * density
    if d == 2:
        return math.isqrt(target - 1) + 1
    g = max(1, int(round(target ** (1.0 / d))))
    while g**d < target:
        g += 1
    while g > 1 and (g - 1) ** d >= target:
        g -= 1
    return g


def density_coordinates(g):
    """Integer coordinates of the density grid's cell centres along one axis.

    Parameters
    ----------
    g : int
        Side of the density grid.

    Returns
    -------
    ndarray of int64
        (g,): ``floor((2k + 1) 2^BITS / (2g))``, the centres rounded down.
    """
    k = np.arange(g, dtype=np.int64)
    return ((2 * k + 1) << it.BITS) // (2 * g)


def density_point(m, g, d):
    """Integer coordinates of density point m (m = Σ_a m_a g^a).

    Parameters
    ----------
    m : int or ndarray of int
        Indices into the g^d grid.
    g, d : int
        Side and dimension of the density grid.

    Returns
    -------
    ndarray of int64
        (..., d).
    """
    coords = density_coordinates(g)
    m = np.asarray(m, dtype=np.int64)
    return np.stack([coords[(m // g**a) % g] for a in range(d)], axis=-1)


def segment_count(g, d=2):
    """Work-items of voronoi_assign per realization: each of the g^(d-1) lines along x of
    the density grid in pieces of SEGMENT points.

    Parameters
    ----------
    g : int
        Side of the density grid.
    d : int
        Dimension.

    Returns
    -------
    int
    """
    return g ** (d - 1) * (-(-g // SEGMENT))


def segment_far(d2, g):
    """Each segment's farthest density point, as the kernel's far_d2 and far_index: where
    an empty site is re-seeded.

    Parameters
    ----------
    d2 : ndarray of int64
        (g^d,) squared distances of the density points to their sites
        (:func:`assign_reference`).
    g : int
        Side of the density grid.

    Returns
    -------
    d2 : ndarray of int64
        (:func:`segment_count`,): each segment's largest squared distance.
    index : ndarray of int64
        The density point it belongs to (the first on a tie).
    """
    per_row = -(-g // SEGMENT)
    lines = d2.size // g
    padded = np.full((lines, per_row * SEGMENT), -1, dtype=np.int64)
    padded[:, :g] = d2.reshape(lines, g)
    blocks = padded.reshape(lines * per_row, SEGMENT)
    arg = np.argmax(blocks, axis=1)
    seg = np.arange(lines * per_row)
    return blocks[seg, arg], (seg // per_row) * g + (seg % per_row) * SEGMENT + arg


def assign_reference(sites, g):
    """Nearest site of every density point of one realization, brute force in chunks.

    Parameters
    ----------
    sites : ndarray (n, d)
        Integer torus coordinates, d = 1 .. 4.
    g : int
        Side of the density grid.

    Returns
    -------
    label, d2 : ndarray (g^d,) of int64
        The nearest site (ties to the smaller index) and the squared distance to it, for
        density point m = Σ_a m_a g^a (in 2-D row * g + column).
    offsets : ndarray (g^d, d) of int64
        Each point's offset from its site along every axis.
    """
    n, d = sites.shape
    M = g**d
    X = density_point(np.arange(M, dtype=np.int64), g, d)
    label = np.empty(M, dtype=np.int64)
    best = np.empty(M, dtype=np.int64)
    step = max(1, (1 << 21) // n)
    S = sites.astype(np.int64)
    for lo in range(0, M, step):
        hi = min(M, lo + step)
        d2 = np.zeros((hi - lo, n), dtype=np.int64)
        for a in range(d):
            delta = it.delta(X[lo:hi, a, None], S[None, :, a])
            d2 += delta * delta
        label[lo:hi] = np.argmin(d2, axis=1)
        best[lo:hi] = d2[np.arange(hi - lo), label[lo:hi]]
    return label, best, it.delta(X, S[label])


class DeviceAssignment:
    """The assignment pass on the device for r realizations of n sites, buffers made once.

    Each call ``assign(sites, t)`` (``sites`` a device array (r, n, d) of uint32) sorts the
    sites into their grid and adds, per site, (the sums of its density points' offsets
    along each axis, their count) to ``acc`` (r, n, d + 1) int64, and the pass's sum of
    squared distances to entry t of ``energy`` (r, passes, 2) as (low 32 bits, high
    bits); ``far_d2`` / ``far_index`` get each segment's farthest point. The caller
    clears ``acc`` between passes.

    Parameters
    ----------
    r, n : int
        Realizations and sites.
    g : int
        Side of the density grid.
    passes : int
        Passes whose energies are kept (entries of ``energy``).
    d : int
        Dimension, 1 .. 4.
    """

    def __init__(self, r, n, g, passes, d=2):
        import pyopencl.array as cla
        q = runtime.queue()
        self.r, self.n, self.g, self.passes, self.d = r, n, g, passes, d
        self.G = site_grid_size(n, d)
        self.segments = segment_count(g, d)
        self.cell_start = cla.empty(q, (r, self.G**d + 1), np.uint32)
        self.cell_sites = cla.empty(q, (r, n), np.uint32)
        self.acc = cla.zeros(q, (r, n, d + 1), np.int64)
        self.energy = cla.zeros(q, (r, passes, 2), np.int64)
        self.far_d2 = cla.empty(q, (r, self.segments), np.int64)
        self.far_index = cla.empty(q, (r, self.segments), np.uint32)
        self._build = runtime.kernel("voronoi.cl", "voronoi_build_grid", defines(d))
        self._assign = runtime.kernel("voronoi.cl", "voronoi_assign", defines(d))

    def __call__(self, sites, t):
        q = runtime.queue()
        u32 = np.uint32
        r, n, G = self.r, self.n, self.G
        self._build(q, (r,), None, sites.data, u32(n), u32(G), self.cell_start.data,
                    self.cell_sites.data, u32(r))
        self._assign(q, (self.segments, r), None, sites.data, u32(n), u32(G),
                     self.cell_start.data, self.cell_sites.data, u32(self.g), u32(self.segments),
                     self.acc.data, self.energy.data, u32(2 * self.passes), u32(2 * t),
                     self.far_d2.data, self.far_index.data)

    def energies(self):
        """Per realization, the exact energy sums of every pass.

        Returns
        -------
        list of list of int
            ``[k][t]``: realization k's sum of squared distances in pass t, exact.
        """
        e = self.energy.get()
        return [it.exact_total(e[k, :, 0], e[k, :, 1]) for k in range(self.r)]


def require_device(what):
    """Refuse where the assignment pass cannot run: it needs 64-bit integer atomics (not
    fp64: every quantity is an exact integer) and loops long per work-item.

    Parameters
    ----------
    what : str
        The caller, named in the message.

    Raises
    ------
    NoDeviceError
        The current device lacks ``cl_khr_int64_base_atomics`` or stops long loops.
    """
    runtime.require_extension("cl_khr_int64_base_atomics", what)
    runtime.require_short_loops(what)


def energy_scale(g, d=2):
    """The divisor that turns an exact energy sum into E: g^d density points, each
    distance in units of 2^-BITS.

    Parameters
    ----------
    g : int
        Side of the density grid.
    d : int
        Dimension.

    Returns
    -------
    float
        g^d 2^(2 BITS).
    """
    return float(g**d) * float(it.SIZE) ** 2


def cvt_energy(sites, density, backend="opencl"):
    """The CVT energy E of each realization: the mean squared toroidal distance from the
    points of the regular density grid to their nearest site.

    Parameters
    ----------
    sites : ndarray or pyopencl.array.Array (r, n, d) of uint32, d = 1 .. 4
        Integer torus coordinates (on the device already, for the OpenCL backend).
    density : int
        Density points per site: the grid has side g = :func:`density_side` (n, density, d).
    backend : {"opencl", "numpy"}

    Returns
    -------
    ndarray (r,) of float64
        Exact sums divided once, so both backends give the same bits.
    """
    r, n, d = sites.shape
    g = density_side(n, density, d)
    if backend == "numpy":
        sites = runtime.to_host(sites)
        totals = [it.split_total(assign_reference(sites[k].astype(np.int64), g)[1])
                  for k in range(r)]
    else:
        require_device("cvt_energy")
        d_sites = runtime.to_device(sites if runtime.is_device_array(sites)
                                    else np.asarray(sites, dtype=np.uint32))
        assignment = DeviceAssignment(r, n, g, 1, d)
        assignment(d_sites, 0)
        totals = [e[0] for e in assignment.energies()]
    return np.array([float(v) for v in totals]) / energy_scale(g, d)
