"""Integrands written in OpenCL C by their user: :meth:`clsamp.Integrand.from_opencl`.

The user's function is appended to the integrand kernels' source (``kernels/integrand.h``
declares it as ``clsamp_user_integrand``), so the same code runs wherever clsamp evaluates
an integrand on the device: at given points (:meth:`OpenCLIntegrand.__call__`), at a
sampler's points (:func:`clsamp.convergence`, ``integrate(method="replications")`` with a
sampler object) and at points made inside the kernel that evaluates it
(:mod:`clsamp.fused`: ``integrate`` with a Sobol' sampler by name or
``method="digital" | "lattice"``), where no point is ever stored.
"""

import math
import re

import numpy as np

from .. import runtime
from ..errors import BuildError, InvalidArgumentError
from ..validation import check_positive_int, plain
from .base import Integrand, _points

USER_SOURCE = 15        # INTEGRAND in kernels/integrand.h
MAX_D = 1024            # a point is a private array of d doubles in the kernel
CHUNK = 2**20           # points a launch of integrand_values evaluates at most

_FUNCTION = re.compile(
    r"\bdouble\s+([A-Za-z_]\w*)\s*\(\s*(?:__private\s+)?const\s+double\s*\*\s*[A-Za-z_]\w*\s*\)\s*\{")
_RETURN = re.compile(r"\breturn\b")
_AT_SOURCE = re.compile(r"^(?:error:\s*(source:\d+:\d+:)|(source:\d+:\d+:)\s*error:)\s*(.*)$", re.M)
_ERROR = re.compile(r"^.*\berror\b.*$", re.M | re.I)

__all__ = ["OpenCLIntegrand", "assemble"]


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
    return f'double clsamp_user_integrand(const double *x)\n{{\n    return (\n#line 1 "source"\n{source}\n    );\n}}'


def _first_error(message):
    """The compiler's first error line in a build failure's message (else its first line)."""
    at = _AT_SOURCE.search(message)
    if at:                  # PoCL writes "error: source:2:15: ...", clang "source:2:15: error: ..."
        return f"{at.group(1) or at.group(2)} error: {' '.join(at.group(3).split())}"
    found = _ERROR.search(message.split("\n", 1)[1] if "\n" in message else message)
    line = found.group(0) if found else message.splitlines()[0]
    return " ".join(line.split())


class OpenCLIntegrand(Integrand):
    """An integrand given as OpenCL C: made by :meth:`clsamp.Integrand.from_opencl`.

    Parameters
    ----------
    source : str
        See :func:`assemble`. The code may call OpenCL's math built-ins (in double) and
        ``to_normal(u)``, the standard normal quantile of :func:`clsamp.transforms.to_normal`
        (``kernels/normal.h``).
    d : int
        The dimension, 1 to 1024.
    integral : float, optional
        The exact integral, where known: :func:`clsamp.convergence` needs it (the errors
        are estimates minus it); :func:`clsamp.integrate` does not.
    name : str
        For reports.

    Attributes
    ----------
    source : str
        The code as given.
    opencl_source : str
        The code appended to the integrand kernels (:func:`assemble`).

    Raises
    ------
    InvalidArgumentError
        ``source`` not a non-empty string, or not compiling (the message holds the
        compiler's first error, its line numbered within ``source``); a bad ``d``,
        ``integral`` or ``name``.
    NoDeviceError
        The current device has no fp64.
    """

    kernel_code = USER_SOURCE

    def __init__(self, source, d, integral=None, name="opencl"):
        if not isinstance(source, str) or not source.strip():
            raise InvalidArgumentError(
                f"'source' must be OpenCL C (an expression in x[0] .. x[d-1], a function body "
                f"or a function double f(const double *x)), got {plain(source)}")
        super().__init__(check_positive_int(d, "d", maximum=MAX_D))
        if integral is not None:
            try:
                integral = float(integral)
            except (TypeError, ValueError):
                integral = math.nan
            if not math.isfinite(integral):
                raise InvalidArgumentError(f"'integral' must be a finite real number or None")
        if not isinstance(name, str) or not name:
            raise InvalidArgumentError(f"'name' must be a non-empty string, got {plain(name)}")
        self.source, self.integral, self.name = source, integral, name
        self.opencl_source = assemble(source)
        self._kernel = self._build()

    def _build(self):
        runtime.require_fp64()
        try:
            return runtime.kernel("integrands.cl", "integrand_values",
                                  defines={"DIM": self.d, "INTEGRAND": USER_SOURCE},
                                  appendix=self.opencl_source)
        except BuildError as error:
            raise InvalidArgumentError(
                f"'source' does not compile for d={self.d}: {_first_error(str(error))}") from None

    def _describe(self):
        text = " ".join(self.source.split())
        return f"d={self.d}, source={text if len(text) <= 60 else text[:57] + '...'!r}"

    def describe(self):
        """A one-line description (for reports).

        Returns
        -------
        str
        """
        known = "unknown" if self.integral is None else repr(float(self.integral))
        return f"{self.name}: {self._describe()}, integral {known}"

    def __call__(self, points):
        """Evaluate at points on the current device (the same code as every kernel runs).

        Parameters
        ----------
        points : array_like
            (n, d) or (r, n, d) points.

        Returns
        -------
        ndarray
            float64 of shape (n,) or (r, n).

        Raises
        ------
        InvalidArgumentError
            Points of the wrong shape.
        """
        return self._evaluate(_points(points, self.d))

    def _evaluate(self, x):
        import pyopencl.array as cla
        queue = runtime.queue()
        flat = np.ascontiguousarray(x.reshape(-1, self.d))
        out = np.empty(len(flat))
        params = runtime.table(("opencl integrand params",), lambda: np.zeros(1), dtype=np.float64)
        local = runtime.local_size()
        for lo in range(0, len(flat), CHUNK):
            part = flat[lo:lo + CHUNK]
            points = cla.to_device(queue, part)
            values = cla.empty(queue, (len(part),), np.float64)
            items = -(-len(part) // 4)
            self._kernel(queue, (-(-items // local) * local,), (local,), points.data,
                         np.uint32(len(part)), params.data, values.data)
            out[lo:lo + len(part)] = values.get()
        return out.reshape(x.shape[:-1])
