"""The contract every registered sampler keeps (the pattern of scipy's QMCEngineTests).

A sampler is tested here by being registered: shape, dtype and range; the same seed
gives the same bits and another seed other points; realization k does not depend on how
many or which realizations are asked for (a range equals the same rows of a larger call);
``start`` continues a sequence; the kernel equals the NumPy reference; the info of
samplers that iterate or reject covers every realization of the call; bad input is
refused with the argument named. Only public API is used.
"""

import numpy as np
import pytest

import clsamp
from clsamp.errors import InvalidArgumentError
from clsamp.samplers import Rate, SampleInfo, sampler_class

# Parameters that keep the slowest samplers small here (their defaults are run elsewhere).
SMALL = {"ccvt": {"points_per_site": 32}, "lloyd": {"iterations": 8, "density": 32}}
NAMES = clsamp.sampler_names()


def _d(name):
    dims = sampler_class(name).dimensions
    return 2 if dims is None or 2 in dims else dims[0]


def make(name, seed=7, **params):
    return clsamp.make_sampler(name, d=_d(name), seed=seed, **{**SMALL.get(name, {}), **params})


def _n(sampler):
    return sampler.valid_n(48)


@pytest.fixture(scope="module")
def batches():
    """Four realizations of every sampler, made once."""
    out = {}
    for name in NAMES:
        s = make(name)
        out[name] = (s, _n(s), s.sample(_n(s), realizations=4))
    return out


@pytest.mark.parametrize("name", NAMES)
def test_shape_dtype_and_range(name, batches):
    s, n, pts = batches[name]
    assert pts.shape == (4, n, s.d) and pts.dtype == np.float64
    assert pts.flags.c_contiguous
    assert np.all(pts >= 0.0) and np.all(pts < 1.0)
    one = s.sample(n)
    assert one.shape == (n, s.d)


@pytest.mark.parametrize("name", NAMES)
def test_same_seed_same_bits_other_seed_other_points(name, batches):
    s, n, pts = batches[name]
    assert np.array_equal(make(name).sample(n, realizations=4), pts)
    other = make(name, seed=8).sample(n, realizations=4)
    assert np.array_equal(other, pts) == (not s.randomized)
    if s.randomized:
        assert not np.array_equal(pts[0], pts[1])            # realizations differ


@pytest.mark.parametrize("name", NAMES)
def test_realizations_are_independent_of_the_request(name, batches):
    s, n, pts = batches[name]
    assert np.array_equal(s.sample(n), pts[0])
    assert np.array_equal(s.sample(n, realizations=2), pts[:2])
    assert np.array_equal(s.sample(n, realizations=range(1, 4)), pts[1:])
    assert np.array_equal(s.sample(n, realizations=range(3, 0, -2)), pts[[3, 1]])
    assert np.array_equal(s.sample(n, realizations=range(2, 3)), pts[2:3])
    device = s.sample_device(n, realizations=range(1, 3))
    assert np.array_equal(device.get(), pts[1:3])
    assert np.array_equal(s.sample_device(n).get(), pts[0])


@pytest.mark.parametrize("name", NAMES)
def test_start_continues_a_sequence(name):
    s = make(name)
    n = _n(s)
    if not s.sequence:
        if not s.accepts_start:
            with pytest.raises(InvalidArgumentError, match="'start'"):
                s.sample(n, start=1)
        return
    whole = s.sample(2 * n, realizations=range(2, 4))
    assert np.array_equal(s.sample(n, realizations=range(2, 4), start=n), whole[:, n:])


@pytest.mark.parametrize("name", NAMES)
def test_kernel_equals_reference(name, batches):
    s, n, pts = batches[name]
    ref = make(name, backend="numpy").sample(n, realizations=range(1, 3))
    assert np.array_equal(ref, pts[1:3])


@pytest.mark.parametrize("name", NAMES)
def test_info_covers_every_realization_of_the_call(name, batches):
    s, n, pts = batches[name]
    if s.info is None:
        with pytest.raises(InvalidArgumentError, match="'return_info'"):
            s.sample(n, return_info=True)
        return
    got, info = s.sample(n, realizations=range(1, 4), return_info=True)
    assert np.array_equal(got, pts[1:])
    assert isinstance(info, SampleInfo) and info.realizations.tolist() == [1, 2, 3]
    for value in vars(info).values():
        if isinstance(value, np.ndarray):
            assert value.shape[0] == 3
    _, one = s.sample(n, return_info=True)
    assert one.realizations.tolist() == [0]


@pytest.mark.parametrize("name", NAMES)
def test_facts(name):
    s = make(name)
    assert isinstance(s.expensive, bool) and None in s.randomizations
    assert s.label.split(":")[0] == s.name == name
    assert clsamp.make_sampler(s.label, d=s.d).name == name
    for alias in s.aliases:
        assert clsamp.make_sampler(alias, d=s.d).name == name
    for case in ("best", "worst", "axis"):
        rate = s.convergence_rate(case)
        assert rate is None or (isinstance(rate, Rate) and rate.exponent < 0 and rate.source)
    other = s.with_seed(99)
    assert other.seed == 99 and s.seed == 7 and type(other) is type(s)


@pytest.mark.parametrize("name", NAMES)
def test_bad_input_names_the_argument(name):
    s = make(name)
    n = _n(s)
    for bad in (0, -1, 2.5, True):
        with pytest.raises(InvalidArgumentError, match="'n'"):
            s.sample(bad)
    for bad in (0, -2, 1.5, range(0), range(-1, 2), range(2**32 - 1, 2**32 + 1)):
        with pytest.raises(InvalidArgumentError, match="'realizations'"):
            s.sample(n, realizations=bad)
    with pytest.raises(InvalidArgumentError, match="'start'"):
        s.sample(n, start=-1)
    with pytest.raises(InvalidArgumentError, match="'seed'"):
        make(name, seed=-1)
    with pytest.raises(InvalidArgumentError, match="'backend'"):
        make(name, backend="cuda")
    with pytest.raises(InvalidArgumentError, match="'d'"):
        clsamp.make_sampler(name, d=0)


@pytest.mark.parametrize("name", NAMES)
def test_a_call_split_into_chunks_is_the_same_call(name, batches, monkeypatch):
    # a device budget of one realization per chunk: the same points, and an info that
    # still covers every realization of the call (merged from the chunks' parts)
    s, n, pts = batches[name]
    whole_info = s.sample(n, realizations=4, return_info=True)[1] if s.info else None
    monkeypatch.setattr(clsamp.runtime, "work_budget", lambda: 8 * n * s.d)
    if s.info is None:
        assert np.array_equal(s.sample(n, realizations=4), pts)
        assert np.array_equal(s.sample_device(n, realizations=4).get(), pts)
        return
    got, info = s.sample(n, realizations=4, return_info=True)
    assert np.array_equal(got, pts)
    assert info.realizations.tolist() == [0, 1, 2, 3]
    for field, value in vars(whole_info).items():
        part = getattr(info, field)
        assert np.array_equal(np.asarray(part), np.asarray(value)), field
