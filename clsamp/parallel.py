"""Sweeps cut into tasks of whole realization blocks, run in-process or on a Dask cluster.

clsamp's randomness is counter-based (realization k of a sampler is the same whoever
computes it), so a sweep splits into pure tasks, each a block of realizations of one
(sampler, n, integrand), and the results are put back in task order: a sweep run here, on
a :class:`dask.distributed.Client` of one machine or of a hundred gives the same bits.
Every caller (``convergence``, ``expected_spectrum``, ``discrepancy_sweep``,
``render_sweep``) builds its tasks, hands them to :func:`run`, and reduces the results in
a fixed order, never in the order workers finish.

Each Dask worker imports clsamp and uses its own default OpenCL device (PoCL on a CPU
worker, the GPU on a GPU worker; ``CLSAMP_DEVICE`` in the worker's environment chooses
another); programs are built once per worker process, and a process runs one clsamp task
at a time (its OpenCL queue and kernel objects are shared), so give workers one thread
each: PoCL spreads each kernel over the cores itself. Dask recomputes the tasks of a
worker that dies (``retries``), and a ``checkpoint`` folder keeps every finished block on
disk (each written whole, with its SHA-256 beside it), so a sweep stopped with its client
resumes where it was. ``dask[distributed]`` is the optional extra ``clsamp[dask]``; nothing
here imports it unless a client or a scheduler address is given.
"""

import hashlib
import io as _io
import json
import math
import os
import pickle
import threading
import time
import uuid
from pathlib import Path

import numpy as np

from . import files
from .errors import InvalidArgumentError
from .validation import check_bool

TASK_WORK = 2**25       # points a task aims at: long beside the scheduler's cost per task
                        # (docs/scale-out.md sizes it)
RETRIES = 3
CONNECT_TIMEOUT = 10.0  # seconds to reach a scheduler
_MANIFEST = "clsamp-checkpoint.json"

__all__ = ["run", "connect", "block_ranges", "TASK_WORK"]


def _dask():
    try:
        import distributed
    except ImportError:
        raise InvalidArgumentError(
            "'client' needs dask.distributed, which is not installed: pip install 'clsamp[dask]'") from None
    return distributed


def check_client(client):
    """``client`` if it is None or a dask.distributed.Client, else a clear error.

    Parameters
    ----------
    client : dask.distributed.Client or None

    Returns
    -------
    dask.distributed.Client or None
        ``client`` itself.

    Raises
    ------
    InvalidArgumentError
        Anything else, or a client given where dask.distributed is not installed.
    """
    if client is None:
        return None
    distributed = _dask()
    if not isinstance(client, distributed.Client):
        raise InvalidArgumentError(
            f"'client' must be a dask.distributed.Client (or None to run here), got {client!r}; "
            "clsamp.parallel.connect(address) makes one from an address")
    return client


def connect(address, timeout=CONNECT_TIMEOUT):
    """A :class:`dask.distributed.Client` from a scheduler address.

    ``"local:N"`` starts a LocalCluster of N single-threaded worker processes on this
    machine (each worker's PoCL limited to its share of the cores); ``"tcp://host:port"``
    (or ``"host:port"``) connects to a running scheduler, failing with a clear error after
    ``timeout`` seconds when nothing answers there.

    Parameters
    ----------
    address : str
        ``"local"``, ``"local:N"``, ``"tcp://host:port"`` or ``"host:port"``.
    timeout : float
        Seconds to wait for a remote scheduler.

    Returns
    -------
    dask.distributed.Client
        Close it (``client.close()``) when done; a local cluster stops with it.

    Raises
    ------
    InvalidArgumentError
        A bad ``"local:N"``, a scheduler that does not answer, or dask.distributed not
        installed.
    """
    distributed = _dask()
    text = str(address).strip()
    if text.startswith("local:") or text == "local":
        count = text.partition(":")[2] or str(os.cpu_count() or 1)
        try:
            workers = int(count)
        except ValueError:
            raise InvalidArgumentError(
                f"'scheduler' 'local:N' needs a number of workers, got {address!r}") from None
        if workers < 1:
            raise InvalidArgumentError(f"'scheduler' 'local:N' needs N >= 1, got {address!r}")
        share = max(1, (os.cpu_count() or 1) // workers)
        cluster = distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                           dashboard_address=":0",
                                           env={"POCL_MAX_PTHREAD_COUNT": str(share)})
        return distributed.Client(cluster)
    if "://" not in text:
        text = "tcp://" + text
    try:
        return distributed.Client(text, timeout=timeout)
    except (OSError, TimeoutError, ValueError) as error:    # ValueError: no port, no host
        raise InvalidArgumentError(
            f"cannot reach a Dask scheduler at 'scheduler'={address!r} within {timeout:g} s "
            f"({type(error).__name__}: {error})") from None


def block_ranges(realizations, work_per_realization, work=None):
    """Realization blocks [(lo, hi), ...] of about ``work`` (default :data:`TASK_WORK`)
    units each (a unit: about the cost of generating and evaluating one point), covering
    range(realizations) in order.

    Parameters
    ----------
    realizations : int
    work_per_realization : float
        Units of one realization.
    work : float, optional
        Units a block aims at.

    Returns
    -------
    list of (int, int)

    Examples
    --------
    >>> block_ranges(10, 4, work=12)
    [(0, 3), (3, 6), (6, 9), (9, 10)]
    """
    work = TASK_WORK if work is None else work
    per = max(1, int(work // max(1, work_per_realization)))
    return [(lo, min(realizations, lo + per)) for lo in range(0, realizations, per)]


# -- checkpoints ---------------------------------------------------------------------
def _fingerprint(fn, tasks):
    h = hashlib.sha256()
    h.update(f"{fn.__module__}.{fn.__qualname__}".encode())
    for task in tasks:
        h.update(hashlib.sha256(pickle.dumps(task, protocol=4)).digest())
    return h.hexdigest()


class _Checkpoint:
    """A folder of finished blocks: block-<i>.npy, block-<i>.seconds (what it took) and
    block-<i>.sha256 (of both, written after them, so a block without its hash is
    unfinished and computed again)."""

    def __init__(self, folder, fn, tasks):
        self.folder = Path(folder)
        fingerprint = _fingerprint(fn, tasks)
        manifest = self.folder / _MANIFEST
        if self.folder.exists() and not self.folder.is_dir():
            raise InvalidArgumentError(f"'checkpoint' {str(folder)!r} is a file, not a folder")
        if manifest.exists():
            try:
                held = json.loads(manifest.read_text())
            except (OSError, ValueError) as error:
                raise InvalidArgumentError(
                    f"'checkpoint' {str(folder)!r}: its {_MANIFEST} cannot be read ({error}); "
                    "remove the folder to start afresh") from None
            if held.get("fingerprint") != fingerprint or held.get("tasks") != len(tasks):
                raise InvalidArgumentError(
                    f"'checkpoint' {str(folder)!r} holds another sweep ({held.get('what', '?')}, "
                    f"{held.get('tasks')} tasks); give a new folder or remove this one")
        elif self.folder.exists() and any(self.folder.iterdir()):
            raise InvalidArgumentError(
                f"'checkpoint' {str(folder)!r} is not empty and holds no {_MANIFEST}: not a clsamp "
                "checkpoint; give an empty or new folder")
        else:
            self.folder.mkdir(parents=True, exist_ok=True)
            what = f"{fn.__module__}.{fn.__qualname__}"
            files.write_text(manifest, json.dumps({"fingerprint": fingerprint, "tasks": len(tasks),
                                                "what": what, "format": 1}))

    def _paths(self, index):
        stem = self.folder / f"block-{index:06d}"
        return stem.with_suffix(".npy"), stem.with_suffix(".sha256"), stem.with_suffix(".seconds")

    def load(self, index):
        """The stored result of task ``index`` and the seconds it took (0 where a checkpoint
        written before those were kept has none), or None if it is not finished."""
        data, digest, took = self._paths(index)
        if not digest.exists():
            return None
        try:
            raw = data.read_bytes()
            want = digest.read_text().strip()
            text = took.read_text() if took.exists() else None
        except OSError as error:
            raise InvalidArgumentError(f"'checkpoint' block {data.name} cannot be read: {error}") from None
        # the hash covers the block and its seconds (the block alone where written before)
        if want not in (hashlib.sha256(raw).hexdigest(),
                        text is not None and hashlib.sha256(raw + text.encode()).hexdigest()):
            raise InvalidArgumentError(
                f"'checkpoint' {str(self.folder)!r}: {data.name} does not match its SHA-256 (corrupt); "
                "remove the folder to start afresh")
        try:
            spent = 0.0 if text is None else float(text)
        except ValueError:
            spent = math.nan
        if not 0.0 <= spent < math.inf:
            raise InvalidArgumentError(
                f"'checkpoint' {str(self.folder)!r}: {took.name} is not a duration (corrupt); "
                "remove the folder to start afresh")
        return np.load(_io.BytesIO(raw), allow_pickle=False), spent

    def store(self, index, value, spent):
        data, digest, took = self._paths(index)
        buffer = _io.BytesIO()
        np.save(buffer, np.asarray(value), allow_pickle=False)
        raw = buffer.getvalue()
        text = repr(float(spent))
        files.write_bytes(data, raw)
        files.write_text(took, text)
        files.write_text(digest, hashlib.sha256(raw + text.encode()).hexdigest())


# -- running -------------------------------------------------------------------------
# One task at a time per process: the OpenCL state (queue, shared kernel objects) is one
# per process, and a kernel's arguments are set and launched in two steps.
_TASK_LOCK = threading.RLock()


def _timed(fn, *args):
    with _TASK_LOCK:
        t0 = time.perf_counter()
        value = fn(*args)
        return value, time.perf_counter() - t0


def run(fn, tasks, client=None, checkpoint=None, progress=True, desc="sweep"):
    """``[fn(*task) for task in tasks]``, each an ndarray, in task order; and the seconds
    each task computed for.

    Parameters
    ----------
    fn : callable
        A module-level function (Dask pickles it by name) returning an ndarray; pure:
        the same task gives the same bits wherever it runs.
    tasks : list of tuple
        Its arguments, one tuple a task.
    client : dask.distributed.Client, optional
        Run the tasks there (retried on another worker when one dies); None: here, one
        after the other.
    checkpoint : str or Path, optional
        A folder that keeps every finished result; a later call with the same ``fn`` and
        tasks takes them from there and computes only the rest. A folder of another
        sweep, or a block that does not match its hash, is refused.
    progress : bool
        A progress bar over the tasks (from 2 s on).

    Returns
    -------
    results : list of ndarray
    seconds : ndarray
        Per task, the seconds it computed for (for one taken from the checkpoint, the
        seconds stored with it; 0 where the checkpoint kept none).
    """
    check_bool(progress, "progress")
    from tqdm import tqdm
    client = check_client(client)
    if checkpoint is not None and not isinstance(checkpoint, (str, os.PathLike)):
        raise InvalidArgumentError(f"'checkpoint' must be a folder's path, got {checkpoint!r}")
    store = _Checkpoint(checkpoint, fn, tasks) if checkpoint is not None else None
    results = [None] * len(tasks)
    seconds = np.zeros(len(tasks))
    todo = []
    for index in range(len(tasks)):
        found = store.load(index) if store is not None else None
        if found is None:
            todo.append(index)
        else:
            results[index], seconds[index] = found
    bar = tqdm(total=len(tasks), initial=len(tasks) - len(todo), desc=desc, unit="task",
               disable=not progress, delay=2)

    def finish(index, value, spent):
        value = np.asarray(value)
        if store is not None:
            store.store(index, value, spent)
        results[index] = value
        seconds[index] = spent
        bar.update(1)

    try:
        if client is None:
            for index in todo:
                value, spent = _timed(fn, *tasks[index])
                finish(index, value, spent)
        else:
            distributed = _dask()
            run_id = uuid.uuid4().hex[:12]
            futures = client.map(_timed, [fn] * len(todo), *zip(*[tasks[i] for i in todo], strict=True),
                                 key=[f"clsamp-{desc.replace(' ', '_')}-{run_id}-{i}" for i in todo],
                                 retries=RETRIES, pure=False) if todo else []
            where = {future.key: index for future, index in zip(futures, todo, strict=True)}
            for future in distributed.as_completed(futures):
                value, spent = future.result()
                finish(where[future.key], value, spent)
    finally:
        bar.close()
    return results, seconds
