"""The convergence sweep, driven from one place: :func:`convergence` checks its arguments,
makes the estimator of its integrand or family (:mod:`clsamp.estimates`), asks it for the
errors of every n (in-process, or in tasks of realization blocks on a Dask cluster,
:mod:`clsamp.parallel`) and returns the result (:mod:`clsamp.results`).
"""

import time

import numpy as np

from . import families, parallel, runtime
from .errors import InvalidArgumentError
from .estimates import FamilyErrors, IntegrandErrors, errors_block
from .experiments_ff import check_target
from .float_float import check_precision
from .integrands import Integrand, make_integrand
from .results import ConvergenceResult, FamilyResult
from .samplers import Sampler, make_quiet_sampler
from .samplers.base import CASES
from .validation import MAX_UINT32, check_bool, check_choice, check_int, check_seed

DEFAULT_MEMBERS = 256

__all__ = ["convergence", "prepare", "parse_ns", "sampler_rates"]


def convergence(sampler, integrand, ns, realizations=1000, homogenize=True, seed=0, progress=True,
                backend="opencl", members=None, client=None, checkpoint=None, precision=None):
    """MSE, bias^2 and variance of a sampler's integral estimates for every n in ``ns``;
    over a family of integrands, the spread of the MSE across its members.

    Parameters
    ----------
    sampler : Sampler or str
        A sampler object (any registered sampler, its own seed and parameters), or a
        name such as ``"jittered"`` or ``"sobol:owen"``, made with
        ``make_sampler(name, d=integrand.d, seed=seed, backend=backend)`` (without its own
        progress bar where it has one: the sweep shows its own).
    integrand : Integrand, Family or str
        An :mod:`clsamp.integrands` object or a name: ``"gaussian"``, ``"disk"``,
        ``"heaviside"``, ``"pmj_disk"``, ``"pmj_gaussian"``, ``"pmj_bilinear"``,
        ``"pmj_step"``, ``"pmj_triangle"`` (default parameters), or one written in OpenCL C
        (``clsamp.Integrand.from_opencl(source, d, integral=...)``); or a family of random
        integrands (:mod:`clsamp.families`): ``"random_gaussians"``,
        ``"random_heavisides"``, ``"random_disks"``, ``"random_boxes"``,
        ``"random_clipped_gaussians"`` (drawn from ``seed``, in the sampler's dimension),
        or a :class:`~clsamp.families.Family`.
    ns : sequence of int
        Sample counts (sorted; each must be one the sampler can make).
    realizations : int
        Independent estimates per n, at least 2.
    homogenize : bool
        Shift each realization by its own uniform toroidal vector (Stream.EXPERIMENT of
        ``seed``): unbiased estimates for any sampler.
    seed : int
        Seed of the shifts (and of the sampler when given by name).
    progress : bool
        Show a progress bar over ``ns`` when the sweep takes more than 2 s.
    backend : {"opencl", "numpy"}
        ``"numpy"``: the NumPy reference (points from ``sampler.sample``, evaluation and
        sums in NumPy; a sampler given by name uses its NumPy reference too).
    members : int, optional
        For a family given by name: how many members to draw (default 256).
    client : dask.distributed.Client, optional
        Run the sweep on a Dask cluster, in tasks of whole realization blocks
        (:mod:`clsamp.parallel`): the same errors, bit for bit, as in-process. ``seconds``
        are then the tasks' compute seconds per n, summed over workers.
    checkpoint : str or Path, optional
        A folder that keeps every finished block; calling again with the same sweep
        resumes from it (with or without a client).
    precision : {"double", "float-float"}, optional
        What the device computes the errors in; default ``"double"`` where the device has
        fp64, ``"float-float"`` where it has not (:mod:`clsamp.experiments_ff`: every
        error e_k within :func:`clsamp.experiments_ff.error_bound` of the fp64 one, about
        1e-12 of the integrand's scale; an integrand written in OpenCL C has no
        float-float form; the result's ``device`` ends in ``" (float-float)"``). The NumPy
        backend computes in float64 whatever it says.

    Returns
    -------
    ConvergenceResult, or FamilyResult for a family
        A :class:`~clsamp.results.FamilyResult` has ``.mse`` of shape (len(ns),
        members), the summaries ``mean``, ``median``, ``q90`` and ``max`` per n, and
        ``rate(statistic)`` with a bootstrap confidence interval.

    Raises
    ------
    InvalidArgumentError
        Empty or repeated ``ns``; an n the sampler cannot make (naming the sampler and
        the nearest valid n); ``realizations`` < 2; an unknown integrand (listing the
        known ones); dimensions that do not match; an unknown ``precision``.
    NoDeviceError
        ``precision="double"`` on a device without fp64.

    Notes
    -----
    ``seconds[k]`` is the wall time of the k-th n: generating every realization,
    shifting, evaluating, summing, and reading back the r errors. The kernels are
    built before the clock starts (a one-realization warm-up at the smallest n), except
    on Dask workers (``client``), where a worker's first block includes its builds.

    Examples
    --------
    >>> import clsamp
    >>> res = clsamp.convergence("jittered", "gaussian", [16, 64, 256], realizations=100,
    ...                          progress=False)
    >>> bool(res.mse[-1] < res.mse[0])
    True
    """
    check_bool(progress, "progress")
    from tqdm import tqdm
    estimator, label, values, r = prepare(sampler, integrand, ns, realizations, homogenize, seed,
                                          backend, members, precision)
    what = f"{r} realizations x {estimator.width} members" if estimator.width > 1 else f"{r} realizations"
    runtime.check_host_bytes(8 * r * estimator.width * len(values), f"the errors of {what} x {len(values)} n")
    desc = f"convergence {label} / {estimator.name}"
    if client is None:
        estimator.warm_up(values[0])
    if client is not None or checkpoint is not None:
        tasks, owners = sweep_tasks(estimator, values, r)
        blocks, spent = parallel.run(errors_block, tasks, client=client, checkpoint=checkpoint,
                                     progress=progress, desc=desc)
        errors = [np.concatenate([blocks[i] for i in mine]) for mine in owners]
        seconds = [float(np.sum(spent[mine])) for mine in owners]
    else:
        errors, seconds = [], []
        bar = tqdm(values, desc=desc, unit="n", disable=not progress, delay=2)
        for n in bar:
            t0 = time.perf_counter()
            errors.append(estimator.block(n, 0, r))
            seconds.append(time.perf_counter() - t0)
        bar.close()
    return _result(estimator, label, values, errors, seconds, r)


def prepare(sampler, integrand, ns, realizations=1000, homogenize=True, seed=0, backend="opencl",
            members=None, precision=None):
    """Check a :func:`convergence` request, without its work (a command line checks every
    sweep it will run before the first).

    Parameters
    ----------
    sampler, integrand, ns, realizations, homogenize, seed, backend, members, precision
        As :func:`convergence` takes them.

    Returns
    -------
    (estimator, str, list of int, int)
        The estimator, the sampler's label, the checked ns and realizations.

    Raises
    ------
    InvalidArgumentError
        What :func:`convergence` refuses before its work.
    """
    backend = check_choice(backend, "backend", ("opencl", "numpy"))
    seed = check_seed(seed)
    r = check_int(realizations, "realizations", minimum=2, maximum=MAX_UINT32)
    if not isinstance(homogenize, (bool, np.bool_)):
        raise InvalidArgumentError(f"'homogenize' must be True or False, got {homogenize!r}")
    precision = check_precision(precision, backend)
    estimator, label = _estimator(sampler, integrand, seed, backend, members, homogenize)
    estimator.precision = precision
    if precision == "float-float" and backend == "opencl":
        check_target(estimator.target)
    return estimator, label, _check_ns(ns, estimator.sampler, label), r


def _sampler(sampler, d, seed, backend):
    """(Sampler, label) from a sampler or its name (made in ``d`` dimensions)."""
    if isinstance(sampler, str):
        # the sweep shows its own bar: one made by name shows none of its own (bnot's)
        return make_quiet_sampler(sampler, d=d, seed=seed, backend=backend), sampler
    if isinstance(sampler, Sampler):
        return sampler, sampler.label
    raise InvalidArgumentError(
        f"'sampler' must be a Sampler or a sampler name such as 'jittered' or 'sobol:owen', "
        f"got {sampler!r}")


def _estimator(sampler, integrand, seed, backend, members, homogenize):
    """The estimator of the sweep and the sampler's label: the integrand or family made
    in the sampler's dimension (or the sampler in theirs, when given by name)."""
    if families.is_family(integrand):
        given = isinstance(integrand, families.Family)
        if given and members is not None and members != integrand.members:
            raise InvalidArgumentError(
                f"'members'={members!r} differs from the family's own {integrand.members} members")
        s, label = _sampler(sampler, integrand.d if given else 2, seed, backend)
        target = integrand if given else families.make_family(
            integrand, d=s.d, members=DEFAULT_MEMBERS if members is None else members, seed=seed)
        kind, make = f"family {target.name!r}", FamilyErrors
    else:
        if members is not None:
            raise InvalidArgumentError(
                f"'members' is for integrand families ({', '.join(families.family_names())}); "
                f"integrand {integrand!r} is one function")
        given = isinstance(integrand, Integrand)
        if isinstance(sampler, str):
            target = integrand if given else make_integrand(integrand)
            s, label = _sampler(sampler, target.d, seed, backend)
        else:
            s, label = _sampler(sampler, None, seed, backend)
            target = integrand if given else make_integrand(integrand, d=s.d)
        kind, make = repr(target.name), IntegrandErrors
        if target.integral is None:
            raise InvalidArgumentError(
                f"'integrand' {kind} has no exact integral, which the errors need: give "
                "Integrand.from_opencl(..., integral=...)")
    if target.d != s.d:
        raise InvalidArgumentError(
            f"'integrand' {kind} is {target.d}-dimensional but 'sampler' {label!r} makes "
            f"{s.d}-dimensional points")
    return make(s, target, homogenize, seed, backend), label


def sampler_rates(sampler):
    """The published rates of a sampler by case, as a result records them.

    Parameters
    ----------
    sampler : Sampler

    Returns
    -------
    dict
        ``{case: (exponent, source) or None}`` for each case of
        :meth:`Sampler.convergence_rate`.
    """
    out = {}
    for case in CASES:
        rate = sampler.convergence_rate(case)
        out[case] = None if rate is None else (rate.exponent, rate.source)
    return out


def _check_ns(ns, sampler, label):
    if isinstance(ns, (str, bytes)) or not hasattr(ns, "__iter__"):
        raise InvalidArgumentError(f"'ns' must be a sequence of sample counts, got {ns!r}")
    values = [check_int(n, "ns", minimum=1, maximum=sampler.max_n) for n in ns]
    if not values:
        raise InvalidArgumentError("'ns' must hold at least one sample count, got an empty sequence")
    values = sorted(values)
    if len(set(values)) != len(values):
        raise InvalidArgumentError(f"'ns' must not repeat a sample count, got {list(ns)!r}")
    for n in values:
        valid = sampler.valid_n(n)
        if valid != n:
            raise InvalidArgumentError(
                f"sampler {label!r} with d={sampler.d} cannot make n={n} points (in 'ns'); "
                f"the nearest valid n is {valid}")
    return values


def sweep_tasks(estimator, ns, r):
    """The tasks of a sweep, one block of realizations of one n each (:func:`errors_block`).

    Parameters
    ----------
    estimator : IntegrandErrors or FamilyErrors
    ns : sequence of int
    r : int
        Realizations per n.

    Returns
    -------
    tasks : list of tuple
        ``(estimator, n, lo, hi)``.
    owners : list of list of int
        Per n, the indices of its tasks, in order.
    """
    tasks, owners = [], []
    for n in ns:
        mine = []
        for lo, hi in parallel.block_ranges(r, n * estimator.cost):
            mine.append(len(tasks))
            tasks.append((estimator, n, lo, hi))
        owners.append(mine)
    return tasks, owners


def _result(estimator, label, values, errors, seconds, r):
    s, f, homogenize = estimator.sampler, estimator.target, estimator.homogenize
    edges = f.edges_when_shifted() if homogenize else f.edges
    traits = {"smooth": bool(f.smooth and (f.periodic or not homogenize)), "periodic": f.periodic,
              "edges": edges}
    device = str(runtime.current_device()) if estimator.backend == "opencl" else "numpy"
    if estimator.backend == "opencl" and estimator.precision == "float-float":
        device += " (float-float)"
    common = dict(ns=values, errors=errors, seconds=seconds, realizations=r, d=f.d,
                  homogenize=homogenize, seed=estimator.seed, backend=estimator.backend,
                  device=device, kind=s.label, traits=traits, rates=sampler_rates(s))
    if isinstance(estimator, FamilyErrors):
        return FamilyResult(sampler=label, family=f.name, integrals=f.integrals, members=f.members,
                            **common)
    return ConvergenceResult(sampler=label, integrand=f.name, integral=f.integral,
                             randomized=bool(s.randomized), **common)


# -- the command line's sample counts --------------------------------------------------
def parse_ns(text):
    """Sample counts from the command line's text.

    Parameters
    ----------
    text : str
        ``"16,64,256"``; ``"a..b"`` for a, 4a, 16a, ... <= b (powers of 4 from a: squares stay
        squares, as jittered needs); or ``"a..b:q"`` for ratio q (``"16..4096:2"``: powers
        of 2).

    Returns
    -------
    list of int

    Raises
    ------
    InvalidArgumentError
        Text of another form, or a range with a < 1, b < a or q < 2.

    Examples
    --------
    >>> from clsamp.sweep import parse_ns
    >>> parse_ns("16..1024"), parse_ns("16..64:2")
    ([16, 64, 256, 1024], [16, 32, 64])
    """
    text = str(text).strip()
    if ".." in text:
        span, _, ratio = text.partition(":")
        a, _, b = span.partition("..")
        try:
            a, b, q = int(a), int(b), int(ratio) if ratio else 4
        except ValueError:
            raise InvalidArgumentError(f"'ns' must look like 'a..b' or 'a..b:q', got {text!r}") from None
        if a < 1 or b < a or q < 2:
            raise InvalidArgumentError(
                f"'ns' range needs 1 <= a <= b and ratio q >= 2, got {text!r}")
        values = []
        while a <= b:
            values.append(a)
            a *= q
        return values
    try:
        return [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise InvalidArgumentError(f"'ns' must be integers like '16,64,256', got {text!r}") from None
