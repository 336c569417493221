"""Convergence experiments: fitted rates against theory, the statistics' identities and
precision, the kernel against the NumPy reference, the accuracy-time front, argument
errors, and the command line.

Statistical tolerances: for near-normal errors the MSE over r realizations has relative
standard deviation sqrt(2 / r), so log MSE has sd 0.045 at r = 1000; a least-squares slope
over k sample counts spaced by 4x (ln 4 apart) then has sd 0.045 / (ln 4 sqrt(sum (j - j_mean)^2)):
0.010 for k = 5, 0.014 for k = 4 (what repeated seeds show: 0.01-0.02). Tolerances are about
five of those, plus what the theory says about pre-asymptotic terms. Seeds are fixed, so a
test is deterministic; the margins say why it is not brittle.
"""

import dataclasses
import json
import math
import os
import subprocess
import sys
from fractions import Fraction

import numpy as np
import pytest

import clsamp
from clsamp import philox, runtime, theory
from clsamp.errors import InvalidArgumentError
from clsamp.geometry.torus import homogenization_shifts, shift
from clsamp.integrands import Gaussian, make_integrand
from clsamp.results import ConvergenceResult, pareto_front, time_to_mse
from clsamp.sweep import parse_ns

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def run(sampler, integrand, ns, r, seed=0, **kw):
    return clsamp.convergence(sampler, integrand, ns, realizations=r, seed=seed, progress=False, **kw)


# -- fitted rates ----------------------------------------------------------------------
def test_random_converges_as_one_over_n():
    # MSE = Var f / N exactly at every N: no curvature, only noise (sd 0.010 here)
    res = run("random", "gaussian", [16, 64, 256, 1024, 4096], 1000, seed=1)
    slope, stderr = res.rate(n_min=16)
    assert abs(slope + 1.0) < 0.05
    assert 0.003 < stderr < 0.05


def test_jittered_rates_best_and_worst_case():
    # Pilleboue et al. 2015: N^-2 for the smooth Gaussian (next term O(N^-3)), N^-1.5 for the disk
    smooth = run("jittered", "gaussian", [64, 256, 1024, 4096], 1000, seed=2)
    assert abs(smooth.rate(n_min=64)[0] + 2.0) < 0.08
    edge = run("jittered", "disk", [64, 256, 1024, 4096], 1000, seed=2)
    assert abs(edge.rate(n_min=64)[0] + 1.5) < 0.1
    assert theory.compare(smooth)["verdict"].startswith("matches")
    assert theory.compare(edge)["verdict"].startswith("matches")


def test_owen_sobol_converges_near_n_to_the_minus_three():
    # Owen 1997: N^-3 (log N)^(d-1); the local slope of N^-3 log N is -3 + 1/ln N, -2.82..-2.90
    # over N = 256..16384; seeds scatter it by ~0.04
    res = run("sobol:owen", "gaussian", [256, 1024, 4096, 16384], 256, seed=3)
    slope, _ = res.rate(n_min=256)
    assert -3.1 < slope < -2.6
    cmp = theory.compare(res)
    assert cmp["case"] == "best" and cmp["expected"] == -3.0
    assert cmp["verdict"].split()[0] == "matches"


# -- the statistics --------------------------------------------------------------------
def test_mse_is_variance_plus_bias2_and_homogenized_estimators_are_unbiased():
    for name in ("random", "jittered", "sobol:owen", "latin_hypercube"):
        res = run(name, "disk", [16, 256], 400, seed=4)
        for k, e in enumerate(res.errors):
            assert res.mse[k] == pytest.approx(res.variance[k] + res.bias2[k], rel=1e-13)
            assert res.mse[k] == math.fsum(e * e) / len(e)
            # the mean error within 4 standard errors of zero (bias^2 within its error)
            assert abs(res.mean[k] - res.integral) < 4 * math.sqrt(res.variance[k] / (len(e) - 1))
            assert res.bias2[k] < 16 * res.variance[k] / (len(e) - 1)


def test_a_fixed_grid_is_biased_unless_shifted():
    fixed = run("regular", "disk", [64], 8, homogenize=False)
    assert fixed.variance[0] == 0.0 and fixed.bias2[0] == fixed.mse[0] > 1e-8
    assert theory.compare(fixed)["verdict"].startswith("unknown")
    shifted = run("regular", "disk", [64], 2000)
    assert abs(shifted.mean[0] - shifted.integral) < 4 * math.sqrt(shifted.variance[0] / 1999)


def test_tiny_mse_has_no_rounding_floor():
    # Owen-scrambled Sobol on the Gaussian at N = 2^16: errors ~1e-7, MSE ~1e-14
    n, r = 2**16, 8
    sampler = clsamp.make_sampler("sobol", randomize="owen", seed=11)
    f = Gaussian()
    res = run(sampler, f, [n], r, seed=5)
    assert 1e-17 < res.mse[0] < 1e-12
    # reference: the same points and shifts in NumPy, each sum of f - I correctly rounded
    # (n is a power of two, so n * I and the division by n are exact)
    x = shift(sampler.sample(n, realizations=r), homogenization_shifts(5, np.arange(r), 2)[:, None, :])
    values = f(x)
    want = np.array([math.fsum([*row, -n * f.integral]) / n for row in values])
    np.testing.assert_allclose(res.errors[0], want, rtol=1e-9)
    assert res.mse[0] == pytest.approx(math.fsum(want * want) / r, rel=1e-8)
    # the tour's check: against exact rationals of the returned errors
    exact = sum(Fraction(e) ** 2 for e in res.errors[0]) / r
    assert abs(Fraction(float(res.mse[0])) - exact) / exact < 1e-15


def test_errors_against_exact_rationals_on_a_small_case():
    n, r = 1000, 3
    sampler = clsamp.make_sampler("jittered", seed=6, strata=(40, 25))
    f = make_integrand("gaussian")
    res = run(sampler, f, [n], r, seed=6)
    x = shift(sampler.sample(n, realizations=r), homogenization_shifts(6, np.arange(r), 2)[:, None, :])
    for row, got in zip(f(x), res.errors[0], strict=True):
        exact = (sum(Fraction(v) for v in row) - n * Fraction(f.integral)) / n
        assert abs(Fraction(float(got)) - exact) <= abs(exact) * Fraction(1, 10**10)


def test_a_hundred_thousand_realizations_keep_the_mean_exact():
    r = 100_000
    res = run("random", "gaussian", [4], r, seed=7)
    e = res.errors[0]
    exact_mean = sum(Fraction(v) for v in e) / r
    assert Fraction(float(res.mean[0])) - Fraction(res.integral) == pytest.approx(
        float(exact_mean), abs=4e-17)
    assert res.bias2[0] == pytest.approx(float(exact_mean**2), rel=1e-14)
    # the NumPy reference agrees realization by realization
    ref = run("random", "gaussian", [4], r, seed=7, backend="numpy")
    np.testing.assert_allclose(e, ref.errors[0], rtol=1e-13, atol=1e-16)
    # and the mean error is statistically zero with r = 1e5
    assert abs(float(exact_mean)) < 4 * math.sqrt(res.variance[0] / (r - 1))


# -- kernel against the NumPy reference ------------------------------------------------
@pytest.mark.parametrize("name,integrand,homogenize", [("random", "gaussian", True),
                                                       ("jittered", "disk", True),
                                                       ("sobol:owen", "gaussian", False),
                                                       ("latin_hypercube", "pmj_triangle", True)])
def test_kernel_path_equals_numpy_path(name, integrand, homogenize):
    ns = [16, 64, 4096]
    a = run(name, integrand, ns, 12, seed=8, homogenize=homogenize)
    b = run(name, integrand, ns, 12, seed=8, homogenize=homogenize, backend="numpy")
    assert b.backend == "numpy" and a.backend == "opencl"
    for ea, eb in zip(a.errors, b.errors, strict=True):
        np.testing.assert_allclose(ea, eb, rtol=1e-11, atol=1e-15)
    np.testing.assert_allclose(a.mse, b.mse, rtol=1e-10)


def test_every_registered_sampler_runs():
    # generic on purpose: samplers registered later (poisson_disk, lloyd, ccvt) run here too
    for name in clsamp.sampler_names():
        dims = clsamp.samplers.sampler_class(name).dimensions
        d = 2 if dims is None or 2 in dims else dims[0]
        sampler = clsamp.make_sampler(name, d=d, seed=3)
        n = sampler.valid_n(16)
        f = make_integrand("gaussian", d=d)
        res = run(sampler, f, [n], 3, seed=2)
        x = shift(sampler.sample(n, realizations=3), homogenization_shifts(2, np.arange(3), d)[:, None, :])
        want = np.sum(f(x) - f.integral, axis=1) / n
        np.testing.assert_allclose(res.errors[0], want, rtol=1e-11, atol=1e-15, err_msg=name)
        assert res.kind.split(":")[0] == name


def test_chunks_give_the_same_errors(monkeypatch):
    from clsamp import estimates as module
    whole = run("jittered", "disk", [64], 10, seed=9)
    whole_np = run("jittered", "disk", [64], 10, seed=9, backend="numpy")
    monkeypatch.setattr(module, "HOST_CHUNK", 4 * 64 * 2)
    with runtime.forced_shape(dataclasses.replace(runtime.shape(), chunk=3 * 64 * 2)):
        parts = run("jittered", "disk", [64], 10, seed=9)
    parts_np = run("jittered", "disk", [64], 10, seed=9, backend="numpy")
    np.testing.assert_array_equal(whole.errors[0], parts.errors[0])
    np.testing.assert_array_equal(whole_np.errors[0], parts_np.errors[0])
    # a sampler with the NumPy backend feeds the kernel path too, whole and in chunks
    numpy_sampler = clsamp.make_sampler("jittered", seed=9, backend="numpy")
    np.testing.assert_array_equal(run(numpy_sampler, "disk", [64], 10, seed=9).errors[0], parts.errors[0])
    monkeypatch.undo()
    np.testing.assert_array_equal(run(numpy_sampler, "disk", [64], 10, seed=9).errors[0], parts.errors[0])


def test_shift_is_the_experiment_stream():
    u = homogenization_shifts(12, np.arange(5), 3)
    assert np.array_equal(u, philox.uniform(12, philox.Stream.EXPERIMENT, np.arange(5)[:, None], 0,
                                            np.arange(3)[None, :]))


# -- rates, fronts, targets on known numbers -------------------------------------------
def synthetic(name, ns, mse, seconds, r=100):
    # errors +-sqrt(mse): MSE exact, no bias, and the same relative error at every n
    errors = [np.array([1.0, -1.0] * (r // 2)) * math.sqrt(m) for m in mse]
    return ConvergenceResult(sampler=name, integrand="disk", ns=ns, errors=errors,
                             seconds=np.asarray(seconds) * r, realizations=r, integral=0.5,
                             kind=name, traits={"smooth": False, "periodic": True, "edges": "curved"})


def test_rate_fits_the_larger_half():
    ns = [16, 64, 256, 1024, 4096, 16384]
    mse = [1.0 / n for n in ns[:3]] + [1e3 * n**-2.5 for n in ns[3:]]
    res = synthetic("jittered", ns, mse, [1] * 6)
    assert list(res.ns[res.fit_range()]) == [1024, 4096, 16384]
    slope, stderr = res.rate()
    assert slope == pytest.approx(-2.5, abs=1e-9)
    assert res.rate(n_min=16)[0] > -2.5
    cmp = theory.compare(res)
    assert cmp["expected"] == -1.5 and cmp["verdict"].split()[0] == "differs"
    assert theory.compare(synthetic("nosuch", ns, mse, [1] * 6))["verdict"].split()[0] == "unknown"


def test_pareto_front_and_time_to_mse():
    fast = synthetic("cheap", [16, 64, 256], [1e-2, 2.5e-3, 6e-4], [1e-6, 2e-6, 4e-6])
    slow = synthetic("costly", [16, 64, 256], [1e-3, 1e-5, 1e-7], [1e-3, 2e-3, 4e-3])
    front = pareto_front([fast, slow])
    # costly N=16 (1e-3 s, MSE 1e-3) loses to cheap N=256 (4e-6 s, MSE 6e-4)
    assert [(p["sampler"], p["n"]) for p in front] == [("cheap", 16), ("cheap", 64), ("cheap", 256),
                                                        ("costly", 64), ("costly", 256)]
    dominated = synthetic("worse", [16], [5e-2], [1e-5])
    assert all(p["sampler"] != "worse" for p in pareto_front([fast, slow, dominated]))
    reach = time_to_mse(slow, 1e-4)
    assert reach["n"] == 64 and reach["mse"] == pytest.approx(1e-5)
    assert reach["seconds"] == pytest.approx(2e-3)
    assert 16 < reach["n_interpolated"] < 64
    assert reach["n_interpolated"] == pytest.approx(32.0, rel=1e-9)   # halfway in log-log
    assert time_to_mse(fast, 1e-6) is None


def test_plots_and_to_dict(tmp_path):
    from clsamp import plots
    a = run("random", "gaussian", [16, 64, 256], 20)
    b = run("jittered", "disk", [16, 64, 256], 20)
    assert plots.convergence([a, b], tmp_path / "c.png").stat().st_size > 1000
    assert plots.accuracy_time([a, b], tmp_path / "t.png").stat().st_size > 1000
    d = json.loads(json.dumps(a.to_dict(errors=True)))
    assert d["ns"] == [16, 64, 256] and len(d["errors"][0]) == 20 and d["kind"] == "random"
    assert np.allclose(a.seconds_per_estimate, a.seconds / 20)


# -- bad input -------------------------------------------------------------------------
def test_bad_input_names_the_problem():
    with pytest.raises(InvalidArgumentError, match="'ns'.*empty"):
        run("random", "gaussian", [], 10)
    with pytest.raises(InvalidArgumentError, match=r"'jittered'.*n=50.*nearest valid n is 49"):
        run("jittered", "gaussian", [16, 50], 10)
    # a sampler's own limit on n (its density points, 32-bit counts) before any n runs, not
    # after the smaller ones (it was found 10-24 s into the sweep): valid_n knows it
    for name, largest in (("bnot", 2**24 - 1), ("ccvt", 2**22 - 1), ("lloyd", 2**24 - 1)):
        with pytest.raises(InvalidArgumentError, match=rf"'{name}'.*n=33554432 points \(in 'ns'\); "
                                                       rf"the nearest valid n is {largest}"):
            run(name, "gaussian", [16, 2**25], 10)
    lloyd = clsamp.make_sampler("lloyd", d=3)
    largest = lloyd.valid_n(2**25)
    assert lloyd.valid_n(largest) == largest and lloyd.valid_n(largest + 1) == largest
    # one density point a site counts 2^32 - 1 sites, past max_n: valid_n gave what sample() refused
    for name in ("ccvt", "bnot"):
        one = clsamp.make_sampler(name, points_per_site=1)
        assert one.valid_n(2**32) == one.max_n
        with pytest.raises(InvalidArgumentError, match="'n' must be an integer >= 1"):
            one.valid_n(-5)
    with pytest.raises(InvalidArgumentError, match="'realizations'"):
        run("random", "gaussian", [16], 1)
    with pytest.raises(InvalidArgumentError, match="Known integrands: gaussian, disk, heaviside"):
        run("random", "nosuch", [16], 10)
    with pytest.raises(InvalidArgumentError, match="'ns'"):
        run("random", "gaussian", [16, 16], 10)
    with pytest.raises(InvalidArgumentError, match="2-dimensional"):
        run(clsamp.make_sampler("random", d=3), "pmj_disk", [16], 10)
    with pytest.raises(InvalidArgumentError, match="'sampler' 'random' makes 3-dimensional"):
        run(clsamp.make_sampler("random", d=3), Gaussian(), [16], 10)
    with pytest.raises(InvalidArgumentError, match="'sampler'"):
        run(42, "gaussian", [16], 10)
    with pytest.raises(InvalidArgumentError, match="unknown sampler"):
        run("nosuch", "gaussian", [16], 10)
    with pytest.raises(InvalidArgumentError, match="'ns'"):
        parse_ns("16..4")


def test_parse_ns():
    assert parse_ns("16..65536") == [16, 64, 256, 1024, 4096, 16384, 65536]
    assert parse_ns("16..128:2") == [16, 32, 64, 128]
    assert parse_ns("4, 9,16") == [4, 9, 16]


# -- the command line ------------------------------------------------------------------
def test_cli_writes_plot_and_json(tmp_path):
    env = dict(os.environ, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    out = subprocess.run([sys.executable, "-m", "clsamp", "convergence", "--samplers",
                          "random,jittered,sobol:owen", "--integrand", "gaussian,disk", "--ns", "16..1024",
                          "--realizations", "40", "--no-progress", "-o", str(tmp_path / "conv.png")],
                         capture_output=True, text=True, env=env, cwd=ROOT, timeout=300)
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "conv.png").stat().st_size > 1000 and (tmp_path / "conv_time.png").exists()
    doc = json.loads((tmp_path / "conv.json").read_text())
    assert len(doc["results"]) == 6 and doc["ns"] == [16, 64, 256, 1024]
    assert doc["results"][0]["comparison"]["verdict"].split()[0] in ("matches", "pre-asymptotic",
                                                                      "differs", "unknown")
    assert "sobol:owen" in out.stdout
    bad = subprocess.run([sys.executable, "-m", "clsamp", "convergence", "--samplers", "jittered",
                          "--ns", "8", "-o", str(tmp_path / "x.png")],
                         capture_output=True, text=True, env=env, cwd=ROOT, timeout=300)
    assert bad.returncode == 2 and "nearest valid n is 9" in bad.stderr and "Traceback" not in bad.stderr


# -- published rates come from the samplers ----------------------------------------------
@pytest.mark.parametrize("name, params, best, worst", [
    ("uncorrelated_jitter", {"groups": (1, 1)}, -1.0, -1.0),      # a Latin hypercube
    ("uncorrelated_jitter", {}, -2.0, -1.5),                      # one group: jittered
    ("jittered", {"strata": (4096, 1)}, None, None),              # not k^2 square cells
    ("jittered", {"strata": (64, 64)}, -2.0, -1.5),
    ("ccvt", {"density": "random"}, None, None),                  # an N^-1 floor
    ("ccvt", {}, -3.0, -1.5),
    ("sobol", {"randomize": "xor"}, None, None),
    ("poisson_disk", {"radius": 0.05}, None, None),
])
def test_rates_follow_the_parameters(name, params, best, worst):
    s = clsamp.make_sampler(name, **params)
    assert theory.expected_rate(s, "best")[0] == best
    assert theory.expected_rate(s, "worst")[0] == worst


def test_a_result_carries_the_rates_of_its_sampler():
    s = clsamp.make_sampler("uncorrelated_jitter", groups=(1, 1), seed=1)
    res = run(s, "disk", [16, 64, 256], 64)
    assert res.rates["worst"] == (-1.0, "Stein 1987")
    cmp = theory.compare(res)
    assert cmp["expected"] == -1.0 and cmp["source"] == "Stein 1987"
    assert json.loads(json.dumps(res.to_dict()))["rates"]["worst"] == [-1.0, "Stein 1987"]
    # jittered in 3-D: the d-D rates
    assert theory.expected_rate("jittered", "best", d=3)[0] == pytest.approx(-1 - 2 / 3)


def test_the_table_in_the_theory_docstring_is_what_the_samplers_say():
    rows = [line.split() for line in theory.__doc__.splitlines()
            if line[:1].isalpha() and len(line.split()) > 3 and line.split()[1].startswith("-")]
    with_rates = set()
    for name in clsamp.sampler_names():
        try:
            s = clsamp.make_sampler(name, d=2)
        except InvalidArgumentError:          # a 1-D sampler
            continue
        if s.convergence_rate("best") is not None or s.convergence_rate("worst") is not None:
            with_rates.add(name)
    assert {row[0] for row in rows} == with_rates | {"sobol:owen"}
    for name, best, worst, *_ in rows:
        s = clsamp.make_sampler(name, d=2)
        assert theory.expected_rate(s, "best")[0] == float(best), name
        assert theory.expected_rate(s, "worst")[0] == float(worst), name


class _Fit:
    """A stand-in result: a given fit against the disk (worst case) of a sampler kind."""

    def __init__(self, kind, slope, stderr):
        self.kind, self.sampler, self._fit = kind, kind, (slope, stderr)
        self.traits, self.d, self.rates = {"smooth": False, "edges": "curved"}, 2, {}

    def rate(self):
        return self._fit


@pytest.mark.parametrize("slope, stderr, word", [
    (-1.05, 0.04, "matches"),            # 1.25 sigma
    (-1.15, 0.04, "pre-asymptotic"),     # 3.75 sigma, within 3 sigma + 0.15
    (-1.30, 0.04, "differs"),            # 7.5 sigma
    (-0.75, 0.02, "differs"),             # 12.5 sigma, beyond 3 sigma + 0.15
])
def test_the_verdict_says_how_far(slope, stderr, word):
    cmp = theory.compare(_Fit("poisson_disk", slope, stderr))
    assert cmp["verdict"].split()[0] == word
    assert cmp["distance"] == pytest.approx(slope + 1.0)
    assert cmp["sigmas"] == pytest.approx(abs(slope + 1.0) / stderr)
    side = "steeper" if slope < -1 else "shallower"
    assert f"{abs(slope + 1.0):.2f} {side} than N^-1" in cmp["verdict"]
    assert f"{cmp['sigmas']:.1f} standard errors" in cmp["verdict"]


def test_a_result_prints_in_two_lines():
    res = run("jittered", "disk", [16, 64, 256], 200)
    text = repr(res)
    assert text.count("\n") == 1 and len(text) < 300
    assert "jittered" in text and "disk" in text and "N = 16..256" in text and "theory N^-1.5" in text


def test_a_sampler_made_by_name_shows_no_bar_of_its_own():
    # bnot's own progress bar showed inside a sweep run with progress=False
    from clsamp.sweep import _sampler
    assert _sampler("bnot", 2, 0, "opencl")[0].progress is False
    assert clsamp.make_sampler("bnot").progress is True
