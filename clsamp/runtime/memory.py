"""Device memory: outputs over host memory, copies, small tables, and the one rule that
sizes every launch (:func:`fit`, :func:`chunk_ranges`).

Work too large for the device is split into chunks of a quarter of its largest allocation,
never refused or truncated; a host result the machine cannot hold is refused before any
work (:func:`check_host_bytes`).
"""

import os
import time

import numpy as np

from ..errors import InvalidArgumentError
from . import discovery, programs

__all__ = [
    'table', 'Output', 'is_device_array', 'to_device', 'to_host', 'bounds', 'device_block',
    'concatenate', 'host_memory_available', 'check_host_bytes', 'gib', 'work_budget', 'fit',
    'chunk_ranges', 'wait', 'input_buffer', 'work_buffer']


_tables = {}            # (device index, key) -> pyopencl.array.Array, least recently used first


_TABLES = 64            # tables kept per process


def table(key, build, dtype=np.uint32):
    """A small read-only device array, uploaded once per (device, ``key``).

    Later calls on the same device get the same device array (the 64 most recently used
    tables are kept).

    Parameters
    ----------
    key : hashable
        What the table is, unique within the process.
    build : callable
        Makes the host array, called only when the table is not kept already.
    dtype : numpy dtype, optional
        The element type of the device array.

    Returns
    -------
    pyopencl.array.Array
    """
    import pyopencl.array as cla
    full = (discovery.current_device().index, key)
    with discovery._lock:
        found = _tables.pop(full, None)
        if found is None:
            found = cla.to_device(discovery.queue(), np.ascontiguousarray(build(), dtype=dtype))
        _tables[full] = found
        while len(_tables) > _TABLES:
            _tables.pop(next(iter(_tables)))
        return found


class Output:
    """Where a kernel writes its result.

    Without ``host`` a new device array; with ``host`` (a C-contiguous NumPy array) a
    buffer over that array's memory, so that on a CPU device the kernel writes straight
    into the array the caller gets. Pass :attr:`buffer` to the kernel, then
    :meth:`finish` gives the result (the host array, its writes visible, or the device
    array). A kernel that also reads what it writes there (``+=``) needs ``read_write=True``:
    the host buffer is write-only otherwise, and reading it is undefined (Oclgrind reports
    it; tests/test_oclgrind.py).
    """

    def __init__(self, shape, dtype=np.float64, host=None, read_write=False):
        import pyopencl.array as cla
        self.host = host
        if host is None:
            self.array = cla.empty(discovery.queue(), shape, dtype)
            self.buffer = self.array.data
        else:
            cl = discovery._cl()
            self.array = host
            access = cl.mem_flags.READ_WRITE if read_write else cl.mem_flags.WRITE_ONLY
            self.buffer = cl.Buffer(discovery.context(), access | cl.mem_flags.USE_HOST_PTR,
                                    hostbuf=host)

    def finish(self):
        """The result, once the kernel that wrote :attr:`buffer` is done: the host array
        (its writes visible) or the device array."""
        if self.host is not None:
            # mapping makes the kernel's writes visible in host memory (no copy on PoCL)
            cl = discovery._cl()
            # (non-blocking on PoCL, where a blocking map waits longer than map, unmap and
            # finish: docs/performance.md, "random in vector lanes, and the zero-copy map";
            # rusticl refuses to unmap a map that has not completed)
            pocl = discovery.current_device().platform == "Portable Computing Language"
            mapped, _ = cl.enqueue_map_buffer(discovery.queue(), self.buffer, cl.map_flags.READ, 0,
                                              self.host.shape, self.host.dtype, is_blocking=not pocl)
            mapped.base.release(discovery.queue())
            discovery.queue().finish()
        return self.array


def is_device_array(value):
    """Whether ``value`` is a device array.

    Parameters
    ----------
    value : object

    Returns
    -------
    bool
        True for a ``pyopencl.array.Array``.
    """
    import pyopencl.array as cla
    return isinstance(value, cla.Array)


def to_device(array):
    """``array`` on the current device.

    Parameters
    ----------
    array : array_like or pyopencl.array.Array

    Returns
    -------
    pyopencl.array.Array
        ``array`` itself if it is a device array, else a copy of it.
    """
    if is_device_array(array):
        return array
    import pyopencl.array as cla
    return cla.to_device(discovery.queue(), np.ascontiguousarray(array))


def input_buffer(array):
    """A read-only buffer holding a copy of ``array``, made in one call: for the inputs of
    a launch repeated many times a second (an optimizer's pass), where building a
    ``pyopencl.array.Array`` costs more than the copy (docs/performance.md, "Gaussian blue
    noise (issue 37)").

    Parameters
    ----------
    array : ndarray

    Returns
    -------
    pyopencl.Buffer
    """
    cl = discovery._cl()
    flags = cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR
    return cl.Buffer(discovery.context(), flags, hostbuf=np.ascontiguousarray(array))


def work_buffer(nbytes=0, array=None):
    """A read-write buffer made in one call, for the state of a loop of launches that stays
    on the device (sliced optimal transport's points and scratch rows): a copy of ``array``,
    or ``nbytes`` bytes left uninitialized.

    Parameters
    ----------
    nbytes : int
        The size without ``array`` (at least one byte is allocated).
    array : ndarray, optional

    Returns
    -------
    pyopencl.Buffer
    """
    cl = discovery._cl()
    flags = cl.mem_flags.READ_WRITE
    if array is None:
        return cl.Buffer(discovery.context(), flags, max(int(nbytes), 1))
    return cl.Buffer(discovery.context(), flags | cl.mem_flags.COPY_HOST_PTR,
                     hostbuf=np.ascontiguousarray(array))


#: the factor by which :func:`wait`'s sleeps grow: past the first milliseconds each sleep
#: is about this less one of the time slept before it, which bounds how late the wait
#: notices the event
WAIT_GROWTH = 1.25


def wait(event=None):
    """Wait for ``event``, or for all the work enqueued on the current queue, so that Ctrl-C
    is taken while a long kernel runs.

    A blocking read waits inside OpenCL, where Python cannot take a signal until the kernel
    ends (seconds for a large CCVT launch); this polls the event's status with sleeps
    growing by :data:`WAIT_GROWTH` from 0.1 ms to 10 ms, so a KeyboardInterrupt arrives
    within about 10 ms, and past the first milliseconds the wait ends within about a quarter
    of the time already waited after the event completes (sleeps that doubled could wait
    as long again). It is for launches that run long (CCVT's and bnot's power passes,
    CCVT's solve chunks, a gbn run kept on the device), not for every read.

    Parameters
    ----------
    event : pyopencl.Event, optional
        By default a marker after everything enqueued so far.

    Returns
    -------
    pyopencl.Event
        The event waited for, complete.
    """
    import pyopencl as cl
    q = discovery.queue()
    if event is None:
        event = cl.enqueue_marker(q)
    q.flush()
    delay = 1e-4
    while event.command_execution_status > cl.command_execution_status.COMPLETE:
        time.sleep(delay)
        delay = min(WAIT_GROWTH * delay, 0.01)
    event.wait()                    # raises where the command failed (a negative status)
    return event


def to_host(array, into=None):
    """``array`` as a NumPy array.

    Parameters
    ----------
    array : array_like or pyopencl.array.Array
        A device array is read back; anything else goes through ``np.asarray``.
    into : ndarray, optional
        Where to write the result (of ``array``'s shape).

    Returns
    -------
    ndarray
        ``into`` when given.
    """
    if is_device_array(array):
        return array.get() if into is None else array.get(ary=into)
    if into is None:
        return np.asarray(array)
    into[...] = array
    return into


def bounds(array):
    """The range of the doubles of a device array, computed on the device
    (``kernels/points.cl``).

    Parameters
    ----------
    array : pyopencl.array.Array
        float64 values.

    Returns
    -------
    tuple of (float, float, int)
        The smallest and largest finite value and how many values are NaN or infinite.

    Notes
    -----
    Comparisons only, exact on every device; without fp64 the kernel compares the values'
    bit patterns (``kernels/points.cl``).
    """
    import pyopencl.array as cla
    items = 64 * max(1, discovery.current_device().compute_units)
    q = discovery.queue()
    lo = cla.empty(q, items, np.float64)
    hi = cla.empty(q, items, np.float64)
    bad = cla.empty(q, items, np.uint32)
    programs.kernel("points.cl", "points_bounds")(q, (items,), None, array.base_data, np.uint64(array.size),
                                         lo.data, hi.data, bad.data)
    return float(lo.get().min()), float(hi.get().max()), int(bad.get().sum())


def device_block(array, r0, r1, k0=0, k1=None):
    """``array[r0:r1, k0:k1]`` of a device array of shape (r, n, d), contiguous.

    Parameters
    ----------
    array : pyopencl.array.Array
        Shape (r, n, d).
    r0, r1 : int
        The first and past-the-last index on the first axis.
    k0, k1 : int, optional
        The same on the second axis (``k1=None``: to its end).

    Returns
    -------
    pyopencl.array.Array
        ``array`` itself where the block is all of it, else a copy made on the device.
    """
    import pyopencl.array as cla
    r, n, d = array.shape
    k1 = n if k1 is None else k1
    if (r0, r1, k0, k1) == (0, r, 0, n) and array.offset == 0:
        return array
    out = cla.empty(discovery.queue(), (r1 - r0, k1 - k0, d), array.dtype)
    item = array.dtype.itemsize
    row = n * d * item
    discovery._cl().enqueue_copy(discovery.queue(), out.data, array.base_data,
                       src_origin=(array.offset + k0 * d * item, r0, 0), dst_origin=(0, 0, 0),
                       region=((k1 - k0) * d * item, r1 - r0, 1), src_pitches=(row, 0),
                       dst_pitches=((k1 - k0) * d * item, 0))
    return out


def concatenate(parts):
    """Device arrays joined along their first axis.

    Parameters
    ----------
    parts : sequence of pyopencl.array.Array

    Returns
    -------
    pyopencl.array.Array
        The one part itself when it is alone.
    """
    if len(parts) == 1:
        return parts[0]
    import pyopencl.array as cla
    return cla.concatenate(parts, axis=0, queue=discovery.queue())


def host_memory_available():
    """Bytes of host memory free for new allocations (Linux: MemAvailable), or None where
    the system does not say."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def check_host_bytes(need, what):
    """Refuse, before any work, a result the host's available memory cannot hold.

    The available memory is read only for requests above 256 MiB.

    Parameters
    ----------
    need : int
        Bytes the result takes.
    what : str
        What asks, for the message.

    Raises
    ------
    InvalidArgumentError
        ``need`` exceeds the memory available.
    """
    if need <= 2**28:
        return
    room = host_memory_available()
    if room is not None and need > room:
        raise InvalidArgumentError(
            f"{what} needs {gib(need)}; this machine has {gib(room)} available. Ask for less "
            "at a time")


def gib(nbytes):
    """Bytes as a message shows them.

    Parameters
    ----------
    nbytes : int

    Returns
    -------
    str
        ``"1.5 GiB"``, or ``"12.0 MiB"`` below a GiB.
    """
    return f"{nbytes / 2**30:.1f} GiB" if nbytes >= 2**30 else f"{nbytes / 2**20:.1f} MiB"


def work_budget():
    """Bytes one launch's buffers may hold on the current device: a quarter of its largest
    single allocation (the one rule every module asks, through :func:`fit`)."""
    return max(1, discovery.current_device().max_allocation // 4)


def fit(bytes_per_item, limit=None):
    """How many items one launch may hold: :func:`work_budget` over ``bytes_per_item``.

    Parameters
    ----------
    bytes_per_item : int
        Bytes of device memory one item takes.
    limit : int, optional
        A further cap on the bytes, where a caller has its own reason (a working set that
        should stay in the caches, a host-memory cap).

    Returns
    -------
    int
        At least 1.
    """
    budget = work_budget() if limit is None else min(work_budget(), int(limit))
    return max(1, budget // max(1, int(bytes_per_item)))


def chunk_ranges(total, bytes_per_item, limit=None):
    """Split ``total`` items into contiguous ranges that each fit one launch (:func:`fit`),
    so work too large for the device is split, never refused or truncated.

    Parameters
    ----------
    total : int
        How many items.
    bytes_per_item, limit
        As :func:`fit` takes them.

    Returns
    -------
    list of (int, int)
        The (start, stop) of each range, in order.
    """
    step = fit(bytes_per_item, limit)
    return [(lo, min(total, lo + step)) for lo in range(0, total, step)]
