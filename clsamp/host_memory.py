"""Host memory for kernel outputs that is recycled: :func:`host_empty` gives sampler outputs
(the arrays their kernels write into in place on CPU devices, ``runtime.Output``) the
memory of earlier outputs of the same size once nothing uses it any more."""

import threading
import weakref

import numpy as np

HOST_POOL_BYTES = 1 << 30      # freed output memory kept for reuse, at most (0: none)
HOST_POOL_MIN = 1 << 20        # smaller outputs come from NumPy (its allocator reuses them)


class _Block:
    """The owner of a pooled piece of host memory, as arrays see it: every array made by
    :func:`host_empty`, and every view of one, has it as its ``base``. When the last of
    them is gone, the memory goes back to the pool."""

    def __init__(self, memory, shape, dtype):
        self.memory = memory
        self.__array_interface__ = {
            "shape": tuple(shape), "typestr": np.dtype(dtype).str, "version": 3,
            "data": (memory.ctypes.data, False)}


class _HostPool:
    """Freed output memory by size, oldest dropped first beyond ``HOST_POOL_BYTES``."""

    def __init__(self):
        self.lock = threading.Lock()
        self.free = {}            # nbytes -> [uint8 arrays], in the order freed
        self.held = 0

    def take(self, nbytes):
        """Freed memory of exactly ``nbytes`` (a uint8 array), or None where none is kept."""
        with self.lock:
            stack = self.free.get(nbytes)
            if stack:
                self.held -= nbytes
                return stack.pop()
        return None

    def give(self, memory):
        """Keep freed ``memory`` for reuse, dropping the oldest beyond HOST_POOL_BYTES."""
        nbytes = memory.nbytes
        with self.lock:
            if nbytes > HOST_POOL_BYTES:
                return
            self.free.setdefault(nbytes, []).append(memory)
            self.held += nbytes
            while self.held > HOST_POOL_BYTES:
                size = next(k for k, v in self.free.items() if v)
                self.free[size].pop(0)
                self.held -= size
                if not self.free[size]:
                    del self.free[size]

    def clear(self):
        """Drop every piece kept (the system gets it back once no array uses it)."""
        with self.lock:
            self.free.clear()
            self.held = 0


_host_pool = _HostPool()


def host_empty(shape, dtype=np.float64):
    """An uninitialized C-contiguous host array for a kernel's output, like ``np.empty``.

    Its memory may be an earlier output's, freed: the pool keeps up to
    ``HOST_POOL_BYTES`` of them (by exact size), so a loop of same-sized calls writes into
    memory that is already mapped instead of paying the operating system's page faults
    and zeroing for new pages every time (docs/performance.md has what that costs).
    Memory goes back to the pool only when no array or view uses it any more;
    :func:`release_host_memory` empties the pool. Outputs under ``HOST_POOL_MIN`` bytes
    or over ``HOST_POOL_BYTES`` come from ``np.empty``.

    Parameters
    ----------
    shape : int or tuple of int
    dtype : data-type
        Default float64.

    Returns
    -------
    ndarray
        Uninitialized, C-contiguous, writeable.

    Examples
    --------
    >>> import numpy as np
    >>> from clsamp.host_memory import host_empty
    >>> out = host_empty((1024, 1024, 2))
    >>> out.shape, out.dtype, out.flags.c_contiguous
    ((1024, 1024, 2), dtype('float64'), True)
    """
    dtype = np.dtype(dtype)
    nbytes = int(np.prod(shape, dtype=np.int64)) * dtype.itemsize
    if nbytes < HOST_POOL_MIN or HOST_POOL_BYTES <= 0 or nbytes > HOST_POOL_BYTES:
        return np.empty(shape, dtype)
    memory = _host_pool.take(nbytes)
    if memory is None:
        memory = np.empty(nbytes, np.uint8)
    block = _Block(memory, shape, dtype)
    array = np.asarray(block)
    weakref.finalize(block, _host_pool.give, memory)
    return array


def release_host_memory():
    """Return the pooled host memory of freed outputs (:func:`host_empty`) to the system.

    The memory of arrays still in use is not in the pool; it enters the pool when they
    are freed.
    """
    _host_pool.clear()
