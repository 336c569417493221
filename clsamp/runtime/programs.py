"""Kernel sources and built programs: read, their headers inlined, built once per process.

Programs are cached by (device, kernel file, build options), so a kernel is compiled once
per process (PoCL also keeps binaries on disk between processes), and kernel objects are
fetched once per program. A source that computes in double never reaches a compiler
without fp64 (:func:`active_source`, :func:`needs_fp64`).
"""

import re
import threading
from importlib import resources

from ..errors import BuildError, NoDeviceError
from . import discovery

__all__ = [
    'CAPABILITIES', 'needs_fp64', 'capabilities', 'kernel_folder', 'kernel_source', 'active_source',
    'device_defines', 'program', 'kernel', 'build_count']


_programs = {}          # (device index, file, options) -> pyopencl.Program


_kernels = {}           # (program key, kernel name, instance) -> pyopencl.Kernel
_kernel_types = {}      # the same keys -> the scalar types declared on that object


_build_count = 0


# What each capability builds (the kernel files its code asks for), for `clsamp devices`.
CAPABILITIES = {
    # poisson_disk's distances too, by kernels/f64bits.h without fp64
    "samplers": ("random.cl", "stratified.cl", "lowdiscrepancy.cl", "lattice.cl", "zsobol.cl",
                 "pmj.cl", "permutation.cl", "dart_throwing.cl"),
    # ccvt is exact integers (like lloyd's kernels it needs 64-bit atomics instead, which
    # runtime.require_extension checks)
    "distance samplers": ("ccvt.cl",),
    "spectra": ("spectrum.cl", "nufft.cl"),
    # without double precision (precision="float-float")
    "spectra in float-float": ("spectrum_ff.cl",),
    "discrepancies in float-float": ("discrepancy_ff.cl",),
    "pair correlation and nearest neighbours in float-float": ("neighbors_ff.cl",),
    "experiments in float-float": ("experiments_ff.cl",),
    # comparisons only: exact on every device (bit patterns where there is no fp64)
    "certified star-discrepancy bounds": ("anchored_counts.cl",),
    # the fp64 result's bits in integer arithmetic
    "exact star discrepancy": ("star_discrepancy.cl",),
    "metrics": ("discrepancy.cl", "star_discrepancy.cl", "anchored_counts.cl", "neighbors.cl"),
    "experiments": ("integrands.cl", "fused_integrals.cl", "families.cl"),
    "render": ("render.cl",),
}


def needs_fp64(file):
    """Whether a kernel file computes in double precision even where ``CLSAMP_FP64`` is 0
    (its integer paths left out of account).

    Parameters
    ----------
    file : str
        A file name inside ``kernels/``; its headers are inlined.

    Returns
    -------
    bool
    """
    return bool(_DOUBLE.search(active_source(kernel_source(file), fp64=False)))


def capabilities(spec=None):
    """What runs on a device.

    A capability runs where every kernel file it builds compiles for the device; on a
    device without fp64 those that compute in double refuse with :class:`NoDeviceError`
    before any compiler sees them.

    Parameters
    ----------
    spec : int, str or Device, optional
        The device, as :func:`use_device` takes it; the current device when None.

    Returns
    -------
    dict
        ``{capability: None}`` for each capability of :data:`CAPABILITIES` that runs, else
        the reason it refuses (``"needs fp64"``, ``"its compiler fails"``).

    Raises
    ------
    InvalidArgumentError
        ``spec`` names no device.
    """
    device = discovery.devices()[discovery._resolve(spec)] if spec is not None else discovery.current_device()
    out = {}
    for name, files in CAPABILITIES.items():
        if not discovery.compiles(device.index):
            out[name] = "its compiler fails"
        elif not device.fp64 and any(needs_fp64(f) for f in files):
            out[name] = "needs fp64"
        else:
            out[name] = None
    return out


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
    """The text of a kernel file with its ``#include "x.h"`` lines inlined.

    Headers are inlined here rather than found through ``-I`` so that the source handed to
    the compiler is complete, and binary caches keyed by the source (pyopencl's, PoCL's)
    see a header change.

    Parameters
    ----------
    file : str
        A file name inside :func:`kernel_folder`.

    Returns
    -------
    str
        The source a compiler is given.

    Raises
    ------
    BuildError
        The file or one of its headers is missing.
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
    """``source`` without comments and without the lines a compiler skips for a given
    ``CLSAMP_FP64``.

    The branches of ``#if CLSAMP_FP64`` / ``#if !CLSAMP_FP64`` (and their ``#else``) that do
    not apply are dropped. Other conditionals are kept whole, so a ``double`` left here may
    still be compiled.

    Parameters
    ----------
    source : str
        OpenCL C source, headers inlined (:func:`kernel_source`).
    fp64 : bool
        The value of ``CLSAMP_FP64``.

    Returns
    -------
    str
        What the compiler sees of it.

    Raises
    ------
    BuildError
        An ``#elif`` follows ``#if CLSAMP_FP64``.
    """
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


def device_defines(device):
    """The ``-D`` options every build for ``device`` gets: ``CLSAMP_FP64`` (1 where it has
    double precision), and ``CLSAMP_OCLGRIND`` on the Oclgrind simulator, whose interpreter
    lacks some LLVM intrinsics (kernels/lowdiscrepancy.h).

    Parameters
    ----------
    device : Device
        The device built for.

    Returns
    -------
    dict
    """
    return {"CLSAMP_FP64": int(device.fp64), "CLSAMP_OCLGRIND": device.simulator}


def program(file, defines=None, options=(), appendix=None):
    """The built program of ``kernels/<file>`` for the current device, built once per
    (device, file, options, appendix).

    Parameters
    ----------
    file : str
        Kernel file name inside ``kernels/``.
    defines : dict, optional
        ``-D`` build options (``{"DIM": 3}`` becomes ``-DDIM=3``; ``True`` becomes 1;
        ``False`` or ``None`` leave the name undefined). Code-changing parameters go
        here so each variant compiles only what it needs.
    options : sequence of str
        Other compiler options (``-cl-mad-enable``: only where results need not be
        bit-identical across devices).
    appendix : str, optional
        OpenCL C appended to the file's source (a user's function that the file declares:
        ``clsamp.Integrand.from_opencl``); its ``#line`` directives name it in the log.

    Returns
    -------
    pyopencl.Program

    Raises
    ------
    NoDeviceError
        When the source uses ``double`` and the device has no fp64 (``cl_khr_fp64``): the
        kernel never reaches a compiler that lacks the type.
    BuildError
        With the file, the device and the compiler's log.
    """
    global _build_count
    cl = discovery._cl()
    device = discovery.current_device()
    defines = {**device_defines(device), **(defines or {})}
    key = (device.index, file, _options(defines, options), appendix)
    with discovery._lock:
        built = _programs.get(key)
        if built is not None:
            return built
        ctx = discovery._state(device.index)[0]
        source = kernel_source(file) + ("\n" + appendix if appendix else "")
        if not device.fp64 and _DOUBLE.search(active_source(source, fp64=False)):
            raise NoDeviceError(
                f"kernels/{file} computes in double precision and device {device.name} "
                f"({device.platform}) has none (no cl_khr_fp64); choose another with "
                "clsamp.use_device or CLSAMP_DEVICE (`clsamp devices` lists them)")
        try:
            built = discovery._build(cl.Program(ctx, source), key[2])
        except cl.RuntimeError as error:
            hint = f"\n{discovery._UNKNOWN_CPU_HINT}" if "unknown target CPU" in str(error) else ""
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


def kernel(file, name, defines=None, options=(), instance=None, appendix=None,
           scalar_types=None):
    """A kernel object from :func:`program`, fetched once per program and thread.

    Callers in one thread share the object, so each launch sets all its arguments. Each
    thread gets objects of its own: setting a kernel's arguments and launching it are two
    steps, which two threads must not interleave on one object.

    Parameters
    ----------
    file, defines, options, appendix
        As :func:`program` takes them.
    name : str
        The kernel's name in the file.
    instance : hashable, optional
        A key for an object of its own, kept with the program: for a loop that sets
        arguments once and launches many times.
    scalar_types : sequence, optional
        The kernel's arguments for pyopencl's fast argument setting
        (``Kernel.set_scalar_arg_dtypes``): a NumPy type for each scalar, None for each
        buffer; declared once on the object. pyopencl otherwise sets each scalar through
        a slow generic path, which a launch loop pays on every launch.

    Returns
    -------
    pyopencl.Kernel

    Raises
    ------
    NoDeviceError, BuildError
        As :func:`program` raises them.
    """
    prog = program(file, defines, options, appendix)
    key = (id(prog), name, instance, threading.get_ident())
    with discovery._lock:
        k = _kernels.get(key)
        if k is None:
            k = discovery._cl().Kernel(prog, name)
            _kernels[key] = k
            _kernel_types.pop(key, None)
        if scalar_types is not None and _kernel_types.get(key) != tuple(scalar_types):
            k.set_scalar_arg_dtypes(list(scalar_types))
            _kernel_types[key] = tuple(scalar_types)
        return k


def build_count():
    """How many programs this process has built (a cache hit builds nothing)."""
    return _build_count
