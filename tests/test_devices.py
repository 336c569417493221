"""Every OpenCL device found, against the default one: the same bits where the contract says
bits (every sampler and randomization, a convergence experiment), the stated tolerance where
it says so (spectra, metrics, the float32 renderer). A device without fp64 gives every
sampler's bits too (poisson_disk's distances by kernels/f64bits.h, ccvt's in exact integers),
but those that compute in double (needs_fp64), and refuses those and the analyses with
NoDeviceError, never a BuildError, but for what it computes in float-float (spectra, the L2
discrepancies, the PCF and nearest neighbours) or exactly (the star discrepancy's certified
bounds, tests/test_float_float.py; its exact value, tests/test_star_without_fp64.py); so
does a device that lacks what a kernel needs (lloyd's and ccvt's 64-bit atomics) or stops
long loops (llvmpipe: pmj02bn, lloyd, ccvt, poisson_disk). CI installs Debian's PoCL and
Mesa's rusticl beside PyPI's PoCL, and Intel's CPU runtime from PyPI (.ci/run; registered by
scripts/ensure-opencl.sh), so four implementations meet here; with one device the module is
skipped. Oclgrind, a simulator, is left out: tests/test_oclgrind.py runs every kernel on it
at sizes an interpreter manages, against the NumPy twins."""

import numpy as np
import pytest

import clsamp
from clsamp import runtime
from clsamp.errors import NoDeviceError
from clsamp.metrics import discrepancy, pair_correlation
from clsamp.render import render
from clsamp.samplers import sampler_class
from clsamp.scene import Scene
from clsamp.spectrum import power_spectrum

DEFAULT = runtime.current_device()
# (a simulator interprets kernels thousands of times slower: tests/test_oclgrind.py has it)
OTHERS = [d for d in runtime.devices()
          if d.index != DEFAULT.index and not d.simulator and runtime.compiles(d.index)]
WITH_FP64 = [d for d in OTHERS if d.fp64]
WITHOUT_FP64 = [d for d in OTHERS if not d.fp64]
pytestmark = pytest.mark.skipif(not OTHERS, reason="one usable OpenCL device: nothing to compare")


def _label(device):
    return f"{device.index}-{device.platform[:12]}"


def on(device, fn):
    """fn() computed on ``device``, the default device restored after."""
    runtime.use_device(device.index)
    try:
        return fn()
    finally:
        runtime.use_device(DEFAULT.index)


def _samplers():
    cases = []
    for name in clsamp.sampler_names():
        cls = sampler_class(name)
        d = 2 if cls.dimensions is None or 2 in cls.dimensions else cls.dimensions[0]
        for randomize in cls.randomizations:
            cases.append((name, d, randomize))
    return cases


def _make(name, d, randomize):
    params = {"randomize": randomize} if randomize is not None else {}
    return clsamp.make_sampler(name, d=d, seed=5, **params)


def _points(name, d, randomize):
    s = _make(name, d, randomize)
    return s.sample(s.valid_n(64), realizations=range(1, 3))


def refusal(device, name):
    """The NoDeviceError message pattern with which ``device`` refuses sampler ``name``,
    or None where it runs it."""
    if not device.fp64 and sampler_class(name).needs_fp64:
        return "fp64|double"
    if name in ("pmj02bn", "poisson_disk") and on(device, runtime.loop_limit) is not None:
        return "loops"
    # exact integers, no fp64: 64-bit atomics and long loops instead
    if name in ("lloyd", "ccvt") and ("cl_khr_int64_base_atomics" not in device.extensions
                                      or on(device, runtime.loop_limit) is not None):
        return "cl_khr_int64_base_atomics|loops"
    return None


@pytest.mark.parametrize("device", OTHERS, ids=_label)
@pytest.mark.parametrize("name, d, randomize", _samplers())
def test_every_sampler_gives_the_same_bits(device, name, d, randomize):
    """With or without fp64: the samplers without double arithmetic build their float64
    coordinates by integers there (kernels/f64bits.h); the others refuse by name."""
    why = refusal(device, name)
    if why is not None:
        with pytest.raises(NoDeviceError, match=why):
            on(device, lambda: _points(name, d, randomize))
        return
    here = _points(name, d, randomize)
    there = on(device, lambda: _points(name, d, randomize))
    assert np.array_equal(here.view(np.uint64), there.view(np.uint64)), (name, randomize, str(device))


@pytest.mark.parametrize("device", OTHERS, ids=_label)
def test_bnot_exact_cells_give_the_same_bits(device):
    """bnot's cells="exact" clips its cells in double (kernels/bnot_cells.cl): the same
    sets on every fp64 device, a refusal by name elsewhere."""
    def points():
        return clsamp.make_sampler("bnot", seed=5, cells="exact", iterations=4,
                                   progress=False).sample(300, realizations=range(1, 3))
    if not device.fp64:
        with pytest.raises(NoDeviceError, match="fp64|double"):
            on(device, points)
        return
    assert np.array_equal(points().view(np.uint64), on(device, points).view(np.uint64))


@pytest.mark.parametrize("device", OTHERS, ids=_label)
def test_dither_masks_give_the_same_ranks(device):
    """dither_mask's void and cluster (kernels/dither.cl, one work-item) where a device
    shares the host's memory and does fp64 and long loops, NumPy elsewhere: the same ranks."""
    def masks():
        return clsamp.dither_mask(13, seed=4), clsamp.dither_mask(6, seed=4, temporal=5)
    for here, there in zip(masks(), on(device, masks), strict=True):
        assert np.array_equal(here, there)


@pytest.mark.parametrize("device", OTHERS, ids=_label)
@pytest.mark.parametrize("name, params, n", [
    ("sot", {"d": 3, "iterations": 6, "projections": "pairs"}, 513),
    ("gbn", {"d": 4, "iterations": 3}, 300),
    ("gbn", {"d": 2, "iterations": 40, "tol": 3e-3}, 513)])
def test_float_optimizers_give_the_same_bits_past_a_groups_tail(device, name, params, n):
    """Sizes where a work-group's tail holds a lone work-item: Intel's compiler summed such
    an item's terms in partial sums until kernels/in_order.h forbade it; the histories
    (sot's costs, gbn's energies) as well. The 2-D gbn run's sets stop apart (CPU devices
    keep its iterations on the device: exact sums, the step control, the counting sort)."""
    def run():
        pts, info = clsamp.make_sampler(name, seed=5, **params).sample(
            n, realizations=2, return_info=True)
        return pts, info.cost_history if name == "sot" else info.energy_history
    if not device.fp64:
        with pytest.raises(NoDeviceError, match="fp64|double"):
            on(device, run)
        return
    for here, there in zip(run(), on(device, run), strict=True):
        assert np.array_equal(here.view(np.uint64), there.view(np.uint64)), (name, str(device))


# many dimensions, or permutations longer than 65535: a work-item's loops exceed llvmpipe's
# loop limit unless the runtime splits them (runtime.dimension_split, the swaps in pieces)
WIDE = [("halton", 300, None, 256), ("halton", 300, "owen", 256), ("halton", 300, "permute", 64),
        ("sobol", 1000, "shift", 256), ("random", 3000, None, 64),
        ("latin_hypercube", 1000, None, 100), ("uncorrelated_jitter", 1001, None, 64),
        ("latin_hypercube", 2, None, 70000), ("multijittered", 2, None, 2**18),
        ("kronecker", 256, "shift", 128), ("lattice", 250, None, 128)]


@pytest.mark.parametrize("device", OTHERS, ids=_label)
@pytest.mark.parametrize("name, d, randomize, n", WIDE)
def test_many_dimensions_give_the_same_bits(device, name, d, randomize, n):
    params = {"randomize": randomize} if randomize is not None else {}
    if name == "uncorrelated_jitter":
        params["groups"] = (2,) * 500 + (1,)
    s = clsamp.make_sampler(name, d=d, seed=2, **params)
    here = s.sample(n, realizations=2)
    there = on(device, lambda: s.sample(n, realizations=2))
    assert np.array_equal(here.view(np.uint64), there.view(np.uint64))


@pytest.mark.parametrize("device", WITHOUT_FP64, ids=_label)
@pytest.mark.parametrize("d, params", [(2, {"radius": 0.12}), (3, {"radius": 0.25}), (2, {}),
                                       (5, {})])
def test_poisson_disk_without_fp64_gives_the_same_bits(monkeypatch, device, d, params):
    """The dart-throwing kernels' integer path (kernels/f64bits.h) built by the device's own
    compiler: the bits of the default device. Sets this small stay far below llvmpipe's
    loop limit, which the sampler otherwise refuses."""
    monkeypatch.setattr(runtime.discovery, "loop_limit", lambda: None)
    s = clsamp.make_sampler("poisson_disk", d=d, seed=6, **params)

    def sets():
        return s.sample_sets(2) if params else list(s.sample(48, realizations=2))

    here, there = sets(), on(device, sets)
    assert [len(p) for p in here] == [len(p) for p in there]
    assert all(np.array_equal(a.view(np.uint64), b.view(np.uint64)) for a, b in zip(here, there, strict=True))


@pytest.mark.parametrize("device", OTHERS, ids=_label)
def test_owen_halton_past_the_loop_limit_refuses_by_name(device):
    s = clsamp.make_sampler("halton", d=310, seed=2, randomize="owen")
    if on(device, runtime.loop_limit) is None:
        assert on(device, lambda: s.sample(16)).shape == (16, 310)
    else:
        with pytest.raises(NoDeviceError, match="loops after"):
            on(device, lambda: s.sample(16))


def _experiment():
    res = clsamp.convergence(clsamp.make_sampler("jittered", seed=2), "disk", [16, 64, 256],
                             realizations=64, progress=False)
    return np.concatenate([np.ravel(e) for e in res.errors])        # every estimate's error


@pytest.mark.parametrize("device", WITH_FP64, ids=_label)
def test_a_convergence_experiment_gives_the_same_bits(device):
    assert np.array_equal(_experiment(), on(device, _experiment))


@pytest.mark.parametrize("device", WITH_FP64, ids=_label)
def test_the_walsh_state_and_a_device_integrand_agree(device, monkeypatch):
    # kernels/walsh.cl from the host's values: the same bits; a device integrand's values
    # (fused_integrals.cl in 3-D, normal.h) written into it: the libm's last bits apart
    from clsamp import cubature
    from clsamp.cubature import Cubature
    from clsamp.integrands import keister
    monkeypatch.setattr(cubature, "DEVICE_FROM", 2**11)

    def walsh(method):
        rule = Cubature(lambda x: np.exp(np.sum(x, axis=1)) * np.cos(9.0 * x[:, 0]), 3, method, 4,
                        device=True)
        return [rule.step() for _ in range(5)], rule.coefficients, rule.kappa

    def fused():
        res = clsamp.integrate(keister(3), 3, abs_tol=1e-4, method="digital", seed=2, progress=False)
        return res.n, res.estimate, res.half_width

    for method in ("digital", "lattice"):            # a lattice: its ordering on the device
        here, there = walsh(method), on(device, lambda m=method: walsh(m))
        assert here[0] == there[0] and np.array_equal(here[2], there[2])
        assert np.array_equal(here[1].view(np.uint64), there[1].view(np.uint64))
    here, there = fused(), on(device, fused)
    assert here[0] == there[0]
    np.testing.assert_allclose(here[1:], there[1:], rtol=1e-12)


@pytest.mark.parametrize("device", WITH_FP64, ids=_label)
def test_spectra_and_metrics_agree_to_their_stated_tolerance(device):
    pts = clsamp.make_sampler("jittered", seed=3).sample(1024, realizations=4)
    n = pts.shape[1]

    def analyses():
        direct = power_spectrum(pts, resolution=64, method="direct", progress=False)
        fast = power_spectrum(pts, resolution=64, method="fast", tol=1e-6, progress=False)
        return direct, fast, discrepancy(pts, "CD"), pair_correlation(pts)[1]

    here, there = analyses(), on(device, analyses)
    assert np.max(np.abs(here[0] - there[0])) <= 4e-15 * n * 4      # both exact to ~4e-15 N
    assert np.max(np.abs(here[1] - there[1])) <= 2 * 1e-6 * n       # each within tol N
    np.testing.assert_allclose(here[2], there[2], rtol=1e-12)
    np.testing.assert_allclose(here[3], there[3], rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("device", WITH_FP64, ids=_label)
def test_a_render_agrees_to_the_float32_tolerance(device):
    scene = Scene.from_file("ao")

    def image():
        return render(scene, "random", spp=4, resolution=16, progress=False)

    assert np.max(np.abs(image() - on(device, image))) <= 2e-5 * 4


@pytest.mark.parametrize("device", WITHOUT_FP64, ids=_label)
def test_a_device_without_fp64_refuses_what_needs_it_by_name(device):
    scene = Scene.from_file("ao")
    pts = np.random.default_rng(1).random((64, 2))
    calls = [lambda name=name, d=d, r=r: _points(name, d, r) for name, d, r in _samplers()
             if sampler_class(name).needs_fp64]
    calls += [lambda: power_spectrum(pts, resolution=32, method="direct", precision="double", progress=False),
              lambda: power_spectrum(pts, resolution=32, method="fast", tol=1e-3, precision="double",
                                     progress=False),
              lambda: discrepancy(pts, "CD", precision="double"),
              lambda: render(scene, "random", spp=1, resolution=8, progress=False)]
    assert len(calls) > 4
    for call in calls:
        with pytest.raises(NoDeviceError, match="fp64|double"):
            on(device, call)
    runs = runtime.capabilities(device.index)
    running = ["samplers", "distance samplers", "certified star-discrepancy bounds",
               "exact star discrepancy"] + [
        name for name in runs if name.endswith("in float-float")]
    assert len(running) >= 5
    assert all(runs[name] is None for name in running)
    assert {why for name, why in runs.items() if name not in running} == {"needs fp64"}
