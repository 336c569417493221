"""The sampler contract: one thin base class, the registry, and what a call reports.

As in ``scipy.stats.qmc``, the base checks every argument once and subclasses write two
small methods over a ``range`` of realization indices:

* ``_reference(n, realizations, start)``: the NumPy reference, an ndarray
  (len(realizations), n, d);
* ``_device(n, realizations, start, out=None)``: the OpenCL path, a ``pyopencl.array.Array``
  of that shape (or an ndarray, for samplers whose work ends on the host). A sampler with
  ``host_output = True`` also accepts ``out``, a C-contiguous host array of that shape to
  write into: on CPU devices the kernel then writes straight into the array the caller
  gets, with no second copy.

Samplers that iterate or reject (``info`` set to a :class:`SampleInfo` subclass) return
``(points, info)`` from both methods, ``info`` covering those realizations; the base
merges the parts of a call split into chunks, so ``sample(..., return_info=True)`` always
describes every realization it returned.

Realization k never depends on how many realizations are asked for, or which: that is
what lets the base split requests into chunks that fit the device, and lets any caller
ask for realizations lo..hi alone (``realizations=range(lo, hi)``).
"""

import abc
import copy
import dataclasses
import difflib
import functools

import numpy as np

from .. import host_memory, runtime
from ..errors import InvalidArgumentError
from ..validation import (
    MAX_UINT32,
    check_bool,
    check_choice,
    check_image_size,
    check_int,
    check_positive_int,
    check_seed,
)

_REGISTRY = {}   # name -> class
_ALIASES = {}    # alias -> name

BACKENDS = ("opencl", "numpy")
MAX_D = 1 << 16        # dimensions any sampler makes at most (Sobol' has 21201)
CASES = ("best", "worst", "axis")   # the integrand cases of clsamp.theory
PILLEBOUE = "Pilleboue et al. 2015"


@dataclasses.dataclass(frozen=True)
class Rate:
    """A published convergence rate: MSE ~ N^exponent, and where it is published."""

    exponent: float
    source: str


def register(name, *aliases):
    """Class decorator: make a sampler available to :func:`make_sampler` as ``name``.

    Parameters
    ----------
    name : str
        The sampler's name, set as its ``name``.
    *aliases : str
        Other names that make it, set as its ``aliases``.

    Returns
    -------
    callable
        The decorator, which returns the class itself.

    Raises
    ------
    RuntimeError
        A name registered twice.
    """
    def wrap(cls):
        if name in _REGISTRY or name in _ALIASES:
            raise RuntimeError(f"sampler name {name!r} registered twice")
        cls.name = name
        cls.aliases = tuple(aliases)
        _REGISTRY[name] = cls
        for alias in aliases:
            _ALIASES[alias] = name
        return cls
    return wrap


def sampler_names(aliases=False):
    """The registered sampler names, sorted.

    Parameters
    ----------
    aliases : bool, optional
        Include the aliases.

    Returns
    -------
    list of str

    Examples
    --------
    >>> from clsamp.samplers import sampler_names
    >>> "sobol" in sampler_names()
    True
    """
    names = set(_REGISTRY)
    if aliases:
        names |= set(_ALIASES)
    return sorted(names)


def sampler_class(name):
    """The class registered under a name.

    Parameters
    ----------
    name : str
        A name or an alias, with a randomization after a colon if the sampler takes one
        (``"sobol:owen"`` names ``sobol``; the randomization is checked, not applied).

    Returns
    -------
    type
        A subclass of :class:`Sampler`.

    Raises
    ------
    InvalidArgumentError
        For an unknown name or randomization, with the nearest known one and the list of
        all.

    Examples
    --------
    >>> from clsamp.samplers import sampler_class
    >>> sampler_class("sobol:owen").name
    'sobol'
    >>> sampler_class("sobol:owne")     # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    clsamp.errors.InvalidArgumentError: unknown randomization 'owne' of sampler 'sobol'; did you mean ...
    """
    if not isinstance(name, str):
        raise InvalidArgumentError(f"'name' must be a sampler name (str), got {name!r}")
    base, colon, variant = name.partition(":")
    cls = _REGISTRY.get(_ALIASES.get(base, base))
    if cls is None:
        close = difflib.get_close_matches(base, sampler_names(aliases=True), n=1)
        hint = f"; did you mean {close[0] + colon + variant!r}?" if close else "."
        raise InvalidArgumentError(
            f"unknown sampler {base!r}{hint} Known samplers: " + ", ".join(sampler_names(aliases=True)))
    if colon:
        _check_randomization(cls, base, variant)
    return cls


def _check_randomization(cls, base, variant):
    """``variant`` (after the colon of ``base:variant``) must be one of ``cls``'s
    randomizations; the message suggests the nearest full name."""
    known = [r for r in cls.randomizations if r is not None]
    if variant in known:
        return
    if not known:
        raise InvalidArgumentError(
            f"sampler {base!r} takes no randomization, so {base + ':' + variant!r} names none")
    close = difflib.get_close_matches(variant, known, n=1)
    hint = f"; did you mean {base + ':' + close[0]!r}?" if close else "."
    raise InvalidArgumentError(
        f"unknown randomization {variant!r} of sampler {base!r}{hint} Its randomizations: "
        + ", ".join(f"{base}:{r}" for r in known))


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

    Returns
    -------
    Sampler

    Raises
    ------
    InvalidArgumentError
        An unknown name (with the nearest known one), or a parameter the sampler refuses.

    Examples
    --------
    >>> import clsamp
    >>> pts = clsamp.make_sampler("random", d=3, seed=11).sample(1000)
    >>> pts.shape, pts.dtype
    ((1000, 3), dtype('float64'))
    """
    cls = sampler_class(name)
    base, _, variant = name.partition(":")
    if variant:
        if "randomize" in params:
            raise InvalidArgumentError(
                f"'name' {name!r} names a randomization and 'randomize' is given too")
        params["randomize"] = variant
    accepted = _parameters(cls)
    unknown = sorted(set(params) - accepted) if accepted is not None else []
    if unknown:
        close = difflib.get_close_matches(unknown[0], sorted(accepted), n=1)
        hint = f" Did you mean {close[0]!r}?" if close else ""
        raise InvalidArgumentError(
            f"sampler {cls.name!r} has no parameter {unknown[0]!r}.{hint} Its parameters: "
            f"{', '.join(sorted(accepted - {'d', 'seed'}))}")
    return cls(d=d, seed=seed, **params)


@functools.cache
def _parameters(cls):
    """The keyword parameters ``cls(...)`` accepts, or None if it takes any (**kwargs);
    once per class (``inspect.signature`` costs tens of microseconds, and the optimizers
    make their start's sampler on every call)."""
    import inspect
    signature = inspect.signature(cls.__init__)
    if any(p.kind is p.VAR_KEYWORD for p in signature.parameters.values()):
        return None
    return frozenset(name for name in signature.parameters if name != "self")


def _merge_field(values, how):
    if how == "same":
        return values[0]
    if how == "sum":
        return type(values[0])(sum(values))
    if how == "max":
        return max(values)
    if how == "pad":      # rows of different lengths: each padded with its last value
        length = max(v.shape[1] for v in values)
        return np.concatenate([np.pad(v, ((0, 0), (0, length - v.shape[1])), mode="edge")
                               if v.shape[1] < length else v for v in values])
    return np.concatenate(values)


def _summary(value):
    """A field of an info as a line shows it: small arrays whole, others by shape and range."""
    if isinstance(value, np.ndarray) and value.size > 8:
        if value.size and np.issubdtype(value.dtype, np.number):
            return f"<{value.dtype} {value.shape}, {value.min():.6g}..{value.max():.6g}>"
        return f"<{value.dtype} {value.shape}>"
    return repr(value.tolist() if isinstance(value, np.ndarray) else value)


@dataclasses.dataclass(frozen=True, repr=False)
class SampleInfo:
    """What one call of a sampler that iterates or rejects did, realization by realization.

    Every array has the call's realizations on its first axis, in the order of
    ``realizations`` (the realization indices, also for a call with
    ``realizations=None``, which has one: realization 0). Subclasses add their fields;
    a field's ``merge`` metadata says how the parts of a call split into chunks combine
    ("concat" by default, "pad" for histories of different lengths, "sum", "max", or
    "same" for a value every part shares).
    """

    realizations: np.ndarray

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if "__repr__" not in cls.__dict__:      # before the dataclass decorator writes one
            cls.__repr__ = SampleInfo.__repr__

    def __repr__(self):
        fields = ", ".join(f"{f.name}={_summary(getattr(self, f.name))}"
                           for f in dataclasses.fields(self))
        return f"{type(self).__name__}({fields})"

    @classmethod
    def merge(cls, parts):
        """One info for the realizations of ``parts``, in order, each field merged as its ``merge``
        metadata says.

        Parameters
        ----------
        parts : sequence of SampleInfo
            The infos of the chunks of one call.

        Returns
        -------
        SampleInfo
        """
        if len(parts) == 1:
            return parts[0]
        values = {}
        for field in dataclasses.fields(cls):
            how = field.metadata.get("merge", "concat")
            values[field.name] = _merge_field([getattr(p, field.name) for p in parts], how)
        return cls(**values)


def info_field(how="concat", **kwargs):
    """A :class:`SampleInfo` field that says how its parts merge.

    Parameters
    ----------
    how : {"concat", "pad", "sum", "max", "same"}
        How the values of a call's chunks combine (see :class:`SampleInfo`).
    **kwargs
        For ``dataclasses.field`` (``default``, ...).

    Returns
    -------
    dataclasses.Field
    """
    return dataclasses.field(metadata={"merge": how}, **kwargs)


class Sampler(abc.ABC):
    """Base of every sampler.

    Subclasses set ``name`` and ``aliases`` (via :func:`register`) and the facts below,
    and write ``_reference`` and ``_device`` (module docstring). ``valid_n`` maps a
    requested n to the nearest one the sampler can make; ``convergence_rate`` gives the
    published rate for the parameters of the instance. The facts are class attributes, or
    properties where a parameter decides them; an instance never overwrites one.

    What a renderer may ask of any sampler is declared here too, with defaults:
    ``pixel_indexed`` and :meth:`for_image` (samplers that decorrelate the pixels of one
    image themselves), and :meth:`sample_sets` (sets that may differ in size).

    Attributes
    ----------
    dimensions : tuple of int or None
        The supported d (None: any d from 1 to ``max_d``).
    max_d : int
        The largest d (a table's length where one limits it); ``max_d_source`` names it.
    randomize : str or None
        The randomization of this instance (one of ``randomizations``).
    randomized : bool
        Whether the seed changes the points.
    sequence : bool
        Whether ``start`` continues a sequence (``sample(n, start=k)`` continues
        ``sample(k)``).
    accepts_start : bool
        False for point sets made whole (dart throwing, optimizers): ``start`` must be 0.
    needs_n : bool
        False where n may follow from the parameters (a maximal Poisson-disk set).
    max_n : int
        The largest n (point indices are 32-bit counters).
    expensive : bool
        Whether a point costs far more than a counter-based draw (optimizers, dart
        throwing): callers such as the renderer reuse a few sets of such samplers.
    randomizations : tuple
        The values ``randomize=`` accepts; ``(None,)`` for a sampler without it.
    info : type or None
        The :class:`SampleInfo` subclass ``sample(..., return_info=True)`` returns, for
        samplers that iterate or reject; None where there is nothing to report.
    host_output : bool
        Whether ``_device`` can write into a host array (zero copy on CPU devices).
    needs_fp64 : bool
        Whether the OpenCL path computes in double precision (distances, energies), so
        that a device without fp64 refuses it with :class:`NoDeviceError`; the others
        build their float64 coordinates by integer arithmetic there, the same bits.
    pixel_indexed : bool
        Whether the sampler decorrelates the pixels of an image itself, realization k
        being pixel k (row-major) of the image :meth:`for_image` names (``zsobol``): a
        renderer then uses one sampler for the whole image, unpadded. False: the
        renderer gives each pixel its own realizations and pads the dimensions.
    variable_size : bool
        Whether the sets may differ in size (a maximal Poisson-disk set): read them with
        :meth:`sample_sets`.
    """

    name = None
    aliases = ()
    dimensions = None
    max_d = MAX_D
    max_d_source = None
    randomize = None
    randomized = True
    sequence = False
    accepts_start = True
    needs_n = True
    max_n = MAX_UINT32
    expensive = False
    randomizations = (None,)
    info = None
    host_output = False
    needs_fp64 = False
    pixel_indexed = False
    variable_size = False
    rates = {}              # case -> Rate for d = 2 (see convergence_rate)

    def __init__(self, d=2, seed=0, backend="opencl"):
        d = check_positive_int(d, "d")
        if self.dimensions is not None and d not in self.dimensions:
            allowed = ", ".join(str(x) for x in self.dimensions)
            raise InvalidArgumentError(
                f"sampler {self.name!r} supports 'd' in ({allowed}), got {d}")
        if d > self.max_d:
            source = f" ({self.max_d_source})" if self.max_d_source else ""
            raise InvalidArgumentError(
                f"'d' must be at most {self.max_d} for {self.name}{source}, got {d}")
        self.d = d
        self.seed = check_seed(seed)
        self.backend = check_choice(backend, "backend", BACKENDS)

    def __repr__(self):
        return f"{type(self).__name__}(name={self.name!r}, d={self.d}, seed={self.seed})"

    # -- facts -----------------------------------------------------------------------
    @property
    def label(self):
        """The sampler's name with its randomization, as :func:`make_sampler` reads it
        (``"sobol:owen"``, ``"jittered"``)."""
        return f"{self.name}:{self.randomize}" if self.randomize else str(self.name)

    def convergence_rate(self, case):
        """The published rate of the MSE of this sampler's estimates, or None.

        Parameters
        ----------
        case : {"best", "worst", "axis"}
            The integrand as the estimator sees it (:func:`clsamp.theory.case_of`): smooth,
            discontinuous along a curve, or discontinuous only along the axes.

        Returns
        -------
        Rate or None
            The exponent a of MSE ~ N^a and its source, for this instance's parameters
            and dimension; None where nothing is published.
        """
        return self.rates.get(case) if self.d == 2 else None

    def with_seed(self, seed):
        """A copy of this sampler with another seed, every other parameter kept.

        Parameters
        ----------
        seed : int
            In [0, 2^64).

        Returns
        -------
        Sampler
            Of this sampler's class.

        Raises
        ------
        InvalidArgumentError
            A seed out of range or not an integer.
        """
        other = copy.copy(self)
        other.seed = check_seed(seed)
        return other

    def for_image(self, width, height):
        """This sampler for an image of ``width`` x ``height`` pixels (what a renderer asks).

        A pixel-indexed sampler (``pixel_indexed``) returns a copy whose realization k is
        pixel k, row-major, of that image; any other sampler does not depend on the image
        and returns itself.

        Parameters
        ----------
        width, height : int
            The image's size in pixels.

        Returns
        -------
        Sampler
        """
        check_image_size((width, height), "(width, height)")
        return self

    def sample_sets(self, realizations, n=None, return_info=False):
        """Sets as a list of (n_k, d) arrays, one per realization: the form for samplers
        whose sets differ in size (``variable_size``; a maximal Poisson-disk set), and a
        list of the rows of :meth:`sample` for every other.

        Parameters
        ----------
        realizations : int or range
            r for the realizations 0..r-1, or a range for exactly those; set k does not
            depend on which others are asked for.
        n : int, optional
            Points per set, where the sampler needs it (as :meth:`sample`).
        return_info : bool
            Also return the call's info (samplers that iterate or reject).

        Returns
        -------
        sets : list of ndarray
        info : SampleInfo
            Only with ``return_info``.

        Examples
        --------
        >>> import clsamp
        >>> sets = clsamp.make_sampler("jittered", seed=1).sample_sets(3, n=16)
        >>> len(sets), sets[0].shape
        (3, (16, 2))
        """
        if realizations is None:
            raise InvalidArgumentError("'realizations' must be an int or a range for sample_sets")
        result = self.sample(n, realizations=realizations, return_info=return_info)
        points, info = result if return_info else (result, None)
        sets = list(points)
        return (sets, info) if return_info else sets

    # -- the public entry points -------------------------------------------------------
    def sample(self, n=None, realizations=None, start=0, return_info=False):
        """Generate points.

        Parameters
        ----------
        n : int
            Number of points per set (some samplers derive it from their parameters
            when it is left out).
        realizations : None, int or range
            None for one set of shape (n, d) (realization 0); an integer r for the
            realizations 0..r-1, shape (r, n, d); a range for exactly those
            realizations, shape (len(range), n, d), equal to the same rows of a larger
            call. Realization k is the same whatever else is asked for.
        start : int
            Index of the first point: ``sample(n, start=k)`` continues ``sample(k)``
            for sequences; for other samplers it offsets the counters of the jitter.
        return_info : bool
            Also return what the call did (samplers that iterate or reject: ``info`` of
            the class; the others raise).

        Returns
        -------
        points : ndarray of float64 in [0, 1)^d
        info : SampleInfo
            Only with ``return_info``.

        Raises
        ------
        InvalidArgumentError
            An n the sampler cannot make (naming the nearest valid one), a bad
            ``realizations`` or ``start``, or ``return_info`` where there is no info.
        """
        n, runs, single, start = self._check_call(n, realizations, start, return_info)
        self._check_size(n, runs, device=False)
        self._warn_weaker(n, start)
        points, infos = self._generate(n, runs, start)
        if single:
            points = points[0]
        if not return_info:
            return points
        return points, self.info.merge(infos)

    def sample_device(self, n=None, realizations=None, start=0, return_info=False):
        """Like :meth:`sample`, but the points stay on the current device.

        Parameters
        ----------
        n, realizations, start, return_info
            As :meth:`sample` takes them.

        Returns
        -------
        points : pyopencl.array.Array of float64, shape (n, d) or (r, n, d)
            On the current device's queue, for kernels that consume them (spectra,
            integrands, metrics), with no copy through the host.
        info : SampleInfo
            Only with ``return_info``.

        Raises
        ------
        InvalidArgumentError
            As :meth:`sample` raises it, or for an output larger than the device's memory.
        """
        n, runs, single, start = self._check_call(n, realizations, start, return_info)
        self._check_size(n, runs, device=True)
        self._warn_weaker(n, start)
        parts, infos = [], []
        for run in runs:
            for chunk in self._chunks(run, n):
                points, info = self._split(self._make(n, chunk, start))
                parts.append(runtime.to_device(points))
                infos.append(info)
        points = runtime.concatenate(parts)
        if single:
            points = points.reshape(points.shape[1:])
        if not return_info:
            return points
        return points, self.info.merge(infos)

    # -- what the entry points share --------------------------------------------------
    @property
    def splits_along_n(self):
        """Whether a set can be made in pieces of consecutive points (``start`` continues a
        sequence): how a set larger than one device buffer is streamed."""
        return self.sequence and self.accepts_start

    def _check_size(self, n, runs, device):
        """Refuse, before any work, an output that cannot fit: on the host (``sample``) or
        in the device's memory (``sample_device``), or one set larger than the device's
        largest buffer where the sampler cannot stream it in pieces."""
        if n is None:
            return
        total = sum(len(run) for run in runs)
        need = total * (n * self.d * 8 + self._history_bytes())
        what = f"{total} x {n} points in {self.d}-D of {self.label!r}"
        if device:
            room = runtime.current_device().global_memory
            if need > room:
                raise InvalidArgumentError(
                    f"sample_device of {what} needs {runtime.gib(need)} of device memory; the device "
                    f"has {runtime.gib(room)}. Ask for fewer realizations or points at a time")
        else:
            work = self._work_bytes(n)
            parts = ["its output"] + ["each set's history"] * bool(self._history_bytes()) \
                + ["one set's working memory"] * bool(work)
            held = ", ".join(parts[:-1]) + " and " + parts[-1] if len(parts) > 1 else "its output alone"
            runtime.check_host_bytes(need + work, f"sample of {what} ({held})")
        if self.backend == "numpy":
            return
        one = n * self.d * 8
        largest = runtime.current_device().max_allocation
        if one > largest and (device or not self.splits_along_n):
            hint = ("the points stay on the device in one buffer" if device else
                    f"{self.label!r} makes a set whole, not in pieces")
            raise InvalidArgumentError(
                f"one set of {n} points in {self.d}-D of {self.label!r} needs {runtime.gib(one)} in "
                f"one device buffer, above the device's largest, {runtime.gib(largest)} ({hint}); "
                "use a smaller n, or backend='numpy'")

    def _work_bytes(self, n):
        """The host memory one set of n points takes while it is made, besides the output:
        0 for samplers that write their output and little else; the optimizers' estimates
        come from peak RSS measured at 2^16 to 2^20 points (docs/performance.md, "Working
        memory refused before the work")."""
        return 0

    def _history_bytes(self):
        """The host bytes each set's info keeps besides its points: an optimizer's history,
        8 bytes an iteration (its cap, ``iterations``); 0 for the other samplers."""
        return 8 * getattr(self, "iterations", 0) if self.info is not None else 0

    def _warn_weaker(self, n, start):
        """Warn (UserWarning) where a legal request gives a weaker set than the sampler
        promises; nothing by default."""
        return None

    def _pieces(self, n):
        """[(offset, count)] of a set made in pieces of consecutive points, each fitting the
        device's work budget (one piece unless the set is larger)."""
        if self.backend == "numpy" or not self.splits_along_n:
            return [(0, n)]
        step = max(1, runtime.work_budget() // (8 * self.d))
        return [(lo, min(n, lo + step) - lo) for lo in range(0, n, step)]

    def _chunks(self, run, n):
        """``run`` in consecutive pieces whose output fits the device (the runtime's rule);
        the NumPy reference takes it whole."""
        if self.backend == "numpy":
            return [run]
        per = 8 * self.d * (n if n is not None else 1)
        return [range(run.start + lo, run.start + hi)
                for lo, hi in runtime.chunk_ranges(len(run), per)]

    def _split(self, result):
        return result if self.info is not None else (result, None)

    def _make(self, n, realizations, start, out=None):
        if self.backend == "numpy":
            return self._reference(n, realizations, start)
        if out is not None:
            return self._device(n, realizations, start, out=out)
        return self._device(n, realizations, start)

    def _generate(self, n, runs, start):
        """Host points (total, n, d) of every run, and the infos of their chunks."""
        total = sum(len(run) for run in runs)
        host = (self.host_output and self.backend == "opencl" and n is not None
                and runtime.shape().host_output)
        out = host_memory.host_empty((total, n, self.d)) if n is not None else None
        infos, row, single_set = [], 0, None
        pieces = self._pieces(n) if n is not None else [(0, None)]
        if len(pieces) > 1:                     # sets larger than a device buffer, in pieces
            for run in runs:
                for k in run:
                    for offset, count in pieces:
                        points = self._make(count, range(k, k + 1), start + offset)
                        out[row, offset:offset + count] = runtime.to_host(self._split(points)[0])[0]
                    row += 1
            return out, [None]
        for run in runs:
            for chunk in self._chunks(run, n):
                target = out[row:row + len(chunk)] if out is not None else None
                result = self._make(n, chunk, start, out=target if host else None)
                points, info = self._split(result)
                infos.append(info)
                if out is None:                       # a maximal set: n follows from the run
                    single_set = runtime.to_host(points)
                elif not (host and points is target):
                    runtime.to_host(points, into=target)
                row += len(chunk)
        return (out if out is not None else single_set), infos

    def _default_n(self):
        """n when the caller leaves it out (None: n is required)."""
        return None

    def _check_call(self, n, realizations, start, return_info=False):
        if check_bool(return_info, "return_info") and self.info is None:
            raise InvalidArgumentError(
                f"'return_info': sampler {self.name!r} does not iterate or reject, so it has no "
                "info to return")
        if n is None:
            n = self._default_n()
        if n is None and self.needs_n:
            raise InvalidArgumentError(f"'n' is required for sampler {self.name!r}")
        if n is not None:
            n = check_positive_int(n, "n", maximum=self.max_n)
            n = self._check_n(n)
        runs, single = _check_realizations(realizations)
        start = check_int(start, "start", minimum=0)
        if start != 0 and not self.accepts_start:
            raise InvalidArgumentError(
                f"'start' must be 0 for {self.name!r} (its points are a set, not a sequence), "
                f"got {start}")
        if n is not None and start + n - 1 > self._last_index():
            raise InvalidArgumentError(
                f"'start' + 'n' must stay within the {self._last_index() + 1} point indices of "
                f"{self.label!r}, got start={start}, n={n}")
        return n, runs, single, start

    def _last_index(self):
        """The largest index a point may have (``start + n - 1``): ``max_n`` unless the
        sampler's parameters say otherwise (a net's b^m points, 64-bit indices)."""
        return self.max_n

    # -- what subclasses write ----------------------------------------------------------
    def valid_n(self, n):
        """The valid point count nearest to ``n``.

        A sampler that makes only some counts (k^d strata, powers of two) says here which;
        :meth:`sample` refuses any other n, naming this one. The base accepts every n.

        Parameters
        ----------
        n : int
            A requested number of points.

        Returns
        -------
        int
            ``n`` itself where it is valid.
        """
        return n

    def _check_n(self, n):
        valid = self.valid_n(n)
        if valid != n:
            raise InvalidArgumentError(
                f"sampler {self.name!r} with d={self.d} cannot make n={n} points; "
                f"the nearest valid n is {valid}")
        return n

    @abc.abstractmethod
    def _reference(self, n, realizations, start):
        """NumPy reference: ndarray (len(realizations), n, d); ``realizations`` is a range."""

    @abc.abstractmethod
    def _device(self, n, realizations, start, out=None):
        """OpenCL: pyopencl Array (len(realizations), n, d) on ``runtime.queue()``."""


def _check_realizations(realizations):
    """The runs of consecutive realization indices asked for, and whether one (n, d) set is."""
    if realizations is None:
        return [range(1)], True
    if isinstance(realizations, range):
        if len(realizations) == 0:
            raise InvalidArgumentError(f"'realizations' must not be empty, got {realizations!r}")
        if min(realizations) < 0 or max(realizations) > MAX_UINT32:
            raise InvalidArgumentError(
                f"'realizations' must lie in [0, {MAX_UINT32}] (32-bit counters), got {realizations!r}")
        if realizations.step == 1:
            return [realizations], False
        return [range(k, k + 1) for k in realizations], False
    r = check_positive_int(realizations, "realizations", maximum=MAX_UINT32)
    return [range(r)], False

