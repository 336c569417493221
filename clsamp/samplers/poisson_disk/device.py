"""Dart throwing in OpenCL (``kernels/dart_throwing.cl``): each step one launch over every
active entry of every realization.

The kernels hold every double as its IEEE-754 bit pattern and compute it through
``kernels/f64bits.h``, so a device without fp64 gives the same points; the threshold r^2
goes to them as its bits (:func:`_bits`)."""

import numpy as np
import pyopencl as cl
import pyopencl.array as cla

from ... import philox, runtime
from .coarse import COARSE_STEPS
from .grid import IN, OPEN, OUT, rank_overflow, resolve_steps


def _bits(x):
    """The IEEE-754 bit pattern of the double x, the kernels' form of a scalar double."""
    return np.float64(x).view(np.uint64)


def _check_loops():
    """Refuse a device that ends long loops (llvmpipe): a work-item of these kernels loops
    over a window of grid cells, the darts of its cells and every cell of its realization
    (the gather), for as long as the sets need."""
    runtime.require_short_loops("poisson_disk's dart throwing")


class DeviceDarts:
    """Runs each step as one launch over every active entry of every realization.

    The methods are :class:`~clsamp.samplers.poisson_disk.reference.NumpyDarts`'s, with
    the same results bit for bit; ``m`` is the number of active entries.

    Parameters
    ----------
    geo : Geometry
        Dimension, radius, grid and acceptance threshold.
    ids : array_like of int
        The (global) realization numbers of the batch.
    attempt : int
        The redraw number.
    seed : int
        The sampler's seed.

    Raises
    ------
    NoDeviceError
        The current device ends long loops (:func:`clsamp.runtime.loop_limit`).
    """

    def __init__(self, geo, ids, attempt, seed):
        _check_loops()
        self.geo, self.attempt, self.seed = geo, attempt, seed
        self.B = len(ids)
        q = self.q = runtime.queue()
        self.ls = runtime.local_size(64)
        self.defines = {"DIM": geo.d, "D": geo.d}   # D: cells.h
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
        buffers grow only; creating buffers every round costs more than a small round."""
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
            self.mask = cla.empty(q, m, np.uint16)   # 2^d <= 16 children
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
        table = runtime.table(("dart window", rows.shape, rows.tobytes()), rows.ravel, np.int32)
        return table, np.uint32(len(rows)), np.int32(np.abs(offsets).max())

    def _cover_window(self, level):
        if level not in self._covers:
            self._covers[level] = self._table(self.geo.cover(level))
        return self._covers[level]

    def _common(self, window=None):
        g = self.geo
        table, rows, reach = window or self.window
        return (np.uint32(self.m), np.uint32(g.G), table.data, rows, reach, np.uint32(g.cells))

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
        self._run("dart_throw", self.m, self.rel.data, self.base.data, self.sub.data,
                  self.first.data, self.occ.data, self.pts.data, self.cand.data, self.prio.data,
                  self.valid.data, self.cand_round.data, self.cand_first.data,
                  self.overflow.data, *self._common(),
                  np.uint32(level), np.uint32(round_), _bits(self.geo.r2), self.ids.data,
                  np.uint32(self.attempt), *philox.seed_key(self.seed),
                  np.uint32(philox.Stream.CANDIDATES))

    def resolve(self, round_):
        """Accept a conflict-free subset of the round's valid darts (``dart_resolve``).

        A few steps (:func:`resolve_steps`) of the greedy independent set in priority
        order; darts still undecided stay out this round. Accepted darts are written
        into the grid.

        Parameters
        ----------
        round_ : int
        """
        state, other = self.valid, self.state
        for step in range(resolve_steps(round_)):
            self._run("dart_resolve", self.m, self.rel.data, self.base.data, self.cand.data,
                      self.prio.data, state.data, other.data, self.cand_round.data,
                      self.cand_first.data, self.occ.data, self.pts.data, self.accepted_.data,
                      *self._common(), np.uint32(round_), np.uint32(step),
                      _bits(self.geo.r2))
            state, other = other, state
        self.won = state

    def accepted(self):
        """Darts accepted so far, per realization (trimmed ones included).

        Returns
        -------
        ndarray
            int64 of shape (B,).

        Raises
        ------
        SamplingError
            More entries in one grid cell than a dart's tag can number (a bug).
        """
        if self.overflow.get()[0]:
            raise rank_overflow()
        return self.accepted_.get().astype(np.int64)

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
        m = self.m
        won = self.won[:m].get() == IN
        rel = self.rel[:m].get()[won].astype(np.int64)
        base = self.base[:m].get()[won].astype(np.int64)
        return rel, rel * self.geo.cells + base, self.prio[:m].get()[won]

    def clear(self, slots):
        """Remove the points of grid ``slots`` (``dart_clear``): the lowest-priority darts
        of the round that passed n, so that exactly n remain.

        Parameters
        ----------
        slots : array_like of int
        """
        if len(slots):
            buf = cla.to_device(self.q, np.asarray(slots, dtype=np.uint32))
            self._run("dart_clear", len(slots), self.occ.data, buf.data, np.uint32(len(slots)))

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
        if not np.array_equal(done, self._done):
            self._done = done.copy()
            self.done.set(self._done)
        if tally:
            self.remaining.set(np.zeros(self.B, dtype=np.uint32))
        self._run("dart_refine", self.m, self.rel.data, self.base.data, self.sub.data,
                  self.occ.data, self.pts.data, self.done.data, self.mask.data, self.count.data,
                  self.remaining.data, *self._common(self._cover_window(level + split)),
                  np.uint32(level), np.uint32(split), _bits(self.geo.r2))
        return (self.count[:self.m].get(),
                self.remaining.get().astype(np.int64) if tally else None)

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
        self._run("dart_gather", self.B, self.occ.data, self.pts.data,
                  cla.to_device(self.q, np.asarray(dst, dtype=np.uint32)).data, out.data,
                  np.uint32(self.geo.cells), np.uint32(self.B))


class DeviceCoarse:
    """The coarse kernels (``coarse_throw``, ``coarse_resolve``) for d = 5..8, with
    :class:`~clsamp.samplers.poisson_disk.reference.NumpyCoarse`'s methods and results bit
    for bit, made with the same arguments (a ``CoarseGeometry``, the realizations, the
    attempt, the seed); the round loop and the sorts by cell are the host's
    (:func:`~clsamp.samplers.poisson_disk.coarse.throw_coarse`). Like :class:`DeviceDarts`
    it raises ``NoDeviceError`` on a device that ends long loops.
    """

    def __init__(self, geo, ids, attempt, seed):
        _check_loops()
        self.geo, self.attempt, self.seed = geo, attempt, seed
        self.ids = np.asarray(ids, dtype=np.uint32)
        self.B = len(ids)
        self.q = runtime.queue()
        self.ls = runtime.local_size(64)
        self.defines = {"DIM": geo.d, "D": geo.d}

    def _run(self, name, items, *args):
        k = runtime.kernel("dart_throwing.cl", name, defines=self.defines)
        size = max(self.ls, -(-items // self.ls) * self.ls)
        k(self.q, (size,), (self.ls,), *args)

    def _grid(self):
        g = self.geo
        return np.int32(g.G), np.uint32(g.stencil), np.uint32(g.cells)

    def throw(self, active, pts, start, round_):
        """As :meth:`~clsamp.samplers.poisson_disk.reference.NumpyCoarse.throw`."""
        q, g = self.q, self.geo
        m = len(active) * g.darts
        cand = cla.empty(q, (m, g.d), np.float64)
        prio = cla.empty(q, m, np.uint32)
        valid = cla.empty(q, m, np.uint8)
        ids = cla.to_device(q, self.ids[active])
        dpts = cla.to_device(q, np.ascontiguousarray(pts).reshape(-1) if len(pts) else
                             np.zeros(1))
        dstart = cla.to_device(q, start)
        self._run("coarse_throw", m, ids.data, np.uint32(g.darts), np.uint32(m), dpts.data,
                  dstart.data, *self._grid(), _bits(g.r2), np.uint32(round_),
                  np.uint32(self.attempt), *philox.seed_key(self.seed),
                  np.uint32(philox.Stream.CANDIDATES), cand.data, prio.data, valid.data)
        return cand.get(), prio.get(), valid.get().astype(bool)

    def resolve(self, cand, prio, valid, start):
        """As :meth:`~clsamp.samplers.poisson_disk.reference.NumpyCoarse.resolve`."""
        q, g = self.q, self.geo
        m = len(prio)
        dcand = cla.to_device(q, np.ascontiguousarray(cand))
        dprio = cla.to_device(q, np.ascontiguousarray(prio, dtype=np.uint32))
        dstart = cla.to_device(q, start)
        state = cla.to_device(q, np.where(valid, OPEN, OUT).astype(np.uint8))
        other = cla.empty(q, m, np.uint8)
        for step in range(COARSE_STEPS):
            self._run("coarse_resolve", m, dcand.data, dprio.data, dstart.data, state.data,
                      other.data, np.uint32(g.darts), np.uint32(m), *self._grid(),
                      np.uint32(step), _bits(g.r2))
            state, other = other, state
        return state.get()
