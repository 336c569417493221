"""Exact power cells on the unit torus and BNOT over them: ``bnot``'s ``cells="exact"``.

de Goes, Breeden, Ostromoukhov and Desbrun (2012) solve for the power weights with the
exact areas of the power cells of the uniform measure, their centroids and the Hessian
of the dual (|edge| / (2 |x_i - x_j|) between neighbouring cells), from a regular
triangulation. Here each cell is clipped on its own (``bnot_cells`` in
``kernels/bnot_cells.cl``, one work-item a site; NumPy twin :func:`power_cells_reference`,
the same bits), and the weights come from damped Newton steps on the host, the same
arithmetic for both backends.
"""

import numpy as np

from .. import runtime
from ..errors import SamplingError
from ..geometry.cells import sorted_by_cell

VMAX = 32               # vertices a cell may have (status 2 beyond)
LMAX = 64               # lines that cut a cell on the way (status 2 beyond)
SITES_PER_CELL = 4      # the grid's cells hold about this many sites
NEWTON = 16             # cap on the Newton steps of one weight solve
HALVINGS = 12           # step halvings before a Newton step gives up
CAPACITY_TOL = 1e-5     # a solve stops once every area is within this fraction of 1/n
COARSE = 1e-2           # the loosest capacities of an iteration before the last
MAX_IMAGES = 4          # the widest stencil of images of the torus (G == 1)
NEAR = 2.0              # sites within sqrt(NEAR / n) cut a cell first: its natural neighbours
EMPTY = 5e-324          # the least positive double: a cell of a smaller area is empty


def grid(n, R):
    """The grid of cells for the clipping kernel's candidates.

    Parameters
    ----------
    n : int
        Sites.
    R : int
        The stencil's radius in cells.

    Returns
    -------
    G : int
        Cells per axis: about sqrt(n / SITES_PER_CELL) when that is at least 2 R + 1,
        else 1 (every site, in the (2 R + 1)^2 images of the torus).
    reach : float
        The least distance from a site to a site no candidate of it: R / G, or R.
    """
    G = int(np.sqrt(n / SITES_PER_CELL))
    if G < 2 * R + 1:
        return 1, float(R)
    return G, R / G


def _ring(k):
    """The cells at Chebyshev distance k, in the kernel's order: the first axis outer."""
    return [(ox, oy) for ox in range(-k, k + 1) for oy in range(-k, k + 1)
            if max(abs(ox), abs(oy)) == k]


def _stencil(R):
    """The kernel's order of the (2 R + 1)^2 neighbouring cells: by ring, then first axis."""
    return [cell for ring in range(R + 1) for cell in _ring(ring)]


def _bounds(w, start, G, R, reach, wmax, far=None, cellmax=None):
    """The certificate's ``far`` and ``cellmax`` (:func:`power_cells_reference`), each
    where not given: (R + 1) / G (``reach`` when G == 1), and each grid cell's largest
    weight (the largest of all when G == 1)."""
    if far is None:
        far = (R + 1) / G if G > 1 else reach
    if cellmax is None:
        cellmax = cell_max(w, start) if G > 1 else np.array([float(wmax)])
    return far, cellmax


def cell_max(w, start):
    """The largest weight in each cell of the grid.

    Parameters
    ----------
    w : ndarray (n,)
        Weights of the sites sorted by cell.
    start : ndarray (G * G + 1,)
        Each cell's first sorted index.

    Returns
    -------
    ndarray (G * G,)
        -inf for an empty cell.
    """
    start = np.asarray(start, dtype=np.int64)
    out = np.full(start.size - 1, -np.inf)
    full = np.flatnonzero(start[1:] > start[:-1])
    if full.size:
        out[full] = np.maximum.reduceat(w, start[full])
    return out


def power_cells_reference(sites, w, start, G, R, reach, wmax, order=None, todo=None, far=None,
                          cellmax=None, near=None):
    """NumPy twin of the ``bnot_cells`` kernel (``kernels/bnot_cells.cl``): the same
    candidates in the same order, the same operations, the same bits.

    Parameters
    ----------
    sites : ndarray (n, 2) of float64
        Sorted by cell (:func:`clsamp.geometry.cells.sorted_by_cell`).
    w : ndarray (n,) of float64
        Their weights, in the same order.
    start : ndarray (G * G + 1,) of uint32
        Each cell's first sorted index.
    G, R : int
        Cells per axis, stencil radius in cells.
    reach, wmax : float
        The least distance of a site outside the stencil; the largest weight.
    order : ndarray (n,), optional
        Sorted index -> the site's own index, which ``nbr`` gives (default: the sorted
        index).
    todo : ndarray (m,), optional
        The sorted indices of the cells to clip (default: every one).
    far : float, optional
        The least distance of a site beyond the stencil's next ring of cells: (R + 1) / G
        (default; ``reach`` when G == 1).
    cellmax : ndarray (G * G,), optional
        The largest weight in each grid cell (:func:`cell_max`, by default from ``w``).
    near : float, optional
        The squared distance below which a candidate cuts in the first pass (default
        ``NEAR`` / n).

    Returns
    -------
    out : ndarray (m, 4)
        Area, centroid offset (x, y), second moment about the site, a row for each of
        ``todo`` in its order.
    nbr : ndarray (m, VMAX) of int32
        The neighbours across each edge (``order`` of their sorted index; -1: none).
    coef : ndarray (m, VMAX)
        |edge| / (2 |d|) of each.
    status : ndarray (m,) of int32
        0 certified, 1 needs a wider stencil, 2 too many vertices or lines.
    """
    rows = np.arange(sites.shape[0]) if todo is None else np.asarray(todo, dtype=np.int64)
    n = rows.size
    px = np.zeros((n, VMAX))
    py = np.zeros((n, VMAX))
    lab = np.full((n, VMAX), -1, dtype=np.int64)
    px[:, :4] = [-0.5, 0.5, 0.5, -0.5]
    py[:, :4] = [-0.5, -0.5, 0.5, 0.5]
    cnt = np.full(n, 4, dtype=np.int64)
    lines = np.zeros(n, dtype=np.int64)
    tj = np.zeros((n, LMAX), dtype=np.int64)
    tn = np.zeros((n, LMAX))
    st = np.zeros(n, dtype=np.int64)
    r2 = np.full(n, 0.5)
    xi, yi, wi = sites[rows, 0], sites[rows, 1], w[rows]
    if G > 1:
        cx = np.minimum((xi * float(G)).astype(np.int64), G - 1)
        cy = np.minimum((yi * float(G)).astype(np.int64), G - 1)
    else:
        cx = cy = np.zeros(n, dtype=np.int64)
    starts = start.astype(np.int64)
    a = np.arange(VMAX)
    near = NEAR / sites.shape[0] if near is None else near
    for first_pass in (True, False):      # the near sites first (the kernel's passes)
        for ox, oy in _stencil(R):
            if G == 1:
                shx = np.full(n, ox)
                shy = np.full(n, oy)
                cell = np.zeros(n, dtype=np.int64)
            else:
                gx, gy = cx + ox, cy + oy
                shx = np.where(gx < 0, -1, np.where(gx >= G, 1, 0))
                shy = np.where(gy < 0, -1, np.where(gy >= G, 1, 0))
                cell = (gx - shx * G) * G + (gy - shy * G)
            first, count = starts[cell], starts[cell + 1] - starts[cell]
            for slot in range(int(count.max(initial=0))):
                j = first + slot
                live = (slot < count) & (cnt > 0) & (st == 0) & (j != rows)
                r = np.flatnonzero(live)
                if r.size == 0:
                    continue
                jr = j[r]
                dx = (sites[jr, 0] + shx[r].astype(np.float64)) - xi[r]
                dy = (sites[jr, 1] + shy[r].astype(np.float64)) - yi[r]
                dd = dx * dx + dy * dy
                now = (dd < near) == first_pass
                r, jr, dx, dy, dd = (a[now] for a in (r, jr, dx, dy, dd))
                h = 0.5 * ((dd + wi[r]) - w[jr])
                reaches = ~((h > 0.0) & (h * h >= r2[r] * dd))
                r, jr, dx, dy, h = (a[reaches] for a in (r, jr, dx, dy, h))
                inside = a[None, :] < cnt[r, None]
                s = (px[r] * dx[:, None] + py[r] * dy[:, None]) - h[:, None]
                cut = ((s > 0.0) & inside).any(axis=1)
                r, jr, dx, dy, s, inside = (a[cut] for a in (r, jr, dx, dy, s, inside))
                full = lines[r] == LMAX
                st[r[full]] = 2
                keep = ~full
                r, jr, dx, dy, s, inside = (a[keep] for a in (r, jr, dx, dy, s, inside))
                if r.size == 0:
                    continue
                _clip(r, jr, dx, dy, s, inside, px, py, lab, cnt, lines, tj, tn, st, r2)
    far, cellmax = _bounds(w, start, G, R, reach, wmax, far, cellmax)
    wring = np.full(n, float(wmax))
    if G > 1:
        wring = np.max([cellmax[((cx + ox) % G) * G + (cy + oy) % G]
                        for ox, oy in _ring(R + 1)], axis=0)
    out, nbr, coef, status = _moments(px, py, lab, cnt, tj, tn, st, wi, reach, far, wmax,
                                      wring, r2)
    if order is not None:
        nbr = np.where(nbr >= 0, np.asarray(order)[np.maximum(nbr, 0)], -1).astype(np.int32)
    return out, nbr, coef, status


def _clip(r, jr, dx, dy, s, inside, px, py, lab, cnt, lines, tj, tn, st, r2):
    """One Sutherland-Hodgman clip of the cells of rows r, in place (the kernel's loop)."""
    a = np.arange(VMAX)
    b = np.where(a[None, :] + 1 < cnt[r, None], a[None, :] + 1, 0)
    sb = np.take_along_axis(s, b, axis=1)
    ina = s <= 0.0
    inb = sb <= 0.0
    e1 = ina & inside
    e2 = (ina != inb) & inside
    total = (e1.astype(np.int64) + e2).sum(axis=1)
    over = total > VMAX
    st[r[over]] = 2
    ok = ~over
    r, jr, dx, dy, s, sb, b, ina, e1, e2, total = (
        a[ok] for a in (r, jr, dx, dy, s, sb, b, ina, e1, e2, total))
    if r.size == 0:
        return
    emitted = e1.astype(np.int64) + e2
    off = np.cumsum(emitted, axis=1) - emitted
    ax, ay, al = px[r], py[r], lab[r]
    bx = np.take_along_axis(ax, b, axis=1)
    by = np.take_along_axis(ay, b, axis=1)
    nx = np.zeros_like(ax)
    ny = np.zeros_like(ay)
    nl = np.full_like(al, -1)
    k, v = np.nonzero(e1)
    p = off[k, v]
    nx[k, p], ny[k, p], nl[k, p] = ax[k, v], ay[k, v], al[k, v]
    k, v = np.nonzero(e2)
    p = off[k, v] + e1[k, v]
    t = s[k, v] / (s[k, v] - sb[k, v])
    nx[k, p] = ax[k, v] + t * (bx[k, v] - ax[k, v])
    ny[k, p] = ay[k, v] + t * (by[k, v] - ay[k, v])
    nl[k, p] = np.where(ina[k, v], lines[r][k], al[k, v])
    tj[r, lines[r]] = jr
    tn[r, lines[r]] = np.sqrt(dx * dx + dy * dy)
    lines[r] += 1
    px[r], py[r], lab[r] = nx, ny, nl
    cnt[r] = total
    ra = nx * nx + ny * ny
    r2[r] = np.where(a[None, :] < total[:, None], ra, 0.0).max(axis=1, initial=0.0)


def _moments(px, py, lab, cnt, tj, tn, st, w, reach, far, wmax, wring, r2):
    """Area, centroid, second moment, edges and status of clipped cells (the kernel's
    last loops, in its order)."""
    n = px.shape[0]
    A2, mx, my, second = (np.zeros(n) for _ in range(4))
    for a in range(VMAX):
        on = a < cnt
        if not on.any():
            break
        b = np.where(a + 1 < cnt, a + 1, 0)
        xa, ya = px[:, a], py[:, a]
        xb, yb = px[np.arange(n), b], py[np.arange(n), b]
        cr = xa * yb - ya * xb
        A2 = np.where(on, A2 + cr, A2)
        mx = np.where(on, mx + cr * (xa + xb), mx)
        my = np.where(on, my + cr * (ya + yb), my)
        second = np.where(on, second + cr * (((xa * xa + ya * ya) + (xb * xb + yb * yb))
                                             + (xa * xb + ya * yb)), second)
    a = np.arange(VMAX)
    b = np.where(a[None, :] + 1 < cnt[:, None], a[None, :] + 1, 0)
    edge = (lab >= 0) & (a[None, :] < cnt[:, None])
    k, v = np.nonzero(edge)
    slot = (np.cumsum(edge, axis=1) - 1)[k, v]
    ex = px[k, b[k, v]] - px[k, v]
    ey = py[k, b[k, v]] - py[k, v]
    nbr = np.full((n, VMAX), -1, dtype=np.int32)
    coef = np.zeros((n, VMAX))
    nbr[k, slot] = tj[k, lab[k, v]]
    coef[k, slot] = np.sqrt(ex * ex + ey * ey) / (2.0 * tn[k, lab[k, v]])
    rr = np.sqrt(r2)
    certified = ((rr < reach) & ((reach * reach - 2.0 * rr * reach) + (w - wring) >= 0.0)
                 & ((far * far - 2.0 * rr * far) + (w - wmax) >= 0.0))
    status = np.where(st != 0, st, np.where(certified, 0, 1)).astype(np.int32)
    out = np.empty((n, 4))
    out[:, 0] = 0.5 * A2
    with np.errstate(divide="ignore", invalid="ignore"):
        out[:, 1] = np.where(A2 > 0.0, mx / (3.0 * A2), 0.0)
        out[:, 2] = np.where(A2 > 0.0, my / (3.0 * A2), 0.0)
    out[:, 3] = second / 12.0
    return out, nbr, coef, status


def power_cells_device(sites, w, start, order, G, R, reach, wmax, todo=None, outputs=None,
                       far=None, cellmax=None, near=None):
    """:func:`power_cells_reference` by the ``bnot_cells`` kernel (the same bits), its rows
    written in the sites' own order.

    Parameters
    ----------
    sites, w, start, G, R, reach, wmax
        As :func:`power_cells_reference` takes them; ``sites`` and ``start`` may be
        buffers already on the device (:class:`PowerCells` keeps them for the passes
        over the same sites).
    order : ndarray (n,) or buffer of uint32
        Sorted index -> the site's own index: the row each cell is written to, and the
        index ``nbr`` gives.
    todo : ndarray (m,), optional
        The sorted indices of the cells to clip (default: every one); the other rows of
        ``outputs`` are left as they are.
    outputs : tuple, optional
        The two :class:`clsamp.runtime.Output` the kernel writes (n, 4 + VMAX) float64 and
        (n, 1 + VMAX) int32, kept by the caller for its passes; new ones by default.
    far, cellmax, near : optional
        As :func:`power_cells_reference` takes them (``cellmax`` needed where G > 1 and
        ``start`` is a buffer).

    Returns
    -------
    out, nbr, coef, status
        As :func:`power_cells_reference` returns them, for every site in its own order
        (views of the outputs).

    Raises
    ------
    NoDeviceError
        A device without fp64.
    """
    runtime.require_fp64()
    n = int(w.shape[0])
    kernel = runtime.kernel("bnot_cells.cl", "bnot_cells", {"VMAX": VMAX, "LMAX": LMAX})
    floats, ints = outputs or _outputs(n)
    if todo is None:
        m = n
        todo = runtime.table(("bnot_cells.every", n), lambda: np.arange(n)).data
    else:
        m = int(len(todo))
        todo = runtime.input_buffer(np.asarray(todo, dtype=np.uint32))
    far, cellmax = _bounds(w, start, G, R, reach, wmax, far, cellmax)
    near = NEAR / n if near is None else near
    local = runtime.local_size(64)
    sites, start = (a if not isinstance(a, np.ndarray) else runtime.input_buffer(a)
                    for a in (sites, start))
    if isinstance(order, np.ndarray):
        order = runtime.input_buffer(order.astype(np.uint32))
    kernel(runtime.queue(), (-(-m // local) * local,), (local,), sites, runtime.input_buffer(w),
           start, order, todo, np.uint32(m), np.int32(G), np.int32(R), np.float64(near),
           np.float64(reach), np.float64(far), np.float64(wmax), runtime.input_buffer(cellmax),
           floats.buffer, ints.buffer)
    f, i = floats.finish(), ints.finish()
    return f[:, :4], i[:, 1:], f[:, 4:], i[:, 0]


def _outputs(n):
    """The two outputs of the kernel for n sites, over host arrays: (n, 4 + VMAX) float64
    and (n, 1 + VMAX) int32."""
    return (runtime.Output((n, 4 + VMAX), np.float64, host=np.empty((n, 4 + VMAX))),
            runtime.Output((n, 1 + VMAX), np.int32, host=np.empty((n, 1 + VMAX), dtype=np.int32)))


class PowerCells:
    """The exact power cells of fixed sites, for any weights: ``cells(w)`` -> (area,
    centroid offset, second moment, L), in the sites' order, L the Jacobian of the areas
    in the weights (:func:`laplacian`).

    The sites are sorted by a grid of cells; a call clips every cell with the stencil of
    R cells around it (R = 1, or every site's 5 x 5 images for small n), then clips
    again, with a stencil one ring wider each time, only the cells that are not certified
    (``bnot_cells.cl``), until every cell is exact. Where a stencil leaves most cells
    uncertified, later calls start one ring wider.

    Parameters
    ----------
    sites : ndarray (n, 2) of float64
        In [0, 1).
    backend : {"opencl", "numpy"}
    """

    def __init__(self, sites, backend):
        self.sites = np.asarray(sites, dtype=np.float64)
        self.n = self.sites.shape[0]
        self.device = backend == "opencl"
        self.outputs = _outputs(self.n) if self.device else None
        self.first = 1 if grid(self.n, 1)[0] > 1 else 2
        self.R = self.first     # the widest stencil a call has taken
        self._sorts = {}

    def _sorted(self, G):
        """The sites sorted by a grid of G x G cells, made once: (sites, start, order,
        back, rows, starts), the first two and rows (order as uint32) on the device for
        the device backend, starts ``start`` on the host."""
        if G not in self._sorts:
            pts, _, starts, order = sorted_by_cell(self.sites[None], G)
            back = np.empty(self.n, dtype=np.int64)
            back[order] = np.arange(self.n)
            start, rows = starts, order
            if self.device:     # the same sites for every pass: upload once
                pts, start, rows = (runtime.input_buffer(a) for a in (
                    pts, starts, order.astype(np.uint32)))
            self._sorts[G] = pts, start, order, back, rows, starts
        return self._sorts[G]

    def __call__(self, w, hessian=True, least=None):
        """The cells under weights ``w``: (area, centroid offset, second moment, L), L
        None with ``hessian=False`` (:meth:`laplacian` builds it until the next call);
        None at once where a cell's area falls below ``least`` (a wider stencil only
        clips a cell further)."""
        w = np.asarray(w, dtype=np.float64)
        wmax = float(w.max(initial=0.0))
        if self.device:
            floats, ints = (o.array for o in self.outputs)
        else:
            floats, ints = np.empty((self.n, 4 + VMAX)), np.empty((self.n, 1 + VMAX), np.int32)
        R, uncertified = self.first, None
        while True:
            G, reach = grid(self.n, R)
            pts, start, order, back, rows, starts = self._sorted(G)
            todo = None if uncertified is None else back[uncertified]
            ws = np.ascontiguousarray(w[order])
            far, cellmax = _bounds(ws, starts, G, R, reach, wmax)
            if self.device:
                power_cells_device(pts, ws, start, rows, G, R, reach, wmax, todo, self.outputs,
                                   far, cellmax)
            else:
                out, nbr, coef, status = power_cells_reference(pts, ws, start, G, R, reach, wmax,
                                                               order, todo, far, cellmax)
                at = order if todo is None else order[todo]
                floats[at, :4], floats[at, 4:] = out, coef
                ints[at, 0], ints[at, 1:] = status, nbr
            status = ints[:, 0]
            if (status == 2).any():
                raise SamplingError("bnot: a power cell with more than "
                                    f"{VMAX} vertices or {LMAX} cutting lines")
            if least is not None and floats[:, 0].min() < least:
                return None
            uncertified = np.flatnonzero(status)
            if uncertified.size == 0:
                break
            if G == 1 and R >= MAX_IMAGES:
                raise SamplingError("bnot: weights too far apart for exact power cells")
            if todo is None and 2 * uncertified.size > self.n:
                self.first = R + 1      # most cells need more: the next call starts wider
            R += 1
            self.R = max(self.R, R)
        self._rows = ints[:, 1:], floats[:, 4:]
        return (floats[:, 0].copy(), floats[:, 1:3].copy(), floats[:, 3].copy(),
                self.laplacian() if hessian else None)

    def laplacian(self):
        """The Laplacian (:func:`laplacian`) of the cells of the last call."""
        return laplacian(*self._rows)


def laplacian(nbr, coef):
    """The Jacobian of the cells' areas in the weights, L_ij = dA_i / dw_j: minus the
    edges' coefficients off the diagonal, their sum on it, plus 1e-9 of the mean degree
    there (the Laplacian is singular along the constants, to which the gradient is
    orthogonal). Built as CSR from the kernel's rows (symmetric to rounding: each
    boundary's length is measured from both sides).

    Parameters
    ----------
    nbr, coef : ndarray (n, VMAX)
        The kernel's rows in the sites' order, neighbours as the sites' indices (-1:
        none, after the live slots).

    Returns
    -------
    scipy.sparse.csr_matrix (n, n)
    """
    import scipy.sparse as sp
    n, slots = nbr.shape
    index = np.int32 if n * (1 + slots) < 2**31 else np.int64
    cols = np.empty((n, 1 + slots), dtype=index)
    cols[:, 0] = np.arange(n, dtype=index)
    cols[:, 1:] = nbr
    degree = coef.sum(axis=1)
    vals = np.empty((n, 1 + slots))
    vals[:, 0] = degree + 1e-9 * max(float(degree.mean()), 1e-300)
    np.negative(coef, out=vals[:, 1:])
    live = cols >= 0            # the diagonal first, then the live slots of the row
    indptr = np.zeros(n + 1, dtype=index)
    np.cumsum(np.count_nonzero(live, axis=1), out=indptr[1:])
    return sp.csr_matrix((vals[live], cols[live], indptr), shape=(n, n))


class LaplacianSolver:
    """Solves L x = b for the Laplacians of one optimization, which change little from
    one Newton step or iteration to the next: conjugate gradients preconditioned by the
    LU factors of an earlier L (SuperLU, symmetric mode), factored anew when they take
    more than ``steps`` iterations to reach ``rtol``. The same arithmetic on every
    backend, so the same bits.

    A Newton direction need not be exact: ``rtol`` (1e-3 of the residual) is the
    inexact Newton method's forcing term (Dembo, Eisenstat and Steihaug 1982), and the
    step's line search in :func:`solve_exact_weights` checks every step it takes.
    """

    def __init__(self, rtol=1e-3, steps=12):
        self.rtol, self.steps, self.lu = rtol, steps, None

    def _factor(self, L):
        from scipy.sparse.linalg import splu
        self.lu = None          # the old factors go before the new ones are made
        self.lu = splu(L.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                       options={"SymmetricMode": True})

    def _cg(self, L, b):
        """Preconditioned conjugate gradients from x = 0 (Hestenes and Stiefel), or None
        when ``steps`` iterations do not bring |r| to ``rtol`` |b|."""
        solve = self.lu.solve
        x = np.zeros_like(b)
        r = b.copy()
        z = solve(r)
        p = z.copy()
        rz = float(r @ z)
        bound = self.rtol * float(np.sqrt(b @ b))
        for _ in range(self.steps):
            q = L @ p
            curvature = float(p @ q)
            if not (curvature > 0.0 and rz > 0.0):     # factors that no longer fit L
                return None
            alpha = rz / curvature
            x += alpha * p
            r -= alpha * q
            if float(np.sqrt(r @ r)) <= bound:
                return x
            z = solve(r)
            rz, previous = float(r @ z), rz
            p = z + (rz / previous) * p
        return None

    def __call__(self, L, b):
        if not b.any():
            return np.zeros_like(b)
        if self.lu is not None:
            x = self._cg(L, b)
            if x is not None:
                return x
        self._factor(L)
        return self.lu.solve(b)


def solve_exact_weights(cells, w, solver, newton=NEWTON, tol=CAPACITY_TOL):
    """Weights whose exact power cells all have area 1/n, by the damped Newton method of
    Kitagawa, Merigot and Thibert (2019) on the dual of the semi-discrete transport
    problem (de Goes et al. 2012, section 4).

    The dual F(w) = sum_i (integral over Pow_i(w) of |y - x_i|^2 - w_i) + sum_i w_i / n is
    concave; its gradient is 1/n - A(w) (A: the cells' areas) and its Hessian minus the
    Laplacian L of the cells' adjacency weighted by |edge| / (2 |x_i - x_j|). A step
    w + alpha delta, L delta = 1/n - A, is accepted for the first alpha in 1, 1/2, ...
    (``HALVINGS`` tries) that keeps every area at least half the least area (or 1/n) at
    the start and lowers the gradient's norm to (1 - alpha / 2) of its value. It starts
    from ``w``, or from zero weights (Voronoi cells) where ``w`` leaves a cell empty.

    Parameters
    ----------
    cells : PowerCells
        The sites' cells.
    w : ndarray (n,)
        The weights to start from.
    solver : LaplacianSolver
        Solves L delta = 1/n - A.
    newton : int
        Cap on the steps.
    tol : float
        Stop once every area is within ``tol`` / n of 1 / n.

    Returns
    -------
    w : ndarray (n,)
    cells : tuple
        ``cells(w)``: area, centroid offset, second moment (and None for L, which
        ``cells.laplacian()`` builds).
    steps : int
        Newton steps taken.
    """
    n = cells.n
    m = 1.0 / n
    state = cells(w, hessian=False, least=EMPTY if w.any() else None)
    if state is None:
        w = np.zeros(n)
        state = cells(w, hessian=False)
    least = 0.5 * min(float(state[0].min()), m)
    steps = 0
    for _ in range(newton):
        grad = m - state[0]
        if n == 1 or np.abs(grad).max() <= tol * m:
            break
        delta = solver(cells.laplacian(), grad)     # state is the last call's
        delta -= delta.mean()
        norm, alpha, taken = np.linalg.norm(grad), 1.0, None
        for _ in range(HALVINGS):
            trial = w + alpha * delta
            out = cells(trial, hessian=False, least=least)
            if out is not None and np.linalg.norm(m - out[0]) <= (1.0 - alpha / 2) * norm:
                taken = trial, out
                break
            alpha *= 0.5
        if taken is None:
            break
        (w, state), steps = taken, steps + 1
    return w, state, steps


def exact_optimize(sites, iterations, tol, backend, newton=NEWTON, progress=False):
    """BNOT over exact power cells from given sites (both backends: the same bits).

    Parameters
    ----------
    sites : ndarray (r, n, 2) of float64
        Starting sites in [0, 1).
    iterations, tol, backend, newton, progress
        As :func:`clsamp.samplers.bnot.bnot_optimize` takes them.

    Returns
    -------
    sites : ndarray (r, n, 2)
    history, duals : list of lists
        The cost after each iteration (the cells' mean squared distance to their
        centroids) and the dual at each weight solve's end.
    steps, counts : list of int
        Newton steps and iterations of each realization.
    areas : ndarray (r, n)
        The final cells' areas times n.
    converged : list of bool
    """
    from tqdm import tqdm
    r, n, _ = sites.shape
    out = np.array(sites, dtype=np.float64)
    histories, duals, steps, counts, areas, converged = [], [], [], [], [], []
    bar = tqdm(total=r * iterations, desc=f"bnot {r} x {n} sites", unit="it",
               disable=not progress, delay=2)
    for k in range(r):
        x, w, solver = out[k], np.zeros(n), LaplacianSolver()
        history, dual_history, taken, done, area = [], [], 0, False, np.full(n, 1.0 / n)
        loose = COARSE          # the first sites are far from their centroids
        for t in range(iterations):
            w, (area, centroid, moment, _), used = solve_exact_weights(
                PowerCells(x, backend), w, solver, newton,
                CAPACITY_TOL if t == iterations - 1 else max(CAPACITY_TOL, loose))
            taken += used
            history.append(float(np.sum(moment - area * (centroid * centroid).sum(axis=1))))
            dual_history.append(float(np.sum(moment - w * area) + np.sum(w) / n))
            x = x + centroid
            x -= np.floor(x)
            x[x >= 1.0] = 0.0
            bar.update()
            if len(history) > 1:
                drop = (history[-2] - history[-1]) / history[-1]
                if tol > 0 and drop <= tol and loose <= CAPACITY_TOL:
                    done = True
                    break
                # while the sites move far, the weights need not be exact (the run's last
                # solve, and the one that stops it, are)
                loose = min(COARSE, drop) if drop > tol else 0.0
        bar.update(iterations - len(history))
        out[k] = x
        histories.append(history)
        duals.append(dual_history)
        steps.append(taken)
        counts.append(len(history))
        areas.append(area * n)
        converged.append(done)
    bar.close()
    return out, histories, duals, steps, counts, np.asarray(areas).reshape(r, n), converged
