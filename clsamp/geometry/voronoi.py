"""Nearest-site assignment of a regular density grid, and the CVT energy it gives.

The density is the regular g x g grid of cell centres on the integer torus
(:mod:`clsamp.geometry.integer_torus`), ``X_m = ((2 m + 1) 2^BITS) div (2 g)`` along each
axis, made from its index and never stored. Every density point goes to its nearest site
(ties to the smaller site index, as ``numpy.argmin``), and each site gathers the exact
sums of its points' offsets from it: one pass of Lloyd's method, and the CVT energy
E = mean squared distance from the density points to their nearest site.

OpenCL: ``voronoi_build_grid`` (``kernels/voronoi.h``) sorts each realization's sites into
a grid of power-of-two cells, and ``voronoi_assign`` (``kernels/voronoi.cl``) finds every
density point's nearest site by searching rings of cells until no unvisited cell can hold
a nearer one (exact), accumulating with integer atomics (order-free, so deterministic).
NumPy reference: :func:`assign_reference` (brute force). Both give the same integers.
"""

import math

import numpy as np

from .. import runtime
from . import integer_torus as it

SEGMENT = 16       # density points of one row a work-item of voronoi_assign takes
DEFINES = {**it.DEFINES, "VOR_SEGMENT": SEGMENT}


def site_grid_size(n):
    """Cells per axis of the site grid: the largest power of two G with G^2 <= n (1 to 4
    sites a cell); a power of two makes every cell exactly 2^BITS / G wide.

    Parameters
    ----------
    n : int
        Sites.

    Returns
    -------
    int

    Examples
    --------
    >>> site_grid_size(3), site_grid_size(16), site_grid_size(1024)
    (1, 4, 32)
    """
    G = 1
    while 4 * G * G <= n:
        G *= 2
    return G


def density_side(n, density):
    """Side g of the regular g x g density grid: the smallest with g^2 >= n * density.

    Parameters
    ----------
    n : int
        Sites.
    density : int
        Density points per site.

    Returns
    -------
    int

    Examples
    --------
    >>> density_side(1024, 256), density_side(10, 10)
    (512, 10)
    """
    return math.isqrt(n * density - 1) + 1


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


def segment_count(g):
    """Work-items of voronoi_assign per realization: each row of the g x g density grid in
    pieces of SEGMENT points.

    Parameters
    ----------
    g : int
        Side of the density grid.

    Returns
    -------
    int
    """
    return g * (-(-g // SEGMENT))


def segment_far(d2, g):
    """Each segment's farthest density point, as the kernel's far_d2 and far_index: where
    an empty site is re-seeded.

    Parameters
    ----------
    d2 : ndarray of int64
        (g * g,) squared distances of the density points to their sites
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
    padded = np.full((g, per_row * SEGMENT), -1, dtype=np.int64)
    padded[:, :g] = d2.reshape(g, g)
    blocks = padded.reshape(g * per_row, SEGMENT)
    arg = np.argmax(blocks, axis=1)
    seg = np.arange(g * per_row)
    return blocks[seg, arg], (seg // per_row) * g + (seg % per_row) * SEGMENT + arg


def assign_reference(sites, g):
    """Nearest site of every density point of one realization, brute force in chunks.

    Parameters
    ----------
    sites : ndarray (n, 2)
        Integer torus coordinates.
    g : int
        Side of the density grid.

    Returns
    -------
    label, d2, dx, dy : ndarray (g * g,) of int64
        The nearest site (ties to the smaller index), the squared distance to it and the
        point's offset from it, for density point m = row * g + column.
    """
    coords = density_coordinates(g)
    M = g * g
    m = np.arange(M, dtype=np.int64)
    X, Y = coords[m % g], coords[m // g]
    n = sites.shape[0]
    label = np.empty(M, dtype=np.int64)
    best = np.empty(M, dtype=np.int64)
    step = max(1, (1 << 21) // n)
    sx, sy = sites[:, 0].astype(np.int64), sites[:, 1].astype(np.int64)
    for lo in range(0, M, step):
        hi = min(M, lo + step)
        d2 = it.distance2(X[lo:hi, None], Y[lo:hi, None], sx[None, :], sy[None, :])
        label[lo:hi] = np.argmin(d2, axis=1)
        best[lo:hi] = d2[np.arange(hi - lo), label[lo:hi]]
    return label, best, it.delta(X, sx[label]), it.delta(Y, sy[label])


class DeviceAssignment:
    """The assignment pass on the device for r realizations of n sites, buffers made once.

    Each call ``assign(sites, t)`` (``sites`` a device array (r, n, 2) of uint32) sorts the
    sites into their grid and adds, per site, (sum dx, sum dy, count) of its density
    points to ``acc`` (r, n, 3) int64, and the pass's sum of squared distances to entry t
    of ``energy`` (r, passes, 2) as (low 32 bits, high bits); ``far_d2`` / ``far_index``
    get each segment's farthest point. The caller clears ``acc`` between passes.

    Parameters
    ----------
    r, n : int
        Realizations and sites.
    g : int
        Side of the density grid.
    passes : int
        Passes whose energies are kept (entries of ``energy``).
    """

    def __init__(self, r, n, g, passes):
        import pyopencl.array as cla
        q = runtime.queue()
        self.r, self.n, self.g, self.passes = r, n, g, passes
        self.G = site_grid_size(n)
        self.segments = segment_count(g)
        self.cell_start = cla.empty(q, (r, self.G * self.G + 1), np.uint32)
        self.cell_sites = cla.empty(q, (r, n), np.uint32)
        self.acc = cla.zeros(q, (r, n, 3), np.int64)
        self.energy = cla.zeros(q, (r, passes, 2), np.int64)
        self.far_d2 = cla.empty(q, (r, self.segments), np.int64)
        self.far_index = cla.empty(q, (r, self.segments), np.uint32)
        self._build = runtime.kernel("voronoi.cl", "voronoi_build_grid", DEFINES)
        self._assign = runtime.kernel("voronoi.cl", "voronoi_assign", DEFINES)

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


def energy_scale(g):
    """The divisor that turns an exact energy sum into E: g^2 density points, each
    distance in units of 2^-BITS.

    Parameters
    ----------
    g : int
        Side of the density grid.

    Returns
    -------
    float
        g^2 2^(2 BITS).
    """
    return float(g * g) * float(it.SIZE) ** 2


def cvt_energy(sites, density, backend="opencl"):
    """The CVT energy E of each realization: the mean squared toroidal distance from the
    points of the regular density grid to their nearest site.

    Parameters
    ----------
    sites : ndarray or pyopencl.array.Array (r, n, 2) of uint32
        Integer torus coordinates (on the device already, for the OpenCL backend).
    density : int
        Density points per site: the grid has side g = :func:`density_side` (n, density).
    backend : {"opencl", "numpy"}

    Returns
    -------
    ndarray (r,) of float64
        Exact sums divided once, so both backends give the same bits.
    """
    r, n, _ = sites.shape
    g = density_side(n, density)
    if backend == "numpy":
        sites = runtime.to_host(sites)
        totals = [it.split_total(assign_reference(sites[k].astype(np.int64), g)[1])
                  for k in range(r)]
    else:
        require_device("cvt_energy")
        d_sites = runtime.to_device(sites if runtime.is_device_array(sites)
                                    else np.asarray(sites, dtype=np.uint32))
        assignment = DeviceAssignment(r, n, g, 1)
        assignment(d_sites, 0)
        totals = [e[0] for e in assignment.energies()]
    return np.array([float(v) for v in totals]) / energy_scale(g)
