"""The ``gbn`` sampler: Gaussian blue noise (Ahmed, Ren, Wonka 2022), gradient descent on
the sum of Gaussian kernels between the points, in any dimension, on the unit torus or in
the unit cube.

One step is one pair pass, an n-body sum over the neighbours within the kernel's cutoff
found through a grid of cells (:mod:`clsamp.geometry.cells`), so a step costs O(n):
``gbn_pairs`` in ``kernels/gbn.cl`` on the device, :func:`pair_pass_reference` here in
NumPy, the same bits (an exponential of our own, :func:`exp_neg`, in both). Everything
else -- the binning, the domain's attraction in the cube, the step and its control -- is
host code both backends share (:func:`gbn_optimize`), except where a run stays on a CPU
device (on the torus, without a density: :mod:`clsamp.samplers.gbn_device`), whose
kernel does that code's work with the same bits.
"""

import dataclasses
import decimal
import math

import numpy as np

from .. import runtime
from ..density import Density, as_density
from ..errors import InvalidArgumentError
from ..geometry.cells import cells_for, neighbour_cells, sorted_by_cell
from ..validation import MAX_ITERATIONS, check_bool, check_positive_int, check_real
from . import gbn_device
from .base import SampleInfo, Sampler, info_field, make_sampler, register, sampler_class

SIGMA = 0.5          # the kernel's standard deviation, in mean spacings n^(-1/d)
STEP = math.pi / 2   # the step, relative to the kernel's mass (see GBNSampler)
STEP_MAX = 1024.0    # the largest step accepted
CUT = 4.0            # pairs farther than CUT sigma do not interact
ITERATIONS = 200
TOL = 1e-4
HALVINGS = 40        # a set whose step has been halved this often has converged
MAX_D = 64
RHO_FLOOR = 1e-3     # adaptive widths stop growing where the density is below this (mean 1)

# e^-t by range reduction to |r| <= ln 2 / 64 and a table of 2^(-j/32) (kernels/gbn.cl):
# t = k ln2/32 - r, e^-t = 2^-(k >> 5) T (1 + r P(r)), T = 2^(-(k & 31)/32), 1 + r P(r) the
# Taylor polynomial of e^r of degree 6 (truncation below 4e-18 relative), summed as
# T + T (r P(r)); ln 2 / 32 split as fdlibm's ln 2 (scaled by 2^-5, exactly), so that
# k ln2_hi / 32 is exact for every k of t < 700.
EXP_TABLE_BITS = 5
EXP_INV = 1.44269504088896338700e+00 * (1 << EXP_TABLE_BITS)
EXP_HI = 6.93147180369123816490e-01 / (1 << EXP_TABLE_BITS)
EXP_LO = 1.90821492927058770002e-10 / (1 << EXP_TABLE_BITS)
EXP_COEFFICIENTS = tuple(1.0 / math.factorial(k) for k in range(7))


def _exp2_table(bits):
    """2^(-j / 2^bits), j = 0 .. 2^bits - 1, each correctly rounded to a double."""
    with decimal.localcontext() as ctx:
        ctx.prec = 60
        ln2 = decimal.Decimal(2).ln()
        return tuple(float((-ln2 * j / (1 << bits)).exp()) for j in range(1 << bits))


EXP_TABLE = _exp2_table(EXP_TABLE_BITS)
EXP_DEFINES = {"GBN_EXP_BITS": EXP_TABLE_BITS, "GBN_EXP_INV": repr(EXP_INV),
               "GBN_EXP_HI": repr(EXP_HI), "GBN_EXP_LO": repr(EXP_LO),
               "GBN_EXP_TABLE": ",".join(float.hex(v) for v in EXP_TABLE),
               **{f"GBN_C{k}": repr(c) for k, c in enumerate(EXP_COEFFICIENTS)}}


def exp_neg(t):
    """e^-t for 0 <= t < 700, with the operations of ``gbn_exp_neg`` in ``kernels/gbn.cl``
    (so the kernel and the NumPy reference agree bit for bit; within one unit in the last
    place of the exactly rounded value): t = k ln 2 / 32 - r with |r| <= ln 2 / 64, a table
    of 2^(-j/32) and the Taylor polynomial of e^r of degree 6.

    Parameters
    ----------
    t : ndarray of float64

    Returns
    -------
    ndarray of float64

    Examples
    --------
    >>> import numpy as np
    >>> from clsamp.samplers.gbn import exp_neg
    >>> t = np.linspace(0, 8, 9)
    >>> bool(np.allclose(exp_neg(t), np.exp(-t), rtol=1e-15, atol=0))
    True
    """
    t = np.asarray(t, dtype=np.float64)
    k = (t * EXP_INV + 0.5).astype(np.int64)
    kd = k.astype(np.float64)
    r = (kd * EXP_HI - t) + kd * EXP_LO
    p = np.full_like(r, EXP_COEFFICIENTS[-1])
    for c in EXP_COEFFICIENTS[-2:0:-1]:
        p = p * r + c
    table = np.array(EXP_TABLE)[k & ((1 << EXP_TABLE_BITS) - 1)]
    return np.ldexp(table + table * (r * p), -(k >> EXP_TABLE_BITS))


@dataclasses.dataclass(frozen=True)
class Kernel:
    """The Gaussian of one optimization and what follows from it.

    Attributes
    ----------
    n, d : int
    sigma : float
        Standard deviation in mean spacings; ``s = sigma * n^(-1/d)`` on the unit domain.
    periodic : bool
    cut : float
        Cutoff in sigmas; on the torus at most 1/2 (a pair meets through its nearest image).
    widen : float
        The widest pair's standard deviation in s (adaptive sampling: sqrt of the largest
        relative variance t_i); the grid's cells are ``cut`` s ``widen`` wide.
    """

    n: int
    d: int
    sigma: float
    periodic: bool
    cut: float = CUT
    widen: float = 1.0

    @property
    def s(self):
        """The standard deviation on the unit domain, sigma n^(-1/d)."""
        return self.sigma * float(self.n) ** (-1.0 / self.d)

    @property
    def reach(self):
        """The cutoff R: ``cut`` s ``widen``, at most 1/2 on the torus."""
        reach = self.cut * self.s * self.widen
        return min(reach, 0.5) if self.periodic else reach

    @property
    def inv2s2(self):
        """1 / (2 s^2)."""
        return 1.0 / (2.0 * self.s * self.s)

    @property
    def R2(self):
        """R^2."""
        return self.reach * self.reach

    @property
    def gR(self):
        """exp(-R^2 / 2 s^2), by :func:`exp_neg`: the kernel's value at the cutoff."""
        return float(exp_neg(np.float64(self.R2 * self.inv2s2)))

    @property
    def Rc2(self):
        """(``cut`` s)^2: an adaptive pair interacts while r^2 < Rc2 tau."""
        return (self.cut * self.s) ** 2

    @property
    def gc(self):
        """exp(-cut^2 / 2) by :func:`exp_neg`: an adaptive pair's kernel at its cutoff."""
        return float(exp_neg(np.float64(self.cut * self.cut * 0.5)))

    @property
    def cells(self):
        """Cells per axis of the neighbour grid (:func:`clsamp.geometry.cells.cells_for`), at
        most about 4 cells a point (wider cells find the same pairs)."""
        return cells_for(self.reach, self.n, self.d, cells_a_point=4.0)

    @property
    def stencil(self):
        """Cells a point's neighbours may lie in: 3^d, or 1 for a 1-cell grid."""
        return 3 ** self.d if self.cells > 1 else 1

    @property
    def mass(self):
        """The Gaussian's integral in points, sum_j g(x_i - x_j) for uniform points:
        (2 pi)^(d/2) sigma^d."""
        return (2.0 * math.pi) ** (self.d / 2.0) * self.sigma ** self.d


def pair_pass_reference(pts, cell, start, n, kernel, t=None):
    """NumPy twin of ``gbn_pairs``: per sorted point, its energy and force from the
    neighbours within the cutoff, summed in the kernel's order.

    Each sum is kept as four partial sums: partner j (a sorted index) adds to partial sum
    j mod 4, the partners taken in stencil order, then sorted order; the sum is
    (s0 + s1) + (s2 + s3). The kernel so adds four consecutive partners in four vector
    lanes.

    Parameters
    ----------
    pts : ndarray (total, d)
        Points sorted by (set, cell) (:func:`clsamp.geometry.cells.sorted_by_cell`).
    cell : ndarray of uint32 (total,)
    start : ndarray of uint32 (sets cells^d + 1,)
    n : int
        Points per set.
    kernel : Kernel
    t : ndarray (total,), optional
        Adaptive sampling: each sorted point's variance relative to s^2; a pair's kernel
        has the variance s^2 tau, tau = (t_i + t_j) / 2, and is cut at ``cut`` s sqrt(tau).

    Returns
    -------
    energy : ndarray (total,)
        sum_j (e_ij - gR), e_ij = exp(-r_ij^2 / 2 s^2 tau), over partners within the cutoff
        (tau = 1 without ``t``).
    force : ndarray (total, d)
        sum_j (x_i - x_j) e_ij / tau.
    width : ndarray (total,)
        Only with ``t``: sum_j e_ij (r_ij^2 / 2 s^2) / tau^2, the energy's change with the
        point's width.
    """
    total, d = pts.shape
    G = kernel.cells
    own = np.arange(total, dtype=np.int64)
    slot_base = (own // n) * G ** d
    start = start.astype(np.int64)
    adaptive = t is not None
    sums = d + 1 + adaptive                  # energy, force, width
    part = [np.zeros(4 * total) for _ in range(sums)]   # partial sum j mod 4 of i: (j mod 4) total + i
    R2, inv2s2, gR = (kernel.Rc2, kernel.inv2s2, kernel.gc) if adaptive else \
        (kernel.R2, kernel.inv2s2, kernel.gR)
    for o in range(kernel.stencil):
        slot = slot_base + neighbour_cells(cell, o, G, d)
        first, stop = start[slot], start[slot + 1]
        for k in range(int((stop - first).max(initial=0))):
            j = first + k
            live = np.flatnonzero((j < stop) & (j != own))
            if live.size == 0:
                continue
            i, jj = live, j[live]
            w = [pts[i, a] - pts[jj, a] for a in range(d)]
            if kernel.periodic:
                # the kernel's wrap, v - 1 above 1/2 and v + 1 below -1/2, to the bit
                w = [v - np.rint(v) for v in w]
            r2 = w[0] * w[0]
            for a in range(1, d):
                r2 = r2 + w[a] * w[a]
            if adaptive:
                tau = (t[i] + t[jj]) * 0.5
                near = r2 < R2 * tau
                r2, tau = r2[near], tau[near]
                q = r2 * inv2s2 / tau
                e = exp_neg(q)
                c = e / tau
                terms = [e - gR] + [w[a][near] * c for a in range(d)] + [q * c]
            else:
                near = r2 < R2
                e = exp_neg(r2[near] * inv2s2)
                terms = [e - gR] + [w[a][near] * e for a in range(d)]
            at = (jj[near] & 3) * total + i[near]
            for p, term in zip(part, terms, strict=True):
                p[at] = p[at] + term
    part = np.stack(part).reshape(sums, 4, total)
    summed = (part[:, 0] + part[:, 1]) + (part[:, 2] + part[:, 3])
    if adaptive:
        return summed[0], summed[1:d + 1].T.copy(), summed[d + 1]
    return summed[0], summed[1:d + 1].T.copy()


def _loop_bound(kernel, start):
    """The most loop iterations one work-item of ``gbn_pairs`` can run."""
    most = int(np.diff(start.astype(np.int64)).max(initial=0))
    return kernel.stencil * (2 * kernel.d + 1) * (most + 1)


def pass_defines(d, periodic, adaptive):
    """The build options of ``gbn_pairs`` for the current device.

    Parameters
    ----------
    d : int
    periodic, adaptive : bool
        On the torus; with per-point widths.

    Returns
    -------
    dict
        D, PERIODIC, ADAPTIVE, LANES (the launch shape's ``pair_lanes`` for the pass
        without widths, else 1) and the exponential's constants.
    """
    lanes = 1 if adaptive else runtime.shape().pair_lanes
    return {"D": d, "PERIODIC": int(periodic), "ADAPTIVE": int(adaptive), "LANES": lanes,
            **EXP_DEFINES}


def pair_pass_device(pts, cell, start, n, kernel, t=None):
    """``gbn_pairs`` on the current device: :func:`pair_pass_reference`'s result, the same
    bits.

    Parameters
    ----------
    pts, cell, start, n, kernel, t
        As :func:`pair_pass_reference` takes them.

    Returns
    -------
    energy, force[, width]
        As :func:`pair_pass_reference` returns them.

    Raises
    ------
    NoDeviceError
        A device without fp64, or one that stops long loops where a work-item's loops
        would pass its limit.
    """
    limit = runtime.loop_limit()
    if limit is not None and _loop_bound(kernel, start) > limit:
        runtime.require_short_loops("gbn's pair pass")
    total, d = pts.shape
    adaptive = t is not None
    pairs = runtime.kernel("gbn.cl", "gbn_pairs", pass_defines(d, kernel.periodic, adaptive))
    cols = d + 1 + adaptive
    out = runtime.Output((total, cols), np.float64, host=np.empty((total, cols)))
    local = runtime.local_size(64)
    R2, gR = (kernel.Rc2, kernel.gc) if adaptive else (kernel.R2, kernel.gR)
    widths = (runtime.input_buffer(np.asarray(t, dtype=np.float64)),) if adaptive else ()
    pairs(runtime.queue(), (-(-total // local) * local,), (local,), runtime.input_buffer(pts),
          *widths, runtime.input_buffer(start), np.uint32(n), np.uint32(total),
          np.int32(kernel.cells), np.uint32(kernel.stencil), np.float64(R2),
          np.float64(kernel.inv2s2), np.float64(gR), np.float64(kernel.reach ** 2), out.buffer)
    result = out.finish()
    if adaptive:
        return result[:, 0].copy(), result[:, 1:d + 1], result[:, d + 1].copy()
    return result[:, 0].copy(), result[:, 1:]


def _attraction(x, kernel):
    """The unit cube's pull on each point: A(x) = prod_k a(x_k), the integral of the
    Gaussian over the cube, a(t) = s sqrt(pi/2) (erf(t / s sqrt 2) + erf((1 - t) / s sqrt 2)),
    and its gradient, a'(t) = exp(-t^2 / 2 s^2) - exp(-(1 - t)^2 / 2 s^2) in axis k."""
    from scipy.special import erf
    s = kernel.s
    u = 1.0 / (s * math.sqrt(2.0))
    a = s * math.sqrt(math.pi / 2.0) * (erf(x * u) + erf((1.0 - x) * u))
    da = np.exp(-(x * u) ** 2) - np.exp(-((1.0 - x) * u) ** 2)
    total = np.prod(a, axis=-1)
    grad = np.empty_like(x)
    for k in range(x.shape[-1]):
        others = np.prod(np.delete(a, k, axis=-1), axis=-1) if x.shape[-1] > 1 else 1.0
        grad[..., k] = da[..., k] * others
    return total, grad


def gbn_energy(points, kernel, backend="opencl", density=None):
    """The energy and the descent direction of sets, as the optimizer sees them.

    Parameters
    ----------
    points : ndarray (r, n, d)
        In [0, 1)^d.
    kernel : Kernel
    backend : {"opencl", "numpy"}
        Where the pair pass runs (the same bits either way).
    density : callable or array_like, optional
        Adaptive sampling (:class:`GBNSampler`); None: uniform.

    Returns
    -------
    energy : ndarray (r,)
        Per point: (sum over ordered pairs within the cutoff of g(r) - g(R), less
        2 n sum_i A(x_i) in the cube) / n.
    force : ndarray (r, n, d)
        F_i = sum_j (x_i - x_j) g(r_ij) (+ n s^2 grad A(x_i) in the cube), which is
        -(s^2 / 2) times the gradient of n times the energy.

    Examples
    --------
    >>> import numpy as np
    >>> from clsamp.samplers.gbn import Kernel, gbn_energy
    >>> pts = np.random.default_rng(0).random((1, 64, 2))
    >>> energy, force = gbn_energy(pts, Kernel(n=64, d=2, sigma=0.5, periodic=True))
    >>> energy.shape, force.shape
    ((1,), (1, 64, 2))
    """
    if backend != "numpy":
        runtime.require_fp64()
    density = None if density is None else as_density(density, kernel.d)
    return _evaluate(np.asarray(points, dtype=np.float64), kernel,
                     pair_pass_reference if backend == "numpy" else pair_pass_device, density)


def _adaptive_attraction(x, kernel, t, slope):
    """The cube's pull with per-point widths s_i = s sqrt(t_i): the domain filled at the
    point's own density, rho_i A_{s_i}(x_i) = (sqrt(2 pi) s)^d prod_k P(x_k; s_i),
    P(u; w) = (erf(u / w sqrt 2) + erf((1 - u) / w sqrt 2)) / 2 (rho_i s_i^d = s^d), and
    its gradient, through x directly and through s_i (slope: d s_i / d x_i, (m, d))."""
    from scipy.special import erf
    w = kernel.s * np.sqrt(t)[:, None]
    u = 1.0 / (w * math.sqrt(2.0))
    lo, hi = np.exp(-(x * u) ** 2), np.exp(-((1.0 - x) * u) ** 2)
    P = 0.5 * (erf(x * u) + erf((1.0 - x) * u))
    dP = (lo - hi) / (w * math.sqrt(2.0 * math.pi))
    dW = -(x * lo + (1.0 - x) * hi) / (w * w * math.sqrt(2.0 * math.pi))
    d = x.shape[-1]
    scale = (math.sqrt(2.0 * math.pi) * kernel.s) ** d
    others = np.stack([np.prod(np.delete(P, k, axis=-1), axis=-1) for k in range(d)], axis=-1) \
        if d > 1 else np.ones_like(P)
    through_w = np.sum(others * dW, axis=-1)
    return scale * np.prod(P, axis=-1), scale * (others * dP + slope * through_w[:, None])


def _widths(x, density):
    """Each point's variance relative to s^2, t = rho^(-2/d) (rho at least
    :data:`RHO_FLOOR`), and the slope d s_i / d x_i / s = -(sqrt t / (d rho)) grad rho (0
    where rho is floored)."""
    m, d = x.shape
    rho = density(x)
    floored = rho < RHO_FLOOR
    rho = np.where(floored, RHO_FLOOR, rho)
    t = rho ** (-2.0 / d)
    grad = density.gradient(x)
    slope = np.where(floored[:, None], 0.0, -(np.sqrt(t) / (d * rho))[:, None] * grad)
    return t, slope


def _evaluate(x, kernel, pair_pass, density=None):
    """Energy per point (sets,) and force (sets, n, d) of sets x (sets, n, d)."""
    sets, n, d = x.shape
    if density is None:
        pts, cell, start, order = sorted_by_cell(x, kernel.cells)
        e_sorted, f_sorted = pair_pass(pts, cell, start, n, kernel)
    else:
        t, slope = _widths(x.reshape(-1, d), density)
        kernel = dataclasses.replace(kernel, widen=math.sqrt(float(t.max())))
        pts, cell, start, order = sorted_by_cell(x, kernel.cells)
        e_sorted, f_sorted, q_sorted = pair_pass(pts, cell, start, n, kernel, t[order])
    e = np.empty(sets * n)
    f = np.empty((sets * n, d))
    e[order] = e_sorted
    f[order] = f_sorted
    ss = kernel.s * kernel.s
    if density is not None:
        # the widths follow the points: the pair terms' change with s_i, which
        # d s_i / d x_i = s slope carries to the force (see GBNSampler)
        q = np.empty(sets * n)
        q[order] = q_sorted
        f = f - (ss * np.sqrt(t) * q)[:, None] * slope
        if not kernel.periodic:
            pull, grad = _adaptive_attraction(x.reshape(-1, d), kernel, t, kernel.s * slope)
            e = e - 2.0 * n * pull
            f = f + (n * ss) * grad
    e = e.reshape(sets, n)
    f = f.reshape(sets, n, d)
    if density is None and not kernel.periodic:
        pull, grad = _attraction(x, kernel)
        e = e - 2.0 * n * pull
        f = f + (n * ss) * grad
    energy = np.array([math.fsum(row) / n for row in e])
    return energy, f


def _move(x, tau, f, periodic):
    y = x + tau[:, None, None] * f
    if periodic:
        y = y - np.floor(y)
        return np.where(y >= 1.0, 0.0, y)
    return np.clip(y, 0.0, np.nextafter(1.0, 0.0))


@dataclasses.dataclass(frozen=True)
class GBNInfo(SampleInfo):
    """What a Gaussian-blue-noise optimization did, per realization (first axis).

    Attributes
    ----------
    realizations : ndarray (r,)
        The realization indices.
    energy_history : ndarray (r, T)
        The energy per point after each iteration (entry t after t + 1): never rising.
        A set that converged before the call's longest run holds its last value.
    initial_energy : ndarray (r,)
        The energy of the starting points.
    iterations : ndarray (r,)
        The iterations each set ran (a rejected step counts: it costs a pass).
    converged : ndarray of bool (r,)
        Whether the set stopped because a step lowered the energy by at most ``tol`` of
        it (or the step fell below 2^-40 of its start), before ``iterations``.
    step : ndarray (r,)
        The step it ended with, as the points move: tau = ``step`` / ((2 pi)^(d/2)
        sigma^d) at the start (the kernel's mass in points; 1 in 2-D with the defaults),
        halved at every rejection.
    """

    energy_history: np.ndarray = info_field("pad")
    initial_energy: np.ndarray = info_field()
    iterations: np.ndarray = info_field()
    converged: np.ndarray = info_field()
    step: np.ndarray = info_field()


def gbn_optimize(start_points, kernel, step=STEP, iterations=ITERATIONS, tol=TOL,
                 backend="opencl", realizations=None, density=None):
    """Gradient descent on the Gaussian energy from given starting sets.

    Parameters
    ----------
    start_points : ndarray (r, n, d)
        In [0, 1)^d.
    kernel : Kernel
    step : float
        The step relative to the kernel's mass (:class:`GBNSampler`).
    iterations : int
        The most iterations.
    tol : float
        Converged when an accepted step lowers the energy by at most ``tol`` times its
        magnitude (0: run every iteration).
    backend : {"opencl", "numpy"}
        Where the pair pass runs; the rest is shared host code.
    realizations : array_like of int, optional
        The indices the info names (default 0..r-1).
    density : callable, array_like or Density, optional
        Adaptive sampling (:class:`GBNSampler`); None: uniform.

    Returns
    -------
    points : ndarray (r, n, d)
    info : GBNInfo
    """
    if density is not None and not isinstance(density, Density):
        density = as_density(density, kernel.d)
    pair_pass = pair_pass_reference if backend == "numpy" else pair_pass_device
    if backend != "numpy":
        runtime.require_fp64()
    x = np.array(start_points, dtype=np.float64)
    r = x.shape[0]
    tau0 = step / kernel.mass
    index = np.arange(r) if realizations is None else np.asarray(realizations)
    if backend != "numpy" and gbn_device.resident(kernel, density):
        x, energy, initial, tau, converged, ran, history = gbn_device.optimize_resident(
            x, kernel, pass_defines(kernel.d, True, False), tau0, iterations, tol,
            tau0 * 2.0 ** -HALVINGS)
        return x, GBNInfo(realizations=index.astype(np.int64), energy_history=history,
                          initial_energy=initial, iterations=ran, converged=converged, step=tau)
    energy, force = _evaluate(x, kernel, pair_pass, density)
    initial = energy.copy()
    tau = np.full(r, tau0)
    active = np.ones(r, dtype=bool)
    converged = np.zeros(r, dtype=bool)
    ran = np.zeros(r, dtype=np.int64)
    history = []
    for _ in range(iterations):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        y = _move(x[idx], tau[idx], force[idx], kernel.periodic)
        e_new, f_new = _evaluate(y, kernel, pair_pass, density)
        ran[idx] += 1
        ok = e_new <= energy[idx]
        good, bad = idx[ok], idx[~ok]
        drop = energy[good] - e_new[ok]
        x[good], force[good] = y[ok], f_new[ok]
        energy[good] = e_new[ok]
        tau[bad] *= 0.5
        done = np.zeros(r, dtype=bool)
        done[good] = (drop <= tol * np.abs(energy[good])) & (tol > 0.0)    # 0: every iteration
        done[bad] = tau[bad] < tau0 * 2.0 ** -HALVINGS
        converged |= done
        active &= ~done
        history.append(energy.copy())
    history = np.stack(history, axis=1) if history else np.empty((r, 0))
    info = GBNInfo(realizations=index.astype(np.int64), energy_history=history,
                   initial_energy=initial, iterations=ran, converged=converged, step=tau)
    return x, info


@register("gbn")
class GBNSampler(Sampler):
    """Gaussian blue noise: points that minimize the sum of Gaussian kernels between them.

    Parameters
    ----------
    d : int
        Dimension, 1 to 64.
    seed : int
        Seeds the starting points (the ``init`` sampler's realization k with this seed).
    sigma : float
        The Gaussian's standard deviation in mean spacings n^(-1/d) (default 0.5).
    step : float
        The gradient step relative to the kernel's mass (default pi/2, at most 1024; see
        Notes).
    iterations : int
        The most iterations (default 200).
    tol : float
        Stop once a step lowers the energy by at most this fraction of it (default 1e-4,
        which n = 1024 sets reach after about 110 iterations in 2-D and 60 in 4-D, at
        rho near 0.78; 0 runs every iteration, unless the step has been halved 40 times
        over, where a set stops as converged).
    periodic : bool
        True (default): the unit torus, distances wrapped. False: the unit cube, with the
        boundary treatment of the authors' bounded-domain code (the domain, a uniform
        density, attracts the points; see Notes).
    init : str
        The sampler the starting points come from (default ``"random"``; ``"jittered"``
        and any other registered sampler that makes n points in d dimensions without
        iterating or rejecting: not ``poisson_disk`` or the optimizers).
    cut : float
        Pairs farther apart than ``cut`` sigmas do not interact (default 4).
    density : callable or array_like, optional
        Adaptive sampling: the density the points should follow, a callable on points
        (m, d) in [0, 1)^d returning m non-negative values, or an array with d axes (an
        image in 2-D; entry [i, j] at the cell centre ((i + 1/2) / shape[0],
        (j + 1/2) / shape[1]), multilinear between centres); its scale does not matter
        (:func:`clsamp.density.as_density`). The starting points are drawn from it
        (``init`` is then not used). None (default): uniform.
    backend : {"opencl", "numpy"}

    Notes
    -----
    The energy of n points is the sum over ordered pairs of the Gaussian
    g(r) = exp(-r^2 / 2 s^2), s = sigma n^(-1/d): the squared L2 norm of the points'
    density filtered by a Gaussian, less the self terms, whose minimizers are blue noise
    (Ahmed et al. 2022). Its gradient moves point i along
    F_i = sum_j (x_i - x_j) g(|x_i - x_j|), and an iteration is the step
    x_i <- x_i + tau F_i with tau = step / ((2 pi)^(d/2) sigma^d): the step relative to
    the kernel's mass in points, so that one step moves a point by a like fraction of the
    spacing in every dimension. With sigma = 1 and step = pi/2 in 2-D, tau = 1/4, the
    time step of the authors' published code (which defaults to sigma = 1 mean spacing);
    sigma = 0.5 reaches a large minimum distance in far fewer iterations, at a
    low-frequency power still far below Poisson disk's (docs/performance.md gives the
    measurements behind the defaults).

    The kernel is cut at ``cut`` sigmas and shifted to 0 there (g(r) - g(R) for r < R),
    so that the energy stays continuous and F is exactly -s^2/2 times its gradient (in
    n times the energy per point); pairs are found through a grid of cells at least R
    wide, so a step costs O(n). On the torus the differences wrap and R is at most 1/2.
    In the cube (``periodic=False``) the energy also holds the domain's attraction, as
    the authors' bounded-domain code has it: the cross term -2 n sum_i A(x_i), A(x) the
    Gaussian's integral over the cube (a product of erf terms): near a face nothing
    beyond it pushes back on the points, and the domain's pull, which there points
    inward, takes its place, so the points do not bunch on the faces; a step that leaves
    the cube is projected back.

    A step that would raise the energy is rejected and the step halved, so the energy
    never rises (``energy_history``); a run stops when an accepted step lowers it by at
    most ``tol`` of it. The pair pass runs on the device (``kernels/gbn.cl``); its NumPy
    twin gives the same bits, and so does every device. On a CPU device a run on the
    torus without a density keeps its iterations on the device (the exact sum of the
    energies, the step's control and the sort by cell there too), the same bits again.

    *Adaptive sampling* ([1], section on adaptive sampling): each point's kernel width
    follows the density rho (normalized to mean 1) where the point is,
    s_i = s rho(x_i)^(-1/d), and a pair interacts through its combined width, the
    Gaussian of variance s_ij^2 = (s_i^2 + s_j^2) / 2, g_ij = exp(-r^2 / 2 s_ij^2), cut
    at ``cut`` s_ij. Because the widths move with the points, the force is the energy's
    whole gradient: besides sum_j (x_i - x_j) g_ij s^2 / s_ij^2 it holds the pair terms'
    change with s_i, through grad rho (exact for an array, central differences for a
    callable). Where rho is below 1e-3 the widths stop growing. In the cube the
    domain's pull is that of the cube filled at the point's own density,
    rho(x_i) A_{s_i}(x_i). The points then spread with local spacing proportional to
    s_i, that is with density proportional to rho; with a constant density the
    optimization is the uniform one. Where this differs from the paper: its kernels
    are normalized (amplitude s_i^-d) and the energy holds the density's attraction,
    the image convolved with each kernel; a callable in d dimensions has no closed form
    for that term, and without it normalized kernels let the dense side push harder, so
    the set would not follow rho. The pair kernels here keep amplitude 1, which makes
    the spacing follow s_i with repulsion alone. A smooth density is followed closely (1 +
    0.8 sin 2 pi x, n = 1000, 8 sets: E[sin 2 pi x] within 0.011 of its 0.4 on the torus in
    2 to 4 dimensions, within 0.034 in the cube); a jump is blurred over about a spacing on
    each side, which with few points a side moves visible mass (1 + 4 [x < 0.3], 0.68 of the
    mass below 0.3, n = 1000, 11 sets: 0.59-0.63 of the points below 0.3 on the torus in
    2-D, 0.51-0.54 in 3-D, 0.47-0.49 in 4-D; in the cube 0.63-0.67, 0.56-0.60, 0.54-0.58).

    References
    ----------
    .. [1] A. G. M. Ahmed, J. Ren, P. Wonka, "Gaussian Blue Noise", ACM Trans. Graph.
       41(6), 2022 (SIGGRAPH Asia).

    Examples
    --------
    >>> import clsamp
    >>> s = clsamp.make_sampler("gbn", d=2, seed=1, iterations=30)
    >>> pts, info = s.sample(256, return_info=True)
    >>> pts.shape, bool(info.energy_history[0, -1] < info.initial_energy[0])
    ((256, 2), True)
    >>> bool(clsamp.metrics.relative_radius(pts) > 0.6)
    True

    A linear ramp in x, in the unit square:

    >>> ramp = clsamp.make_sampler("gbn", seed=1, periodic=False, iterations=30,
    ...                            density=lambda x: 0.2 + 1.6 * x[:, 0])
    >>> bool((ramp.sample(512)[:, 0] > 0.5).mean() > 0.6)
    True
    """

    max_d = MAX_D
    max_d_source = "the pair pass keeps a point and its force in private memory"
    expensive = True
    accepts_start = False
    needs_fp64 = True
    info = GBNInfo

    def __init__(self, d=2, seed=0, sigma=SIGMA, step=STEP, iterations=ITERATIONS, tol=TOL,
                 periodic=True, init="random", cut=CUT, density=None, backend="opencl"):
        super().__init__(d=d, seed=seed, backend=backend)
        self.density = None if density is None else as_density(density, d)
        if self.density is not None and init != "random":
            raise InvalidArgumentError(
                f"'init' cannot be combined with 'density' (the start is drawn from the "
                f"density), got init={init!r}")
        self.sigma = check_real(sigma, "sigma", minimum=0.0, open_minimum=True, maximum=64.0)
        # a step no 40 halvings bring to one that lowers the energy would end the run at
        # its start, as converged
        self.step = check_real(step, "step", minimum=0.0, open_minimum=True, maximum=STEP_MAX)
        self.iterations = check_positive_int(iterations, "iterations", maximum=MAX_ITERATIONS)
        self.tol = check_real(tol, "tol", minimum=0.0, maximum=1.0)
        self.periodic = check_bool(periodic, "periodic")
        self.cut = check_real(cut, "cut", minimum=1.0, maximum=8.0)
        if not isinstance(init, str) or init.partition(":")[0] in ("gbn",):
            raise InvalidArgumentError(
                f"'init' must name another sampler (such as 'random' or 'jittered'), got {init!r}")
        cls = sampler_class(init)
        if cls.info is not None or (cls.dimensions is not None and d not in cls.dimensions) \
                or d > cls.max_d:
            raise InvalidArgumentError(
                f"'init' must name a sampler that makes sets in {d}-D without iterating, "
                f"got {init!r}")
        self.init = init

    def valid_n(self, n):
        """The count nearest to ``n`` the ``init`` sampler makes (every n for ``random``).

        Parameters
        ----------
        n : int

        Returns
        -------
        int
        """
        return n if self.density is not None else self._start_sampler().valid_n(n)

    def _start_sampler(self):
        return make_sampler(self.init, d=self.d, seed=self.seed, backend=self.backend)

    def _run(self, n, realizations, backend):
        if self.density is None:
            start = self._start_sampler().sample(n, realizations=realizations)
        else:
            start = self.density.sample(self.seed, realizations, n)
        kernel = Kernel(n=n, d=self.d, sigma=self.sigma, periodic=self.periodic, cut=self.cut)
        return gbn_optimize(start, kernel, self.step, self.iterations, self.tol, backend,
                            np.arange(realizations.start, realizations.stop), self.density)

    def _work_bytes(self, n):
        # measured: 140, 328 and 759 bytes a point in 2-D, 4-D and 8-D
        return 95 * self.d * n

    def _reference(self, n, realizations, start):
        return self._run(n, realizations, "numpy")

    def _device(self, n, realizations, start, out=None):
        return self._run(n, realizations, "opencl")
