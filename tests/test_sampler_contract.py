"""The contract every registered sampler keeps (the pattern of scipy's QMCEngineTests).

A sampler is tested here by being registered, over the whole matrix of its variants:
every randomization it accepts (``randomize=``; the default without the keyword) times
the dimensions {its smallest, 2, a high one: 64 where any d goes, else its largest} it
supports, times ``start`` (0, and an offset where the sampler takes one). In every cell:
shape, dtype and range; the same seed gives the same bits and another seed other points
(the same points where the seed is unused); realization k does not depend on how many or
which realizations are asked for (a range equals the same rows of a larger call, the
device's points the host's); the kernel equals the NumPy reference bit for bit; the info
of samplers that iterate or reject covers every realization of the call; bad input is
refused with the argument named. ``start`` continues a sequence; in a stratified set it
offsets the counters of the jitter only (each point keeps its stratum); a set made whole
refuses it. Only public API is used.
"""

import dataclasses

import numpy as np
import pytest

import clsamp
from clsamp.errors import InvalidArgumentError
from clsamp.samplers import Rate, SampleInfo, Sampler, sampler_class

# Parameters that keep the slowest samplers small here (their defaults are run elsewhere).
SMALL = {"ccvt": {"points_per_site": 32}, "bnot": {"points_per_site": 16, "iterations": 4},
         "lloyd": {"iterations": 8, "density": 32},
         "sot": {"iterations": 6}}
NAMES = clsamp.sampler_names()
HIGH_D = 64         # the high dimension of samplers that take any d
START = 5           # the offset of the matrix's second start: odd, not a power of two
REALIZATIONS = 4


@dataclasses.dataclass(frozen=True)
class Cell:
    """One variant of a sampler: its name, randomization and dimension."""

    name: str
    randomize: object
    d: int

    def make(self, seed=7, **params):
        variant = {} if self.randomize is None else {"randomize": self.randomize}
        return clsamp.make_sampler(self.name, d=self.d, seed=seed,
                                   **{**SMALL.get(self.name, {}), **variant, **params})

    def __str__(self):
        return f"{self.name}:{self.randomize}-d{self.d}" if self.randomize else f"{self.name}-d{self.d}"


def _dimensions(cls):
    """Its smallest d, 2 and a high d, as far as the sampler supports them."""
    if cls.dimensions is None:
        return [1, 2, HIGH_D]
    dims = cls.dimensions
    return sorted({min(dims), max(dims)} | ({2} & set(dims)))


def _cells():
    cells = []
    for name in NAMES:
        cls = sampler_class(name)
        cells += [Cell(name, randomize, d)
                  for randomize in cls.randomizations for d in _dimensions(cls)]
    return cells


CELLS = _cells()
FACTS = {cell: cell.make() for cell in CELLS}     # the instances, for their facts (no sampling)


def _n(sampler):
    return sampler.valid_n(48 if sampler.d <= 3 else 16)


def _params(cells):
    return [pytest.param(cell, id=str(cell)) for cell in cells]


def _starts(cell):
    return (0, START) if FACTS[cell].accepts_start else (0,)


# Cells that fail through a bug outside this test, marked xfail(strict=True) until it is
# fixed: (test, cell id) -> (exception, reason).
KNOWN_BUGS = {}

def _calls(test):
    """(cell, start) of every call of the matrix, a known bug of ``test`` marked."""
    params = []
    for cell in CELLS:
        for start in _starts(cell):
            label = f"{cell}-start{start}"
            bug = KNOWN_BUGS.get((test, label))
            marks = [pytest.mark.xfail(raises=bug[0], reason=bug[1], strict=True)] if bug else []
            params.append(pytest.param(cell, start, id=label, marks=marks))
    return params


CALLS = _calls(None)
SEQUENCES = [c for c in CELLS if FACTS[c].sequence and FACTS[c].accepts_start]
STRATIFIED = [c for c in CELLS if not FACTS[c].sequence and FACTS[c].accepts_start]
WHOLE_SETS = [c for c in CELLS if not FACTS[c].accepts_start]
WITH_INFO = [c for c in CELLS if FACTS[c].info is not None]
WITHOUT_INFO = [c for c in CELLS if FACTS[c].info is None]


@pytest.fixture(scope="module")
def batch():
    """``batch(cell, start)`` -> (sampler, n, its four realizations), each made once."""
    made = {}

    def get(cell, start=0):
        if (cell, start) not in made:
            s = cell.make()
            n = _n(s)
            made[cell, start] = (s, n, s.sample(n, realizations=REALIZATIONS, start=start))
        return made[cell, start]
    return get


def test_the_matrix_covers_every_sampler_and_variant():
    assert {c.name for c in CELLS} == set(NAMES)
    for name in NAMES:
        cls = sampler_class(name)
        assert {c.randomize for c in CELLS if c.name == name} == set(cls.randomizations)
        for d in {c.d for c in CELLS if c.name == name}:
            assert cls.dimensions is None or d in cls.dimensions
    assert {"zsobol", "van_der_corput"} <= set(NAMES)
    # every cell's start is tested: a sequence's, a stratified set's (as STRATA states), or refused
    assert {c.name for c in STRATIFIED} <= set(STRATA)
    assert len(SEQUENCES) + len(STRATIFIED) + len(WHOLE_SETS) == len(CELLS)


# -- every call of the matrix ----------------------------------------------------------------
@pytest.mark.parametrize("cell, start", CALLS)
def test_shape_dtype_and_range(cell, start, batch):
    s, n, pts = batch(cell, start)
    assert pts.shape == (REALIZATIONS, n, cell.d) and pts.dtype == np.float64
    assert pts.flags.c_contiguous
    assert np.all(pts >= 0.0) and np.all(pts < 1.0)
    one = s.sample(n, start=start)
    assert one.shape == (n, cell.d) and one.dtype == np.float64 and one.flags.c_contiguous
    device = s.sample_device(n, realizations=2, start=start)
    assert device.shape == (2, n, cell.d) and device.dtype == np.float64


@pytest.mark.parametrize("cell, start", CALLS)
def test_same_seed_same_bits_other_seed_other_points(cell, start, batch):
    s, n, pts = batch(cell, start)
    assert np.array_equal(cell.make().sample(n, realizations=REALIZATIONS, start=start), pts)
    other = cell.make(seed=8).sample(n, realizations=REALIZATIONS, start=start)
    assert np.array_equal(s.with_seed(8).sample(n, realizations=REALIZATIONS, start=start), other)
    if s.randomized:
        assert not np.array_equal(other, pts)
        for a in range(REALIZATIONS):                          # realizations differ
            for b in range(a):
                assert not np.array_equal(pts[a], pts[b]), (a, b)
    else:
        assert np.array_equal(other, pts)
        assert all(np.array_equal(p, pts[0]) for p in pts)   # the seed is unused


@pytest.mark.parametrize("cell, start", CALLS)
def test_realizations_are_independent_of_the_request(cell, start, batch):
    s, n, pts = batch(cell, start)
    assert np.array_equal(s.sample(n, start=start), pts[0])
    assert np.array_equal(s.sample(n, realizations=2, start=start), pts[:2])
    assert np.array_equal(s.sample(n, realizations=range(1, 4), start=start), pts[1:])
    assert np.array_equal(s.sample(n, realizations=range(3, 0, -2), start=start), pts[[3, 1]])
    assert np.array_equal(s.sample(n, realizations=range(2, 3), start=start), pts[2:3])
    device = s.sample_device(n, realizations=range(1, 3), start=start)
    assert np.array_equal(device.get(), pts[1:3])
    assert np.array_equal(s.sample_device(n, start=start).get(), pts[0])


@pytest.mark.parametrize("cell, start", CALLS)
def test_kernel_equals_reference(cell, start, batch):
    s, n, pts = batch(cell, start)
    reference = cell.make(backend="numpy")
    assert reference.backend == "numpy" and s.backend == "opencl"
    assert np.array_equal(reference.sample(n, realizations=range(1, 3), start=start), pts[1:3])
    assert np.array_equal(reference.sample(n, start=start), pts[0])


@pytest.mark.parametrize("cell, start", _calls("chunks"))
def test_a_call_split_into_chunks_is_the_same_call(cell, start, batch, monkeypatch):
    # a device budget of one realization per chunk: the same points, and an info that
    # still covers every realization of the call (merged from the chunks' parts)
    s, n, pts = batch(cell, start)
    whole_info = (s.sample(n, realizations=REALIZATIONS, start=start, return_info=True)[1]
                  if s.info else None)
    monkeypatch.setattr(clsamp.runtime.memory, "work_budget", lambda: 8 * n * s.d)
    if s.info is None:
        assert np.array_equal(s.sample(n, realizations=REALIZATIONS, start=start), pts)
    else:
        got, info = s.sample(n, realizations=REALIZATIONS, start=start, return_info=True)
        assert np.array_equal(got, pts)
        assert info.realizations.tolist() == list(range(REALIZATIONS))
        for field, value in vars(whole_info).items():
            part = getattr(info, field)
            assert np.array_equal(np.asarray(part), np.asarray(value)), field
    device = s.sample_device(n, realizations=REALIZATIONS, start=start)
    assert np.array_equal(device.get(), pts)


# -- return_info -----------------------------------------------------------------------------
@pytest.mark.parametrize("cell", _params(WITH_INFO))
def test_info_covers_every_realization_of_the_call(cell, batch):
    s, n, pts = batch(cell)
    assert issubclass(s.info, SampleInfo)
    got, info = s.sample(n, realizations=range(1, 4), return_info=True)
    assert np.array_equal(got, pts[1:])
    assert isinstance(info, s.info) and info.realizations.tolist() == [1, 2, 3]
    for value in vars(info).values():
        if isinstance(value, np.ndarray):
            assert value.shape[0] == 3
    one_points, one = s.sample(n, return_info=True)
    assert np.array_equal(one_points, pts[0]) and one.realizations.tolist() == [0]
    device, info = s.sample_device(n, realizations=range(2, 4), return_info=True)
    assert np.array_equal(device.get(), pts[2:]) and info.realizations.tolist() == [2, 3]


@pytest.mark.parametrize("cell", _params(WITHOUT_INFO))
def test_samplers_without_info_refuse_return_info(cell):
    s = FACTS[cell]
    for call in (s.sample, s.sample_device):
        with pytest.raises(InvalidArgumentError, match="'return_info'"):
            call(_n(s), return_info=True)


# -- start -----------------------------------------------------------------------------------
@pytest.mark.parametrize("cell", _params(SEQUENCES))
def test_start_continues_a_sequence(cell):
    s = cell.make()
    n = _n(s)
    for k in (START, n):           # an odd offset, and the next set of n
        assert s.valid_n(k + n) == k + n
        whole = s.sample(k + n, realizations=range(2, 4))
        assert np.array_equal(s.sample(n, realizations=range(2, 4), start=k), whole[:, k:])
        assert np.array_equal(s.sample_device(n, realizations=range(2, 4), start=k).get(),
                              whole[:, k:])
        assert np.array_equal(s.sample(n, start=k), s.sample(k + n)[k:])


def _grid(cols, counts):
    return [(tuple(cols), tuple(counts))]


def _jittered(s, n):
    k = round(n ** (1.0 / s.d))
    assert k ** s.d == n
    return [k] * s.d, _grid(range(s.d), [k] * s.d)


def _uncorrelated_jitter(s, n):
    counts, grids, first = [], [], 0
    for size in s.groups:                  # each group alone is a jittered k^size grid
        k = round(n ** (1.0 / size))
        assert k ** size == n
        counts += [k] * size
        grids += _grid(range(first, first + size), [k] * size)
        first += size
    return counts, grids


def _latin_hypercube(s, n):
    return [n] * s.d, [((j,), (n,)) for j in range(s.d)]


def _multijittered(s, n):
    mx, my = s.factors(n)
    return [n, n], _grid((0, 1), (mx, my)) + [((0,), (n,)), ((1,), (n,))]


def _correlated_multijittered(s, n):
    m, k = s.factors(n)
    # y in n slabs, x in m * k slabs (n of them used); the m x k cells when n = m * k
    cells = _grid((0, 1), (m, k)) if m * k == n else []
    return [m * k, n], [((0,), (m * k,)), ((1,), (n,))] + cells


# For the stratified sets that take start: (the number of strata along each axis, so that
# floor(x_j * count_j) is the stratum of a point, and the grids of which each cell holds one
# point), read from the sampler's docstring.
STRATA = {"regular": _jittered, "jittered": _jittered,
          "uncorrelated_jitter": _uncorrelated_jitter, "latin_hypercube": _latin_hypercube,
          "multijittered": _multijittered, "correlated_multijittered": _correlated_multijittered}


def _assert_one_point_per_cell(pts, grids):
    for realization in pts:
        for cols, counts in grids:
            cells = np.floor(realization[:, list(cols)] * np.array(counts)).astype(np.int64)
            assert len(np.unique(cells, axis=0)) == len(realization), (cols, counts)


@pytest.mark.parametrize("cell", _params(STRATIFIED))
def test_start_offsets_the_jitter_of_a_stratified_set(cell, batch):
    # In these sets (not sequences) start offsets the counters of the jitter only: point i
    # keeps its stratum and shuffles, and takes the jitter that point i + start has at
    # start=0. So the set is deterministic, keeps its structure, and differs from start=0
    # wherever it is jittered (regular, the cell centres, does not change).
    assert cell.name in STRATA, f"state what 'start' does for {cell.name!r} here"
    s, n, base = batch(cell)
    _, _, moved = batch(cell, START)
    assert np.array_equal(s.sample(n, realizations=REALIZATIONS, start=START), moved)
    counts, grids = STRATA[cell.name](s, n)
    counts = np.array(counts, dtype=np.float64)
    strata = np.floor(base * counts)
    assert np.array_equal(np.floor(moved * counts), strata)        # every point keeps its stratum
    _assert_one_point_per_cell(base, grids)
    _assert_one_point_per_cell(moved, grids)
    if s.randomized:
        assert not np.array_equal(moved, base)
        assert not np.array_equal(moved[:, 0], base[:, 0])
        jitter, moved_jitter = base * counts - strata, moved * counts - strata
        np.testing.assert_allclose(moved_jitter[:, :n - START], jitter[:, START:], rtol=0, atol=1e-9)
    else:
        assert np.array_equal(moved, base)


@pytest.mark.parametrize("cell", _params(WHOLE_SETS))
def test_a_set_made_whole_refuses_start(cell, batch):
    s, n, pts = batch(cell)
    assert not s.sequence
    for call in (s.sample, s.sample_device):
        for start in (1, START):
            with pytest.raises(InvalidArgumentError, match="'start'"):
                call(n, start=start)
    assert np.array_equal(s.sample(n, start=0), pts[0])


# -- facts and refusals ----------------------------------------------------------------------
@pytest.mark.parametrize("cell", _params(CELLS))
def test_facts(cell, batch):
    s, n, pts = batch(cell)
    assert isinstance(s.expensive, bool) and isinstance(s.randomized, bool)
    assert None in s.randomizations and cell.randomize in s.randomizations
    assert s.name == cell.name and s.d == cell.d
    assert s.label == (f"{cell.name}:{cell.randomize}" if cell.randomize else cell.name)
    again = clsamp.make_sampler(s.label, d=cell.d, seed=7, **SMALL.get(cell.name, {}))
    assert again.label == s.label and np.array_equal(again.sample(n), pts[0])
    for alias in s.aliases:
        assert clsamp.make_sampler(alias, d=cell.d).name == cell.name
    for case in ("best", "worst", "axis"):
        rate = s.convergence_rate(case)
        assert rate is None or (isinstance(rate, Rate) and rate.exponent < 0 and rate.source)
    other = s.with_seed(99)
    assert other.seed == 99 and s.seed == 7 and type(other) is type(s)
    assert other.label == s.label and other.d == s.d


BASE_FACTS = {name for name, value in vars(Sampler).items()
              if not name.startswith("_") and not callable(value) and not isinstance(value, property)
              } - {"randomize"}     # a parameter, whose default the base declares


@pytest.mark.parametrize("cell", _params(CELLS))
def test_facts_are_class_facts_never_overwritten_by_an_instance(cell):
    s = FACTS[cell]
    assert not set(vars(s)) & BASE_FACTS, set(vars(s)) & BASE_FACTS
    assert isinstance(s.pixel_indexed, bool) and isinstance(s.variable_size, bool)
    assert s.max_d >= s.d and s.randomize == cell.randomize
    assert s.randomized == (cell.randomize is not None or type(s).randomized is True)


@pytest.mark.parametrize("cell", _params(CELLS))
def test_what_a_renderer_asks_every_sampler(cell, batch):
    # the renderer's protocol, declared on the base: for_image, pixel_indexed, sample_sets
    s, n, pts = batch(cell)
    image = s.for_image(3, 2)
    assert type(image) is type(s) and image.d == s.d
    if s.pixel_indexed:
        assert image is not s and image.max_n >= 1
    else:
        assert image is s
    sets = s.sample_sets(range(1, 3), n=n)
    assert len(sets) == 2 and all(np.array_equal(a, b) for a, b in zip(sets, pts[1:3], strict=True))


def test_a_sampler_must_write_both_methods():
    class Half(Sampler):
        def _reference(self, n, realizations, start):
            return np.zeros((len(realizations), n, self.d))

    with pytest.raises(TypeError, match="_device"):
        Half()


def test_a_maximal_poisson_disk_set_has_its_own_size():
    s = clsamp.make_sampler("poisson_disk", radius=0.1, seed=3)
    assert s.variable_size and not clsamp.make_sampler("poisson_disk").variable_size
    sets = s.sample_sets(2)
    assert len(sets) == 2 and all(x.ndim == 2 and x.shape[1] == 2 for x in sets)


@pytest.mark.parametrize("cell", _params(CELLS))
def test_bad_input_names_the_argument(cell):
    s = FACTS[cell]
    n = _n(s)
    for bad in (0, -1, 2.5, True):
        with pytest.raises(InvalidArgumentError, match="'n'"):
            s.sample(bad)
    for bad in (0, -2, 1.5, range(0), range(-1, 2), range(2**32 - 1, 2**32 + 1)):
        with pytest.raises(InvalidArgumentError, match="'realizations'"):
            s.sample(n, realizations=bad)
    with pytest.raises(InvalidArgumentError, match="'start'"):
        s.sample(n, start=-1)
    with pytest.raises(InvalidArgumentError, match="'start'"):
        s.sample(n, start=s.max_n - n + 2)  # the last point past the 32-bit point indices
    with pytest.raises(InvalidArgumentError, match="'seed'"):
        cell.make(seed=-1)
    with pytest.raises(InvalidArgumentError, match="'backend'"):
        cell.make(backend="cuda")
    with pytest.raises(InvalidArgumentError, match="'randomize'"):
        cell.make(randomize="no such randomization")
    with pytest.raises(InvalidArgumentError, match="'d'"):
        clsamp.make_sampler(cell.name, d=0)
    if s.dimensions is not None:
        with pytest.raises(InvalidArgumentError, match="'d'"):
            clsamp.make_sampler(cell.name, d=max(s.dimensions) + 1)
    for wrong in (n + 1, n + 2):            # an n the sampler cannot make names the nearest
        valid = s.valid_n(wrong)
        if valid != wrong:
            with pytest.raises(InvalidArgumentError, match=f"nearest valid n is {valid}"):
                s.sample(wrong)
