"""The command line's point sources: a sampler by name (``-n``, ``-d``, ``--seed``, its
``--param`` pairs) or a point file, for the commands that analyse points (``spectrum``,
``metrics``).
"""

from pathlib import Path

from .errors import InvalidArgumentError


def parse_params(items, own=(("d", "-d"), ("seed", "--seed"), ("backend", "--backend"))):
    """``--param key=value`` pairs as a dict, values parsed as int, float, bool or str.

    Parameters
    ----------
    items : list of str or None
        The ``--param`` values as given.
    own : sequence of (str, str)
        The keys the command sets itself, each with the option that sets it.

    Returns
    -------
    dict

    Raises
    ------
    InvalidArgumentError
        An item not of the form key=value, a key the command sets itself, or a key given
        twice.
    """
    params = {}
    for item in items or ():
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise InvalidArgumentError(f"'--param' must look like key=value, got {item!r}")
        if key in dict(own):
            raise InvalidArgumentError(f"'--param {item}': {key} is set by {dict(own)[key]}, not by --param")
        if key in params:
            raise InvalidArgumentError(f"'--param {item}': {key} is given twice")
        for convert in (int, float):
            try:
                params[key] = convert(value)
                break
            except ValueError:
                continue
        else:
            params[key] = {"true": True, "false": False, "none": None}.get(value.lower(), value)
    return params


def add_source(p, dimensions="dimension (sampler only; default 2)"):
    """Add the arguments of a command that reads points from a sampler or a point file.

    Parameters
    ----------
    p : argparse.ArgumentParser
    dimensions : str
        The help of ``-d``.
    """
    p.add_argument("source", help="sampler name (e.g. jittered, sobol:owen) or a point file (.npy, or text)")
    p.add_argument("-n", type=int, help="points per set (sampler only)")
    p.add_argument("-d", type=int, default=None, help=dimensions)
    p.add_argument("--realizations", type=int, default=None,
                   help="independent sets (sampler only; default one)")
    p.add_argument("--seed", type=int, default=None, help="sampler seed (sampler only; default 0)")
    p.add_argument("--param", action="append", metavar="KEY=VALUE",
                   help="sampler parameter, e.g. --param randomize=owen (repeatable)")


def points_from_source(args, check=None):
    """The points a command analyses: a sampler's (``-n``, ``-d``, ...) or a point file's.

    Parameters
    ----------
    args : argparse.Namespace
        With the arguments of :func:`add_source`.
    check : callable, optional
        ``check(d, n)``, run with the points' dimension and count before the sampler's work.

    Returns
    -------
    (ndarray, str)
        The points and a label: the sampler's name or the file's.

    Raises
    ------
    InvalidArgumentError
        No such sampler or file, sampler options with a file, ``-n`` missing for a
        sampler, or what ``check`` or the sampler refuse.
    """
    from . import files
    from .samplers import make_sampler, sampler_names
    source = Path(args.source)
    is_sampler = args.source.split(":")[0] in sampler_names(aliases=True)
    looks_like_path = bool(source.suffix) or "/" in args.source or "\\" in args.source
    if not is_sampler and (source.is_file() or looks_like_path):
        if not source.is_file():
            raise InvalidArgumentError(f"'source' {args.source!r}: no such file (and no sampler "
                                       "of that name)")
        given = [flag for flag, value in (("-n", args.n), ("-d", args.d),
                                          ("--realizations", args.realizations),
                                          ("--seed", args.seed), ("--param", args.param))
                 if value is not None]
        if given:
            raise InvalidArgumentError(
                f"{', '.join(repr(g) for g in given)} applies to a sampler source, not to the "
                f"point file {args.source!r}")
        points = files.load_points(source)
        if check:
            check(points.shape[-1], points.shape[-2])
        return points, source.name
    if args.n is None:
        raise InvalidArgumentError("'-n' is required when the source is a sampler name")
    # --backend is where the analysis runs; the sampler's own is a --param
    sampler = make_sampler(args.source, d=2 if args.d is None else args.d,
                           seed=0 if args.seed is None else args.seed,
                           **parse_params(args.param, (("d", "-d"), ("seed", "--seed"))))
    if check:
        check(sampler.d, args.n)
    return sampler.sample(args.n, realizations=args.realizations), args.source
