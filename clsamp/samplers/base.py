"""The sampler contract: one thin base class and the registry.

As in scipy.stats.qmc, the base validates once and subclasses write two small
methods: ``_device`` (the OpenCL kernel, returning a device array) and
``_reference`` (the NumPy reference, returning an ndarray). Both receive
``realizations`` as a ``range`` of realization indices and give points of shape
(len(realizations), n, d) for point indices ``[start, start + n)``; realization
``k`` never depends on how many were asked for, which lets the base split large
requests into chunks of realizations that fit the device.
"""

import difflib

import numpy as np

from .. import runtime
from ..errors import InvalidArgumentError
from ..validation import MAX_UINT32, check_choice, check_int, check_positive_int, check_seed

_REGISTRY = {}   # name -> class
_ALIASES = {}    # alias -> name

BACKENDS = ("opencl", "numpy")


def register(name, *aliases):
    """Class decorator: make a sampler available to :func:`make_sampler` as ``name``."""
    def wrap(cls):
        if name in _REGISTRY or name in _ALIASES:
            raise RuntimeError(f"sampler name {name!r} registered twice")
        cls.name = name
        _REGISTRY[name] = cls
        for alias in aliases:
            _ALIASES[alias] = name
        return cls
    return wrap


def sampler_names(aliases=False):
    """The registered sampler names (sorted); with ``aliases=True`` the aliases too."""
    names = set(_REGISTRY)
    if aliases:
        names |= set(_ALIASES)
    return sorted(names)


def make_sampler(name, d=2, seed=0, **params):
    """Create the sampler registered as ``name``.

    Parameters
    ----------
    name : str
        One of :func:`sampler_names` or an alias (``n_rooks``). ``"sobol:owen"`` is
        shorthand for ``name="sobol", randomize="owen"``.
    d : int
        Dimension of the points.
    seed : int
        Seed in [0, 2^64) of the counter-based generator; the same seed gives the
        same points on every device.
    **params
        Sampler-specific parameters (``randomize=``, ``radius=``, ``iterations=``,
        ``backend="numpy"`` for the NumPy reference, ...).

    Examples
    --------
    >>> import clsamp
    >>> pts = clsamp.make_sampler("random", d=3, seed=11).sample(1000)
    >>> pts.shape, pts.dtype
    ((1000, 3), dtype('float64'))
    """
    if not isinstance(name, str):
        raise InvalidArgumentError(f"'name' must be a sampler name (str), got {name!r}")
    base, _, variant = name.partition(":")
    if variant:
        if "randomize" in params:
            raise InvalidArgumentError(
                f"'name' {name!r} names a randomization and 'randomize' is given too")
        params["randomize"] = variant
    key = _ALIASES.get(base, base)
    cls = _REGISTRY.get(key)
    if cls is None:
        close = difflib.get_close_matches(base, sampler_names(aliases=True), n=1)
        hint = f" Did you mean {close[0]!r}?" if close else ""
        raise InvalidArgumentError(
            f"unknown sampler 'name'={base!r}.{hint} Known samplers: "
            + ", ".join(sampler_names(aliases=True)))
    return cls(d=d, seed=seed, **params)


class Sampler:
    """Base of every sampler.

    Subclasses set ``name`` (via :func:`register`), may set ``dimensions`` (the
    tuple of supported d, or None for any), ``max_n``, ``randomized`` and ``accepts_start``, and
    implement ``_reference`` and ``_device``. ``_check_n`` maps a requested n to
    itself or raises naming the nearest valid one.
    """

    name = None
    dimensions = None       # e.g. (1,) or (2,) or (2, 3); None = any d >= 1
    randomized = True       # whether the seed changes the points
    sequence = False        # whether `start` continues a sequence
    max_n = MAX_UINT32      # point indices are 32-bit counters
    needs_n = True          # False for samplers whose n follows from parameters (maximal Poisson disk)
    accepts_start = True    # False for point sets made whole (dart throwing, optimizers): start must be 0

    def __init__(self, d=2, seed=0, backend="opencl"):
        self.d = check_positive_int(d, "d")
        if self.dimensions is not None and self.d not in self.dimensions:
            allowed = ", ".join(str(x) for x in self.dimensions)
            raise InvalidArgumentError(
                f"sampler {self.name!r} supports 'd' in ({allowed}), got {self.d}")
        self.seed = check_seed(seed)
        self.backend = check_choice(backend, "backend", BACKENDS)

    def __repr__(self):
        return f"{type(self).__name__}(name={self.name!r}, d={self.d}, seed={self.seed})"

    # -- the public entry point ---------------------------------------------------
    def sample(self, n=None, realizations=None, start=0):
        """Generate points.

        Parameters
        ----------
        n : int
            Number of points per set.
        realizations : int, optional
            None for one set of shape (n, d); an integer r for r independent sets
            of shape (r, n, d) (realization k is the same whatever r is).
        start : int
            Index of the first point: ``sample(n, start=k)`` continues ``sample(k)``
            for sequences; for other samplers it offsets the counters.

        Returns
        -------
        ndarray of float64 in [0, 1)^d, shape (n, d) or (r, n, d)
        """
        n, r, start = self._check_call(n, realizations, start)
        if self.backend == "numpy":
            points = np.asarray(self._reference(n, range(r), start), dtype=np.float64)
        else:
            count = self.d * (n if n is not None else 1)
            parts = runtime.chunk_ranges(r, 8 * count)
            if len(parts) == 1:
                points = self._device(n, range(r), start).get()
            else:
                points = np.concatenate([self._device(n, range(lo, hi), start).get()
                                         for lo, hi in parts])
        return points[0] if realizations is None else points

    def sample_device(self, n=None, realizations=None, start=0):
        """Like :meth:`sample` with ``realizations`` required, but the (r, n, d) points
        stay on the device as a ``pyopencl.array.Array`` (for kernels that consume them)."""
        if realizations is None:
            realizations = 1
        n, r, start = self._check_call(n, realizations, start)
        if self.backend == "numpy":
            import pyopencl.array as cla
            return cla.to_device(runtime.queue(),
                                 np.ascontiguousarray(self._reference(n, range(r), start)))
        return self._device(n, range(r), start)

    def _check_call(self, n, realizations, start):
        if n is None and self.needs_n:
            raise InvalidArgumentError(f"'n' is required for sampler {self.name!r}")
        if n is not None:
            n = check_positive_int(n, "n", maximum=self.max_n)
            n = self._check_n(n)
        r = 1 if realizations is None else check_positive_int(realizations, "realizations",
                                                              maximum=MAX_UINT32)
        start = check_int(start, "start", minimum=0)
        if start != 0 and not self.accepts_start:
            raise InvalidArgumentError(
                f"'start' must be 0 for {self.name!r} (its points are a set, not a sequence), "
                f"got {start}")
        if n is not None and start + n - 1 > self.max_n:
            raise InvalidArgumentError(
                f"'start' + 'n' must stay within the {self.max_n + 1} point indices of "
                f"{self.name!r}, got start={start}, n={n}")
        return n, r, start

    # -- what subclasses write ----------------------------------------------------
    def valid_n(self, n):
        """The valid point count nearest to ``n`` (n itself when valid)."""
        return n

    def _check_n(self, n):
        valid = self.valid_n(n)
        if valid != n:
            raise InvalidArgumentError(
                f"sampler {self.name!r} with d={self.d} cannot make n={n} points; "
                f"the nearest valid n is {valid}")
        return n

    def _reference(self, n, realizations, start):
        """NumPy reference: ndarray (len(realizations), n, d); ``realizations`` is a range."""
        raise NotImplementedError

    def _device(self, n, realizations, start):
        """OpenCL: pyopencl Array (len(realizations), n, d) on ``runtime.queue()``."""
        raise NotImplementedError
