"""Integrands on the device: Integrand.from_opencl, and the fused kernels that make the
points where they evaluate f (clsamp.fused), against the NumPy integrands on the same points."""

import re
import warnings

import numpy as np
import pyopencl
import pytest

import clsamp
from clsamp import fused
from clsamp.cubature import Cubature
from clsamp.fused import FusedRule
from clsamp.integrands import GENZ_KINDS, Integrand, OpenCLIntegrand, genz, keister
from clsamp.integrands.device import device_values
from clsamp.transforms import to_normal

# Device against NumPy, same points: OpenCL's cos, exp and log are within a few ulps of
# NumPy's (seen: 1.5e-15 relative for Keister, 2.2e-16 for the Genz families), so the
# tolerance is |device - numpy| <= TOL (|numpy| + scale), scale = pi^(d/2) for Keister
# (its values cancel around cos = 0), 1 otherwise.
TOL = 1e-14


def _scale(f):
    return f.scale if f.name == "keister" else 1.0


def _cases():
    return [keister(4), keister(8)] + [genz(kind, 5, seed=2) for kind in GENZ_KINDS]


@pytest.fixture(scope="module")
def points():
    return clsamp.make_sampler("random", d=8, seed=11).sample(3000)


# -- from_opencl -------------------------------------------------------------------------
def test_from_opencl_three_forms_agree(points):
    x = points[:, :3]
    want = np.exp(-x[:, 0] * x[:, 1]) + x[:, 2]
    forms = ["exp(-x[0] * x[1]) + x[2]",
             "double t = -x[0] * x[1];\nreturn exp(t) + x[2];",
             "double helper(double a) { return exp(a); }\n"
             "double f(const double *x) { return helper(-x[0] * x[1]) + x[2]; }"]
    for source in forms:
        f = Integrand.from_opencl(source, 3)
        assert isinstance(f, OpenCLIntegrand) and f.d == 3 and f.integral is None
        np.testing.assert_allclose(f(x), want, rtol=TOL, atol=TOL)
        assert f(x[None]).shape == (1, len(x))


def test_from_opencl_to_normal_is_the_transform(points):
    f = Integrand.from_opencl("to_normal(x[0])", 1, name="normal quantile")
    u = np.concatenate([points[:, 0], [0.0, 1e-300, 0.5, 0.975, 1 - 2**-53]])
    z = to_normal(u)
    # the same AS 241 in the same order: equal but for the device's log in the tails
    np.testing.assert_allclose(f(u[:, None]), z, rtol=4e-16, atol=0)
    assert f.name == "normal quantile" and "normal quantile" in f.describe()


@pytest.mark.parametrize("source, d, message", [
    (3, 2, "'source' must be OpenCL C"),
    ("   ", 2, "'source' must be OpenCL C"),
    ("x[0]", 0, "'d'"),
    ("x[0]", 2.5, "'d'"),
    ("x[0] * y", 2, "'source' does not compile for d=2: source:1:8: error:"),
    ("double f(const double *x)\n{\n    return x[0] +;\n}", 2, "source:3:"),
])
def test_from_opencl_refuses_bad_input(source, d, message):
    with pytest.raises(clsamp.InvalidArgumentError, match=re.escape(message)) as info:
        Integrand.from_opencl(source, d)
    assert "\n" not in str(info.value)


def test_from_opencl_refuses_bad_integral():
    with pytest.raises(clsamp.InvalidArgumentError, match="'integral'"):
        Integrand.from_opencl("x[0]", 1, integral=float("nan"))


# -- the shipped integrands on the device ------------------------------------------------
@pytest.mark.parametrize("f", _cases(), ids=lambda f: f"{f.name}-{f.d}")
def test_device_integrand_equals_numpy(f, points):
    x = points[:, :f.d]
    x = np.concatenate([x, np.zeros((1, f.d)), np.full((1, f.d), 1 - 2**-53)])
    got = device_values(f, x)
    want = f(x)
    assert np.all(np.abs(got - want) <= TOL * (np.abs(want) + _scale(f)))


# -- fused points: the samplers' bits ----------------------------------------------------
@pytest.mark.parametrize("randomize", ["owen", "xor", "shift"])
@pytest.mark.parametrize("f", [keister(4), genz("gaussian", 3, seed=1)], ids=lambda f: f.name)
def test_fused_sums_equal_numpy_at_the_sampler_points(f, randomize):
    start, count = 40, 1500           # crosses work-item blocks and ends mid-quad
    x = clsamp.make_sampler("sobol", d=f.d, randomize=randomize, seed=3).sample(
        count, realizations=range(2, 5), start=start)
    want = np.sum(f(x) - f.integral, axis=1)
    got = FusedRule(f, "sobol", 3, randomize).sums(count, start, range(2, 5))
    assert np.all(np.abs(got - want) <= TOL * np.sum(np.abs(f(x)) + _scale(f), axis=1))


@pytest.mark.parametrize("method, periodization", [("digital", "none"), ("lattice", "none"),
                                                   ("lattice", "baker"), ("lattice", "sidi")])
def test_fused_values_equal_the_cubature_points(method, periodization):
    f = keister(3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        want = Cubature(f, 3, method, 5, periodization)._block(1024, 1024)
    got = FusedRule(f, method, 5, periodization=periodization).values(1024, 1024)
    assert np.all(np.abs(got - want) <= TOL * (np.abs(want) + f.scale))


@pytest.mark.parametrize("d", [3, 6, 11, 17])
def test_fused_points_with_padded_rows_are_the_samplers(d):
    # the kernel's Sobol' tables have rows of 4, 8, 16 words for d = 3, 6, 11 (zeros past
    # d), 17 unpadded: every coordinate still the sampler's, in both orders
    f = Integrand.from_opencl(" + ".join(f"{j + 1}.0 * x[{j}]" for j in range(d)), d)
    weights = np.arange(1, d + 1, dtype=np.float64)
    for kind, randomize in (("digital", "xor"), ("sobol", "owen")):
        if kind == "digital":
            x = clsamp.make_sampler("digital_net", d=d, seed=3, randomize="lms+shift").sample(
                512, start=512)
            got = FusedRule(f, kind, 3).values(512, 512)
        else:
            x = clsamp.make_sampler("sobol", d=d, seed=3, randomize=randomize).sample(512)
            got = FusedRule(f, kind, 3, randomize).sums(512, 0, range(1)) / 512
            np.testing.assert_allclose(got, [np.mean(x @ weights)], rtol=1e-13)
            continue
        np.testing.assert_allclose(got, np.minimum(x, 1.0 - 2.0**-53) @ weights, rtol=1e-14)


def test_user_integrand_fuses_with_a_chunked_launch(monkeypatch):
    monkeypatch.setattr(fused, "CHUNK", 512)
    f = Integrand.from_opencl("x[0] * x[1] + x[2] * x[2]", 3)
    x = clsamp.make_sampler("sobol", d=3, randomize="owen", seed=4).sample(2000, realizations=2)
    want = np.sum(x[..., 0] * x[..., 1] + x[..., 2] ** 2, axis=1)
    np.testing.assert_allclose(FusedRule(f, "sobol", 4, "owen").sums(2000, 0, range(2)), want,
                               rtol=1e-14)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        cube = Cubature(f, 3, "digital", 4)._block(0, 2048)
    np.testing.assert_allclose(FusedRule(f, "digital", 4).values(0, 2048), cube, rtol=1e-15)


def test_values_written_on_the_device_equal_those_read_back(monkeypatch):
    # FusedRule.fill (the values stay on the device for the Walsh state) against
    # FusedRule.values uploaded again: the same steps, bit for bit, with launches of 2^11
    # points writing into regions of one buffer
    from clsamp import cubature
    monkeypatch.setattr(fused, "CHUNK", 2**11)
    monkeypatch.setattr(cubature, "DEVICE_FROM", 2**11)
    f = genz("oscillatory", 4, seed=3)
    rule = FusedRule(f, "digital", 6)
    runs = []
    for fill in (None, rule.fill):
        c = Cubature(None, 4, "digital", 6, block=rule.values, device=True, fill=fill)
        runs.append([c.step() for _ in range(6)])
        assert c.walsh is not None and c.n == 2**15
    assert runs[0] == runs[1]


# -- integrate with them -----------------------------------------------------------------
@pytest.mark.parametrize("method", ["digital", "lattice", "replications"])
def test_integrate_device_integrand_matches_numpy(method):
    f = genz("gaussian", 3, seed=1)
    kw = dict(abs_tol=1e-5, method=method, progress=False, seed=2)
    device = clsamp.integrate(f, 3, **kw)
    host = clsamp.integrate(lambda x: f(x), 3, **kw)
    assert device.n == host.n and device.converged and host.converged
    assert abs(device.estimate - host.estimate) <= 1e-12
    assert abs(device.estimate - f.integral) <= 1e-5
    a, u = (", ".join(repr(float(v)) for v in vector) for vector in (f.a, f.u))
    g = Integrand.from_opencl(
        "double s = 0.0;\nfor (int j = 0; j < 3; ++j) {\n"
        f"    const double a[3] = {{{a}}}, u[3] = {{{u}}};\n"
        "    const double w = a[j] * (x[j] - u[j]);\n    s = s + w * w;\n}\nreturn exp(-s);", 3)
    user = clsamp.integrate(g, 3, **kw)
    assert user.n == device.n and abs(user.estimate - device.estimate) <= 1e-12


class _Allocations:
    """The sizes of the OpenCL buffers made while it is on (pyopencl.Buffer wrapped)."""

    def __init__(self, monkeypatch):
        self.sizes = []
        real = pyopencl.Buffer

        def buffer(context, flags, size=0, hostbuf=None):
            self.sizes.append(int(size) if hostbuf is None else int(np.asarray(hostbuf).nbytes))
            return real(context, flags, size, hostbuf) if hostbuf is not None else real(context, flags, size)

        monkeypatch.setattr(pyopencl, "Buffer", buffer)


@pytest.mark.parametrize("method", ["digital", "replications"])
def test_integrate_never_allocates_the_points(monkeypatch, method):
    # replications: device memory O(1) in n: with launches of at most CHUNK points, the
    # largest buffer a call makes does not grow with n, while n * d doubles of points would.
    # digital: the Walsh coefficients live on the device (cubature_device), one double a
    # point, never the d coordinates of the points
    from clsamp import cubature
    monkeypatch.setattr(fused, "CHUNK", 2**11)
    monkeypatch.setattr(cubature, "DEVICE_FROM", 2**11)
    f = keister(4)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        clsamp.integrate(f, 4, abs_tol=1e-12, max_n=2**12, method=method, progress=False)  # builds
    largest = {}
    for max_n in (2**12, 2**16):
        log = _Allocations(monkeypatch)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            res = clsamp.integrate(f, 4, abs_tol=1e-12, max_n=max_n, n_start=2**10, method=method,
                                   progress=False)
        assert not res.converged and res.n * (res.replications) >= max_n
        largest[max_n] = max(log.sizes)
        monkeypatch.undo()
        monkeypatch.setattr(fused, "CHUNK", 2**11)
        monkeypatch.setattr(cubature, "DEVICE_FROM", 2**11)
    if method == "replications":
        assert largest[2**16] == largest[2**12] <= 8 * 2**11
    else:
        # the coefficients (on the device from 2^12 points here) are the largest buffer
        assert largest[2**12] <= 8 * 2**12 and 8 * 2**15 <= largest[2**16] <= 8 * 2**16
    # the same measurement sees the points of a NumPy integrand
    log = _Allocations(monkeypatch)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        clsamp.integrate(lambda x: f(x), 4, abs_tol=1e-12, max_n=2**16, method="digital",
                         progress=False)
    assert max(log.sizes) >= 8 * 4 * 2**15


def test_convergence_accepts_a_device_integrand():
    f = Integrand.from_opencl("x[0] * x[1]", 2, integral=0.25, name="bilinear")
    res = clsamp.convergence("sobol:owen", f, [16, 64], realizations=64, progress=False)
    ref = clsamp.convergence("sobol:owen", clsamp.integrands.PMJBilinear(), [16, 64],
                             realizations=64, progress=False)
    np.testing.assert_allclose(res.mse, ref.mse, rtol=1e-9)
    assert res.integrand == "bilinear"
    with pytest.raises(clsamp.InvalidArgumentError, match="integral"):
        clsamp.convergence("sobol:owen", Integrand.from_opencl("x[0]", 2), [16], realizations=8,
                           progress=False)
