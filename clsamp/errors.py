"""The exceptions clsamp raises.

Every error is a :class:`ClsampError` and also derives from the builtin that
fits, so ``except ValueError`` keeps working for callers who do not know clsamp.
"""


class ClsampError(Exception):
    """Base class of every error clsamp raises on purpose."""


class InvalidArgumentError(ClsampError, ValueError):
    """An argument has the wrong type, shape, range or value.

    The message names the argument and says what was expected.
    """


class NoDeviceError(ClsampError, RuntimeError):
    """No OpenCL platform or device matches what was asked for."""


class BuildError(ClsampError, RuntimeError):
    """An OpenCL program failed to build; the message holds file, device and log."""


class DeviceMemoryError(ClsampError, MemoryError):
    """A single item of work does not fit in the device's memory, even alone."""


class SamplingError(ClsampError, RuntimeError):
    """A sampler could not produce what was asked (e.g. n disks of radius r do not fit)."""
