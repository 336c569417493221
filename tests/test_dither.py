"""Dither masks (issue 37): void and cluster (Ulichney 1993) in 1-4 dimensions and its
spatiotemporal variant (Wolfe et al. 2022): every rank once, progressive blue-noise
levels, low-frequency power far below white noise's, reproducible from the seed."""

import numpy as np
import pytest

import clsamp
from clsamp.errors import InvalidArgumentError
from clsamp.samplers import dither
from clsamp.samplers.dither import INITIAL_DENSITY, mask_spectrum


def _low(power, shape, below):
    """Mean power at integer frequencies 0 < |k| < below."""
    grids = np.meshgrid(*[np.fft.fftfreq(n) * n for n in shape], indexing="ij")
    f = np.sqrt(sum(g * g for g in grids))
    return power[(f > 0) & (f < below)].mean()


def _white(shape, seed=0):
    return np.random.default_rng(seed).permutation(int(np.prod(shape))).reshape(shape)


@pytest.mark.parametrize("size, d", [(64, 2), (128, 1), (16, 3), (8, 4)])
def test_every_rank_once_and_far_less_low_frequency_power_than_white_noise(size, d):
    mask = clsamp.dither_mask(size, d=d, seed=3)
    assert mask.shape == (size,) * d and mask.dtype == np.int64
    assert np.array_equal(np.sort(mask.ravel()), np.arange(size ** d))
    below = max(2, size / 8)
    blue = _low(mask_spectrum(mask), mask.shape, below)
    white = _low(mask_spectrum(_white(mask.shape)), mask.shape, below)
    assert white > 0.5 and blue < 0.02 * white, (blue, white)


def test_every_threshold_level_is_a_blue_pattern_holding_the_levels_below():
    mask = clsamp.dither_mask(64, seed=5)
    n = mask.size
    for level in (n // 16, n // 4, n // 2, 3 * n // 4):
        pattern = mask < level
        assert pattern.sum() == level
        # no two ones adjacent at the lowest level: the minimum spacing of a blue pattern
        if level == n // 16:
            ones = np.argwhere(pattern)
            gaps = np.abs(ones[:, None, :] - ones[None, :, :])
            gaps = np.minimum(gaps, 64 - gaps)
            d2 = (gaps ** 2).sum(-1) + np.eye(len(ones), dtype=int) * 10**6
            assert d2.min() >= 4          # ones at least two pixels apart (mean spacing 4)
        power = mask_spectrum(pattern.astype(float))
        assert _low(power, pattern.shape, 8) < 0.1
    assert INITIAL_DENSITY == 0.1


def test_the_same_seed_gives_the_same_mask_and_seeds_differ():
    a = clsamp.dither_mask(32, seed=11)
    assert np.array_equal(a, clsamp.dither_mask(32, seed=11))
    assert not np.array_equal(a, clsamp.dither_mask(32, seed=12))


def test_spatiotemporal_frames_are_blue_and_each_pixel_is_blue_in_time():
    frames, size = 16, 24
    mask = clsamp.dither_mask(size, seed=2, temporal=frames)
    assert mask.shape == (frames, size, size)
    assert np.array_equal(np.sort(mask.ravel()), np.arange(mask.size))
    white = _white(mask.shape)
    # each frame (its thresholds) blue in space
    space = _low(mask_spectrum(mask, axes=(1, 2)), (size, size), 4)
    assert space < 0.05 * _low(mask_spectrum(white, axes=(1, 2)), (size, size), 4)
    # each pixel's sequence over the frames blue in time: little power at 1 and 2 cycles
    time = mask_spectrum(mask, axes=(0,))
    assert time[1:3].mean() < 0.2 * mask_spectrum(white, axes=(0,))[1:3].mean()
    # a plain 3-D mask of the same shape is blue in 3-D, not per pixel in time as much
    plain = clsamp.dither_mask(size, d=3, seed=2)[:frames]
    assert mask_spectrum(plain, axes=(0,))[1:3].mean() > time[1:3].mean()


@pytest.mark.parametrize("kwargs, match", [
    ({"size": 1}, "'size' must be an integer >= 2"),
    ({"size": 0}, "'size' must be an integer >= 2"),
    ({"size": 8, "d": 5}, "'d' must be 1 to 4"),
    ({"size": 8, "temporal": 1}, "'temporal' must be an integer >= 2"),
    ({"size": 8, "temporal": 0}, "'temporal' must be an integer >= 2"),
    ({"size": 8, "sigma": 0}, "'sigma'"),
    ({"size": 8, "sigma": 1e-170}, "'sigma' must be >= 0.01"),
    ({"size": 8, "sigma": 1e200}, "'sigma' must be <= 1000000.0"),
    ({"size": 8, "sigma": True}, "'sigma' must be a real number"),
    ({"size": 8, "seed": -1}, "'seed'"),
    ({"size": 4096, "d": 3}, "'size' and 'd' give a mask of 68719476736 pixels .*; at most"),
    ({"size": 1024, "temporal": 64}, "'size', 'd' and 'temporal' give .*64 x 1024 x 1024"),
    ({"size": 8, "backend": "cuda"}, "'backend' must be one of"),
    ({"size": 8, "d": 0}, "'d' must be 1 to 4, got 0"),
    # accepted before and ran for hours to months: the pixels times the window bound the work
    ({"size": 4096, "sigma": 1e6}, "'size'=4096, 'd'=2, 'sigma'=1e\\+06: 16777216 pixels, each step "
     "updating a window of 16777216, make 2.81e\\+14 energy updates, more than 2\\^35"),
    ({"size": 64, "d": 4}, "window of 28561, make 4.79e\\+11 energy updates"),
    ({"size": 256, "d": 3}, "more than 2\\^35"),
    ({"size": 2048, "backend": "numpy"}, "'size'=2048: NumPy makes the mask here .backend='numpy'., "
     "an argmax over all 4194304 pixels a step, and takes at most 2\\^20 pixels"),
])
def test_bad_arguments_are_one_line_before_any_work(kwargs, match):
    with pytest.raises(InvalidArgumentError, match=match):
        clsamp.dither_mask(**kwargs)


def test_a_mask_too_large_for_numpy_is_refused_where_the_device_does_not_run_the_steps(monkeypatch):
    # a GPU, Oclgrind or llvmpipe left the default backend on NumPy's O(N^2) twin, which
    # took dither_mask(4096) (123 hours) without a word
    monkeypatch.setattr(dither, "_device_runs_it", lambda: False)
    with pytest.raises(InvalidArgumentError, match="this device does not run the steps"):
        clsamp.dither_mask(2048)


def test_an_integrated_gpu_does_not_run_the_steps(monkeypatch):
    # it shares the host's memory and may have fp64; one work-item for minutes on it was
    # unmeasured, and its watchdog may end the kernel
    import dataclasses

    from clsamp import runtime
    gpu = dataclasses.replace(runtime.current_device(), type="gpu", host_memory=True, fp64=True)
    monkeypatch.setattr(runtime, "current_device", lambda: gpu)
    assert not dither._device_runs_it()


# shapes with blocks of the device's trees left partly empty (49, 343 pixels), 1-D rings
# shorter than the window, windows wider than the grid (sigma 40), 4-D, and time
TWIN_CASES = [dict(size=16), dict(size=7), dict(size=64, d=1), dict(size=2, d=1), dict(size=2),
              dict(size=8, d=3), dict(size=7, d=3), dict(size=4, d=4), dict(size=5, d=4),
              dict(size=8, temporal=4), dict(size=16, temporal=8), dict(size=3, temporal=2),
              dict(size=24, sigma=0.5), dict(size=12, sigma=40.0), dict(size=6, d=3, temporal=3),
              dict(size=3, d=4, temporal=2), dict(size=48)]


@pytest.mark.parametrize("kwargs", TWIN_CASES,
                         ids=lambda k: "-".join(f"{a}{b}" for a, b in k.items()))
def test_the_device_gives_the_numpy_twins_ranks(kwargs):
    """kernels/dither.cl against _void_and_cluster (where the current device runs it)."""
    shape = ((kwargs["temporal"],) if "temporal" in kwargs else ()) + \
        (kwargs["size"],) * kwargs.get("d", 2)
    stencils = dither._mask_stencils(shape, "temporal" in kwargs, kwargs.get("sigma", dither.SIGMA))
    for seed in (0, 5):
        ones, initial = dither._initial_ones(int(np.prod(shape)), seed)
        twin = dither._void_and_cluster(dither._Energy(shape, stencils), int(np.prod(shape)), ones,
                                        initial)
        if dither._device_runs_it():
            device = dither._void_and_cluster_device(shape, stencils, initial[:ones])
            assert np.array_equal(device, twin)
        assert np.array_equal(np.sort(twin), np.arange(twin.size))
        # the public function, on either backend
        mask = clsamp.dither_mask(**kwargs, seed=seed)
        assert np.array_equal(mask.ravel(), twin)
        assert np.array_equal(clsamp.dither_mask(**kwargs, seed=seed, backend="numpy"), mask)
