"""``gbn`` runs kept on the device (clsamp/samplers/gbn_device.py): the exact sum of
kernels/exact_sum.h is math.fsum's value; a resident run gives gbn_optimize's host bits
(points, energies, steps, iterations, convergence), with sets that stop at different
iterations; which runs stay on the device."""

import math

import numpy as np
import pyopencl.array as cla
import pytest

import clsamp
from clsamp import runtime
from clsamp.density import as_density
from clsamp.samplers import gbn, gbn_device
from clsamp.samplers.gbn import HALVINGS, Kernel, gbn_optimize

rng = np.random.default_rng(20261206)


def _rows():
    """Rows of doubles whose exact sums round in every way: halfway cases to even and
    away, cancellation to zero and to few bits, subnormals, the whole exponent range,
    negative totals, many terms."""
    rows = [[1.0, 2.0**-53], [1.0 + 2.0**-52, 2.0**-53], [1.0, 2.0**-53, 2.0**-200],
            [1.0, 2.0**-53, -2.0**-200], [5e-324, 5e-324], [-5e-324], [0.0], [-0.0],
            [1.0, -1.0], [2.0**-1022, -5e-324], [-1.5, 2.0**-60], [2.0**1023, 2.0**1023],
            [1e308, -1e308, 1e-308], [0.1] * 10, [-(2.0**53), -1.0, 1.0, 0.5],
            [2.0**52 - 0.5, 0.25, 0.25, -2.0**52], list(rng.random(5000) - 0.5),
            [math.ldexp(1.0, e) for e in range(-1074, 1024, 7)]]
    for _ in range(200):
        k = int(rng.integers(1, 120))
        wide = rng.random() < 0.3
        e = rng.integers(-1070, 1000, k) if wide else rng.integers(-60, 10, k)
        v = np.ldexp(rng.random(k) * rng.choice([-1.0, 1.0], k), e)
        if rng.random() < 0.4:
            v = np.concatenate([v, -v[: k // 2]])
        rows.append(list(v))
    return rows


def test_the_exact_sum_is_fsums_value():
    rows = _rows()
    cols = max(len(r) for r in rows)
    values = np.zeros((len(rows), cols))
    for i, r in enumerate(rows):
        values[i, :len(r)] = r
    q = runtime.queue()
    out = cla.empty(q, len(rows), np.float64)
    kernel = runtime.kernel("exact_sum_probe.cl", "exact_sum_rows")
    kernel(q, (len(rows),), None, cla.to_device(q, values).data, np.uint32(cols),
           np.uint32(len(rows)), out.data)
    got = out.get()
    for i, r in enumerate(rows):
        try:
            want = math.fsum(r)
        except OverflowError:                   # 2^1023 + 2^1023: past the largest double
            want = math.inf
        assert got[i].tobytes() == np.float64(want).tobytes(), (i, r[:4], got[i], want)


def _same(a, b):
    (pa, ia), (pb, ib) = a, b
    assert np.array_equal(pa, pb)
    for name in ("energy_history", "initial_energy", "iterations", "converged", "step"):
        assert np.array_equal(getattr(ia, name), getattr(ib, name)), name


@pytest.mark.parametrize("d, n, iterations, tol, sets", [
    (2, 1024, 20, 0.0, 1), (2, 256, 80, 1e-4, 3), (1, 100, 30, 1e-3, 2), (3, 500, 12, 1e-4, 2),
    (4, 300, 8, 0.0, 1), (2, 64, 1, 0.0, 2), (2, 200, 200, 1e-3, 4), (5, 128, 10, 1e-2, 3),
    (2, 1, 5, 0.0, 2), (2, 2, 5, 0.0, 1)])
def test_a_resident_run_gives_the_hosts_bits(d, n, iterations, tol, sets):
    pts = clsamp.make_sampler("random", d=d, seed=d + n).sample(n, realizations=sets)
    kernel = Kernel(n=n, d=d, sigma=0.5, periodic=True)
    assert gbn_device.resident(kernel, None)
    _same(gbn_optimize(pts, kernel, iterations=iterations, tol=tol, realizations=range(sets)),
          gbn_optimize(pts, kernel, iterations=iterations, tol=tol, backend="numpy",
                       realizations=range(sets)))


def test_sets_that_stop_apart_keep_their_bits():
    # the sets converge at different iterations (tol), and one by its step's halvings:
    # the passes that follow a set's end skip it
    kernel = Kernel(n=128, d=2, sigma=0.5, periodic=True)
    pts = clsamp.make_sampler("random", d=2, seed=5).sample(128, realizations=4)
    pts[2] = pts[1]
    got = gbn_optimize(pts, kernel, iterations=60, tol=3e-3)
    _same(got, gbn_optimize(pts, kernel, iterations=60, tol=3e-3, backend="numpy"))
    ran = got[1].iterations
    assert got[1].converged.all() and len(set(ran.tolist())) > 1
    # a step so long that it is halved until it falls below its floor
    tau0 = 1e6 / kernel.mass
    x, energy, initial, tau, converged, ran, _ = gbn_device.optimize_resident(
        pts[:1], kernel, gbn.pass_defines(2, True, False), tau0, 80, 0.0, tau0 * 2.0 ** -HALVINGS)
    _, info = gbn_optimize(pts[:1], kernel, step=1e6, iterations=80, tol=0.0, backend="numpy")
    assert np.array_equal(tau, info.step) and np.array_equal(ran, info.iterations)
    assert converged[0] == info.converged[0]


def test_which_runs_stay_on_the_device():
    torus = Kernel(n=64, d=2, sigma=0.5, periodic=True)
    cube = Kernel(n=64, d=2, sigma=0.5, periodic=False)
    cpu = runtime.shape().host_sort
    assert gbn_device.resident(torus, None) == cpu
    assert not gbn_device.resident(cube, None)
    assert not gbn_device.resident(torus, as_density(lambda x: 1.0 + x[:, 0], 2))


def test_the_sampler_on_the_device_equals_its_twin():
    params = {"d": 2, "seed": 4, "iterations": 40}
    made = clsamp.make_sampler("gbn", **params).sample(300, realizations=range(2, 5),
                                                        return_info=True)
    _same(made, clsamp.make_sampler("gbn", backend="numpy", **params).sample(
        300, realizations=range(2, 5), return_info=True))
