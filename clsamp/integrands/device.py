"""Integrands written in OpenCL C by their user (:meth:`clsamp.Integrand.from_opencl`,
:class:`~clsamp.integrands.OpenCLIntegrand`): their source, its build, and evaluation on
the device.

The user's function is appended to the integrand kernels' source (``kernels/integrand.h``
declares it as ``clsamp_user_integrand``), so the same code runs wherever clsamp evaluates
an integrand on the device: at given points (:func:`device_values`), at a
sampler's points (:func:`clsamp.convergence`, ``integrate(method="replications")`` with a
sampler object) and at points made inside the kernel that evaluates it
(:mod:`clsamp.fused`: ``integrate`` with a Sobol' sampler by name or
``method="digital" | "lattice"``), where no point is ever stored.
"""

import re

import numpy as np

from .. import runtime
from ..errors import BuildError, InvalidArgumentError
from ..validation import plain

USER_SOURCE = 15        # INTEGRAND in kernels/integrand.h
MAX_D = 1024            # a point is a private array of d doubles in the kernel
CHUNK = 2**20           # points a launch of integrand_values evaluates at most

_FUNCTION = re.compile(
    r"\bdouble\s+([A-Za-z_]\w*)\s*\(\s*(?:__private\s+)?const\s+double\s*\*\s*[A-Za-z_]\w*\s*\)\s*\{")
_RETURN = re.compile(r"\breturn\b")
_AT_SOURCE = re.compile(r"^(?:error:\s*(source:\d+:\d+:)|(source:\d+:\d+:)\s*error:)\s*(.*)$", re.M)
_ERROR = re.compile(r"^.*\berror\b.*$", re.M | re.I)

__all__ = ["assemble", "compile_source", "device_values"]


def assemble(source):
    """The OpenCL C that defines ``clsamp_user_integrand`` from a user's source.

    Parameters
    ----------
    source : str
        A full function ``double f(const double *x) { ... }`` (with helpers before it if
        needed: the last function of that signature is the integrand), a function body
        with a ``return`` (``x`` the point), or an expression in ``x[0] .. x[d-1]``.

    Returns
    -------
    str
        Source lines numbered from 1 as ``source`` in compiler messages (``#line``).

    Examples
    --------
    >>> print(assemble("x[0] * x[1]"))
    double clsamp_user_integrand(const double *x)
    {
        return (
    #line 1 "source"
    x[0] * x[1]
        );
    }
    """
    functions = _FUNCTION.findall(source)
    if functions:
        return (f'#line 1 "source"\n{source}\n'
                f"double clsamp_user_integrand(const double *x) {{ return {functions[-1]}(x); }}")
    if _RETURN.search(source):
        return f'double clsamp_user_integrand(const double *x)\n{{\n#line 1 "source"\n{source}\n}}'
    return (f'double clsamp_user_integrand(const double *x)\n{{\n    return (\n#line 1 "source"\n'
            f"{source}\n    );\n}}")


def _first_error(message):
    """The compiler's first error line in a build failure's message (else its first line)."""
    at = _AT_SOURCE.search(message)
    if at:                  # PoCL writes "error: source:2:15: ...", clang "source:2:15: error: ..."
        return f"{at.group(1) or at.group(2)} error: {' '.join(at.group(3).split())}"
    found = _ERROR.search(message.split("\n", 1)[1] if "\n" in message else message)
    line = found.group(0) if found else message.splitlines()[0]
    return " ".join(line.split())


def compile_source(source, d):
    """The OpenCL C of a user's ``source`` (:func:`assemble`), built once for dimension d.

    Parameters
    ----------
    source : str
    d : int

    Returns
    -------
    str
        The code appended to the integrand kernels.

    Raises
    ------
    InvalidArgumentError
        ``source`` not a non-empty string, or not compiling: the message holds the
        compiler's first error, its line numbered within ``source``.
    NoDeviceError
        The current device has no fp64.
    """
    if not isinstance(source, str) or not source.strip():
        raise InvalidArgumentError(
            f"'source' must be OpenCL C (an expression in x[0] .. x[d-1], a function body "
            f"or a function double f(const double *x)), got {plain(source)}")
    code = assemble(source)
    runtime.require_fp64()
    try:                # built now, so that a compiler error is the caller's to see
        runtime.kernel("integrands.cl", "integrand_values",
                       defines={"DIM": d, "INTEGRAND": USER_SOURCE}, appendix=code)
    except BuildError as error:
        raise InvalidArgumentError(
            f"'source' does not compile for d={d}: {_first_error(str(error))}") from None
    return code


def device_values(f, points):
    """An integrand's values computed on the current device, by the code every integrand
    kernel runs (``kernels/integrand.h``): the reference the tests hold the NumPy
    integrands and the fused kernels against.

    Parameters
    ----------
    f : Integrand
        Any with ``kernel_code`` (every :mod:`clsamp.integrands` integrand).
    points : array_like
        (n, d) or (r, n, d).

    Returns
    -------
    ndarray
        float64 of shape (n,) or (r, n).

    Examples
    --------
    >>> from clsamp.integrands import keister
    >>> from clsamp.integrands.device import device_values
    >>> round(float(device_values(keister(2), [[0.5, 0.5]])[0]), 12)     # pi cos(0)
    3.14159265359
    """
    import pyopencl.array as cla
    x = np.asarray(points, dtype=np.float64)
    if x.ndim not in (2, 3) or x.shape[-1] != f.d:
        raise InvalidArgumentError(
            f"'points' must have shape (n, {f.d}) or (r, n, {f.d}), got {np.shape(points)}")
    runtime.require_fp64()
    kernel = runtime.kernel("integrands.cl", "integrand_values",
                            defines={"DIM": f.d, "INTEGRAND": f.kernel_code}, appendix=f.opencl_source)
    queue = runtime.queue()
    flat = np.ascontiguousarray(x.reshape(-1, f.d))
    out = np.empty(len(flat))
    params = cla.to_device(queue, np.ascontiguousarray(f.kernel_params(), dtype=np.float64))
    local = runtime.local_size()
    for lo in range(0, len(flat), CHUNK):
        part = flat[lo:lo + CHUNK]
        values = cla.empty(queue, (len(part),), np.float64)
        items = -(-len(part) // 4)
        kernel(queue, (-(-items // local) * local,), (local,), cla.to_device(queue, part).data,
               np.uint32(len(part)), params.data, values.data)
        out[lo:lo + len(part)] = values.get()
    return out.reshape(x.shape[:-1])
