"""The power-diagram pass of the CCVT start: every density point's two power-nearest
sites among those of the 3 x 3 cells of a grid around it.

OpenCL: ``ccvt_power`` (``kernels/ccvt_start.cl``); NumPy reference:
:func:`power_pass_reference`, the same integers.
"""

import math

import numpy as np

from ... import runtime
from ...geometry import integer_torus as it
from .pairs import NO_OWNER, NO_SECOND, ccvt_defines

START_OCCUPANCY = 2    # sites per cell of the start's grid: a 3 x 3 block offers about 18
START_CHUNK = 1 << 16  # candidate distances computed at once by the NumPy twin


def start_table(xy, ids, G, pad):
    """Candidate table of one realization for :func:`start_partition`: row c lists the
    sites (global ids, ascending, padded with ``pad``) of the 3 x 3 cells of a G x G grid
    around cell c, or all the sites when G == 1.

    Parameters
    ----------
    xy : ndarray of int64
        (n, 2) the realization's site coordinates.
    ids : ndarray of int
        (n,) the sites' ids.
    G : int
        Cells per axis (:func:`start_grid_size`).
    pad : int
        The id that fills short rows.

    Returns
    -------
    table : ndarray of int64
        (G * G, width).
    lengths : ndarray of int
        Each row's sites.
    """
    if G == 1:
        return ids[None, :].copy(), np.array([len(ids)])
    start, order = it.build_grid(xy, G)
    count = np.diff(start)
    cy, cx = np.divmod(np.arange(G * G), G)
    near = np.stack([((cy + oy) % G) * G + (cx + ox) % G
                     for oy in (-1, 0, 1) for ox in (-1, 0, 1)], axis=1).ravel()
    each = count[near]                              # sites in each (cell, neighbour) pair
    lengths = each.reshape(G * G, 9).sum(axis=1)
    total = int(each.sum())
    within = np.arange(total) - np.repeat(np.cumsum(each) - each, each)
    site = ids[order[np.repeat(start[near], each) + within]]
    col = np.arange(total) - np.repeat(np.cumsum(lengths) - lengths, lengths)
    table = np.full((G * G, max(1, int(lengths.max()))), pad, dtype=np.int64)
    table[np.repeat(np.arange(G * G), lengths), col] = site
    table.sort(axis=1)                              # index order: argmin breaks ties by index
    return table, lengths


def start_grid_size(n):
    """Cells per axis of the start's candidate grid: about START_OCCUPANCY sites per cell,
    and 1 (every site a candidate) below 4, where 3 x 3 cells would repeat.

    Parameters
    ----------
    n : int
        Sites.

    Returns
    -------
    int

    Examples
    --------
    >>> start_grid_size(16), start_grid_size(1024)
    (1, 22)
    """
    G = math.isqrt(n // START_OCCUPANCY)
    return G if G >= 4 else 1


def power_pass_reference(points, sites, weight, G):
    """NumPy twin of the ``ccvt_power`` kernel (``kernels/ccvt_start.cl``).

    For every point, the two smallest power distances ``|x - s_i|^2 - w_i`` (exact int64
    on the integer torus) among the sites of the 3 x 3 cells of a G x G grid around it
    (every site when G == 1), in the order (power distance, site index).

    Parameters
    ----------
    points : ndarray (r, M, 2) or (1, M, 2)
        Integer torus coordinates; one set of shape (1, M, 2) serves every realization.
    sites : ndarray (r, n, 2)
    weight : ndarray (r, n) of int64
    G : int
        1, or at least 4 (:func:`start_grid_size`).

    Returns
    -------
    owner, second : ndarray (r, M) of uint32
        Site indices; ``owner`` is ``NO_OWNER`` where no site is a candidate, ``second``
        equals ``owner`` where only one is.
    margin : ndarray (r, M) of int64
        Power distance to ``second`` minus that to ``owner`` (``NO_SECOND`` if none).
    """
    return PowerPass(sites, G, "numpy")(points, weight)


def power_pass_device(points, sites, weight, G):
    """:func:`power_pass_reference` by the ``ccvt_power`` kernel (the same integers).

    Parameters
    ----------
    points, sites, weight, G
        As :func:`power_pass_reference`.

    Returns
    -------
    owner, second, margin : ndarray
        As :func:`power_pass_reference`.
    """
    return PowerPass(sites, G, "opencl")(points, weight)


class PowerPass:
    """The power passes over one set of sites (:func:`power_pass_reference`), their
    candidate tables (and, in OpenCL, their buffers and the last point set's) prepared
    once.

    Parameters
    ----------
    sites : ndarray
        (r, n, 2) integer coordinates.
    G : int
        Cells per axis of the candidate grid (:func:`start_grid_size`).
    backend : {"opencl", "numpy"}
    """

    def __init__(self, sites, G, backend):
        self.sites, self.G, self.backend = sites, G, backend
        r, n, _ = sites.shape
        self.tables = [start_table(sites[k].astype(np.int64), np.arange(n), G, n)[0]
                       for k in range(r)]
        if backend == "numpy":
            return
        import pyopencl.array as cla
        q = runtime.queue()
        # every realization's table padded to one width W, as (r, cells, W)
        W = max(t.shape[1] for t in self.tables) if r else 1
        self.table = np.stack([np.pad(t, ((0, 0), (0, W - t.shape[1])), constant_values=n)
                               for t in self.tables]) if r else np.zeros((0, 1, 1), np.int64)
        padded = np.concatenate([np.asarray(sites, dtype=np.uint32),
                                 np.zeros((r, 1, 2), dtype=np.uint32)], axis=1)
        xy = padded[np.arange(r)[:, None, None], self.table]
        self.buffers = [cla.to_device(q, np.ascontiguousarray(a)) for a in
                        (self.table.astype(np.uint32), xy)]
        self.points = (None, None)

    def __call__(self, points, weight, owner_only=False):
        """One power pass.

        Parameters
        ----------
        points : ndarray or pyopencl.array.Array
            (r, M, 2) or (1, M, 2) integer coordinates.
        weight : ndarray of int64
            (r, n) the sites' power weights.
        owner_only : bool
            Return ``(owner,)`` alone.

        Returns
        -------
        tuple of ndarray
            (owner, second, margin), as :func:`power_pass_reference`.
        """
        if self.backend == "numpy":
            out = self._reference(points, weight)
        else:
            out = self._device(points, weight, owner_only)
        return out[:1] if owner_only else out

    def _device(self, points, weight, owner_only):
        import pyopencl.array as cla
        q = runtime.queue()
        r, n, _ = self.sites.shape
        M = points.shape[1]
        if self.points[0] is not points:            # the lattice serves every sweep
            self.points = (points, runtime.to_device(np.asarray(points, dtype=np.uint32)
                                                     if not runtime.is_device_array(points)
                                                     else points))
        owner = cla.empty(q, (r, M), np.uint32)
        second = cla.empty(q, (r, M), np.uint32)
        margin = cla.empty(q, (r, M), np.int64)
        if r and M:
            ids, xy = self.buffers
            w = np.concatenate([np.asarray(weight, dtype=np.int64), np.zeros((r, 1), np.int64)],
                               axis=1)[np.arange(r)[:, None, None], self.table]
            kernel = runtime.kernel("ccvt_start.cl", "ccvt_power", ccvt_defines())
            kernel(q, (M, r), None, self.points[1].data, np.uint32(M),
                   np.uint32(M if points.shape[0] > 1 else 0), ids.data, xy.data,
                   cla.to_device(q, np.ascontiguousarray(w)).data, np.uint32(n),
                   np.uint32(self.G), np.uint32(self.table.shape[2]),
                   owner.data, second.data, margin.data)
            runtime.wait()                      # Ctrl-C is taken while the pass runs
        if owner_only:
            return (owner.get(),)
        return owner.get(), second.get(), margin.get()

    def _reference(self, points, weight):
        sites = self.sites
        r, n, _ = sites.shape
        G = self.G
        M = points.shape[1]
        owner = np.empty((r, M), dtype=np.uint32)
        second = np.empty((r, M), dtype=np.uint32)
        margin = np.empty((r, M), dtype=np.int64)
        for k in range(r):
            xy = sites[k].astype(np.int64)
            table = self.tables[k]
            sx, sy = np.append(xy[:, 0], 0), np.append(xy[:, 1], 0)
            w = np.append(np.asarray(weight[k], dtype=np.int64), 0)
            pts = points[k if points.shape[0] > 1 else 0].astype(np.int64)
            cell = it.cell_of(pts[:, 1], G) * G + it.cell_of(pts[:, 0], G)
            width = max(1, START_CHUNK // table.shape[1])
            for lo in range(0, M, width):
                cand = table[cell[lo:lo + width]]
                dx = it.delta(pts[lo:lo + width, 0:1], sx[cand])
                dy = it.delta(pts[lo:lo + width, 1:2], sy[cand])
                c = dx * dx + dy * dy - w[cand]
                c[cand == n] = NO_SECOND
                rows = np.arange(len(cand))
                # rows are in ascending site order: the first minimum has the smallest index
                b1 = np.argmin(c, axis=1)
                c1 = c[rows, b1]
                c[rows, b1] = NO_SECOND
                b2 = np.argmin(c, axis=1)
                c2 = c[rows, b2]
                i1 = np.where(c1 == NO_SECOND, NO_OWNER, cand[rows, b1])
                lone = c2 == NO_SECOND
                owner[k, lo:lo + width] = i1
                second[k, lo:lo + width] = np.where(lone, i1, cand[rows, b2])
                margin[k, lo:lo + width] = np.where(lone, NO_SECOND, c2 - c1)
        return owner, second, margin


def power_counts(owner, n):
    """Points per site from a power pass's owners (points with none left out).

    Parameters
    ----------
    owner : ndarray of uint32
        (r, M), site indices or ``NO_OWNER``.
    n : int
        Sites.

    Returns
    -------
    ndarray of int64
        (r, n).
    """
    r = owner.shape[0]
    flat = owner.astype(np.int64) + (np.arange(r) * n)[:, None]
    flat = flat[owner != NO_OWNER]
    return np.bincount(flat, minlength=r * n).reshape(r, n)


def nearest_site2(sites, G, tables=None):
    """Squared distance from each site to its nearest other site among the 3 x 3 cells
    around it (every site when G == 1; SIZE^2 when it has none there).

    Parameters
    ----------
    sites : ndarray
        (r, n, 2) integer coordinates.
    G : int
        Cells per axis.
    tables : list of ndarray, optional
        The sites' :func:`start_table` rows, when already built.

    Returns
    -------
    ndarray of float64
        (r, n).
    """
    r, n, _ = sites.shape
    out = np.full((r, n), float(it.SIZE) ** 2)
    for k in range(r):
        xy = sites[k].astype(np.int64)
        table = start_table(xy, np.arange(n), G, n)[0] if tables is None else tables[k]
        cell = it.cell_of(xy[:, 1], G) * G + it.cell_of(xy[:, 0], G)
        nb = table[cell]
        ext = np.append(xy, [[0, 0]], axis=0)
        d2 = it.distance2(xy[:, 0:1], xy[:, 1:2], ext[nb, 0], ext[nb, 1]).astype(np.float64)
        d2[(nb == n) | (nb == np.arange(n)[:, None])] = np.inf
        out[k] = np.minimum(d2.min(axis=1), out[k])
    return out
