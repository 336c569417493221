"""OpenCL runtime: devices, the current context and queue, programs, kernels and buffers.

This module is the one owner of OpenCL state (docs/design.md, "Kernels and the
runtime"): nothing else creates contexts, queues, programs, kernel objects or buffers over
host memory, and every module asks :func:`chunk_ranges` / :func:`fit` how much work one
launch may hold.
Programs are cached by (device, kernel file, build options), so a kernel is compiled once
per process (PoCL also keeps binaries on disk between processes); kernel objects once per
program, and small read-only tables once per device (:func:`table`).

The default device is the first CPU device whose compiler works (PoCL from
``pocl-binary-distribution``, or Debian's PoCL where that one cannot compile for the CPU),
so a fresh install works with no GPU. ``CLSAMP_DEVICE`` (an index into :func:`devices` or a
substring of a device name) or :func:`use_device` choose another.
"""

import contextlib
import dataclasses
import os
import re
import threading
from importlib import resources

import numpy as np

from .errors import BuildError, InvalidArgumentError, NoDeviceError

_INSTALL_HINT = (
    "clsamp needs an OpenCL platform. On a machine without a GPU install PoCL, the CPU "
    "driver: 'pip install pocl-binary-distribution' (a dependency of clsamp) or Debian's "
    "'apt-get install pocl-opencl-icd'. For a GPU install its vendor's OpenCL driver.")

# PoCL 3.0 from PyPI links LLVM 14, which names CPUs newer than itself (AMD Zen 5, family
# 1Ah) 'generic', a target its own front end then refuses: every build fails on them.
_UNKNOWN_CPU_HINT = (
    "This PoCL's LLVM does not know this CPU ('unknown target CPU'), so it cannot compile "
    "any kernel here. Debian's PoCL chooses its code target by CPU features and works: "
    "'apt-get install pocl-opencl-icd' (scripts/ensure-opencl.sh does it); clsamp then "
    "uses it by default.")
_PROBE = "__kernel void clsamp_probe(__global int *x) { x[get_global_id(0)] += 1; }"


@dataclasses.dataclass(frozen=True)
class Device:
    """One OpenCL device as clsamp sees it."""

    index: int
    name: str
    platform: str
    type: str            # 'cpu', 'gpu' or 'other'
    fp64: bool
    compute_units: int
    max_work_group_size: int
    global_memory: int   # bytes
    max_allocation: int  # bytes, largest single buffer
    local_memory: int    # bytes
    implementation: str = ""   # the platform's version string ("OpenCL 3.0 PoCL 3.1 ...")
    extensions: tuple = ()     # the device's OpenCL extensions ("cl_khr_fp64", ...)

    def __str__(self):
        fp64 = "yes" if self.fp64 else "no"
        return f"[{self.index}] {self.name} ({self.type}, {self.platform}, fp64={fp64})"


_lock = threading.RLock()
_cl_devices = None      # list of pyopencl.Device, index-aligned with _records
_records = None
_current = None         # index into _records
_contexts = {}          # device index -> (context, queue)
_programs = {}          # (device index, file, options) -> pyopencl.Program
_kernels = {}           # (program key, kernel name, instance) -> pyopencl.Kernel
_tables = {}            # (device index, key) -> pyopencl.array.Array, least recently used first
_TABLES = 64            # tables kept per process
_build_count = 0
_broken = {}            # device index -> why its compiler failed the probe build
_profiling = False      # queues made with profiling enabled (benchmarks/run.py --profile)


def _cl():
    import pyopencl as cl  # imported lazily: `clsamp --help` should not need a driver
    return cl


def _type_name(cl, device):
    if device.type & cl.device_type.GPU:
        return "gpu"
    if device.type & cl.device_type.CPU:
        return "cpu"
    return "other"


def _discover():
    global _cl_devices, _records
    cl = _cl()
    try:
        platforms = cl.get_platforms()
    except cl.Error as error:  # pyopencl raises when no ICD is installed
        raise NoDeviceError(f"no OpenCL platform found ({error}). {_INSTALL_HINT}") from None
    found = []
    for platform in platforms:
        try:
            found.extend(platform.get_devices())
        except cl.Error:
            continue  # a platform with no devices
    if not found:
        raise NoDeviceError(f"no OpenCL device found. {_INSTALL_HINT}")
    records = []
    for index, device in enumerate(found):
        records.append(Device(
            index=index,
            name=device.name.strip(),
            platform=device.platform.name.strip(),
            type=_type_name(cl, device),
            fp64=bool(device.double_fp_config),
            compute_units=device.max_compute_units,
            max_work_group_size=device.max_work_group_size,
            global_memory=device.global_mem_size,
            max_allocation=device.max_mem_alloc_size,
            local_memory=device.local_mem_size,
            implementation=" ".join(device.platform.version.split()),
            extensions=tuple(device.extensions.split())))
    _cl_devices, _records = found, records


def devices():
    """All OpenCL devices found, as :class:`Device` records (index, name, platform, type, fp64, ...)."""
    with _lock:
        if _records is None:
            _discover()
        return list(_records)


def _resolve(spec):
    records = devices()
    if isinstance(spec, Device):
        spec = spec.index
    if isinstance(spec, (int, np.integer)) and not isinstance(spec, bool):
        if not 0 <= spec < len(records):
            raise InvalidArgumentError(
                f"'device' index must be in [0, {len(records) - 1}], got {spec}; devices: "
                + "; ".join(str(r) for r in records))
        return int(spec)
    if isinstance(spec, str):
        text = spec.strip()
        if text.isdigit():
            return _resolve(int(text))
        if text.lower() in ("cpu", "gpu"):
            for record in records:
                if record.type == text.lower():
                    return record.index
        for record in records:
            if text.lower() in record.name.lower() or text.lower() in record.platform.lower():
                return record.index
        raise NoDeviceError(
            f"no OpenCL device matches 'device'={spec!r}; devices: " + "; ".join(str(r) for r in records))
    raise InvalidArgumentError(
        f"'device' must be an index, a name substring or a Device, got {spec!r}")


def use_device(spec):
    """Make ``spec`` the current device and return its :class:`Device` record.

    ``spec`` is an index into :func:`devices`, a substring of a device or platform
    name (case-insensitive), ``"cpu"``/``"gpu"``, or a :class:`Device`.
    """
    global _current
    with _lock:
        _current = _resolve(spec)
        return _records[_current]


def current_device():
    """The :class:`Device` kernels run on now (chosen by :func:`use_device`,
    ``CLSAMP_DEVICE``, or the first CPU device)."""
    global _current
    with _lock:
        if _current is None:
            env = os.environ.get("CLSAMP_DEVICE")
            if env:
                _current = _resolve(env)
            else:
                _current = _default_device()
        record = _records[_current]
        if _without_fp64 and record.fp64:
            record = dataclasses.replace(record, fp64=False)
        return record


_without_fp64 = False


@contextlib.contextmanager
def without_fp64():
    """Run as if the current device had no fp64 (``cl_khr_fp64``), to test the integer paths.

    Inside the block kernels build with ``CLSAMP_FP64=0`` (the float64 bit patterns by
    integer arithmetic, kernels/f64bits.h) and whatever needs double precision refuses
    with :class:`NoDeviceError`, exactly as on such a device; the results of the
    samplers that run are the same bits as outside it.

    Examples
    --------
    >>> import clsamp
    >>> from clsamp import runtime
    >>> with runtime.without_fp64():
    ...     a = clsamp.make_sampler("halton", d=3, seed=1).sample(8)
    >>> bool((a == clsamp.make_sampler("halton", d=3, seed=1).sample(8)).all())
    True
    """
    global _without_fp64
    with _lock:
        before, _without_fp64 = _without_fp64, True
    try:
        yield
    finally:
        with _lock:
            _without_fp64 = before


# What each capability builds (the kernel files its code asks for), for `clsamp devices`.
CAPABILITIES = {
    "samplers": ("random.cl", "stratified.cl", "lowdiscrepancy.cl", "lattice.cl", "zsobol.cl",
                 "pmj.cl", "permutation.cl"),
    # poisson_disk and ccvt: distances and energies in double precision (lloyd's integer
    # kernels need 64-bit atomics instead, which runtime.require_extension checks)
    "distance samplers": ("dart_throwing.cl", "ccvt.cl"),
    "spectra": ("spectrum.cl", "nufft.cl"),
    "metrics": ("discrepancy.cl", "star_discrepancy.cl", "anchored_counts.cl", "neighbors.cl"),
    "experiments": ("integrands.cl", "families.cl"),
    "render": ("render.cl",),
}


def needs_fp64(file):
    """Whether ``kernels/<file>`` (its headers inlined) computes in double precision even
    where ``CLSAMP_FP64`` is 0 (its integer paths left out of account)."""
    return bool(_DOUBLE.search(active_source(kernel_source(file), fp64=False)))


def capabilities(spec=None):
    """What runs on a device: ``{capability: None}`` where it runs, else the reason it refuses.

    A capability runs where every kernel file it builds compiles for the device; on a
    device without fp64 those that compute in double refuse with :class:`NoDeviceError`
    before any compiler sees them, and the value here is "needs fp64".
    """
    device = devices()[_resolve(spec)] if spec is not None else current_device()
    out = {}
    for name, files in CAPABILITIES.items():
        if not compiles(device.index):
            out[name] = "its compiler fails"
        elif not device.fp64 and any(needs_fp64(f) for f in files):
            out[name] = "needs fp64"
        else:
            out[name] = None
    return out


def compiles(spec):
    """Whether the device ``spec`` (as :func:`use_device` takes it) builds a one-line kernel.

    A driver can list a device it cannot compile for (PoCL 3.0's LLVM 14 on CPUs newer
    than itself); the default choice skips such devices.
    """
    cl = _cl()
    with _lock:
        index = _resolve(spec)
        if index in _broken:
            return False
        try:
            cl.Program(_state(index)[0], _PROBE).build()
            return True
        except cl.Error as error:
            _broken[index] = str(error).strip().splitlines()
            return False


def _default_device():
    """The first CPU device with fp64 (else the first device with fp64, else the first CPU
    device, else any) whose compiler works: clsamp's kernels compute in double precision."""
    records = devices()
    order = [r.index for r in sorted(records, key=lambda r: (not r.fp64, r.type != "cpu", r.index))]
    for index in order:
        if compiles(index):
            return index
    reasons = "; ".join(f"{records[i]}: {' '.join(line for line in _broken[i] if 'error' in line)}"
                        for i in order)
    hint = _UNKNOWN_CPU_HINT if "unknown target CPU" in reasons else _INSTALL_HINT
    raise NoDeviceError(f"no OpenCL device can compile a kernel ({reasons}). {hint}")


def _state(index):
    cl = _cl()
    with _lock:
        if index not in _contexts:
            context = cl.Context([_cl_devices[index]])
            properties = cl.command_queue_properties.PROFILING_ENABLE if _profiling else 0
            _contexts[index] = (context, cl.CommandQueue(context, properties=properties))
        return _contexts[index]


def enable_profiling():
    """Make every queue record OpenCL profiling times (``benchmarks/run.py --profile``).

    Must be called before the first device is used: queues are made once per device.

    Raises
    ------
    RuntimeError
        When a queue exists already.
    """
    global _profiling
    with _lock:
        if _contexts and not _profiling:
            raise RuntimeError("enable_profiling() must be called before any device is used")
        _profiling = True


def context():
    """The pyopencl Context of the current device."""
    return _state(current_device().index)[0]


def queue():
    """The pyopencl CommandQueue of the current device (in-order)."""
    return _state(current_device().index)[1]


def kernel_folder():
    """Where the kernel sources are: the installed package data ``clsamp/kernels``,
    or ``kernels/`` beside the package in a source checkout."""
    try:
        folder = resources.files("clsamp.kernels")
        if folder.joinpath("philox.h").is_file():
            return folder
    except ModuleNotFoundError:
        pass
    return resources.files("clsamp").joinpath("..", "kernels")


def kernel_source(file):
    """The text of ``kernels/<file>`` with its ``#include "x.h"`` lines inlined.

    Headers are inlined here rather than found through ``-I`` so that the
    source handed to the compiler is complete, and binary caches keyed by the
    source (pyopencl's, PoCL's) see a header change.
    """
    folder = kernel_folder()
    seen = set()

    def expand(name):
        if name in seen:
            return ""
        seen.add(name)
        path = folder / name
        if not path.is_file():
            raise BuildError(f"kernel file {name!r} not found in {folder}")
        text = path.read_text()
        return re.sub(r'^\s*#include\s+"([^"]+)"\s*$', lambda m: expand(m.group(1)), text, flags=re.M)

    return expand(file)


def _options(defines, extra):
    options = []
    for key in sorted(defines or {}):
        value = defines[key]
        if value is True:
            options.append(f"-D{key}=1")
        elif value is False or value is None:
            continue
        else:
            options.append(f"-D{key}={value}")
    options.extend(extra or ())
    return tuple(options)


_DOUBLE = re.compile(r"\bdouble[0-9]*\b")


def _strip_comments(source):
    return re.sub(r"/\*.*?\*/|//[^\n]*", " ", source, flags=re.S)


_CONDITIONAL = re.compile(r"^\s*#\s*(if|ifdef|ifndef|elif|else|endif)\b(.*)$")


def active_source(source, fp64):
    """``source`` without comments and without the lines a compiler skips when
    ``CLSAMP_FP64`` is ``fp64``: the branches of ``#if CLSAMP_FP64`` / ``#if !CLSAMP_FP64``
    (and their ``#else``) that do not apply. Other conditionals are kept whole, so a
    ``double`` left here may still be compiled."""
    out = []
    stack = []          # per open #if: None (not ours) or whether its branch is live
    for line in _strip_comments(source).splitlines():
        m = _CONDITIONAL.match(line)
        if m:
            word, rest = m.group(1), m.group(2).strip()
            if word == "if" and rest in ("CLSAMP_FP64", "!CLSAMP_FP64"):
                stack.append(fp64 if rest == "CLSAMP_FP64" else not fp64)
                continue
            if word in ("if", "ifdef", "ifndef"):
                stack.append(None)
            elif word == "else" and stack and stack[-1] is not None:
                stack[-1] = not stack[-1]
                continue
            elif word == "elif" and stack and stack[-1] is not None:
                raise BuildError("kernels: '#elif' after '#if CLSAMP_FP64' is not supported")
            elif word == "endif" and stack:
                if stack.pop() is not None:
                    continue
        if all(live is not False for live in stack):
            out.append(line)
    return "\n".join(out)


def program(file, defines=None, options=()):
    """The built program of ``kernels/<file>`` for the current device.

    Parameters
    ----------
    file : str
        Kernel file name inside ``kernels/``.
    defines : dict, optional
        ``-D`` build options (``{"DIM": 3}`` becomes ``-DDIM=3``; ``True`` becomes 1;
        ``False``/``None`` leave the name undefined). Code-changing parameters go
        here so each variant compiles only what it needs.
    options : sequence of str
        Other compiler options (``-cl-mad-enable``: only where results need not be
        bit-identical across devices).

    Raises
    ------
    NoDeviceError
        When the source uses ``double`` and the device has no fp64 (``cl_khr_fp64``): the
        kernel never reaches a compiler that lacks the type.
    BuildError
        With the file, the device and the compiler's log.
    """
    global _build_count
    cl = _cl()
    device = current_device()
    defines = {"CLSAMP_FP64": int(device.fp64), **(defines or {})}
    key = (device.index, file, _options(defines, options))
    with _lock:
        built = _programs.get(key)
        if built is not None:
            return built
        ctx = _state(device.index)[0]
        source = kernel_source(file)
        if not device.fp64 and _DOUBLE.search(active_source(source, fp64=False)):
            raise NoDeviceError(
                f"kernels/{file} computes in double precision and device {device.name} "
                f"({device.platform}) has none (no cl_khr_fp64); choose another with "
                "clsamp.use_device or CLSAMP_DEVICE (`clsamp devices` lists them)")
        try:
            built = cl.Program(ctx, source).build(options=list(key[2]))
        except cl.RuntimeError as error:
            hint = f"\n{_UNKNOWN_CPU_HINT}" if "unknown target CPU" in str(error) else ""
            raise BuildError(
                f"OpenCL build of kernels/{file} failed on {device.name} "
                f"({device.platform}) with options {' '.join(key[2]) or '(none)'}:\n{error}{hint}") from None
        if not built.kernel_names:
            raise BuildError(
                f"OpenCL build of kernels/{file} on {device.name} ({device.platform}) with options "
                f"{' '.join(key[2]) or '(none)'} gave a program without kernels (a broken binary "
                "from the driver's cache?); clearing ~/.cache/pocl or setting POCL_KERNEL_CACHE=0 "
                "builds it afresh")
        _build_count += 1
        _programs[key] = built
        return built


def kernel(file, name, defines=None, options=(), instance=None):
    """A kernel object from :func:`program`, fetched once per program and thread.

    Callers in one thread share the object, so each launch sets all its arguments. A loop
    that sets arguments once and launches many times asks for its own ``instance`` (any
    hashable key): a distinct object per key, kept with the program. Each thread gets
    objects of its own: setting a kernel's arguments and launching it are two steps, which
    two threads must not interleave on one object.
    """
    prog = program(file, defines, options)
    key = (id(prog), name, instance, threading.get_ident())
    with _lock:
        k = _kernels.get(key)
        if k is None:
            k = _cl().Kernel(prog, name)
            _kernels[key] = k
        return k


def table(key, build, dtype=np.uint32):
    """A small read-only device array, uploaded once per (device, ``key``).

    ``build()`` makes the host array the first time; later calls on the same device get
    the same device array (the most recently used tables are kept, at most 64).
    """
    import pyopencl.array as cla
    full = (current_device().index, key)
    with _lock:
        found = _tables.pop(full, None)
        if found is None:
            found = cla.to_device(queue(), np.ascontiguousarray(build(), dtype=dtype))
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
    array).
    """

    def __init__(self, shape, dtype=np.float64, host=None):
        import pyopencl.array as cla
        self.host = host
        if host is None:
            self.array = cla.empty(queue(), shape, dtype)
            self.buffer = self.array.data
        else:
            cl = _cl()
            self.array = host
            self.buffer = cl.Buffer(context(), cl.mem_flags.WRITE_ONLY | cl.mem_flags.USE_HOST_PTR,
                                    hostbuf=host)

    def finish(self):
        if self.host is not None:
            # mapping makes the kernel's writes visible in host memory (no copy on PoCL)
            cl = _cl()
            # (a blocking map waits about 100 us longer on PoCL than map, unmap and finish;
            # rusticl refuses to unmap a map that has not completed)
            pocl = current_device().platform == "Portable Computing Language"
            mapped, _ = cl.enqueue_map_buffer(queue(), self.buffer, cl.map_flags.READ, 0,
                                              self.host.shape, self.host.dtype, is_blocking=not pocl)
            mapped.base.release(queue())
            queue().finish()
        return self.array


def is_device_array(value):
    """Whether ``value`` is a ``pyopencl.array.Array``."""
    import pyopencl.array as cla
    return isinstance(value, cla.Array)


def to_device(array):
    """``array`` on the current device: itself if it is a device array, else a copy."""
    if is_device_array(array):
        return array
    import pyopencl.array as cla
    return cla.to_device(queue(), np.ascontiguousarray(array))


def to_host(array, into=None):
    """``array`` as a NumPy array (a device array read back), in ``into`` when given."""
    if is_device_array(array):
        return array.get() if into is None else array.get(ary=into)
    if into is None:
        return np.asarray(array)
    into[...] = array
    return into


def bounds(array):
    """(smallest, largest, count of NaN or infinite) of the doubles of a device array,
    computed on the device (``kernels/points.cl``); smallest/largest over finite values."""
    import pyopencl.array as cla
    require_fp64()
    items = 64 * max(1, current_device().compute_units)
    q = queue()
    lo = cla.empty(q, items, np.float64)
    hi = cla.empty(q, items, np.float64)
    bad = cla.empty(q, items, np.uint32)
    kernel("points.cl", "points_bounds")(q, (items,), None, array.base_data, np.uint64(array.size),
                                         lo.data, hi.data, bad.data)
    return float(lo.get().min()), float(hi.get().max()), int(bad.get().sum())


def device_block(array, r0, r1, k0=0, k1=None):
    """``array[r0:r1, k0:k1]`` of a device array (r, n, d) as a contiguous device array:
    the array itself when that is all of it, else a copy made on the device."""
    import pyopencl.array as cla
    r, n, d = array.shape
    k1 = n if k1 is None else k1
    if (r0, r1, k0, k1) == (0, r, 0, n) and array.offset == 0:
        return array
    out = cla.empty(queue(), (r1 - r0, k1 - k0, d), array.dtype)
    item = array.dtype.itemsize
    row = n * d * item
    _cl().enqueue_copy(queue(), out.data, array.base_data,
                       src_origin=(array.offset + k0 * d * item, r0, 0), dst_origin=(0, 0, 0),
                       region=((k1 - k0) * d * item, r1 - r0, 1), src_pitches=(row, 0),
                       dst_pitches=((k1 - k0) * d * item, 0))
    return out


def concatenate(parts):
    """Device arrays joined along their first axis (the one part itself when alone)."""
    if len(parts) == 1:
        return parts[0]
    import pyopencl.array as cla
    return cla.concatenate(parts, axis=0, queue=queue())


LLVMPIPE_LOOP_LIMIT = 65535


def loop_limit():
    """The most loop iterations one work-item may run on the current device, or None.

    Mesa's llvmpipe (rusticl's CPU device) ends all the loops of a work-item after 65535
    iterations in all, silently (gallivm's LP_MAX_TGSI_LOOP_ITERATIONS): a kernel that
    loops longer gives wrong numbers there, not an error. The samplers split their
    dimensions across work-items where there is a limit (:func:`dimension_split`).
    """
    return LLVMPIPE_LOOP_LIMIT if current_device().name.startswith("llvmpipe") else None


def dimension_split(d, per_item, global_size, local_size=None):
    """``(defines, global_size, local_size)`` of a sampler launch over ``d`` dimensions:
    unchanged where the device has no :func:`loop_limit`; else ``-DDIMS_PER_ITEM`` and a
    third grid axis of ``ceil(d / per_item)`` chunks (``kernels/dims.h``). The bits do
    not depend on it."""
    if loop_limit() is None or d <= per_item:
        return {}, tuple(global_size), None if local_size is None else tuple(local_size)
    chunks = -(-d // per_item)
    local = None if local_size is None else (*local_size, 1)
    return {"DIMS_PER_ITEM": per_item}, (*global_size, chunks), local


def build_count():
    """How many programs this process has built (a cache hit builds nothing)."""
    return _build_count


def require_fp64():
    """Raise unless the current device does double precision (the analyses, the renderer,
    dart throwing and CCVT compute in it; the other samplers do not need it)."""
    device = current_device()
    if not device.fp64:
        raise NoDeviceError(
            f"device {device.name} has no double precision (cl_khr_fp64); this computation "
            "needs it. Choose another with clsamp.use_device or CLSAMP_DEVICE.")
    return device


def require_extension(extension, what):
    """Raise :class:`NoDeviceError` unless the current device has the OpenCL ``extension``
    (``what`` names the caller in the message)."""
    device = current_device()
    if extension not in device.extensions:
        raise NoDeviceError(
            f"{what} needs the OpenCL extension {extension}, which device {device.name} "
            f"({device.platform}) lacks; choose another with clsamp.use_device or CLSAMP_DEVICE")
    return device


def require_short_loops(what):
    """Raise :class:`NoDeviceError` where the current device stops long loops
    (:func:`loop_limit`) and ``what`` (a kernel with long per-work-item loops) would give
    wrong numbers there."""
    limit = loop_limit()
    if limit is not None:
        device = current_device()
        raise NoDeviceError(
            f"{what} does not run on {device.name}: it ends a work-item's loops after {limit} "
            "iterations, and this kernel's work-items loop longer; choose another device with "
            "clsamp.use_device or CLSAMP_DEVICE, or backend='numpy'")


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
    """Refuse, before any work, a result of ``need`` bytes that the host's available
    memory cannot hold (the figure is read only for requests above 256 MiB)."""
    if need <= 2**28:
        return
    room = host_memory_available()
    if room is not None and need > room:
        raise InvalidArgumentError(
            f"{what} needs {gib(need)}; this machine has {gib(room)} available. Ask for less "
            "at a time")


def gib(nbytes):
    """Bytes as a message shows them."""
    return f"{nbytes / 2**30:.1f} GiB" if nbytes >= 2**30 else f"{nbytes / 2**20:.1f} MiB"


def work_budget():
    """Bytes one launch's buffers may hold on the current device: a quarter of its largest
    single allocation (the one rule every module asks, through :func:`fit`)."""
    return max(1, current_device().max_allocation // 4)


def fit(bytes_per_item, limit=None):
    """How many items of ``bytes_per_item`` one launch may hold (at least one).

    ``limit`` caps the bytes further where a caller has its own reason (a working set
    that should stay in the caches, a host-memory cap).
    """
    budget = work_budget() if limit is None else min(work_budget(), int(limit))
    return max(1, budget // max(1, int(bytes_per_item)))


def chunk_ranges(total, bytes_per_item, limit=None):
    """Split ``total`` items into contiguous ranges that each fit one launch (:func:`fit`),
    so work too large for the device is split, never refused or truncated."""
    step = fit(bytes_per_item, limit)
    return [(lo, min(total, lo + step)) for lo in range(0, total, step)]


def local_size(preferred=64):
    """A work-group size no larger than the device allows (a power of two)."""
    limit = current_device().max_work_group_size
    size = 1
    while size * 2 <= min(preferred, limit):
        size *= 2
    return size


def key_args(seed):
    """The seed as the two uint32 kernel arguments (key low, key high)."""
    seed = int(seed)
    return np.uint32(seed & 0xFFFFFFFF), np.uint32(seed >> 32)
