"""The device side of the ``sot`` sampler (``kernels/sot.cl``): one pass of a batch a
function, each the same bits as its NumPy twin in :mod:`clsamp.samplers.sot`, and the two
ways a run's batches go.

On GPUs a batch (:func:`batch_device`) projects the points, sorts the projections with a
bitonic network, matches them to their targets (:func:`displacements_device`) and moves
the points, each pass a launch over many work-items. On devices that share the host's
cores (``Shape.host_sort``) a run keeps its points on the device
(:class:`ResidentBatches`): a batch is two launches and no wait -- one row a work-item,
its quantiles, then its projections sorted by a bucket sort and matched (``sot_row``,
the work of ``sot_quantiles`` and ``sot_project_displace``); the move, four points a
work-item in vector lanes (``sot_move4``). Each block of batches' directions and slices
goes up once, and the costs are summed and come back a few batches at a time.
"""

import math

import numpy as np

from .. import runtime

QTOL = 1e-14         # quantile solver: stop when the step is at most QTOL times the range
QMAX = 200
CHUNK = 16           # consecutive quantiles solved in turn, each from the last roots
DEFINES = {"QTOL": repr(QTOL), "QMAX": QMAX, "CHUNK": CHUNK}


def _defines(d, lanes=None):
    """The build options of ``kernels/sot.cl`` in ``d`` dimensions: ``sot_quantiles`` solves
    ``lanes`` chunks of ``CHUNK`` quantiles a work-item (default: the device's vector width,
    one on GPUs)."""
    return {"D": d, "LANES": lanes or runtime.shape().vector_width, **DEFINES}


def _quantile_items(K, n, lanes):
    chunks = -(-((n + 1) // 2) // CHUNK)
    return K * -(-chunks // lanes)


def _launch(name, d, items, *args, lanes=None):
    """Run kernel ``name`` of ``kernels/sot.cl`` over ``items`` work-items."""
    kernel = runtime.kernel("sot.cl", name, _defines(d, lanes))
    local = runtime.local_size(64)
    kernel(runtime.queue(), (-(-items // local) * local,), (local,), *args)


def _output(shape, dtype, host):
    return runtime.Output(shape, dtype, host=np.empty(shape, dtype) if host else None)


def _slice_arrays(sl):
    return sl.c, sl.sign, sl.m, sl.norm, sl.total, sl.base


def quantiles_device(sl, n, host=True, lanes=None):
    """``sot_quantiles``: :func:`~clsamp.samplers.sot.quantiles_reference`'s targets.

    Parameters
    ----------
    sl : Slice
    n : int
    host : bool
        Return a host array (else a device array).
    lanes : int, optional
        Chunks of quantiles a work-item (default: the device's vector width).

    Returns
    -------
    ndarray or pyopencl.array.Array (K, n)
    """
    K = sl.m.shape[0]
    lanes = lanes or runtime.shape().vector_width
    out = _output((K, n), np.float64, host)
    _launch("sot_quantiles", int(round(math.log2(sl.c.shape[1]))), _quantile_items(K, n, lanes),
            *(runtime.to_device(a).data for a in _slice_arrays(sl)), np.uint32(0),
            np.uint32(n), np.uint32(K), out.buffer, lanes=lanes)
    return out.finish()


def project_device(x, theta, host=True):
    """``sot_project``: :func:`~clsamp.samplers.sot.project_reference`'s projections.

    Parameters
    ----------
    x : ndarray (sets, n, d)
    theta : ndarray (sets, K, d)
    host : bool
        Return a host array (else a device array).

    Returns
    -------
    ndarray or pyopencl.array.Array (sets, K, n)
    """
    sets, n, d = x.shape
    K = theta.shape[1]
    out = _output((sets, K, n), np.float64, host)
    _launch("sot_project", d, sets * K * n, runtime.to_device(x).data,
            runtime.to_device(theta).data, np.uint32(n), np.uint32(K), np.uint32(sets), out.buffer)
    return out.finish()


def project_displacements_device(x, theta, q):
    """``sot_project_displace``: the displacements of the projections to their ranks'
    targets (ties by index), one row a work-item.

    Parameters
    ----------
    x : ndarray (sets, n, d)
    theta : ndarray (sets, K, d)
    q : ndarray (sets, K, n)
        The targets.

    Returns
    -------
    ndarray (sets, K, n)
        :func:`~clsamp.samplers.sot.displacements_reference`'s.
    """
    sets, n, d = x.shape
    K = theta.shape[1]
    disp = runtime.Output((sets, K, n), np.float64, host=np.empty((sets, K, n)), read_write=True)
    # keys (doubles), counts (uints, 2n a row) and order (uints)
    scratch = [_output((sets * K, w * n), dtype, False)
               for dtype, w in ((np.float64, 1), (np.uint32, 2), (np.uint32, 1))]
    kernel = runtime.kernel("sot.cl", "sot_project_displace", _defines(d))
    kernel(runtime.queue(), (sets * K,), (1,), runtime.to_device(x).data,
           runtime.to_device(theta).data, np.uint32(0), runtime.to_device(q).data, np.uint32(n),
           np.uint32(K), np.uint32(sets), disp.buffer, *(s.buffer for s in scratch))
    return disp.finish()


def displacements_device(proj, q, d, host=True):
    """The displacements of projections to the targets of their ranks, ties by index, by
    the device's bitonic sort (``sot_displace`` after the network).

    Parameters
    ----------
    proj : ndarray or pyopencl.array.Array (sets, K, n)
    q : ndarray or pyopencl.array.Array (sets, K, n)
        The targets.
    d : int
        The dimension (the build of ``kernels/sot.cl``).
    host : bool
        Return a host array (else a device array).

    Returns
    -------
    ndarray or pyopencl.array.Array (sets, K, n)
        :func:`~clsamp.samplers.sot.displacements_reference`'s.
    """
    import pyopencl.array as cla
    shape = proj.shape
    rows, n = shape[0] * shape[1], shape[2]
    P = 1 << max(n - 1, 1).bit_length()
    queue = runtime.queue()
    proj = runtime.to_device(proj)
    key, index = cla.empty(queue, rows * P, np.float64), cla.empty(queue, rows * P, np.uint32)
    _launch("sot_sort_init", d, rows * P, proj.data, np.uint32(n), np.uint32(P), np.uint32(rows),
            key.data, index.data)
    # stages with j < L in local memory, the longer ones one global launch each
    L2 = 1 << (min(P // 2, runtime.local_size(256)).bit_length() - 1)
    local = _local_sort(d, rows * P // 2, L2, key, index, P)
    local(2, 2 * L2, 1)
    k = 4 * L2
    while k <= P:
        j = k >> 1
        while j >= 2 * L2:
            _launch("sot_bitonic", d, rows * P // 2, key.data, index.data, np.uint32(P),
                    np.uint32(rows), np.uint32(k), np.uint32(j))
            j >>= 1
        local(k, k, L2)
        k <<= 1
    out = _output(shape, np.float64, host)
    _launch("sot_displace", d, rows * n, index.data, runtime.to_device(q).data, proj.data,
            np.uint32(n), np.uint32(P), np.uint32(rows), out.buffer)
    return out.finish()


def _local_sort(d, items, L2, key, index, P):
    """``sot_bitonic_local`` over rows of P pairs, work-groups of L2 items, as a function of
    (kmin, kmax, jtop)."""
    import pyopencl as cl
    kernel = runtime.kernel("sot.cl", "sot_bitonic_local", _defines(d))

    def run(kmin, kmax, jtop):
        kernel(runtime.queue(), (items,), (L2,), key.data, index.data, np.uint32(P),
               np.uint32(kmin), np.uint32(kmax), np.uint32(jtop), cl.LocalMemory(16 * L2),
               cl.LocalMemory(8 * L2))
    return run


def move_device(x, theta, disp, scale, lanes=1):
    """``sot_move``: :func:`~clsamp.samplers.sot.move_reference`'s (points, cost).

    Parameters
    ----------
    x : ndarray (sets, n, d)
    theta : ndarray (sets, K, d)
    disp : ndarray or pyopencl.array.Array (sets, K, n)
    scale : float
    lanes : int
        1: a point a work-item (``sot_move``); 4: four in vector lanes (``sot_move4``,
        as a resident run on a CPU device moves them).

    Returns
    -------
    points : ndarray (sets, n, d)
    cost : ndarray (sets, n)
    """
    sets, n, d = x.shape
    K = theta.shape[1]
    out, cost = _output((sets, n, d), np.float64, True), _output((sets, n), np.float64, True)
    name, items = ("sot_move", sets * n) if lanes == 1 else ("sot_move4", sets * -(-n // 4))
    slot = () if lanes == 1 else (np.uint32(0),)
    _launch(name, d, items, runtime.to_device(x).data, runtime.to_device(theta).data,
            np.uint32(0), runtime.to_device(disp).data, np.uint32(n), np.uint32(K),
            np.uint32(sets), np.float64(scale), out.buffer, cost.buffer, *slot)
    return out.finish(), cost.finish()


def batch_device(x, theta, sl, scale):
    """One batch on a GPU: :func:`~clsamp.samplers.sot.batch_reference`'s (points, cost).

    Parameters
    ----------
    x : ndarray (sets, n, d)
    theta : ndarray (sets, K, d)
    sl : Slice
        Of ``theta`` reshaped to (sets K, d).
    scale : float

    Returns
    -------
    points : ndarray (sets, n, d)
    cost : ndarray (sets, n)
    """
    q = quantiles_device(sl, x.shape[1], host=False)
    proj = project_device(x, theta, host=False)
    disp = displacements_device(proj.reshape(theta.shape[:2] + (x.shape[1],)), q, x.shape[2],
                                host=False)
    return move_device(x, theta, disp, scale)


# the scalar types of the kernels ResidentBatches runs (declared once a kernel object, so
# that a batch sets all of a kernel's arguments in one fast call)
_U, _F = np.uint32, np.float64
RESIDENT_TYPES = {"sot_row": [None] * 8 + [_U, None, _U, _U, _U] + [None] * 4,
                  "sot_move4": [None, None, _U, None, _U, _U, _U, _F, None, None, _U],
                  "sot_cost": [None, _U, _U, None]}


def _resident_kernel(name, d, lanes):
    return runtime.kernel("sot.cl", name, _defines(d, lanes), instance="resident",
                          scalar_types=RESIDENT_TYPES[name])


class ResidentBatches:
    """A run's batches on a device that shares the host's cores, its points kept on the
    device: the same bits as :func:`~clsamp.samplers.sot.batch_reference` batch after batch.

    Parameters
    ----------
    x : ndarray (sets, n, d)
        The starting points of the run's sets.
    K : int
        Directions a batch.
    scale : float
        The step over K.
    settle : int
        The most batches whose costs wait to be read.

    Notes
    -----
    :meth:`block` uploads a block of batches' directions and slices, batch-major, once.
    :meth:`batch` launches ``sot_row`` and ``sot_move4`` (into the other of two point
    buffers) at its batch's rows, without waiting; the move writes its point costs to the
    batch's slot. :meth:`costs` sums every slot's costs per set (``sot_cost``, one launch)
    and reads them at once, or (``wait=False``) while the device runs the next batches.
    (Solving a block's quantiles in one launch was slower: their rows fall out of the cache
    before the moves read them.)
    """

    def __init__(self, x, K, scale, settle):
        sets, n, d = x.shape
        self.sets, self.n, self.d, self.rows = sets, n, d, sets * K
        self.points = [runtime.work_buffer(array=x), runtime.work_buffer(x.nbytes)]
        # targets, displacements and keys (doubles), counts (uints, 2n a row) and order
        # (uints), a row each
        self.scratch = [runtime.work_buffer(self.rows * n * size) for size in (8, 8, 8, 8, 4)]
        self.cost = runtime.work_buffer(8 * settle * sets * n)    # a slot a batch
        self.sums = runtime.work_buffer(8 * settle * sets)
        self.slot = 0
        self.lanes, self.local = runtime.shape().vector_width, runtime.local_size(64)
        self.kernels = {name: _resident_kernel(name, d, self.lanes) for name in RESIDENT_TYPES}
        self.scale = float(scale)
        self.parity = 0
        self.block_buffers = None

    def block(self, theta, sl):
        """Upload a block's directions and their slices.

        Parameters
        ----------
        theta : ndarray (count, sets, K, d)
        sl : Slice
            Of ``theta`` reshaped to (count sets K, d).
        """
        self.block_buffers = [runtime.input_buffer(a)
                              for a in (theta.reshape(-1, self.d),) + _slice_arrays(sl)]

    def _launch(self, name, items, local, *args):
        import pyopencl as cl
        kernel = self.kernels[name]
        kernel.set_args(*args)
        cl.enqueue_nd_range_kernel(runtime.queue(), kernel, (-(-items // local) * local,),
                                   (local,))

    def batch(self, b):
        """Enqueue a batch of the block.

        Parameters
        ----------
        b : int
            The batch's place in the block.
        """
        n, rows, sets = self.n, self.rows, self.sets
        theta, *slices = self.block_buffers
        q, disp, key, count, perm = self.scratch
        x, out = self.points[self.parity], self.points[1 - self.parity]
        self._launch("sot_row", rows, 1, *slices, x, theta, b * rows, q, n, rows // sets, sets,
                     disp, key, count, perm)
        self._launch("sot_move4", sets * -(-n // 4), self.local, x, theta, b * rows, disp, n,
                     rows // sets, sets, self.scale, out, self.cost, self.slot)
        self.parity, self.slot = 1 - self.parity, self.slot + 1
        runtime.queue().flush()

    def costs(self, wait=True):
        """The costs of the batches since the last call, each set's point costs summed in
        index order.

        Parameters
        ----------
        wait : bool
            Wait for them (default); else return at once, while the device runs the
            batches enqueued after (the queue is in order: the next call's sums are
            written after this read).

        Returns
        -------
        ndarray (batches, sets) or tuple
            With ``wait``, the costs; else a ticket ``(array, event)`` whose array holds
            them once the event completes (:meth:`collect`).
        """
        import pyopencl as cl
        out = np.empty((self.slot, self.sets))
        event = None
        if self.slot:
            rows = self.slot * self.sets
            self._launch("sot_cost", rows, 1, self.cost, self.n, rows, self.sums)
            event = cl.enqueue_copy(runtime.queue(), out, self.sums, is_blocking=False)
            runtime.queue().flush()
        self.slot = 0
        return self.collect((out, event)) if wait else (out, event)

    @staticmethod
    def collect(ticket):
        """The costs a ``costs(wait=False)`` call returned, once read.

        Parameters
        ----------
        ticket : tuple
            ``(array, event)`` from :meth:`costs`.

        Returns
        -------
        ndarray (batches, sets)
        """
        out, event = ticket
        if event is not None:
            event.wait()
        return out

    def result(self):
        """The sets' points now: ndarray (sets, n, d)."""
        import pyopencl as cl
        x = np.empty((self.sets, self.n, self.d))
        cl.enqueue_copy(runtime.queue(), x, self.points[self.parity], is_blocking=True)
        return x
