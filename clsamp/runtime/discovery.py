"""OpenCL devices: discovery, the current device, its context and queue, and what it can do.

The default device is the first CPU device whose compiler works (PoCL from
``pocl-binary-distribution``, or Debian's PoCL where that one cannot compile for the CPU),
so a fresh install works with no GPU. ``CLSAMP_DEVICE`` (an index into :func:`devices` or a
substring of a device name) or :func:`use_device` choose another. Contexts and queues are
made once per device; the checks here (:func:`require_fp64`, :func:`require_extension`,
:func:`loop_limit`) say what a device refuses before any work.
"""

import contextlib
import dataclasses
import os
import threading
import warnings

import numpy as np

from ..errors import InvalidArgumentError, NoDeviceError

__all__ = [
    'Device', 'devices', 'use_device', 'current_device', 'without_fp64', 'compiles',
    'enable_profiling', 'context', 'queue', 'LLVMPIPE_LOOP_LIMIT', 'loop_limit', 'dimension_split',
    'require_fp64', 'require_extension', 'require_short_loops']


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
    vendor: str = ""           # the device's vendor string
    driver: str = ""           # the driver's version string (keys the launch-shape cache)
    host_memory: bool = False  # whether it reads and writes host memory in place
    float_width: int = 1       # float lanes of its vector instructions (native width)

    @property
    def simulator(self):
        """Whether the device is Oclgrind, an OpenCL simulator that interprets kernels one
        instruction at a time to check memory accesses and races (tests/test_oclgrind.py):
        correct, but thousands of times slower than a real device, so never the default and
        left out of cross-device comparisons and benchmarks."""
        return self.platform == "Oclgrind"

    def __str__(self):
        fp64 = "yes" if self.fp64 else "no"
        return f"[{self.index}] {self.name} ({self.type}, {self.platform}, fp64={fp64})"


_lock = threading.RLock()


_cl_devices = None      # list of pyopencl.Device, index-aligned with _records


_records = None


_current = None         # index into _records


_contexts = {}          # device index -> (context, queue)


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
            extensions=tuple(device.extensions.split()),
            vendor=device.vendor.strip(),
            driver=device.driver_version.strip(),
            host_memory=bool(device.host_unified_memory),
            float_width=int(device.native_vector_width_float)))
    _cl_devices, _records = found, records


def devices():
    """All OpenCL devices found, in the order of their platforms.

    Returns
    -------
    list of Device
        One record a device: ``index`` (what :func:`use_device` and ``CLSAMP_DEVICE``
        take), ``name``, ``platform``, ``type`` (``"cpu"``, ``"gpu"`` or ``"other"``),
        ``fp64``, memory sizes, the platform's version and the device's extensions.

    Raises
    ------
    NoDeviceError
        No OpenCL platform or device is installed (with how to install PoCL).

    Examples
    --------
    >>> import clsamp
    >>> any(d.type == "cpu" for d in clsamp.devices())
    True
    """
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
    """Make ``spec`` the device every later kernel runs on.

    Parameters
    ----------
    spec : int, str or Device
        An index into :func:`devices`, a substring of a device or platform name
        (case-insensitive), ``"cpu"`` or ``"gpu"`` (the first of that type), or a
        :class:`Device`.

    Returns
    -------
    Device
        The record of the device now current.

    Raises
    ------
    InvalidArgumentError
        An index out of range or a name no device matches (listing the devices).

    Examples
    --------
    >>> import clsamp
    >>> clsamp.use_device("cpu").type
    'cpu'
    """
    global _current
    with _lock:
        _current = _resolve(spec)
        return _records[_current]


def current_device():
    """The device kernels run on now.

    Returns
    -------
    Device
        The one :func:`use_device` chose, else the one ``CLSAMP_DEVICE`` names, else the
        first CPU device with fp64 whose compiler works.
    """
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


def _build(program, options=()):
    """Build a pyopencl Program, hiding what a compiler says on success.

    Intel's CPU runtime logs every build ("Compilation started", vectorizer remarks), which
    pyopencl turns into a ``CompilerWarning`` per program; a failed build still raises with
    its log. ``PYOPENCL_COMPILER_OUTPUT=1`` shows the logs again.

    Parameters
    ----------
    program : pyopencl.Program
    options : sequence of str

    Returns
    -------
    pyopencl.Program
        The built program.
    """
    cl = _cl()
    with warnings.catch_warnings():
        if os.environ.get("PYOPENCL_COMPILER_OUTPUT", "0") in ("", "0"):
            warnings.simplefilter("ignore", cl.CompilerWarning)
        return program.build(options=list(options))


def compiles(spec):
    """Whether a device builds a one-line kernel.

    A driver can list a device it cannot compile for (PoCL 3.0's LLVM 14 on CPUs newer than
    itself); the default choice skips such devices.

    Parameters
    ----------
    spec : int, str or Device
        The device, as :func:`use_device` takes it.

    Returns
    -------
    bool

    Raises
    ------
    InvalidArgumentError
        ``spec`` names no device.
    """
    cl = _cl()
    with _lock:
        index = _resolve(spec)
        if index in _broken:
            return False
        try:
            _build(cl.Program(_state(index)[0], _PROBE))
            return True
        except cl.Error as error:
            _broken[index] = str(error).strip().splitlines()
            return False


def _default_device():
    """The first CPU device with fp64 (else the first device with fp64, else the first CPU
    device, else any) whose compiler works: clsamp's kernels compute in double precision.
    A simulator (Oclgrind, which calls itself a GPU) comes last."""
    records = devices()
    rank = lambda r: (r.simulator, not r.fp64, r.type != "cpu", r.index)  # noqa: E731
    order = [r.index for r in sorted(records, key=rank)]
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
    """How a sampler launch over ``d`` dimensions is split on the current device.

    Unchanged where the device has no :func:`loop_limit`; else ``-DDIMS_PER_ITEM`` and a
    third grid axis of ``ceil(d / per_item)`` chunks (``kernels/dims.h``). The bits the
    kernel writes do not depend on it.

    Parameters
    ----------
    d : int
        Dimensions of the points.
    per_item : int
        Most dimensions one work-item computes where there is a limit.
    global_size : tuple of int
        The launch's grid without the split.
    local_size : tuple of int, optional
        Its work-group shape.

    Returns
    -------
    tuple of (dict, tuple, tuple or None)
        The defines, the global size and the local size of the launch.
    """
    if loop_limit() is None or d <= per_item:
        return {}, tuple(global_size), None if local_size is None else tuple(local_size)
    chunks = -(-d // per_item)
    local = None if local_size is None else (*local_size, 1)
    return {"DIMS_PER_ITEM": per_item}, (*global_size, chunks), local


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
    """Raise unless the current device has an OpenCL extension.

    Parameters
    ----------
    extension : str
        Such as ``"cl_khr_int64_base_atomics"``.
    what : str
        The caller, for the message.

    Returns
    -------
    Device
        The current device.

    Raises
    ------
    NoDeviceError
        The device lacks ``extension``.
    """
    device = current_device()
    if extension not in device.extensions:
        raise NoDeviceError(
            f"{what} needs the OpenCL extension {extension}, which device {device.name} "
            f"({device.platform}) lacks; choose another with clsamp.use_device or CLSAMP_DEVICE")
    return device


def require_short_loops(what):
    """Raise where the current device stops long loops (:func:`loop_limit`), on which a
    kernel with long per-work-item loops would give wrong numbers.

    Parameters
    ----------
    what : str
        The kernel, for the message.

    Raises
    ------
    NoDeviceError
        The device has a loop limit.
    """
    limit = loop_limit()
    if limit is not None:
        device = current_device()
        raise NoDeviceError(
            f"{what} does not run on {device.name}: it ends a work-item's loops after {limit} "
            "iterations, and this kernel's work-items loop longer; choose another device with "
            "clsamp.use_device or CLSAMP_DEVICE, or backend='numpy'")
