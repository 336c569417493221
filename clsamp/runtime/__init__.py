"""OpenCL runtime: the one owner of OpenCL state (docs/design.md, "Kernels and the runtime").

Nothing else creates contexts, queues, programs, kernel objects or buffers over host
memory, and every module asks :func:`chunk_ranges` / :func:`fit` how much work one launch
may hold. Four modules, one concern each:

* :mod:`~clsamp.runtime.discovery`: devices, the current device, contexts and queues, and
  what a device can do (fp64, extensions, loop limits);
* :mod:`~clsamp.runtime.programs`: kernel sources with their headers inlined, programs
  built once per (device, file, options), kernel objects;
* :mod:`~clsamp.runtime.memory`: outputs over host memory, copies, tables, and the sizing
  rule of every launch;
* :mod:`~clsamp.runtime.shapes`: each device's launch shape (points a work-item, group
  sizes, what runs on the host), measured once and kept beside pyopencl's cache.

Their public names are this package's (``runtime.queue()``, ``runtime.kernel(...)``): each
resolves to its home module when it is read, so a test that patches
``runtime.memory.work_budget`` changes it for every caller.
"""

from . import discovery, memory, programs, shapes

_HOMES = {name: module for module in (discovery, programs, memory, shapes) for name in module.__all__}
__all__ = sorted(_HOMES)


def __getattr__(name):
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module 'clsamp.runtime' has no attribute {name!r}")
    return getattr(home, name)


def __dir__():
    return sorted(set(globals()) | set(_HOMES))
