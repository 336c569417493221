"""lattice and kronecker: closed forms, the embedded lattices of the extensible sequence,
uniform shifts, and (where qmcpy is installed) qmcpy's points."""

from decimal import Decimal, getcontext
from fractions import Fraction

import numpy as np
import pytest

import clsamp
from clsamp.errors import InvalidArgumentError
from clsamp.samplers.lattice import fibonacci, korobov, kuo_vector


@pytest.mark.parametrize("n", [13, 89, 987, 46368])
def test_unshifted_fibonacci_lattice_is_its_closed_form(n):
    fib = fibonacci(40)
    step = fib[fib.index(n) - 1]
    i = np.arange(n)
    expected = np.stack([i / n, (i * step % n) / n], axis=1)
    got = clsamp.make_sampler("lattice", d=2, generator="fibonacci").sample(n)
    assert np.array_equal(got, expected)
    # a lattice: the set is closed under addition mod 1 (point 1 + point k is a point)
    keys = set(map(tuple, np.round(got * n).astype(np.int64) % n))
    moved = np.round((got + got[1]) * n).astype(np.int64) % n
    assert set(map(tuple, moved)) == keys


def test_every_power_of_two_prefix_is_the_lattice_of_that_size():
    d = 6
    z = kuo_vector(d).astype(np.int64)
    pts = clsamp.make_sampler("lattice", d=d).sample(2**12)
    for m in (1, 4, 10, 12):
        n = 2**m
        expected = {tuple((k * z) % n) for k in range(n)}
        got = {tuple(row) for row in np.round(pts[:n] * n).astype(np.int64)}
        assert got == expected
    s = clsamp.make_sampler("lattice", d=d, randomize="shift", seed=3)
    assert np.array_equal(s.sample(100, start=50, realizations=2), s.sample(150, realizations=2)[:, 50:])


@pytest.mark.parametrize("name, params", [("lattice", {}), ("lattice", {"generator": "fibonacci"}),
                                          ("kronecker", {})])
def test_shifts_are_uniform(name, params):
    # unshifted point 0 is the origin, so the shifted one is the shift: 4096 realizations of
    # each coordinate in 16 bins, chi-square well inside its 15 degrees of freedom
    s = clsamp.make_sampler(name, d=2, seed=5, randomize="shift", **params)
    n = s.valid_n(8)
    first = s.sample(n, realizations=4096)[:, 0, :]
    for j in range(2):
        counts = np.bincount((first[:, j] * 16).astype(int), minlength=16)
        chi2 = np.sum((counts - 256.0) ** 2 / 256.0)
        assert chi2 < 40, chi2
    # the shift moves the whole set rigidly on the torus
    plain = clsamp.make_sampler(name, d=2, **params).sample(n)
    delta = (s.sample(n) - plain) % 1.0
    assert np.allclose(delta, delta[0], atol=1e-12)


def test_kronecker_is_frac_i_alpha():
    getcontext().prec = 60
    d = 3
    phi = Decimal(2)
    for _ in range(100):
        phi = phi - (phi ** (d + 1) - phi - 1) / ((d + 1) * phi ** d - 1)
    assert abs(phi ** 4 - phi - 1) < Decimal(10) ** -50
    alphas = [1 / phi ** (j + 1) for j in range(d)]
    s = clsamp.make_sampler("kronecker", d=d)
    pts = s.sample(10, start=10**9)
    for row, i in zip(pts, range(10**9, 10**9 + 10), strict=True):
        exact = [float((i * a) % 1) for a in alphas]
        assert np.allclose(row, exact, rtol=0, atol=2e-10)       # 2^-65 per unit of i
    golden = clsamp.make_sampler("kronecker", d=1).sample(3)[:, 0]
    assert abs(golden[1] - (np.sqrt(5) - 1) / 2) < 1e-15


def test_matches_qmcpy_lattice_in_natural_order():
    qmcpy = pytest.importorskip("qmcpy")
    theirs = qmcpy.Lattice(7, randomize=False, order="natural").gen_samples(2048, warn=False)
    assert np.array_equal(clsamp.make_sampler("lattice", d=7).sample(2048), theirs)


def test_bad_parameters_are_named():
    with pytest.raises(InvalidArgumentError, match="'generator'"):
        clsamp.make_sampler("lattice", generator="korobov")
    with pytest.raises(InvalidArgumentError, match="'d'"):
        clsamp.make_sampler("lattice", d=3, generator="fibonacci")
    with pytest.raises(InvalidArgumentError, match="'d'"):
        clsamp.make_sampler("lattice", d=9126)
    with pytest.raises(InvalidArgumentError, match="nearest valid n is 89"):
        clsamp.make_sampler("lattice", generator="fibonacci").sample(90)
    with pytest.raises(InvalidArgumentError, match="'start'"):
        clsamp.make_sampler("lattice", generator="fibonacci").sample(89, start=1)


# -- issue 38: a generating vector of one's own, Korobov's, three orders ------------------
def _rows(a):
    return {tuple(r) for r in np.asarray(a).tolist()}


@pytest.mark.parametrize("params", [
    {"order": "gray"}, {"order": "natural"}, {"order": "gray", "randomize": "shift", "seed": 4},
    {"generating_vector": [1, 182667, 469891, 498753], "d": 4, "order": "radical_inverse"},
    {"generating_vector": [1, 182667, 469891, 498753], "d": 3, "order": "natural", "randomize": "shift"},
])
def test_every_order_and_vector_equals_its_twin_bit_for_bit(params):
    for n, start in ((1000, 0), (256, 0), (100, 37)):
        if params.get("order") == "natural" and start:
            continue
        s = clsamp.make_sampler("lattice", **params)
        got = s.sample(n, realizations=3, start=start)
        ref = clsamp.make_sampler("lattice", backend="numpy", **params).sample(n, realizations=3, start=start)
        assert np.array_equal(got.view(np.uint64), ref.view(np.uint64))


def test_the_orders_hold_the_same_lattice_at_powers_of_two():
    z = korobov(76393, 5)
    ri = clsamp.make_sampler("lattice", d=5, generating_vector=z).sample(1024)
    gray = clsamp.make_sampler("lattice", d=5, generating_vector=z, order="gray").sample(1024)
    natural = clsamp.make_sampler("lattice", d=5, generating_vector=z, order="natural").sample(1024)
    assert _rows(ri) == _rows(gray) == _rows(natural) and len(_rows(ri)) == 1024
    # Gray order: consecutive indices differ in one bit, so each step adds +-z / 2^k mod 1
    assert not np.array_equal(ri, gray)
    # every 2^m prefix of the Gray order is the lattice of 2^m points
    for m in range(1, 10):
        assert _rows(gray[:2**m]) == _rows(natural[::1024 // 2**m])


def test_natural_order_is_the_lattice_rule_of_any_n():
    n, z = 1009, [1, 76, 503]
    pts = clsamp.make_sampler("lattice", d=3, generating_vector=z, order="natural").sample(n)
    exact = np.array([[float(Fraction(i * zj % n, n)) for zj in z] for i in range(n)])
    assert np.array_equal(pts, exact)                 # one correctly rounded division
    np.testing.assert_allclose(pts[22], (pts[5] + pts[17]) % 1, rtol=0, atol=1e-15)  # a lattice
    with pytest.raises(InvalidArgumentError, match="'start'"):
        clsamp.make_sampler("lattice", d=3, generating_vector=z, order="natural").sample(n, start=1)


def test_korobov_vectors_and_the_fibonacci_lattice_as_a_natural_order():
    assert korobov(3, 5, 2**32).tolist() == [1, 3, 9, 27, 81]
    assert korobov(5, 3, 7).tolist() == [1, 5, 4]
    fib = clsamp.make_sampler("lattice", d=2, generator="fibonacci").sample(233)
    same = clsamp.make_sampler("lattice", generating_vector=[1, 144], order="natural").sample(233)
    assert np.array_equal(fib, same)


def test_matches_qmcpy_in_gray_and_linear_order():
    qmcpy = pytest.importorskip("qmcpy")
    z = np.array([1, 433461, 315689, 441789], dtype=np.uint64)
    for ours, theirs in (("gray", "GRAY"), ("natural", "LINEAR")):
        q = qmcpy.Lattice(4, randomize="FALSE", order=theirs, generating_vector=z, m_max=20)
        mine = clsamp.make_sampler("lattice", d=4, generating_vector=z, order=ours).sample(1024)
        assert np.allclose(mine, q.gen_samples(1024, warn=False), rtol=0, atol=1e-15), ours


@pytest.mark.parametrize("params, match", [
    ({"generating_vector": [1, 0]}, "entries must be in"),
    ({"generating_vector": [1]}, r"'d' must be in \[1, 1\]"),
    ({"generating_vector": [1, 2**32]}, "entries must be in"),
    ({"generating_vector": [[1, 3]]}, "1-D array"),
    ({"generating_vector": [1.5, 3]}, "1-D array"),
    ({"generating_vector": [1, 3], "d": 3}, r"'d' must be in \[1, 2\]"),
    ({"generating_vector": [1, 3], "generator": "fibonacci"}, "Fibonacci"),
    ({"order": "linear"}, "'order'"),
    ({"order": "gray", "generator": "fibonacci"}, "one order"),
])
def test_bad_vectors_and_orders_are_named(params, match):
    with pytest.raises(InvalidArgumentError, match=match):
        clsamp.make_sampler("lattice", **params)
