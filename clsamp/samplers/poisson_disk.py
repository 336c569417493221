"""The ``poisson_disk`` sampler: parallel dart throwing into tracked voids.

Two modes:

* fixed n (the default, ``rho=0.75``): ``sample(n)`` returns exactly n points whose
  minimum toroidal distance is at least ``rho * d_max(n)``
  (:func:`clsamp.point_metrics.max_min_distance`);
* maximal (``radius=r``, n left out): ``sample()`` returns a maximal set, one where no
  further disk centre of radius r fits anywhere on the torus.

Both run the same process (Ebeida et al. 2011, 2012) with the darts' acceptance in
OpenCL (``kernels/dart_throwing.cl``); ``backend="numpy"`` runs the NumPy twin in
this module (class ``_NumpyDarts``, one method per kernel), which gives the same set
bit for bit. The round loop that both share is :func:`_throw_darts`.
"""

import math

import numpy as np
import pyopencl as cl
import pyopencl.array as cla

from .. import philox, runtime
from ..errors import InvalidArgumentError, SamplingError
from ..point_metrics import max_min_distance, toroidal_distance2
from ..validation import check_positive_int, check_real
from .base import Sampler, register

HEXAGONAL_DENSITY = math.pi / math.sqrt(12.0)   # 0.9069: the largest 'rho' accepted
MAX_RADIUS = 0.5            # beyond, a disk overlaps its own periodic image
MAX_CELLS = 2**24           # grid cells per realization (memory: ~ 9 + 8 d bytes each,
                            # and about as much again for the active cells)
BATCH_CELLS = 2**21         # grid cells of the realizations handled in one launch
LEVEL0_ROUNDS = 2           # rounds of darts at grid-cell level before refining every round
MAX_LEVEL = 30              # subcell coordinates are 32-bit
MAX_ROUNDS = 2048           # the dart tag holds the round in 11 bits
MAX_RANK = 2**20            # and the rank within a grid cell's entries in 20 bits
RESOLVE_STEPS = (4, 2)      # greedy steps per round at level 0 and deeper (dart_resolve);
                            # darts still open stay out (deep darts rarely conflict)
MAX_ATTEMPTS = 8            # redraws of a realization that became maximal below n
_NO_ROUND = np.uint32(0xFFFFFFFF)
_OUT, _OPEN, _IN = 0, 1, 2     # dart states of dart_resolve


# -- the geometry both backends share -------------------------------------------------------
def grid_size(radius, d):
    """Grid cells per axis, G = floor(sqrt(d) / r) + 1: cells of side 1/G < r / sqrt(d),
    so a cell's diagonal is shorter than r and a cell holds at most one point."""
    return int(math.floor(math.sqrt(d) / radius)) + 1


def reach(radius, G):
    """K: grid cells at offset above K on some axis are r or more apart (side 1/G)."""
    return int(math.floor(radius * G)) + 1


def acceptance_threshold(radius, scale=1.0, target=None):
    """The smallest double r2 >= radius^2 with sqrt(r2) / scale >= target in double
    arithmetic (target defaults to radius / scale).

    Darts are accepted when their squared distance is >= r2, so the minimum distance that
    :func:`clsamp.point_metrics.min_distance` measures (a square root of the same bits),
    divided by ``scale`` (d_max for a relative radius, whose target is rho), is never
    below the promise, not even by an ulp.
    """
    if target is None:
        target = radius / scale
    r2 = radius * radius
    while math.sqrt(r2) < radius or math.sqrt(r2) / scale < target:
        r2 = math.nextafter(r2, math.inf)
    return r2


def level_of(round_):
    """Refinement level of round ``round_``: level 0 for LEVEL0_ROUNDS rounds, then one
    level deeper each round (the same for all realizations, so none depends on another)."""
    return max(0, round_ - (LEVEL0_ROUNDS - 1))


def resolve_steps(round_):
    """Greedy steps of round ``round_`` (a function of the round alone, as the level)."""
    return RESOLVE_STEPS[0] if level_of(round_) == 0 else RESOLVE_STEPS[1]


def window_offsets(radius, G, d):
    """The grid offsets whose cells can hold a point closer than r to a point of the
    centre cell, nearest first (ties in np.ndindex order): the kernels' window table.

    Cells at offset o are at least sqrt(sum_k max(|o_k| - 1, 0)^2) / G apart; offsets
    beyond K = floor(r G) + 1 on an axis are at least r apart, and so are those the bound
    puts at r or more (kept, with a margin of 1e-9, when the bound is within rounding of r).
    Order does not change any result (the kernels ask "is there any"), only how soon the
    loops stop.
    """
    K = reach(radius, G)
    offsets = np.array(list(np.ndindex(*(2 * K + 1,) * d)), dtype=np.int64) - K
    gap = np.maximum(np.abs(offsets) - 1, 0).astype(np.float64) / G
    bound2 = np.sum(gap * gap, axis=1)
    keep = bound2 < radius * radius * (1.0 + 1e-9)
    order = np.argsort(bound2[keep], kind="stable")
    return offsets[keep][order]


def cover_window(radius, G, d, level):
    """The grid offsets whose points can cover a whole level-``level`` box (side
    w = 1 / (G 2^level)) of the centre cell, nearest first: dart_refine's table.

    A point in the cell at offset o is, along axis k, at least w / 2 from the farther end
    of the box when o_k = 0 and (|o_k| - 1) / G + w when o_k != 0; offsets whose bound
    reaches r (with a margin of 1e-9) can cover nothing. At level 0 this leaves the 3^d
    nearest cells of the 5^d that dart_throw must search, where most entries are refined.
    """
    offsets = window_offsets(radius, G, d)
    w = 1.0 / (G * 2.0 ** level)
    a = np.abs(offsets)
    gap = np.where(a == 0, w / 2.0, (np.maximum(a, 1) - 1) / G + w)
    keep = np.sum(gap * gap, axis=1) < radius * radius * (1.0 + 1e-9)
    return offsets[keep]


def _cell_coords(flat, G, d):
    coords = np.empty(flat.shape + (d,), dtype=np.int64)
    rest = flat.astype(np.int64)
    for k in range(d - 1, -1, -1):
        coords[..., k] = rest % G
        rest = rest // G
    return coords


def _flat(coords, G):
    flat = np.zeros(coords.shape[:-1], dtype=np.int64)
    for k in range(coords.shape[-1]):
        flat = flat * G + coords[..., k] % G
    return flat


def _torus_delta(a, b):
    t = np.abs(a - b)
    return np.minimum(t, 1.0 - t)


def _far_corner2(c, M, p):
    """Squared distance from p to the farthest corner of the boxes with integer coordinates
    c (side 1/M), as far_corner2 in the kernel."""
    lo = c.astype(np.float64) / M
    hi = (c + 1).astype(np.float64) / M
    f = np.maximum(_torus_delta(lo, p), _torus_delta(hi, p))
    f = np.where(f > 0.5 - (hi - lo), 0.5, f)
    total = f[..., 0] * f[..., 0]
    for k in range(1, f.shape[-1]):
        total = total + f[..., k] * f[..., k]
    return total


def _child_bits(children, d):
    """Bit k of child t is its half on axis k (axis 0 the most significant), as in the kernel."""
    t = np.arange(children)
    return np.stack([(t >> (d - 1 - k)) & 1 for k in range(d)], axis=-1)


class _Geometry:
    """The parameters of one run: dimension, radius, grid and threshold."""

    def __init__(self, d, radius, r2):
        self.d = d
        self.radius = radius
        self.r2 = r2
        self.G = grid_size(radius, d)
        self.cells = self.G ** d
        self.window = window_offsets(radius, self.G, d)
        # the kernels wrap a neighbour's coordinate with one correction
        assert np.abs(self.window).max() <= self.G
        self.nblocks = d // 2 + 1
        self._cover = {}

    def cover(self, level):
        """The cover window for boxes at ``level`` (cached)."""
        if level not in self._cover:
            self._cover[level] = cover_window(self.radius, self.G, self.d, level)
        return self._cover[level]


# -- the NumPy twin of kernels/dart_throwing.cl ---------------------------------------------
class _NumpyDarts:
    """Reference backend: one method per kernel, the same arithmetic in the same order.

    ``ids`` are the (global) realization numbers of the batch and ``attempt`` the
    redraw number (see :func:`_sample_sets`).
    """

    def __init__(self, geo, ids, attempt, seed):
        self.geo, self.ids, self.attempt, self.seed = geo, np.asarray(ids), attempt, seed
        self.B = len(ids)
        slots = self.B * geo.cells
        self.occ = np.zeros(slots, dtype=np.uint8)
        self.pts = np.zeros((slots, geo.d), dtype=np.float64)
        self.cand_round = np.full(slots, _NO_ROUND, dtype=np.uint32)
        self.cand_first = np.zeros(slots, dtype=np.int64)
        self.total = np.zeros(self.B, dtype=np.int64)
        i = np.arange(slots, dtype=np.int64)
        self.rel, self.base, self.first = i // geo.cells, i % geo.cells, i.copy()
        self.sub = np.zeros((slots, geo.d), dtype=np.int64)

    @property
    def m(self):
        return self.rel.size

    def throw(self, round_, level):
        g = self.geo
        m = self.m
        slot = self.rel * g.cells + self.base
        heads = np.flatnonzero(self.first == np.arange(m))
        self.cand_round[slot[heads]] = round_
        self.cand_first[slot[heads]] = heads
        tag = (np.uint32(round_) << np.uint32(20)) | (np.arange(m) - self.first).astype(np.uint32)
        index = self.base.astype(np.uint32) | np.uint32(self.attempt << 26)
        key = np.stack(philox.seed_key(self.seed))
        u = np.empty((m, g.d))
        prio = np.zeros(m, dtype=np.uint32)
        for b in range(g.nblocks):
            counter = np.stack([index, self.ids[self.rel].astype(np.uint32),
                                tag * np.uint32(g.nblocks) + np.uint32(b),
                                np.full(m, philox.Stream.CANDIDATES, dtype=np.uint32)], axis=-1)
            w = philox.philox4x32(counter, key)
            if 2 * b < g.d:
                u[:, 2 * b] = philox.words_to_unit(w[:, 0], w[:, 1])
            else:
                prio = w[:, 0]
            if 2 * b + 1 < g.d:
                u[:, 2 * b + 1] = philox.words_to_unit(w[:, 2], w[:, 3])
            elif 2 * b < g.d:
                prio = w[:, 2]
        bc = _cell_coords(self.base, g.G, g.d)
        c = (bc << level) | self.sub
        x = (c.astype(np.float64) + u) / float(g.G << level)
        x[x >= 1.0] = 0.0
        ok = self.occ[slot] == 0
        for off in g.window:
            nslot = self.rel * g.cells + _flat(bc + off, g.G)
            hit = ok & (self.occ[nslot] == 1)
            if hit.any():
                h = np.flatnonzero(hit)
                ok[h[toroidal_distance2(x[h], self.pts[nslot[h]]) < g.r2]] = False
        self.cand, self.prio, self.valid = x, prio, ok
        if m and int(np.max(np.arange(m) - self.first)) >= MAX_RANK:
            raise _rank_overflow()

    def accepted(self):
        """Darts accepted so far, per realization (trimmed ones included)."""
        return self.total.copy()

    def resolve(self, round_):
        g = self.geo
        m = self.m
        slot = self.rel * g.cells + self.base
        state = np.where(self.valid, _OPEN, _OUT).astype(np.uint8)
        for _ in range(resolve_steps(round_)):
            idx = np.flatnonzero(state == _OPEN)
            bc = _cell_coords(self.base[idx], g.G, g.d)
            rel, pi = self.rel[idx], self.prio[idx]
            beaten = np.zeros(idx.size, dtype=bool)
            blocked = np.zeros(idx.size, dtype=bool)
            for off in g.window:
                nb = _flat(bc + off, g.G)
                nslot = rel * g.cells + nb
                live = self.cand_round[nslot] == round_
                j = self.cand_first[nslot]
                while True:
                    jj = np.minimum(j, m - 1)
                    live &= (j < m) & (self.rel[jj] == rel) & (self.base[jj] == nb)
                    if not live.any():
                        break
                    sj, pj = state[jj], self.prio[jj]
                    higher = (pj > pi) | ((pj == pi) & (jj < idx))
                    ask = live & higher & (sj != _OUT)
                    if ask.any():
                        q = np.flatnonzero(ask)
                        close = toroidal_distance2(self.cand[idx[q]], self.cand[jj[q]]) < g.r2
                        beaten[q[close & (sj[q] == _IN)]] = True
                        blocked[q[close & (sj[q] == _OPEN)]] = True
                    j = j + 1
            nxt = np.where(beaten, _OUT, np.where(blocked, _OPEN, _IN)).astype(np.uint8)
            state[idx] = nxt
            won = idx[nxt == _IN]
            self.occ[slot[won]] = 1
            self.pts[slot[won]] = self.cand[won]
            self.total += np.bincount(self.rel[won], minlength=self.B)
        self.won = state == _IN

    def won_entries(self):
        """(realization, slot, priority) of each dart accepted this round."""
        w = np.flatnonzero(self.won)
        return self.rel[w], self.rel[w] * self.geo.cells + self.base[w], self.prio[w]

    def clear(self, slots):
        self.occ[slots] = 0

    def refine(self, level, split, done, tally):
        g = self.geo
        children = (1 << g.d) if split else 1
        slot = self.rel * g.cells + self.base
        active = (done[self.rel] == 0) & (self.occ[slot] == 0)
        open_ = np.zeros((self.m, children), dtype=bool)
        open_[active] = True
        idx = np.flatnonzero(active)
        bc = _cell_coords(self.base[idx], g.G, g.d)
        cp = (bc << level) | self.sub[idx]
        cc = (cp[:, None, :] << 1) | _child_bits(children, g.d)[None]
        Mp, Mc = float(g.G << level), float(g.G << (level + 1))
        for off in g.cover(level + split):
            nslot = self.rel[idx] * g.cells + _flat(bc + off, g.G)
            has = self.occ[nslot] == 1
            if not has.any():
                continue
            h = np.flatnonzero(has)
            p = self.pts[nslot[h]]
            covered = _far_corner2(cp[h], Mp, p) < g.r2
            open_[idx[h[covered]]] = False
            if split:
                open_[idx[h]] &= ~(_far_corner2(cc[h], Mc, p[:, None, :]) < g.r2)
        self.mask = open_
        counts = open_.sum(axis=1)
        return counts, np.bincount(self.rel, weights=counts, minlength=self.B).astype(np.int64)

    def emit(self, counts, offs, split):
        g = self.geo
        # row-major nonzero: parents in order, each parent's children in bit order
        parent, t = np.nonzero(self.mask)
        bits = _child_bits(1 << g.d, g.d)[t] if split else np.zeros((t.size, g.d), dtype=np.int64)
        self.sub = (self.sub[parent] << split) | bits
        self.first = offs[self.first[parent]].astype(np.int64)
        self.rel, self.base = self.rel[parent], self.base[parent]

    def gather(self, dst, out):
        occ = self.occ.reshape(self.B, self.geo.cells)
        pts = self.pts.reshape(self.B, self.geo.cells, self.geo.d)
        for r in range(self.B):
            if dst[r] != _SKIP:
                got = pts[r][occ[r] == 1]
                out[dst[r]:dst[r] + len(got)] = got


# -- the OpenCL backend ---------------------------------------------------------------------
class _DeviceDarts:
    """Runs each step as one launch over every active entry of every realization."""

    def __init__(self, geo, ids, attempt, seed):
        runtime.require_fp64()
        self.geo, self.attempt, self.seed = geo, attempt, seed
        self.B = len(ids)
        q = self.q = runtime.queue()
        self.ls = runtime.local_size(64)
        self.defines = {"DIM": geo.d}
        slots = self.B * geo.cells
        self.ids = cla.to_device(q, np.asarray(ids, dtype=np.uint32))
        self.window = self._table(geo.window)
        self._covers = {}
        # dart_init clears occ and cand_round; the small buffers come from the host (no
        # pyopencl fill kernels: runtime builds every program)
        self.occ = cla.empty(q, slots, np.uint8)
        self.pts = cla.empty(q, slots * geo.d, np.float64)
        self.cand_round = cla.empty(q, slots, np.uint32)
        self.cand_first = cla.empty(q, slots, np.uint32)
        self.accepted_ = cla.to_device(q, np.zeros(self.B, dtype=np.uint32))
        self.overflow = cla.to_device(q, np.zeros(1, dtype=np.uint32))
        self.remaining = cla.to_device(q, np.zeros(self.B, dtype=np.uint32))
        self.done = cla.to_device(q, np.zeros(self.B, dtype=np.uint8))
        self._done = np.zeros(self.B, dtype=np.uint8)
        self.m = slots
        self._alloc_entries(slots)
        self._run("dart_init", self.m, self.rel.data, self.base.data, self.sub.data,
                  self.first.data, self.occ.data, self.cand_round.data, np.uint32(geo.cells),
                  np.uint32(self.m))

    def _alloc_entries(self, m):
        """Entry buffers for m entries: the (rel, base, sub, first) set not in use is
        reused when large enough (emit reads one set and writes the other), the per-dart
        buffers grow only; creating buffers every round cost more than a small round."""
        q, d, m = self.q, self.geo.d, max(m, 1)
        spare = getattr(self, "_spare", None)
        current = getattr(self, "rel", None)
        if current is not None:
            self._spare = (self.rel, self.base, self.sub, self.first)
        if spare is not None and spare[0].size >= m:
            self.rel, self.base, self.sub, self.first = spare
        else:
            self.rel = cla.empty(q, m, np.uint32)
            self.base = cla.empty(q, m, np.uint32)
            self.sub = cla.empty(q, m * d, np.uint32)
            self.first = cla.empty(q, m, np.uint32)
        if getattr(self, "_darts", 0) < m:
            self._darts = m
            self.cand = cla.empty(q, m * d, np.float64)
            self.prio = cla.empty(q, m, np.uint32)
            self.valid = cla.empty(q, m, np.uint8)
            self.state = cla.empty(q, m, np.uint8)
            self.mask = cla.empty(q, m, np.uint8)
            self.count = cla.empty(q, m, np.uint8)

    def _run(self, name, items, *args):
        k = runtime.kernel("dart_throwing.cl", name, defines=self.defines)
        size = max(self.ls, -(-items // self.ls) * self.ls)
        k(self.q, (size,), (self.ls,), *args)

    def _table(self, offsets):
        """A window table for the kernels: rows of d offsets and their flat difference,
        with the rows' count and their reach along an axis."""
        G, d = self.geo.G, self.geo.d
        flat = offsets @ (G ** np.arange(d - 1, -1, -1))
        rows = np.concatenate([offsets, flat[:, None]], axis=1).astype(np.int32)
        return (cla.to_device(self.q, np.ascontiguousarray(rows).ravel()), np.uint32(len(rows)),
                np.int32(np.abs(offsets).max()))

    def _cover_window(self, level):
        if level not in self._covers:
            self._covers[level] = self._table(self.geo.cover(level))
        return self._covers[level]

    def _common(self, window=None):
        g = self.geo
        table, rows, reach = window or self.window
        return (np.uint32(self.m), np.uint32(g.G), table.data, rows, reach, np.uint32(g.cells))

    def throw(self, round_, level):
        self._run("dart_throw", self.m, self.rel.data, self.base.data, self.sub.data,
                  self.first.data, self.occ.data, self.pts.data, self.cand.data, self.prio.data,
                  self.valid.data, self.cand_round.data, self.cand_first.data,
                  self.overflow.data, *self._common(),
                  np.uint32(level), np.uint32(round_), np.float64(self.geo.r2), self.ids.data,
                  np.uint32(self.attempt), *runtime.key_args(self.seed),
                  np.uint32(philox.Stream.CANDIDATES))

    def resolve(self, round_):
        state, other = self.valid, self.state
        for step in range(resolve_steps(round_)):
            self._run("dart_resolve", self.m, self.rel.data, self.base.data, self.cand.data,
                      self.prio.data, state.data, other.data, self.cand_round.data,
                      self.cand_first.data, self.occ.data, self.pts.data, self.accepted_.data,
                      *self._common(), np.uint32(round_), np.uint32(step),
                      np.float64(self.geo.r2))
            state, other = other, state
        self.won = state

    def accepted(self):
        """Darts accepted so far, per realization (trimmed ones included)."""
        if self.overflow.get()[0]:
            raise _rank_overflow()
        return self.accepted_.get().astype(np.int64)

    def won_entries(self):
        m = self.m
        won = self.won[:m].get() == _IN
        rel = self.rel[:m].get()[won].astype(np.int64)
        base = self.base[:m].get()[won].astype(np.int64)
        return rel, rel * self.geo.cells + base, self.prio[:m].get()[won]

    def clear(self, slots):
        if len(slots):
            buf = cla.to_device(self.q, np.asarray(slots, dtype=np.uint32))
            self._run("dart_clear", len(slots), self.occ.data, buf.data, np.uint32(len(slots)))

    def refine(self, level, split, done, tally):
        if not np.array_equal(done, self._done):
            self._done = done.copy()
            self.done.set(self._done)
        if tally:
            self.remaining.set(np.zeros(self.B, dtype=np.uint32))
        self._run("dart_refine", self.m, self.rel.data, self.base.data, self.sub.data,
                  self.occ.data, self.pts.data, self.done.data, self.mask.data, self.count.data,
                  self.remaining.data, *self._common(self._cover_window(level + split)),
                  np.uint32(level), np.uint32(split), np.float64(self.geo.r2))
        return (self.count[:self.m].get(),
                self.remaining.get().astype(np.int64) if tally else None)

    def emit(self, counts, offs, split):
        total = int(offs[-1] + counts[-1]) if len(counts) else 0
        m = self.m
        if getattr(self, "_offs", None) is None or self._offs.size < m:
            self._offs = cla.empty(self.q, max(m, 1), np.uint32)
        # not blocking: the host array is kept until the next round's blocking read
        self._offs_host = np.ascontiguousarray(offs, dtype=np.uint32)
        cl.enqueue_copy(self.q, self._offs.data, self._offs_host, is_blocking=False)
        old = (self.rel, self.base, self.sub, self.first, self.mask)
        self._alloc_entries(total)
        self._run("dart_emit", m, old[0].data, old[1].data, old[2].data, old[3].data,
                  old[4].data, self._offs.data, self.rel.data, self.base.data, self.sub.data,
                  self.first.data, np.uint32(m), np.uint32(split))
        self.m = total

    def gather(self, dst, out):
        self._run("dart_gather", self.B, self.occ.data, self.pts.data,
                  cla.to_device(self.q, np.asarray(dst, dtype=np.uint32)).data, out.data,
                  np.uint32(self.geo.cells), np.uint32(self.B))


_SKIP = 0xFFFFFFFF   # gather: a realization that is redrawn


def _rank_overflow():
    return SamplingError(
        f"poisson_disk: more than {MAX_RANK} active subcells in one grid cell "
        "(a bug: please report it with the seed and radius)")


# -- the round loop -------------------------------------------------------------------------
def _throw_darts(backend, n):
    """Run rounds until every realization is maximal or (n given) holds n points.

    Each round: one dart per active entry (``throw``), a few greedy steps among the
    valid darts (``resolve``), then the entries are refined (``refine``/``emit``): covered ones are
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
    while backend.m:
        level = level_of(round_)
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
    return counts, short, {"rounds": round_, "darts": darts}


@register("poisson_disk")
class PoissonDiskSampler(Sampler):
    """Poisson-disk points by parallel dart throwing, on the unit torus.

    Parameters
    ----------
    d : int
        Dimension, 1 to 3.
    seed : int
        Seed of the darts (``Stream.CANDIDATES``).
    rho : float, optional
        Relative radius in (0, 0.9069] for a fixed n (default 0.75 when ``radius`` is not
        given): the points are at least ``rho * d_max(n)`` apart, d_max from
        :func:`clsamp.point_metrics.max_min_distance` (2-D: sqrt(2 / (sqrt(3) n))).
        Saturated (maximal) dart throwing reaches about 0.77 in 2-D (0.80 in 3-D, 0.75 in
        1-D), so values close to that may need redraws and values above it fail: the
        error says so.
    radius : float, optional
        Absolute radius in (0, 0.5]. With ``sample()`` (n left out) the set is maximal:
        no point of the torus is r or more from every point. With ``sample(n)`` exactly n
        points at least r apart. Not together with ``rho``.
    backend : {"opencl", "numpy"}
        ``"numpy"`` runs the NumPy reference, which gives the same points.

    Attributes
    ----------
    counts : ndarray of int
        Points per realization of the last call.
    radius_used : float
        The radius the last call kept (``rho * d_max(n)`` in fixed-n mode).
    rho_bound : ndarray of float
        ``radius_used / d_max(count)`` per realization: a lower bound of the realized
        relative radius (:func:`clsamp.point_metrics.relative_radius` measures it).
    stats : dict
        Rounds and darts thrown by the last call.

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
    rho of about 0.75 in 1-D (Renyi's parking constant 0.7476), 0.77 in 2-D and 0.80 in 3-D,
    so at the default 0.75 large 1-D sets fail: use a smaller rho there.

    In radius mode the count differs between realizations, so ``sample()`` accepts
    ``realizations`` of None (shape (m, d)) or 1 (shape (1, m, d)) only;
    :meth:`sample_sets` returns a list of k maximal sets (made in one batch). ``start``
    must be 0 (a set, not a sequence).

    Points are returned in grid-cell order (row-major), not in the order of acceptance.

    References
    ----------
    M. S. Ebeida, A. A. Davidson, A. Patney, P. M. Knupp, S. A. Mitchell, J. D. Owens,
    "Efficient maximal Poisson-disk sampling", ACM Trans. Graph. 30(4), 2011.
    M. S. Ebeida, S. A. Mitchell, A. Patney, A. A. Davidson, J. D. Owens, "A simple
    algorithm for maximal Poisson-disk sampling in high dimensions", Comput. Graph.
    Forum 31(2), 2012.
    L.-Y. Wei, "Parallel Poisson disk sampling", ACM Trans. Graph. 27(3), 2008.
    M. Luby, "A simple parallel algorithm for the maximal independent set problem",
    SIAM J. Comput. 15(4), 1986.
    A. Lagae, P. Dutre, "A comparison of methods for generating Poisson disk
    distributions", Comput. Graph. Forum 27(1), 2008.

    Examples
    --------
    >>> import clsamp
    >>> from clsamp.point_metrics import relative_radius
    >>> pts = clsamp.make_sampler("poisson_disk", seed=1).sample(256, realizations=2)
    >>> pts.shape, bool(relative_radius(pts).min() >= 0.75)
    ((2, 256, 2), True)
    >>> s = clsamp.make_sampler("poisson_disk", radius=0.1, seed=1)
    >>> s.sample().shape == (s.counts[0], 2)
    True
    """

    dimensions = (1, 2, 3)
    accepts_start = False

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
            G = grid_size(self.radius, self.d)
            if G ** self.d > MAX_CELLS:
                raise InvalidArgumentError(
                    f"'radius'={self.radius} is too small for d={self.d}: its background grid "
                    f"would have {G ** self.d} cells, more than {MAX_CELLS}")
            self.rho = None
            self.needs_n = False
        else:
            self.radius = None
            self.rho = 0.75 if rho is None else check_real(rho, "rho", minimum=0.0,
                                                           open_minimum=True)
            if self.rho > HEXAGONAL_DENSITY:
                raise InvalidArgumentError(
                    f"'rho' must be <= {HEXAGONAL_DENSITY:.4f} (pi / sqrt(12), beyond "
                    f"hexagonal packing), got {self.rho}; maximal dart throwing reaches "
                    "about 0.77 in 2-D")
        self.counts = None
        self.radius_used = None
        self.rho_bound = None
        self.stats = None

    def __repr__(self):
        what = f"radius={self.radius}" if self.radius is not None else f"rho={self.rho}"
        return f"{type(self).__name__}(d={self.d}, seed={self.seed}, {what})"

    # -- the public surface -------------------------------------------------------------
    def sample(self, n=None, realizations=None, start=0):
        """Fixed n: (n, d) or (realizations, n, d). Radius mode, n left out: one maximal
        set (m, d), or (1, m, d) for ``realizations=1`` (use :meth:`sample_sets` for more)."""
        self._check_maximal(n, realizations)
        return super().sample(n, realizations, start)

    def sample_device(self, n=None, realizations=None, start=0):
        self._check_maximal(n, realizations)
        return super().sample_device(n, realizations, start)

    def sample_sets(self, realizations):
        """``realizations`` maximal sets (radius mode) as a list of (m_k, d) arrays.

        Set k is the same as ``make_sampler(..., seed=s).sample()`` gives for k = 0 and does
        not depend on how many sets are asked for; all sets are made in one batch.
        """
        if self.radius is None:
            raise InvalidArgumentError("sample_sets needs 'radius' (maximal sets)")
        r = check_positive_int(realizations, "realizations")
        return self._run(None, range(r), device=self.backend == "opencl", as_list=True)

    def _check_maximal(self, n, realizations):
        if n is None and self.radius is not None and realizations not in (None, 1):
            raise InvalidArgumentError(
                f"'realizations'={realizations!r}: maximal sets (radius mode, n left out) have "
                "different sizes, so they do not fit one (r, n, d) array; use "
                "sample_sets(realizations) for a list, or give n for exactly n points each")

    # -- what the base calls ------------------------------------------------------------
    def _reference(self, n, realizations, start):
        return self._run(n, realizations, device=False)

    def _device(self, n, realizations, start):
        return self._run(n, realizations, device=True)

    # -- the work -------------------------------------------------------------------------
    def _geometry(self, n):
        if self.radius is not None:
            return _Geometry(self.d, self.radius, acceptance_threshold(self.radius))
        d_max = max_min_distance(n, self.d)
        radius = self.rho * d_max
        G = grid_size(radius, self.d)
        if G ** self.d > MAX_CELLS:
            raise InvalidArgumentError(
                f"'n'={n} is too large for d={self.d}: the background grid would have "
                f"{G ** self.d} cells, more than {MAX_CELLS}")
        return _Geometry(self.d, radius, acceptance_threshold(radius, d_max, self.rho))

    def _run(self, n, realizations, device, as_list=False):
        geo = self._geometry(n)
        ids = np.arange(realizations.start, realizations.stop, dtype=np.int64)
        if self.radius is not None:
            what = f"'radius'={self.radius:.6g}"
        else:
            what = f"'rho'={self.rho:.6g} (radius {geo.radius:.6g})"
        parts, counts, stats = _draw(geo, ids, n, self.seed, device, what)
        self.counts = counts
        self.radius_used = geo.radius
        sizes, where = np.unique(counts, return_inverse=True)
        self.rho_bound = np.array([geo.radius / max_min_distance(int(c), self.d)
                                   for c in sizes])[where]
        self.stats = stats
        if as_list:
            sets = []
            for out, c in parts:
                host = out.get() if device else out
                sets.extend(np.split(host[:int(c.sum())], np.cumsum(c)[:-1]))
            return sets
        (out, c), = parts if n is None else ((parts, counts),)
        m = int(c[0])
        shape = (len(ids), m, self.d)
        if m * len(ids) < out.shape[0]:  # a maximal set's buffer is one row long when empty
            out = out[:m * len(ids)]
        return out.reshape(shape)


def _draw(geo, ids, n, seed, device, what):
    """Draw realizations ``ids`` in batches of at most BATCH_CELLS grid cells.

    Fixed n: returns ``(out, counts, stats)`` with out of shape (len(ids) * n, d) (device or
    host), realization after realization. A realization that becomes maximal below n is
    drawn again with the next ``attempt`` (the Philox counters' grid-cell word carries it
    in bits 26-31), up to MAX_ATTEMPTS times; so realization k still depends on k alone, and
    its points follow the process conditioned on reaching n.

    Maximal (n None): returns ``([(out, counts) per batch], counts, stats)``.
    """
    make = _DeviceDarts if device else _NumpyDarts
    per_batch = max(1, BATCH_CELLS // geo.cells)
    if device:  # the point grid, the largest buffer, within a quarter of one allocation
        per_batch = max(1, min(per_batch, runtime.current_device().max_allocation
                               // (4 * 8 * geo.d * geo.cells)))
    stats = {"rounds": 0, "darts": 0, "redraws": 0}

    def alloc(rows):
        if device:
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
            counts, short, st = _throw_darts(backend, n)
            account(st)
            backend.gather(np.where(short, _SKIP, batch * n).astype(np.int64), out)
            if short.any():
                best = max(best, int(counts[short].max()))
            still.append(batch[short])
        pending = np.concatenate(still)
    if pending.size:
        raise InvalidArgumentError(
            f"n={n} points cannot be placed at {what} in d={geo.d}: realization "
            f"{int(ids[pending[0]])} became maximal below n in {MAX_ATTEMPTS} attempts (at most "
            f"{best} points). Use a smaller 'rho' (saturated dart throwing reaches about 0.75 "
            "in 1-D, 0.77 in 2-D, 0.80 in 3-D) or a smaller 'radius'")
    return out, np.full(len(ids), n, dtype=np.int64), stats


__all__ = ["PoissonDiskSampler", "grid_size", "reach", "acceptance_threshold"]
