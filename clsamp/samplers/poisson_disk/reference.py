"""The NumPy twin of ``kernels/dart_throwing.cl``: one method per kernel, the same
arithmetic in the same order, so it gives the kernels' sets bit for bit."""

import numpy as np

from ... import philox
from ...geometry import torus
from ...geometry.cells import neighbour_cells
from .coarse import COARSE_STEPS
from .grid import (
    IN,
    MAX_RANK,
    NO_ROUND,
    OPEN,
    OUT,
    SKIP,
    cell_coords,
    child_bits,
    far_corner2,
    flat_index,
    rank_overflow,
    resolve_steps,
)


def draw_darts(seed, index, realization, block0, d):
    """The darts' uniforms and priorities, as ``dart_draw`` in the kernel: Philox blocks
    ``block0`` to ``block0 + d // 2`` of (index, realization) in ``Stream.CANDIDATES``, two
    coordinates a block, the priority the first word left over.

    Parameters
    ----------
    seed : int
    index, realization, block0 : ndarray of uint32
        Per dart, broadcast together.
    d : int

    Returns
    -------
    u : ndarray (m, d) of float64 in [0, 1)
    priority : ndarray (m,) of uint32
    """
    index, realization, block0 = np.broadcast_arrays(
        *(np.asarray(a, dtype=np.uint32) for a in (index, realization, block0)))
    m = index.size
    key = np.stack(philox.seed_key(seed))
    u = np.empty((m, d))
    prio = np.zeros(m, dtype=np.uint32)
    for b in range(d // 2 + 1):
        counter = np.stack([index, realization, block0 + np.uint32(b),
                            np.full(m, philox.Stream.CANDIDATES, dtype=np.uint32)], axis=-1)
        w = philox.philox4x32(counter, key)
        if 2 * b < d:
            u[:, 2 * b] = philox.words_to_unit(w[:, 0], w[:, 1])
        else:
            prio = w[:, 0]
        if 2 * b + 1 < d:
            u[:, 2 * b + 1] = philox.words_to_unit(w[:, 2], w[:, 3])
        elif 2 * b < d:
            prio = w[:, 2]
    return u, prio


class NumpyDarts:
    """Reference backend: one method per kernel, the same arithmetic in the same order.

    A round is :meth:`throw`, :meth:`resolve`, then :meth:`refine` and :meth:`emit`; the
    round loop (``sampler._throw_darts``) also reads :meth:`accepted` and, to stop at n
    points, :meth:`won_entries` and :meth:`clear`; :meth:`gather` collects the sets.
    :class:`~clsamp.samplers.poisson_disk.device.DeviceDarts` has the same methods.

    Parameters
    ----------
    geo : Geometry
        Dimension, radius, grid and acceptance threshold.
    ids : array_like of int
        The (global) realization numbers of the batch.
    attempt : int
        The redraw number (a realization that became maximal below n is drawn again).
    seed : int
        The sampler's seed.
    """

    def __init__(self, geo, ids, attempt, seed):
        self.geo, self.ids, self.attempt, self.seed = geo, np.asarray(ids), attempt, seed
        self.B = len(ids)
        slots = self.B * geo.cells
        self.occ = np.zeros(slots, dtype=np.uint8)
        self.pts = np.zeros((slots, geo.d), dtype=np.float64)
        self.cand_round = np.full(slots, NO_ROUND, dtype=np.uint32)
        self.cand_first = np.zeros(slots, dtype=np.int64)
        self.total = np.zeros(self.B, dtype=np.int64)
        i = np.arange(slots, dtype=np.int64)
        self.rel, self.base, self.first = i // geo.cells, i % geo.cells, i.copy()
        self.sub = np.zeros((slots, geo.d), dtype=np.int64)

    @property
    def m(self):
        """The number of active entries."""
        return self.rel.size

    def throw(self, round_, level):
        """Throw one dart per active entry, uniform in its subcell (``dart_throw``).

        A dart is valid when no point accepted so far is closer than r.

        Parameters
        ----------
        round_ : int
            The round; with the entry's grid cell, rank and realization it numbers the
            dart's Philox counter.
        level : int
            The entries' refinement level (:func:`level_of` of the round).
        """
        g = self.geo
        m = self.m
        slot = self.rel * g.cells + self.base
        heads = np.flatnonzero(self.first == np.arange(m))
        self.cand_round[slot[heads]] = round_
        self.cand_first[slot[heads]] = heads
        tag = (np.uint32(round_) << np.uint32(20)) | (np.arange(m) - self.first).astype(np.uint32)
        index = self.base.astype(np.uint32) | np.uint32(self.attempt << 26)
        u, prio = draw_darts(self.seed, index, self.ids[self.rel], tag * np.uint32(g.nblocks),
                             g.d)
        bc = cell_coords(self.base, g.G, g.d)
        c = (bc << level) | self.sub
        x = (c.astype(np.float64) + u) / float(g.G << level)
        x[x >= 1.0] = 0.0
        ok = self.occ[slot] == 0
        for off in g.window:
            nslot = self.rel * g.cells + flat_index(bc + off, g.G)
            hit = ok & (self.occ[nslot] == 1)
            if hit.any():
                h = np.flatnonzero(hit)
                ok[h[torus.distance2(x[h], self.pts[nslot[h]]) < g.r2]] = False
        self.cand, self.prio, self.valid = x, prio, ok
        if m and int(np.max(np.arange(m) - self.first)) >= MAX_RANK:
            raise rank_overflow()

    def accepted(self):
        """Darts accepted so far, per realization (trimmed ones included).

        Returns
        -------
        ndarray
            int64 of shape (B,).
        """
        return self.total.copy()

    def resolve(self, round_):
        """Accept a conflict-free subset of the round's valid darts (``dart_resolve``).

        A few steps (:func:`resolve_steps`) of the greedy independent set in priority
        order; darts still undecided stay out this round. Accepted darts are written
        into the grid.

        Parameters
        ----------
        round_ : int
        """
        g = self.geo
        m = self.m
        slot = self.rel * g.cells + self.base
        state = np.where(self.valid, OPEN, OUT).astype(np.uint8)
        for _ in range(resolve_steps(round_)):
            idx = np.flatnonzero(state == OPEN)
            bc = cell_coords(self.base[idx], g.G, g.d)
            rel, pi = self.rel[idx], self.prio[idx]
            beaten = np.zeros(idx.size, dtype=bool)
            blocked = np.zeros(idx.size, dtype=bool)
            for off in g.window:
                nb = flat_index(bc + off, g.G)
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
                    ask = live & higher & (sj != OUT)
                    if ask.any():
                        q = np.flatnonzero(ask)
                        close = torus.distance2(self.cand[idx[q]], self.cand[jj[q]]) < g.r2
                        beaten[q[close & (sj[q] == IN)]] = True
                        blocked[q[close & (sj[q] == OPEN)]] = True
                    j = j + 1
            nxt = np.where(beaten, OUT, np.where(blocked, OPEN, IN)).astype(np.uint8)
            state[idx] = nxt
            won = idx[nxt == IN]
            self.occ[slot[won]] = 1
            self.pts[slot[won]] = self.cand[won]
            self.total += np.bincount(self.rel[won], minlength=self.B)
        self.won = state == IN

    def won_entries(self):
        """The darts accepted this round.

        Returns
        -------
        rel : ndarray
            Each dart's realization within the batch.
        slot : ndarray
            Its grid slot, ``rel * cells + cell``.
        priority : ndarray of uint32
            Its priority (higher wins).
        """
        w = np.flatnonzero(self.won)
        return self.rel[w], self.rel[w] * self.geo.cells + self.base[w], self.prio[w]

    def clear(self, slots):
        """Remove the points of grid ``slots`` (``dart_clear``): the lowest-priority darts
        of the round that passed n, so that exactly n remain.

        Parameters
        ----------
        slots : array_like of int
        """
        self.occ[slots] = 0

    def refine(self, level, split, done, tally):
        """Find which part of every active entry is still uncovered (``dart_refine``).

        Parameters
        ----------
        level : int
            The entries' level.
        split : int
            1 to look at the 2^d halves of each entry (the next round is a level deeper),
            0 at the entry itself.
        done : ndarray of uint8
            Per realization, 1 where it needs no more points (its entries are dropped).
        tally : bool
            Also count the uncovered children per realization.

        Returns
        -------
        counts : ndarray
            Per entry, its uncovered children (0 to 2^d, or 0 or 1).
        remaining : ndarray of int64 or None
            Per realization, the sum of ``counts``; :class:`DeviceDarts` gives None
            without ``tally``.
        """
        g = self.geo
        children = (1 << g.d) if split else 1
        slot = self.rel * g.cells + self.base
        active = (done[self.rel] == 0) & (self.occ[slot] == 0)
        open_ = np.zeros((self.m, children), dtype=bool)
        open_[active] = True
        idx = np.flatnonzero(active)
        bc = cell_coords(self.base[idx], g.G, g.d)
        cp = (bc << level) | self.sub[idx]
        cc = (cp[:, None, :] << 1) | child_bits(children, g.d)[None]
        Mp, Mc = float(g.G << level), float(g.G << (level + 1))
        for off in g.cover(level + split):
            nslot = self.rel[idx] * g.cells + flat_index(bc + off, g.G)
            has = self.occ[nslot] == 1
            if not has.any():
                continue
            h = np.flatnonzero(has)
            p = self.pts[nslot[h]]
            covered = far_corner2(cp[h], Mp, p) < g.r2
            open_[idx[h[covered]]] = False
            if split:
                open_[idx[h]] &= ~(far_corner2(cc[h], Mc, p[:, None, :]) < g.r2)
        self.mask = open_
        counts = open_.sum(axis=1)
        return counts, np.bincount(self.rel, weights=counts, minlength=self.B).astype(np.int64)

    def emit(self, counts, offs, split):
        """Make the uncovered children of :meth:`refine` the new active entries
        (``dart_emit``).

        Parameters
        ----------
        counts : ndarray
            Per entry, its uncovered children, as :meth:`refine` gave them.
        offs : ndarray
            The exclusive prefix sum of ``counts``: where each entry's children go.
        split : int
            As given to :meth:`refine`.
        """
        g = self.geo
        # row-major nonzero: parents in order, each parent's children in bit order
        parent, t = np.nonzero(self.mask)
        bits = child_bits(1 << g.d, g.d)[t] if split else np.zeros((t.size, g.d), dtype=np.int64)
        self.sub = (self.sub[parent] << split) | bits
        self.first = offs[self.first[parent]].astype(np.int64)
        self.rel, self.base = self.rel[parent], self.base[parent]

    def gather(self, dst, out):
        """Copy each realization's points, in grid-cell order, into ``out``
        (``dart_gather``).

        Parameters
        ----------
        dst : ndarray of int
            Per realization, the row of ``out`` its first point goes to; ``SKIP`` leaves
            it out (it will be redrawn).
        out : ndarray or pyopencl.array.Array
            (total, d) float64: host memory for :class:`NumpyDarts`, a device array for
            :class:`DeviceDarts`.
        """
        occ = self.occ.reshape(self.B, self.geo.cells)
        pts = self.pts.reshape(self.B, self.geo.cells, self.geo.d)
        for r in range(self.B):
            if dst[r] != SKIP:
                got = pts[r][occ[r] == 1]
                out[dst[r]:dst[r] + len(got)] = got


class NumpyCoarse:
    """Reference backend of the coarse kernels (``coarse_throw``, ``coarse_resolve``) for
    d = 5..8: the same arithmetic in the same order, the same darts bit for bit. Made as
    :class:`NumpyDarts` is, from a ``CoarseGeometry``, the batch's (global) realization
    numbers, the redraw number and the seed.

    The round loop is :func:`~clsamp.samplers.poisson_disk.coarse.throw_coarse`;
    :class:`~clsamp.samplers.poisson_disk.device.DeviceCoarse` has the same methods.
    """

    def __init__(self, geo, ids, attempt, seed):
        self.geo, self.ids, self.attempt, self.seed = geo, np.asarray(ids), attempt, seed
        self.B = len(ids)

    def _near(self, x, sets, others, start, live, visit):
        """Walk the points of ``others`` (sorted by (set, cell), ``start``) in the stencil
        of each ``x``'s cell while ``live``; ``visit(h, q)`` gets the rows and the other
        points' indices, one rank within a cell at a time."""
        g = self.geo
        flat = flat_index(np.minimum((x * g.G).astype(np.int64), g.G - 1), g.G)
        for o in range(g.stencil):
            slot = sets * g.cells + neighbour_cells(flat, o, g.G, g.d)
            q, end = start[slot].astype(np.int64), start[slot + 1].astype(np.int64)
            while True:
                h = np.flatnonzero(live() & (q < end))
                if not h.size:
                    break
                visit(h, q[h])
                q = q + 1

    def throw(self, active, pts, start, round_):
        """Throw ``geo.darts`` darts into each set of ``active`` (``coarse_throw``).

        Parameters
        ----------
        active : ndarray of int
            The batch's realizations still short of n, in order: set a of the round.
        pts : ndarray (p, d)
            Their accepted points, sorted by (set, cell).
        start : ndarray of uint32
            The first sorted point of each (set, cell).
        round_ : int

        Returns
        -------
        cand : ndarray (A darts, d)
            Dart a * darts + j of set a.
        prio : ndarray of uint32
        valid : ndarray of bool
            No accepted point of its set closer than r.
        """
        g = self.geo
        A, D = len(active), g.darts
        sets = np.repeat(np.arange(A), D)
        j = np.tile(np.arange(D, dtype=np.uint32), A)
        x, prio = draw_darts(self.seed, j | np.uint32(self.attempt << 26),
                             self.ids[active][sets], np.uint32(round_ * g.nblocks), g.d)
        ok = np.ones(A * D, dtype=bool)

        def visit(h, q):
            ok[h[torus.distance2(x[h], pts[q]) < g.r2]] = False
        self._near(x, sets, pts, start, lambda: ok, visit)
        return x, prio, ok

    def resolve(self, cand, prio, valid, start):
        """``COARSE_STEPS`` greedy steps among the round's darts (``coarse_resolve``).

        Parameters
        ----------
        cand : ndarray (m, d)
            The darts sorted by (set, cell).
        prio : ndarray of uint32
        valid : ndarray of bool
        start : ndarray of uint32
            The first sorted dart of each (set, cell).

        Returns
        -------
        ndarray of uint8
            Each dart's state: ``IN`` for the accepted ones.
        """
        state = np.where(valid, OPEN, OUT).astype(np.uint8)
        for _ in range(COARSE_STEPS):
            state = self._resolve_step(cand, prio, state, start)
        return state

    def _resolve_step(self, cand, prio, state, start):
        """One step of ``coarse_resolve``: the states after it."""
        g = self.geo
        idx = np.flatnonzero(state == OPEN)
        beaten = np.zeros(idx.size, dtype=bool)
        blocked = np.zeros(idx.size, dtype=bool)

        def visit(h, j):
            i, sj = idx[h], state[j]
            pj, pi = prio[j], prio[i]
            ask = ((pj > pi) | ((pj == pi) & (j < i))) & (sj != OUT)
            q = np.flatnonzero(ask)
            close = torus.distance2(cand[i[q]], cand[j[q]]) < g.r2
            beaten[h[q[close & (sj[q] == IN)]]] = True
            blocked[h[q[close & (sj[q] == OPEN)]]] = True
        self._near(cand[idx], idx // g.darts, cand, start, lambda: ~beaten, visit)
        out = state.copy()
        out[idx] = np.where(beaten, OUT, np.where(blocked, OPEN, IN))
        return out
