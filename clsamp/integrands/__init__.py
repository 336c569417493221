"""Test integrands with exact integrals, for variance and convergence experiments.

Two families:

* On the unit torus (periodic, so a random toroidal shift -- homogenization -- creates
  no new edge): :class:`Gaussian` (wrapped; smooth, the best case of Pilleboue et al.
  2015) and :class:`Disk` (wrapping; discontinuous along a curve, the worst case).
* On the unit square (not periodic): :class:`Heaviside` (a straight edge) and the set
  used by Christensen, Kensler and Kilpatrick (2018) to compare progressive
  multi-jittered sequences with other samplers (:func:`pmj_set`): a quarter disk
  x^2 + y^2 < 2/pi, the Gaussian exp(-x^2 - y^2), the bilinear xy, the step x < 1/pi
  and the triangle y > x. A toroidal shift keeps their estimators unbiased but makes
  the square's sides edges of the shifted integrand; use ``homogenize=False`` in
  :func:`clsamp.convergence` to compare with that paper.

Each integrand is a callable on points of shape (n, d) or (r, n, d) (NumPy, the
reference), has its exact ``.integral`` over [0, 1)^d, and an OpenCL evaluation in
``kernels/integrands.cl`` selected by ``.kernel_code`` with its parameters in
``.kernel_params()``. ``.smooth``, ``.periodic`` and ``.edges`` classify it for
:mod:`clsamp.theory`.

References
----------
.. [1] A. Pilleboue, G. Singh, D. Coeurjolly, M. Kazhdan, V. Ostromoukhov, "Variance
   analysis for Monte Carlo integration", ACM TOG 34(4), 2015.
.. [2] P. Christensen, A. Kensler, C. Kilpatrick, "Progressive multi-jittered sample
   sequences", Computer Graphics Forum 37(4), 2018.
"""

import difflib

from ..errors import InvalidArgumentError
from .base import (  # noqa: F401  (the package's names)
    _PMJ,
    DISK,
    GAUSSIAN,
    GENZ,
    HEAVISIDE,
    KEISTER,
    PMJ_BILINEAR,
    PMJ_DISK,
    PMJ_GAUSSIAN,
    PMJ_STEP,
    PMJ_TRIANGLE,
    Disk,
    Gaussian,
    Heaviside,
    Integrand,
    OpenCLIntegrand,
    PMJBilinear,
    PMJDisk,
    PMJGaussian,
    PMJStep,
    PMJTriangle,
    halfspace_volume,
)
from .qmc import GENZ_DIFFICULTY, GENZ_KINDS, MAX_GENZ_D, Genz, Keister, genz, keister  # noqa: F401

_FACTORIES = {
    "gaussian": Gaussian,
    "disk": Disk,
    "heaviside": Heaviside,
    "pmj_disk": PMJDisk,
    "pmj_gaussian": PMJGaussian,
    "pmj_bilinear": PMJBilinear,
    "pmj_step": PMJStep,
    "pmj_triangle": PMJTriangle,
}


GENZ_NAMES = {f"genz_{kind}": kind for kind in GENZ_KINDS}
_BY_D = {"keister": Keister}      # made in d dimensions by name


def integrand_names():
    """The names :func:`make_integrand` knows.

    Returns
    -------
    list of str
    """
    return list(_FACTORIES) + list(GENZ_NAMES) + list(_BY_D)


def pmj_set():
    """The five integrands of Christensen et al. (2018), in their order.

    Returns
    -------
    list of Integrand
        The quarter disk, the Gaussian, the bilinear, the step and the triangle.
    """
    return [PMJDisk(), PMJGaussian(), PMJBilinear(), PMJStep(), PMJTriangle()]


def make_integrand(spec, d=None):
    """An :class:`Integrand` from a name (default parameters) or an integrand itself.

    Parameters
    ----------
    spec : str or Integrand
        One of :func:`integrand_names`.
    d : int, optional
        For ``"gaussian"``, ``"disk"`` and ``"heaviside"`` by name: the dimension (the
        default centre or normal is repeated/cut to d; 2 when None); for the Genz
        families (``"genz_oscillatory"``, ...): :func:`genz` of seed 0 in d dimensions.

    Returns
    -------
    Integrand
        ``spec`` itself where it is one.

    Raises
    ------
    InvalidArgumentError
        An unknown name (the message suggests the nearest), or a ``d`` that a 2-D
        integrand cannot take.

    Examples
    --------
    >>> from clsamp.integrands import make_integrand
    >>> f = make_integrand("pmj_bilinear")
    >>> f.integral, float(f([[0.5, 0.5]])[0])
    (0.25, 0.25)
    """
    if isinstance(spec, Integrand):
        return spec
    if not isinstance(spec, str):
        raise InvalidArgumentError(
            f"'integrand' must be an Integrand or one of {', '.join(_FACTORIES)}; got {spec!r}")
    key = spec.strip().lower()
    if key in GENZ_NAMES:
        return genz(GENZ_NAMES[key], 2 if d is None else d)
    if key in _BY_D:
        return _BY_D[key](2 if d is None else d)
    factory = _FACTORIES.get(key)
    if factory is None:
        close = difflib.get_close_matches(spec, integrand_names(), n=1)
        hint = f" Did you mean {close[0]!r}?" if close else ""
        raise InvalidArgumentError(
            f"unknown 'integrand' {spec!r}.{hint} Known integrands: {', '.join(integrand_names())}")
    if d is None or d == 2 or issubclass(factory, _PMJ):
        made = factory()
        if d is not None and made.d != d:
            raise InvalidArgumentError(f"integrand {spec!r} is {made.d}-dimensional, got 'd'={d}")
        return made
    default = {"gaussian": (0.4142, 0.7320), "disk": (0.7311, 0.2243),
               "heaviside": (0.9553, 0.2955)}[factory.name]
    first = "center" if factory is not Heaviside else "normal"
    values = [default[j % 2] * (1 + 0.01 * (j // 2)) for j in range(d)]
    return factory(**{first: values})
