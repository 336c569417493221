"""Launch shapes per device: how many points a work-item makes, work-group sizes, chunks,
and which side (the device or the host) does the steps both can do.

Every launch that could be shaped more than one way asks :func:`shape` instead of asking
what kind of device it runs on. The table has one row per device, keyed by its name,
vendor, platform and driver version:

* a device that calls itself a GPU gets :func:`gpu_shape` (one point a work-item,
  work-groups of 128, everything on the device) without measuring;
* any other device is measured once, on first use (:func:`calibrate`: a few kernels at a
  few shapes, about a second after their builds), and the row is kept in a JSON file beside
  pyopencl's compiler cache (``~/.cache/clsamp/launch-shapes.json``, or
  ``CLSAMP_SHAPES_FILE``), so later processes read it; ``CLSAMP_SHAPES=default`` skips
  measuring (the unmeasured :func:`host_shape`), as a test run that must not wait may;
* :func:`forced_shape` makes every launch of a block use a given shape (the tests force
  each shape and compare bits).

No shape changes a result: the samplers give the same bits at every shape (integer
arithmetic and exactly rounded operations whatever the grid), and the analyses their
documented tolerances.
"""

import contextlib
import dataclasses
import json
import os
import tempfile
import threading
import time
import warnings

import numpy as np

from . import discovery, programs

__all__ = ['Shape', 'shape', 'gpu_shape', 'host_shape', 'calibrate', 'forced_shape',
           'shapes_file', 'local_size', 'known_shape', 'describe']

VERSION = 2             # of the measurement: a row written by another is measured again


@dataclasses.dataclass(frozen=True)
class Shape:
    """How launches are shaped on one device.

    Attributes
    ----------
    points_per_item : int
        Points a work-item of the ``random`` sampler makes: 1, or a multiple of 4 (Philox
        blocks in four vector lanes, whose chains of dependent multiplies overlap).
    block : int
        Consecutive points a work-item of the digital nets and radical inverses makes (the
        first from its index, the others by an increment).
    local : int
        The work-group size of launches of one point (or one block) a work-item.
    vector_width : int
        Samples a renderer work-item traces at once in vector lanes (1, 4 or 8).
    host_output : bool
        Samplers write their points straight into host memory (a buffer over it).
    host_sort : bool
        Sliced optimal transport sorts its projections the way a CPU does, one row a
        work-item by buckets with its points kept on the device, not with the bitonic
        network (the name is from when the host's NumPy sort did it).
    host_gemm : bool
        2-D direct spectra form their product in the host's BLAS, not in a kernel.
    prefetch : bool
        CCVT's pair scans carry prefetch hints (PoCL lowers them to CPU prefetches).
    tile_group : int
        Work-items a group of the direct spectrum's tile product (1 where the compiler
        would vectorize across work-items what the kernel already writes in vectors).
    pair_lanes : int
        Points a work-item of a neighbour pass (Gaussian blue noise's pair pass, sample
        elimination's lists) takes at once, in vector lanes: 16 on a CPU's vector units,
        1 (one at a time) on a GPU.
    chunk : int
        Points one launch of the convergence error sums holds.
    source : str
        ``"gpu"``, ``"host"`` (defaults), ``"measured"`` or ``"forced"``.
    """

    points_per_item: int
    block: int
    local: int
    vector_width: int
    host_output: bool
    host_sort: bool
    host_gemm: bool
    prefetch: bool
    tile_group: int
    pair_lanes: int
    chunk: int
    source: str = "host"


def _pocl(device):
    return device.platform == "Portable Computing Language"


def _group(device, size):
    return max(1, min(size, device.max_work_group_size))


def gpu_shape(device):
    """The shape a GPU gets without measuring: one point a work-item in groups of 128,
    every step on the device, one sample a renderer lane.

    Parameters
    ----------
    device : Device

    Returns
    -------
    Shape
    """
    return Shape(points_per_item=1, block=1, local=_group(device, 128), vector_width=1,
                 host_output=device.host_memory, host_sort=False, host_gemm=False,
                 prefetch=False, tile_group=16, pair_lanes=1, chunk=2**25, source="gpu")


def host_shape(device):
    """The shape a device that shares the host's memory and cores starts from, before it is
    measured: many points a work-item (in vector lanes), groups of 64, outputs over host
    memory, the CPU's way to sort and the host's BLAS where they compete with a kernel.

    Parameters
    ----------
    device : Device

    Returns
    -------
    Shape
    """
    width = 8 if device.float_width >= 8 else 4 if device.float_width >= 4 else 1
    return Shape(points_per_item=16, block=256, local=_group(device, 64), vector_width=width,
                 host_output=device.host_memory, host_sort=device.host_memory,
                 host_gemm=device.host_memory, prefetch=_pocl(device), tile_group=1,
                 pair_lanes=16, chunk=2**21, source="host")


_lock = threading.RLock()
_table = {}             # device key -> Shape, this process
_forced = None


def _key(device):
    return "|".join((device.name, device.vendor, device.platform, device.driver))


def shapes_file():
    """The JSON file that keeps measured shapes: ``CLSAMP_SHAPES_FILE``, else
    ``launch-shapes.json`` in a ``clsamp`` folder beside pyopencl's compiler cache.

    Returns
    -------
    str
    """
    path = os.environ.get("CLSAMP_SHAPES_FILE")
    if path:
        return path
    base = os.environ.get("XDG_CACHE_HOME")
    if not base:
        try:
            import platformdirs
            base = os.path.dirname(platformdirs.user_cache_dir("pyopencl", "pyopencl"))
        except ImportError:
            base = os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "clsamp", "launch-shapes.json")


def _read():
    path = shapes_file()
    try:
        with open(path) as f:
            rows = json.load(f)
        if not isinstance(rows, dict):
            raise ValueError("not a JSON object")
        return rows
    except FileNotFoundError:
        return {}
    except (OSError, ValueError) as error:
        warnings.warn(f"clsamp: ignoring the launch-shape cache {path} ({error}); "
                      "the shapes are measured again", RuntimeWarning, stacklevel=3)
        return {}


def _write(key, row):
    # written to a temporary name and renamed, as clsamp.files does (which the runtime,
    # below it in the layers, cannot import): a reader sees the old table or the new one
    rows = _read()
    rows[key] = row
    path = shapes_file()
    tmp = None
    try:
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=".launch-shapes.", suffix=".tmp",
                                   dir=os.path.dirname(os.path.abspath(path)))
        with os.fdopen(fd, "w") as f:
            json.dump(rows, f, indent=1, sort_keys=True)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except OSError as error:
        if tmp is not None and os.path.exists(tmp):
            os.unlink(tmp)
        warnings.warn(f"clsamp: launch shapes not cached in {path} ({error})", RuntimeWarning,
                      stacklevel=3)


def _from_row(device, row):
    if not isinstance(row, dict) or row.get("version") != VERSION:
        return None
    try:
        return dataclasses.replace(host_shape(device), points_per_item=int(row["points_per_item"]),
                                   block=int(row["block"]), local=_group(device, int(row["local"])),
                                   source="measured")
    except (KeyError, TypeError, ValueError):
        return None


def shape(device=None):
    """The launch shape of ``device`` (the current one by default).

    A forced shape (:func:`forced_shape`) wins; else this process's row; else the row kept
    on disk; else a GPU gets :func:`gpu_shape` and any other device is measured
    (:func:`calibrate`) and the row kept, unless ``CLSAMP_SHAPES=default``.

    Parameters
    ----------
    device : Device, optional

    Returns
    -------
    Shape
    """
    if _forced is not None:
        return _forced
    device = device or discovery.current_device()
    key = _key(device)
    with _lock:
        found = _table.get(key)
        if found is not None:
            return found
        if device.type == "gpu":
            found = gpu_shape(device)
        else:
            found = _from_row(device, _read().get(key))
        if found is None:
            if os.environ.get("CLSAMP_SHAPES", "").lower() == "default" or device.simulator:
                found = host_shape(device)
            else:
                found = calibrate(device)
        _table[key] = found
        return found


def known_shape(device):
    """``device``'s shape where it is known without measuring (this process's row, the
    cached row, a GPU's default), else None.

    Parameters
    ----------
    device : Device

    Returns
    -------
    Shape or None
    """
    with _lock:
        found = _table.get(_key(device))
    if found is None and device.type == "gpu":
        found = gpu_shape(device)
    return found or _from_row(device, _read().get(_key(device)))


def describe(found):
    """One line saying what a shape is.

    Parameters
    ----------
    found : Shape

    Returns
    -------
    str
    """
    where = ("CPU sort, host BLAS and outputs" if found.host_sort and found.host_gemm
             else "outputs in host memory" if found.host_output else "everything on the device")
    return (f"{found.source}: {found.points_per_item} points a work-item, Sobol' blocks of "
            f"{found.block}, groups of {found.local}, render width {found.vector_width}, {where}")


@contextlib.contextmanager
def forced_shape(forced):
    """Shape every launch in the block with ``forced`` (a :class:`Shape`), on any device.

    Parameters
    ----------
    forced : Shape

    Yields
    ------
    Shape
        ``forced``, with ``source`` ``"forced"``.

    Examples
    --------
    >>> import dataclasses
    >>> from clsamp import runtime
    >>> one = dataclasses.replace(runtime.shape(), points_per_item=1, block=1)
    >>> with runtime.forced_shape(one):
    ...     runtime.shape().block
    1
    """
    global _forced
    with _lock:
        before, _forced = _forced, dataclasses.replace(forced, source="forced")
    try:
        yield _forced
    finally:
        with _lock:
            _forced = before


def _rounds(launches, default, rounds=9):
    """Seconds of each launch in each of ``rounds`` rounds that run every launch once in
    turn, each round starting one further along (after one untimed round, which builds),
    so that a busy machine's bursts, and whatever a launch leaves the next, fall on the
    candidates alike. A candidate more than three times slower than ``default`` and
    over 20 ms in the first timed round is out after it (a slow shape on a slow device costs
    one launch, not nine); ``default`` always runs."""
    queue = discovery.queue()
    times = {key: [] for key in launches}
    running = dict(launches)
    for round_ in range(rounds + 1):
        order = list(running.items())
        for key, launch in order[round_ % len(order):] + order[:round_ % len(order)]:
            t0 = time.perf_counter()
            launch()
            queue.finish()
            if round_:
                times[key].append(time.perf_counter() - t0)
        if round_ == 1:
            limit = max(3 * times[default][0], 0.02)
            running = {k: f for k, f in running.items() if k == default or times[k][0] <= limit}
    return times


def _relative(times, default):
    """Each candidate's time over the default's, the larger of two estimates: the median,
    over the rounds it ran, of its seconds over the default's in the same round (pairs
    taken moments apart cancel a shared machine's drift, the median ignores the rounds a
    burst hit) and the ratio of their least seconds (a busy machine only adds time; and an
    implementation that pays for switching shapes, as Intel's does for group sizes, shows
    its steady state there)."""
    least = min(times[default])
    return {key: float(max(np.median(np.array(t) / np.array(times[default][:len(t)])),
                           min(t) / least))
            for key, t in times.items()}


def _random_launch(out, n, per_item, local):
    items = -(-n // per_item)
    items = -(-items // local) * local
    defines, grid, group = discovery.dimension_split(2, 256, (items, 1), (local, 1))
    # a kernel object of its own per group size: PoCL specializes a kernel for its group
    # size, and an object launched at sizes in turn would pay for that at every launch
    kernel = programs.kernel("random.cl", "random_points",
                             defines={**defines, "POINTS_PER_ITEM": per_item},
                             instance=f"shape-{local}")
    return lambda: kernel(discovery.queue(), grid, group, out.data, np.uint32(n), np.uint32(2),
                          np.uint32(0), np.uint32(0), np.uint32(1), np.uint32(0), np.uint32(0))


def _sobol_launch(out, table, n, block, local):
    items = -(-n // block)
    split, grid, group = discovery.dimension_split(4, 256, (-(-items // local) * local, 1),
                                                   (local, 1))
    kernel = programs.kernel("lowdiscrepancy.cl", "sobol_points",
                             defines={"RANDOMIZE": 0, "LD_BLOCK": block, "LD_WIDTH": 4,
                                      "LD_LMS": 0, **split})
    return lambda: kernel(discovery.queue(), grid, group, out.data, table.data, np.uint32(n),
                          np.uint32(4), np.uint32(0), np.uint32(0), np.uint32(1), np.uint32(0),
                          np.uint32(0), np.uint32(0))


def measure(device=None, n=2**19):
    """Time the candidate shapes on ``device``: seconds of the ``random`` kernel per points
    a work-item and per work-group size, and of the Sobol' kernel per block.

    Parameters
    ----------
    device : Device, optional
        The current device by default.
    n : int, optional
        Points a timed launch makes (2-D for ``random``, 4-D for Sobol').

    Returns
    -------
    dict
        ``{"points_per_item": {p: [s, ...]}, "local": {size: [...]}, "block": {b: [...]}}``:
        each candidate's seconds in nine rounds of launches taking turns (one, for a slow
        candidate; :func:`_rounds`), the defaults those of :func:`host_shape`.
    """
    import pyopencl.array as cla
    device = device or discovery.current_device()
    out = cla.empty(discovery.queue(), n * 4, np.uint64)
    table = cla.zeros(discovery.queue(), 32 * 4, np.uint32)   # the zero net: the same work
    start = host_shape(device)
    times = {"points_per_item": _rounds({p: _random_launch(out, n, p, start.local)
                                         for p in (1, 4, 16)}, start.points_per_item)}
    best = _fastest(_relative(times["points_per_item"], start.points_per_item),
                    start.points_per_item)
    times["local"] = _rounds({size: _random_launch(out, n, best, size)
                              for size in sorted({_group(device, s) for s in (16, 64, 256)})},
                             start.local)
    times["block"] = _rounds({b: _sobol_launch(out, table, n, b, start.local)
                              for b in (1, 16, 256)}, start.block)
    return times


MARGIN = 0.75           # a candidate replaces the default only below this share of its time


def _fastest(ratios, default):
    """The candidate of least relative time (:func:`_relative`), but the default unless
    another takes less than MARGIN of its time: on a shared machine launches of
    milliseconds vary by tens of percent, and a row should not follow the noise (the shapes
    that matter differ by 2-15x on CPUs)."""
    best = min(ratios, key=ratios.get)
    return best if ratios[best] < MARGIN else default


def calibrate(device=None):
    """Measure ``device``'s launch shape (:func:`measure`), keep it on disk and return it.

    The points a work-item, the work-group size and the block are the fastest candidates
    (:func:`host_shape`'s unless another takes less than ``MARGIN``, 3/4, of its time);
    the other fields are :func:`host_shape`'s, decided by what the device reports (whether
    it shares host memory, its vector width, its platform).

    Parameters
    ----------
    device : Device, int or str, optional
        The current device by default; an index or name as :func:`clsamp.use_device` takes.

    Returns
    -------
    Shape
    """
    previous = discovery.current_device().index
    if device is not None and not isinstance(device, discovery.Device):
        device = discovery.use_device(device)
    device = device or discovery.current_device()
    try:
        discovery.use_device(device.index)
        t0 = time.perf_counter()
        times = measure(device)
        start = host_shape(device)
        ratios = {field: _relative(t, getattr(start, field)) for field, t in times.items()}
        fastest = {field: _fastest(r, getattr(start, field)) for field, r in ratios.items()}
        row = {"version": VERSION, **fastest, "seconds": round(time.perf_counter() - t0, 3),
               "relative": {field: {str(k): round(v, 3) for k, v in r.items()}
                            for field, r in ratios.items()},
               "least": {field: {str(k): min(v) for k, v in t.items()}
                         for field, t in times.items()}}
    finally:
        discovery.use_device(previous)
    _write(_key(device), row)
    result = _from_row(device, row)
    with _lock:
        _table[_key(device)] = result
    return result


def local_size(preferred=None):
    """A work-group size the current device allows.

    Parameters
    ----------
    preferred : int, optional
        The size wanted; by default the device's shape's (:func:`shape`).

    Returns
    -------
    int
        The largest power of two no larger than ``preferred`` and the device's limit.
    """
    device = discovery.current_device()
    if preferred is None:
        preferred = shape(device).local
    size = 1
    while size * 2 <= min(preferred, device.max_work_group_size):
        size *= 2
    return size
