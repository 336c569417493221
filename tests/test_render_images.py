"""Rectangular images, the reference's measured noise, and the error spectrum."""

import numpy as np
import pytest

from clsamp import render as rendering
from clsamp.errors import InvalidArgumentError
from clsamp.scene import Scene


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("CLSAMP_CACHE", str(tmp_path / "cache"))


# -- rectangular images -------------------------------------------------------------------------
def test_width_and_height_give_an_image_of_shape_height_width():
    scene = Scene.from_file("combined")
    wide = rendering.render(scene, "jittered", 16, (12, 5), seed=3, progress=False)
    assert wide.shape == (5, 12) and np.isfinite(wide).all()
    square = rendering.render(scene, "jittered", 16, 7, seed=3, progress=False)
    np.testing.assert_array_equal(square, rendering.render(scene, "jittered", 16, (7, 7), seed=3,
                                                           progress=False))


@pytest.mark.parametrize("size, offset", [((24, 16), (0, 4)), ((10, 16), (3, 0))])
def test_a_rectangle_holds_the_square_image_where_they_overlap(size, offset):
    # pbrt's film: the fov spans the shorter side, so a wider image adds columns on both
    # sides (a taller one rows) with pixels of the same size; given the same samples per
    # pixel, the overlap is the same image
    scene = Scene.from_file("combined")
    width, height = size
    side = min(size)
    rows, cols = np.divmod(np.arange(width * height), width)
    inner = (rows - offset[0], cols - offset[1])
    square = rendering.pixel_samples(scene, "random", 8, side, seed=5)
    wide = rendering.pixel_samples(scene, "random", 8, size, seed=6)
    inside = (inner[0] >= 0) & (inner[0] < side) & (inner[1] >= 0) & (inner[1] < side)
    wide[inside] = square[inner[0][inside] * side + inner[1][inside]]
    a = rendering.render_samples(scene, square, side, backend="numpy").reshape(side, side)
    b = rendering.render_samples(scene, wide, size, backend="numpy").reshape(height, width)
    crop = b[offset[0]:offset[0] + side, offset[1]:offset[1] + side]
    np.testing.assert_allclose(crop, a, rtol=0, atol=1e-6)
    kernel = rendering.render_samples(scene, wide, size).reshape(height, width)
    assert np.mean(np.abs(kernel - b) > 2e-5) < 0.01                 # the kernel agrees (fp32)


def test_bad_resolutions_are_named():
    for bad in ((0, 4), (4,), (4, 4, 4), (2.5, 3), -1):
        with pytest.raises(InvalidArgumentError, match="resolution"):
            rendering.render("ao", "random", 4, bad, progress=False)


# -- the reference and its noise ----------------------------------------------------------------
def test_the_reference_reports_its_noise_and_the_estimate_is_honest():
    scene = Scene.from_file("ao")
    a, se_a = rendering.reference(scene, 16, spp=512, progress=False, return_noise=True)
    b, se_b = rendering.reference(scene, 16, spp=512, seed=7, progress=False, return_noise=True)
    assert a.shape == se_a.shape == (16, 16) and np.all(se_a >= 0)
    # two independent references differ by their two noises: E|a - b|^2 = floor_a + floor_b
    spread = rendering.mse(a, b)
    floors = rendering.noise_floor(se_a) + rendering.noise_floor(se_b)
    assert 0.6 < spread / floors < 1.6, (spread, floors)
    # and a scrambled-Sobol' reference is far less noisy than random's at the same spp
    random = rendering.render(scene, "random", 512, 16, seed=9, pad=False, progress=False)
    assert rendering.mse(random, a) > 5 * rendering.noise_floor(se_a)
    # cached with its noise
    again, se_again = rendering.reference(scene, 16, spp=512, progress=False, return_noise=True)
    np.testing.assert_array_equal(again, a)
    np.testing.assert_array_equal(se_again, se_a)


def test_compare_reports_the_floor_and_the_excess():
    scene = Scene.from_file("ao")
    ref, se = rendering.reference(scene, 8, spp=256, progress=False, return_noise=True)
    image = rendering.render(scene, "jittered", 16, 8, seed=1, progress=False)
    m = rendering.compare(image, ref, se)
    assert m["floor"] == pytest.approx(float(np.mean(se.astype(np.float64) ** 2)))
    assert m["mse_excess"] == pytest.approx(m["mse"] - m["floor"])
    with pytest.raises(InvalidArgumentError, match="'stderr'"):
        rendering.compare(image, ref, se[:4])


def test_reference_spp_is_passes_of_powers_of_two():
    with pytest.raises(InvalidArgumentError, match="nearest is 128"):
        rendering.reference("ao", 4, spp=100, progress=False)
    with pytest.raises(InvalidArgumentError, match="'spp'"):
        rendering.reference("ao", 4, spp=0, progress=False)


# -- the error spectrum -------------------------------------------------------------------------
def test_white_error_is_flat_and_its_mean_is_the_mse():
    rng = np.random.default_rng(0)
    ref = rng.random((96, 64)).astype(np.float32)
    noisy = (ref + rng.normal(0, 0.1, ref.shape)).astype(np.float32)
    f, p = rendering.error_spectrum(noisy, ref)
    assert len(f) == 32 and f[0] > 0 and f[-1] < 0.5
    np.testing.assert_allclose(p[6:], 0.01, rtol=0.4)          # rings of >= ~40 frequencies
    assert np.mean(p) == pytest.approx(0.01, rel=0.1)
    power = np.abs(np.fft.fft2(noisy.astype(np.float64) - ref)) ** 2 / noisy.size
    assert power.mean() == pytest.approx(rendering.mse(noisy, ref))   # Parseval
    assert 0.8 < rendering.low_frequency_power(noisy, ref) < 1.2


def test_a_sinusoidal_error_peaks_at_its_frequency():
    y, x = np.mgrid[0:64, 0:64]
    error = 0.01 * np.cos(2 * np.pi * (8 * x + 6 * y) / 64)          # |f| = 10 / 64 cycles/pixel
    ref = np.zeros((64, 64), np.float32)
    f, p = rendering.error_spectrum((ref + error).astype(np.float32), ref)
    assert abs(f[np.nanargmax(p)] - 10 / 64) <= 0.5 / 32
    smooth = 0.01 * np.cos(2 * np.pi * x / 64)                        # the lowest frequency
    assert rendering.low_frequency_power((ref + smooth).astype(np.float32), ref) > 5
