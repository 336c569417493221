"""Convergence experiments without fp64 (kernels/experiments_ff.cl, clsamp.experiments_ff):
every integrand and every family in float-float within the stated bound of the fp64
errors, realization by realization, and the MSE within what that bound allows. With fp64
on PoCL (``precision="float-float"``), under ``runtime.without_fp64()`` (the same bits:
what a device without fp64 runs) and on a real device without fp64 where one is installed
(Mesa's rusticl on llvmpipe)."""

import numpy as np
import pytest

import clsamp
from clsamp import families, runtime
from clsamp.errors import InvalidArgumentError, NoDeviceError
from clsamp.experiments_ff import constants, error_bound
from clsamp.float_float import join
from clsamp.integrands import Integrand, make_integrand
from clsamp.integrands.base import Gaussian
from clsamp.integrands.qmc import GENZ_KINDS, genz, keister

DEFAULT = runtime.current_device()
WITHOUT_FP64 = [d for d in runtime.devices()
                if not d.fp64 and not d.simulator and runtime.compiles(d.index)]

NAMED = ["gaussian", "disk", "heaviside", "pmj_disk", "pmj_gaussian", "pmj_bilinear", "pmj_step",
         "pmj_triangle"]


def _targets():
    out = [(name, make_integrand(name)) for name in NAMED]
    out += [(f"genz_{kind}_{d}", genz(kind, d, seed=d)) for kind in GENZ_KINDS for d in (1, 3)]
    out += [("gaussian_3d_narrow", Gaussian(center=(0.2, 0.9, 0.5), sigma=0.03))]
    return out + [("keister_1", keister(1)), ("keister_5", keister(5))]


def _errors(result):
    return np.asarray(result.errors)


def _both(sampler, target, ns, realizations, homogenize=True):
    kw = dict(realizations=realizations, homogenize=homogenize, seed=4, progress=False)
    want = clsamp.convergence(sampler, target, ns, precision="double", **kw)
    got = clsamp.convergence(sampler, target, ns, precision="float-float", **kw)
    return want, got


def _within(want, got, target, ns):
    for k, n in enumerate(ns):
        diff = np.abs(_errors(got)[k] - _errors(want)[k])
        assert np.all(diff <= error_bound(target, n)), (n, diff.max(), error_bound(target, n))


@pytest.mark.parametrize("name,target", _targets(), ids=[t[0] for t in _targets()])
@pytest.mark.parametrize("homogenize", [True, False])
def test_every_integrand_in_float_float_is_within_its_bound(name, target, homogenize):
    """Sets that fill part of a work-group's slice, one slice, and several groups."""
    ns = [7, 256, 4100]
    want, got = _both("sobol:owen", target, ns, 4, homogenize)
    _within(want, got, target, ns)
    assert got.device.endswith("(float-float)") and not want.device.endswith("(float-float)")


def test_the_quantile_of_zero_and_the_tails():
    """Unscrambled Sobol' starts at 0 (AS 241 takes it as 2^-1022) and reaches 1 - 2^-k."""
    f = keister(3)
    want, got = _both("sobol", f, [16, 1024], 2, homogenize=False)
    _within(want, got, f, [16, 1024])


@pytest.mark.parametrize("name", families.family_names())
@pytest.mark.parametrize("d", [1, 2, 4])
def test_every_family_in_float_float_is_within_its_bound(name, d):
    fam = families.make_family(name, d=d, members=9, seed=d)
    ns = [5, 300, 4097]
    want, got = _both("random", fam, ns, 3)
    _within(want, got, fam, ns)


def test_a_family_over_more_than_one_chunk():
    """2^16 + 5 points: two chunks a member, added on the host."""
    fam = families.make_family("random_clipped_gaussians", d=2, members=5, seed=1)
    want, got = _both("random", fam, [2**16 + 5], 2)
    _within(want, got, fam, [2**16 + 5])


def test_the_mse_of_a_good_sampler_at_large_n_is_resolved():
    """Owen-scrambled Sobol' on the smooth Gaussian at n = 2^14: the MSE is about 1e-12 of
    the squared scale, and float-float keeps it to 2 B sqrt(MSE) + B^2 of the fp64 MSE."""
    f = make_integrand("gaussian")
    want, got = _both("sobol:owen", f, [2**14], 32)
    b = error_bound(f, 2**14)
    mse = want.mse[0]
    assert mse < 1e-9
    assert abs(got.mse[0] - mse) <= 2 * b * np.sqrt(mse) + b * b
    assert abs(got.mse[0] / mse - 1) < 1e-3


def test_without_fp64_the_default_is_float_float_with_the_same_bits():
    fam = families.make_family("random_gaussians", d=3, members=6, seed=2)
    for target in (keister(2), make_integrand("disk"), fam):
        ff = clsamp.convergence("halton:owen", target, [64, 300], realizations=3, progress=False,
                                precision="float-float")
        with runtime.without_fp64():
            got = clsamp.convergence("halton:owen", target, [64, 300], realizations=3, progress=False)
        assert np.array_equal(_errors(got), _errors(ff))
        assert got.device.endswith("(float-float)")


def test_precision_is_checked_in_one_line():
    with pytest.raises(InvalidArgumentError, match="'precision' must be one of"):
        clsamp.convergence("random", "gaussian", [16], realizations=2, progress=False, precision="single")
    with runtime.without_fp64(), pytest.raises(NoDeviceError, match="'precision' 'double' needs fp64"):
        clsamp.convergence("random", "random_disks", [16], realizations=2, members=4, progress=False,
                           precision="double")
    f = Integrand.from_opencl("x[0] * x[1]", 2, integral=0.25)
    with pytest.raises(InvalidArgumentError, match="cannot evaluate integrand 'opencl'.*computes in double"):
        clsamp.convergence("random", f, [16], realizations=2, progress=False, precision="float-float")
    # the NumPy reference computes in float64 whatever precision says
    res = clsamp.convergence("random", f, [16], realizations=2, progress=False, precision="float-float",
                             backend="numpy")
    assert res.device == "numpy"


def test_the_constants_are_the_float64_ones_to_within_u2():
    c = constants()
    assert c.shape == (88, 2)
    assert abs(join(c[33]) + float(c[34, 0]) - np.pi / 2) <= 2.0**-70
    assert abs(join(c[23]) - 1.0) == 0 and abs(join(c[32]) - 1.0) == 0      # the constant terms
    assert abs(join(c[35]) - 1 / np.pi) <= 2.0**-49 / np.pi


def test_the_kernel_uses_no_double_without_fp64():
    assert not runtime.needs_fp64("experiments_ff.cl")
    assert runtime.capabilities()["experiments in float-float"] is None


@pytest.mark.parametrize("device", WITHOUT_FP64, ids=lambda d: f"{d.index}-{d.platform[:12]}")
def test_a_device_without_fp64_runs_the_experiments_in_float_float(device):
    """llvmpipe stops a work-item's loops after 65535 iterations: the kernels split long
    sums there (a family's 20000 points, Keister's 8-D quantiles)."""
    fam = families.make_family("random_gaussians", d=3, members=6, seed=3)
    cases = [(keister(8), [4096]), (genz("oscillatory", 2, seed=1), [100, 3000]), (fam, [20000])]
    want = [clsamp.convergence("random", t, ns, realizations=2, progress=False) for t, ns in cases]
    runtime.use_device(device.index)
    try:
        got = [clsamp.convergence("random", t, ns, realizations=2, progress=False) for t, ns in cases]
    finally:
        runtime.use_device(DEFAULT.index)
    for (target, ns), a, b in zip(cases, want, got, strict=True):
        _within(a, b, target, ns)


def test_integrate_in_float_float():
    """The replications of an integrand at the sampler's points in float-float: each round's
    estimate within the bound of the fp64 one (the same points), and the same rounds."""
    f = keister(3)
    kw = dict(abs_tol=1e-3, progress=False, sampler=clsamp.make_sampler("sobol", d=3, randomize="owen"))
    want = clsamp.integrate(f, 3, precision="double", **kw)
    got = clsamp.integrate(f, 3, precision="float-float", **kw)
    assert got.n == want.n and abs(got.estimate - want.estimate) <= error_bound(f, got.n)
    with runtime.without_fp64():
        assert clsamp.integrate(f, 3, **kw).estimate == got.estimate
        with pytest.raises(InvalidArgumentError, match="'method' 'digital' evaluates an integrand in double"):
            clsamp.integrate(f, 3, abs_tol=1e-3, method="digital", progress=False)


def test_integrands_beyond_floats_range_are_refused_by_name():
    from clsamp.integrands.qmc import Genz
    f = Genz("discontinuous", [60.0, 40.0], [0.9, 0.9])
    with pytest.raises(InvalidArgumentError, match="'genz_discontinuous': its values reach .*beyond float's"):
        clsamp.convergence("random", f, [16], realizations=2, progress=False, precision="float-float")
    steep = Genz("corner_peak", [40.0] * 16, [0.5] * 16)         # t^17 passes float's range
    want, got = _both("random", steep, [64], 2)
    _within(want, got, steep, [64])
