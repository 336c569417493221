"""zsobol: each pixel's samples are a (0, m, 2)-net, pixels never share Sobol' indices, the
kernel equals the reference for odd and even m and any image size, and a render's error is
blue (less low-frequency power than sobol:owen's, measured on the shipped AO scene)."""

import numpy as np
import pytest
from conftest import is_net

import clsamp
from clsamp import render as rendering
from clsamp.errors import InvalidArgumentError
from clsamp.samplers.zsobol import morton2
from clsamp.scene import Scene


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("CLSAMP_CACHE", str(tmp_path / "cache"))


@pytest.mark.parametrize("m", range(0, 9))
def test_every_pixel_is_a_0m2_net(m):
    s = clsamp.make_sampler("zsobol", d=4, seed=m + 11, resolution=(12, 9))
    pts = s.sample(2**m, realizations=range(0, 108))
    for pixel in pts:
        assert is_net(pixel[:, :2], m) and is_net(pixel[:, 2:], m)


def test_pixels_never_share_an_index_and_aligned_squares_tile_the_sequence():
    s = clsamp.make_sampler("zsobol", d=2, seed=4, resolution=16, backend="numpy")
    for n in (1, 2, 8, 32):
        m = n.bit_length() - 1
        index = s.sample_indices(n, np.arange(256), pair_seed=0x1234_5678_9ABC_DEF0)
        assert len(np.unique(index)) == index.size == 256 * n        # all 2^(8+m) indices
        blocks = index >> np.uint64(m)
        assert np.all(blocks == blocks[:, :1])                       # one aligned block a pixel
        # the 4 pixels of every aligned 2 x 2 Morton square take 4 n consecutive indices
        code = morton2(np.arange(256) % 16, np.arange(256) // 16)
        square = (blocks[:, 0] >> np.uint64(2)).astype(np.int64)
        assert np.array_equal(np.sort(square), np.sort((code >> np.uint64(2)).astype(np.int64)))
    # points: no two pixels' sets are the same
    pts = clsamp.make_sampler("zsobol", d=2, seed=4, resolution=16).sample(16, realizations=256)
    assert len({p.tobytes() for p in pts}) == 256


@pytest.mark.parametrize("n, d, size", [(1, 1, 5), (2, 3, (7, 3)), (32, 2, (33, 2)), (128, 5, 4)])
def test_kernel_equals_reference(n, d, size):
    args = dict(d=d, seed=99, resolution=size)
    pixels = range(0, size * size if isinstance(size, int) else size[0] * size[1])
    kernel = clsamp.make_sampler("zsobol", **args).sample(n, realizations=pixels)
    reference = clsamp.make_sampler("zsobol", backend="numpy", **args).sample(n, realizations=pixels)
    assert np.array_equal(kernel, reference)


def test_refuses_pixels_outside_the_image_and_too_many_samples():
    s = clsamp.make_sampler("zsobol", d=2, resolution=(4, 3))
    with pytest.raises(InvalidArgumentError, match="'realizations'"):
        s.sample(4, realizations=13)
    big = clsamp.make_sampler("zsobol", d=2, resolution=1024)       # 2^20 Morton codes
    assert big.max_n == 4096
    with pytest.raises(InvalidArgumentError, match="'n'.*4096"):
        big.sample(8192)
    with pytest.raises(InvalidArgumentError, match="nearest valid n is 8"):
        s.sample(7)
    with pytest.raises(InvalidArgumentError, match="'resolution'"):
        clsamp.make_sampler("zsobol", resolution=(4, 3, 2))


def test_zsobol_error_is_bluer_than_sobol_owen_on_the_ao_scene():
    # a test-sized image: 64^2 at 16 spp over two seeds (the shares at 128^2:
    # docs/performance.md, "Renderer samplers: zsobol, the reference, error spectra")
    scene = Scene.from_file("ao")
    ref = rendering.reference(scene, 64, spp=2048, progress=False)
    low = {}
    for name in ("zsobol", "sobol:owen"):
        low[name] = np.mean([rendering.low_frequency_power(
            rendering.render(scene, name, 16, 64, seed=s, progress=False), ref) for s in (1, 2)])
    assert low["zsobol"] < 0.8 * low["sobol:owen"], low
    assert 0.8 < low["sobol:owen"] < 1.25, low                       # independent pixels: white
