"""Hostile input to the public entry points (hypothesis): every call gives a result or an
InvalidArgumentError (a ValueError) that names the problem, never another exception.

The example counts are small enough for CI (the "ci" profile of tests/conftest.py);
``pytest tests/test_fuzz.py --hypothesis-profile=long`` tries 50 times as many before a
release.
"""

import warnings

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import clsamp
from clsamp import families, files
from clsamp.errors import InvalidArgumentError

ALLOWED = (InvalidArgumentError,)

hostile = st.one_of(
    st.none(), st.booleans(), st.integers(-2**40, 2**40), st.sampled_from([0, 1, 2, 3, 4, 16, -1]),
    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=6),
    st.lists(st.integers(-3, 5), max_size=3), st.just(2**64), st.just(1.5),
)

small = st.one_of(st.integers(-4, 300), hostile)


@st.composite
def hostile_points(draw):
    """Arrays of odd shapes, dtypes and values: NaN, inf, negatives, >= 1, empty."""
    ndim = draw(st.integers(0, 4))
    shape = tuple(draw(st.lists(st.integers(0, 9), min_size=ndim, max_size=ndim)))
    kind = draw(st.sampled_from(["unit", "wild", "int", "bool", "complex"]))
    size = int(np.prod(shape)) if shape else 1
    if kind == "unit":
        values = np.asarray(draw(st.lists(st.floats(0, 1, exclude_max=True), min_size=size, max_size=size)))
    elif kind == "wild":
        values = np.asarray(draw(st.lists(st.floats(allow_nan=True, allow_infinity=True, width=64),
                                          min_size=size, max_size=size)))
    elif kind == "int":
        values = np.asarray(draw(st.lists(st.integers(-5, 5), min_size=size, max_size=size)))
    elif kind == "bool":
        values = np.asarray(draw(st.lists(st.booleans(), min_size=size, max_size=size)))
    else:
        values = np.asarray([complex(v, 1) for v in draw(st.lists(st.floats(0, 1), min_size=size,
                                                                  max_size=size))])
    return values.reshape(shape) if shape else (values[0] if values.size else values)


def _call(fn, *args, **kwargs):
    """fn(...), an allowed refusal, or the failure of the test."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            return fn(*args, **kwargs)
        except ALLOWED as error:
            assert str(error), "a refusal must say why"
            return error


@given(name=st.sampled_from(clsamp.sampler_names() + ["sobol:owen", "halton:owen", "nope"]),
       d=small, seed=small, n=small, realizations=small, start=small)
def test_samplers(name, d, seed, n, realizations, start):
    made = _call(clsamp.make_sampler, name, d=d, seed=seed)
    if isinstance(made, Exception):
        return
    if made.expensive and isinstance(n, int) and n > 64:
        n = 64
    if isinstance(realizations, int) and realizations > 4:
        realizations = 4
    out = _call(made.sample, n, realizations=realizations, start=start)
    if isinstance(out, np.ndarray) and out.size:
        assert np.all((out >= 0) & (out < 1))


@given(name=st.sampled_from(clsamp.sampler_names()), key=st.sampled_from(
    ["strata", "rho", "radius", "iterations", "points_per_site", "randomize", "groups", "density",
     "relax", "bases", "bogus"]), value=hostile)
def test_sampler_parameters(name, key, value):
    made = _call(clsamp.make_sampler, name, d=2, seed=1, **{key: value})
    if not isinstance(made, Exception):
        _call(made.sample, made.valid_n(16))


@given(points=hostile_points(), resolution=small, method=st.sampled_from(["auto", "direct", "fast", "x"]),
       tol=st.one_of(st.none(), st.floats(allow_nan=True)))
def test_power_spectrum(points, resolution, method, tol):
    if isinstance(resolution, int) and resolution > 64:
        resolution = 64
    _call(clsamp.power_spectrum, points, resolution=resolution, method=method, tol=tol, progress=False)


@given(points=hostile_points(), method=st.sampled_from(["CD", "WD", "MD", "L2-star", "symmetric", "L2", "?"]))
def test_discrepancies(points, method):
    _call(clsamp.discrepancy, points, method)
    _call(clsamp.star_discrepancy, points)
    _call(clsamp.nearest_neighbor_distances, points)


@given(points=hostile_points(), radii=st.one_of(st.none(), hostile, st.lists(st.floats(allow_nan=True),
                                                                            max_size=4)),
       sigma=st.one_of(st.none(), hostile))
def test_pair_correlation(points, radii, sigma):
    _call(clsamp.pair_correlation, points, radii=radii, sigma=sigma)


@given(sampler=st.sampled_from(["random", "jittered", "sobol:owen", 3, None]),
       integrand=st.sampled_from(["gaussian", "disk", "random_boxes", "pmj_step", "what", 7]),
       ns=st.one_of(hostile, st.lists(small, max_size=3)), realizations=small, members=st.one_of(
           st.none(), small))
def test_convergence(sampler, integrand, ns, realizations, members):
    if isinstance(realizations, int) and realizations > 16:
        realizations = 16
    if isinstance(members, int) and members > 8:
        members = 8
    if isinstance(ns, list):
        ns = [n if not isinstance(n, int) or n < 512 else 512 for n in ns]
    _call(clsamp.convergence, sampler, integrand, ns, realizations=realizations, members=members,
          progress=False)


def _good(x):
    return np.ones(len(x))


@given(f=st.sampled_from([_good, "gaussian", lambda x: x, lambda x: np.full(len(x), np.nan), 5]),
       d=small, abs_tol=st.one_of(st.none(), hostile), rel_tol=st.one_of(st.none(), hostile),
       replications=small, confidence=st.one_of(hostile, st.floats(0, 1)), max_n=small)
def test_integrate(f, d, abs_tol, rel_tol, replications, confidence, max_n):
    if isinstance(max_n, int) and max_n > 4096:
        max_n = 4096
    if isinstance(d, int) and d > 8:
        d = 8
    _call(clsamp.integrate, f, d, abs_tol=abs_tol, rel_tol=rel_tol, replications=replications,
          confidence=confidence, max_n=max_n, progress=False)


@given(name=st.sampled_from(families.family_names() + ["boxes", "x"]), d=small, members=small, seed=small)
def test_families(name, d, members, seed):
    if isinstance(members, int) and members > 64:
        members = 64
    _call(families.make_family, name, d=d, members=members, seed=seed)


@given(sampler=st.sampled_from(["random", "jittered", "sobol:owen", "?"]), spp=small, resolution=small,
       seed=small)
def test_render(sampler, spp, resolution, seed):
    if isinstance(spp, int) and spp > 64:
        spp = 64
    if isinstance(resolution, int) and resolution > 16:
        resolution = 16
    _call(clsamp.render.render, "ao", sampler, spp, resolution, seed=seed, progress=False)


@given(data=st.binary(max_size=200), suffix=st.sampled_from([".npy", ".txt", ".exr"]))
def test_files(tmp_path_factory, data, suffix):
    path = tmp_path_factory.mktemp("fuzz") / f"f{suffix}"
    path.write_bytes(data)
    reader = files.read_exr if suffix == ".exr" else files.load_points
    _call(reader, path)
    with pytest.raises(FileNotFoundError):
        reader(path.with_name("missing" + suffix))



COMMANDS = ["devices", "sample", "spectrum", "metrics", "convergence", "integrate", "render", "tour"]
FLAGS = ["-n", "-d", "--realizations", "--seed", "--metric", "--resolution", "--ns", "--samplers",
         "--integrand", "--family", "--members", "--spp", "--sampler", "--abs-tol", "--max-n",
         "--method", "--tol", "--param", "--quick", "--scheduler", "--checkpoint", "--bogus"]
VALUES = ["0", "-1", "3", "1e400", "nan", "x", "16..4", "1,2,,", "random", "disk", "cd,zz", "sobol:owen",
          "local:0", "a=b", "strata=0x0", ""]


@given(command=st.sampled_from(COMMANDS),
       positional=st.sampled_from(["random", "jittered", "sobol:owen", "ao", "gaussian", "nope", ""]),
       words=st.lists(st.one_of(st.sampled_from(FLAGS), st.sampled_from(VALUES)), max_size=6))
def test_command_line(tmp_path_factory, command, positional, words):
    # every subcommand with hostile arguments: a result, a clear error (exit 2 with a
    # message) or argparse's usage error, never a traceback
    from clsamp import cli
    out = tmp_path_factory.mktemp("cli")
    args = [command, *([positional] if positional else []), *words]
    if command in ("sample", "spectrum", "metrics", "convergence", "render", "integrate"):
        args += ["-o", str(out / "o.json" if command in ("metrics", "integrate") else out / "o.npy"
                           if command == "sample" else out / "o.png" if command != "render" else
                           out / "o.exr")]
    if command == "tour":
        return      # minutes a call; its arguments are checked in tests/test_cli.py
    if "--scheduler" in words:
        return      # starting clusters is tests/test_parallel.py's business
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            code = cli.main(args)
        except SystemExit as exit_:               # argparse: usage error or --help
            code = exit_.code
    assert code in (0, 1, 2), code
