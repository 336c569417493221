"""The renderer: a scene, a sampler and a number of samples per pixel in, an image out.

``render(scene, sampler, spp, resolution, seed)`` ray-casts a :class:`~clsamp.scene.Scene`
with ``kernels/render.cl`` and returns a float32 image of shape (height, width) (one
channel: the scenes are gray). ``reference`` renders (and caches) a high-spp reference
with its measured noise; ``compare``, ``mse`` and ``error_spectrum`` measure an image
against it.

Which samples each pixel gets (dimensions, padding, seeds per block, pools of
expensive samplers) is :mod:`clsamp.pixel_sampling`; the NumPy twin of the kernel is
:mod:`clsamp.render_numpy`. Images are rendered in tiles of whole seed blocks that fit
one launch (:func:`clsamp.runtime.chunk_ranges`) and at most :data:`TILE_BYTES` of
samples, so large images never exceed device (or host) memory; the tiling does not
change the image. Samples cross to the kernel as float32, rounded toward zero (so they
stay below 1); the pixel mean is accumulated in double.
"""

import hashlib
import math
import os
import warnings
from pathlib import Path

import numpy as np

from . import files, parallel, philox, runtime
from .errors import InvalidArgumentError
from .pixel_sampling import (  # noqa: F401  (block_size, float32_samples: public here too)
    DEFAULT_POOL,
    PURPOSE_PASS,
    block_size,
    derived_seed,
    float32_samples,
    image_size,
    pixel_samples,
    sample_plan,
)
from .render_numpy import camera_frame, render_reference, screen_window
from .scene import Scene, as_scene  # noqa: F401  (Scene: README imports it from here)
from .validation import check_bool, check_choice, check_int, check_positive_int, check_real, check_seed

TILE_BYTES = 128 * 2**20            # float32 sample bytes of one tile at most (host memory)
REFERENCE_SAMPLER = "sobol:owen"    # what a reference render is made with...
REFERENCE_PASSES = 16               # ...in this many independent passes (its noise estimate)
REFERENCE_SEED = 0x5EED_0F_2EF
RENDER_VERSION = "2"                # bump when the renderer's output changes (cache key)


# -- the kernel and its NumPy reference ------------------------------------------------------
def _scene_arrays(scene, size):
    """The float32 buffers of render.cl for a (width, height) image: camera, shading, spheres,
    planes, boxes, light."""
    eye, forward, right, up = camera_frame(scene)
    cam = scene.camera
    lens = cam.get("lens") or {"aperture": 0.0, "focus_distance": 1.0}
    camera = np.concatenate([eye, forward, right, up, [math.tan(math.radians(cam["fov"]) / 2),
                             lens["aperture"], lens["focus_distance"], *cam["shutter"],
                             *screen_window(scene, *size)]])
    shading = np.array([scene.ambient, scene.background, scene.ao_distance, scene.epsilon])
    spheres = [[*s["center"], s["radius"], *s["velocity"], s["albedo"]]
               for s in scene.shapes if s["type"] == "sphere"]
    planes = [[*s["point"], *s["normal"], s["albedo"]] for s in scene.shapes if s["type"] == "plane"]
    boxes = [[*s["min"], *s["max"], s["albedo"]] for s in scene.shapes if s["type"] == "box"]
    light = scene.light
    light = (np.zeros(10) if light is None else
             np.array([*light["corner"], *light["edge1"], *light["edge2"], light["emission"]]))
    f32 = lambda rows, width: np.asarray(rows, dtype=np.float32).reshape(-1, width)  # noqa: E731
    return (camera.astype(np.float32), shading.astype(np.float32), f32(spheres, 8), f32(planes, 7),
            f32(boxes, 7), light.astype(np.float32))


def vector_width():
    """Samples per vector lane group in render.cl, the device's shape's
    (``runtime.shape().vector_width``): 8 on CPU devices with 8 float lanes (PoCL vectorizes
    explicit vectors only), 1 on GPUs (one sample per lane of a warp is the natural width)."""
    return runtime.shape().vector_width


def render_samples(scene, samples, resolution, pixel0=0, backend="opencl", width=None):
    """Render given samples: the pixel values of pixels [pixel0, pixel0 + len(samples)).

    Float64 samples are rounded toward zero to float32 first on both backends; float32
    samples are taken as they are.

    Parameters
    ----------
    scene : Scene, dict or path
        As :func:`render` takes it.
    samples : ndarray, shape (pixels, scene.sample_dimensions, spp)
        In [0, 1), as from :func:`pixel_samples`.
    resolution : int or (int, int)
        As :func:`render` takes it.
    pixel0 : int, optional
        The number of the first pixel (``row * width + col``).
    backend : {"opencl", "numpy"}
        ``"numpy"``: the NumPy reference (float64 ray math).
    width : {1, 4, 8}, optional
        The kernel's vector width instead of :func:`vector_width`.

    Returns
    -------
    ndarray of float32, shape (pixels,)

    Raises
    ------
    InvalidArgumentError
        ``samples`` not of shape (pixels, the scene's dimensions, spp), pixels past the
        image, or another argument out of its range.
    """
    scene = as_scene(scene)
    size = image_size(resolution)
    samples = np.asarray(samples)
    if samples.ndim != 3 or samples.dtype.kind != "f":
        raise InvalidArgumentError(f"'samples' must be floats of shape (pixels, "
                                   f"{scene.sample_dimensions}, spp), got {samples.shape} of {samples.dtype}")
    npix, dims, spp = samples.shape
    if not samples.size or not (samples.min() >= 0 and samples.max() < 1):   # NaN fails too
        raise InvalidArgumentError("'samples' must hold at least one sample a pixel, each "
                                   "coordinate in [0, 1)")
    if dims != scene.sample_dimensions:
        raise InvalidArgumentError(f"'samples' must have {scene.sample_dimensions} dimensions "
                                   f"(axis 1), got {dims}")
    pixel0 = check_int(pixel0, "pixel0", minimum=0)
    if pixel0 + npix > size[0] * size[1]:
        raise InvalidArgumentError(f"'pixel0'={pixel0} and {npix} pixels of 'samples' pass the "
                                   f"image's {size[0] * size[1]} pixels")
    backend = check_choice(backend, "backend", ("opencl", "numpy"))
    if width is not None:
        width = check_choice(check_int(width, "width"), "width", (1, 4, 8))
    f32 = samples if samples.dtype == np.float32 else float32_samples(samples)
    if backend == "numpy":
        return render_reference(scene, f32.astype(np.float64), size, pixel0)
    spp_pad = -(-spp // (width or vector_width())) * (width or vector_width())
    host = np.full((npix, max(dims, 1), spp_pad), 0.5, dtype=np.float32)
    host[:, :dims, :spp] = f32
    return _launch(scene, host, pixel0, npix, size, spp, width)


def _launch(scene, host, pixel0, npix, size, spp, width=None, keys=None, block=1):
    """Run render_pixels of a (width, height) image on ``host`` samples (npix, dims, spp_pad)
    float32, or, with
    ``keys`` ((blocks, 2) uint32 seeds of the seed blocks), on Philox draws made in the kernel."""
    import pyopencl.array as cla
    width = width or vector_width()
    runtime.require_fp64()
    queue = runtime.queue()
    spp_pad = -(-spp // width) * width
    arrays = _scene_arrays(scene, size)
    camera, shading, spheres, planes, boxes, light = (
        cla.to_device(queue, np.ascontiguousarray(a).reshape(-1) if a.size else np.zeros(1, np.float32))
        for a in arrays)
    counts = [len(a) for a in arrays[2:5]]
    out = cla.empty(queue, (npix,), np.float32)
    defines = {**scene.kernel_defines(), "VW": width}
    if keys is None:
        samples_d = cla.to_device(queue, host.reshape(-1))
        keys_d = cla.to_device(queue, np.zeros(2, np.uint32))
    else:
        samples_d = cla.to_device(queue, np.zeros(1, np.float32))
        keys_d = cla.to_device(queue, np.ascontiguousarray(keys, dtype=np.uint32).reshape(-1))
        defines.update(SAMPLES_PHILOX=True, SAMPLES_PHILOX_STREAM=int(philox.Stream.POINTS))
    kernel = runtime.kernel("render.cl", "render_pixels", defines=defines, options=("-cl-mad-enable",))
    local = runtime.local_size(64 if width == 1 else 8)
    kernel(queue, (-(-npix // local) * local,), (local,), out.data, samples_d.data,
           np.uint32(pixel0), np.uint32(npix), np.uint32(size[0]), np.uint32(size[1]), np.uint32(spp),
           np.uint32(spp_pad), camera.data, shading.data, spheres.data, np.uint32(counts[0]),
           planes.data, np.uint32(counts[1]), boxes.data, np.uint32(counts[2]), light.data,
           keys_d.data, np.uint32(block))
    return out.get()


# -- the public entry points ----------------------------------------------------------------
def render(scene, sampler, spp, resolution, seed=0, sampler_params=None, pad=True, progress=True,
           pool=DEFAULT_POOL):
    """Render ``scene`` with ``spp`` samples per pixel from ``sampler``.

    Parameters
    ----------
    scene : Scene, dict or path
        The scene (a path or a shipped scene's bare name goes to :meth:`Scene.from_file`).
    sampler : str or Sampler
        A registered name (``"random"``, ``"jittered"``, ``"sobol:owen"``, ``"ccvt"``, ...)
        made with :func:`clsamp.make_sampler`, or a Sampler object (``d=2`` with
        ``pad=True``, ``d=scene.sample_dimensions`` with ``pad=False``), re-seeded per
        seed block by copying it (an expensive one, as poisson_disk, lloyd or ccvt, once a
        set, for its pool).
    spp : int
        Samples per pixel (>= 1); the sampler must be able to make spp points
        (jittered in 2-D needs k^2 or its ``strata`` product).
    resolution : int or (int, int)
        The image is resolution x resolution pixels, or (width, height) pixels; the
        camera's fov spans the shorter side (as pbrt's film and perspective camera).
    seed : int
        Seed in [0, 2^64); the same seed gives the same image.
    sampler_params : dict, optional
        Passed to :func:`clsamp.make_sampler` (e.g. ``{"strata": (12, 8)}``).
    pad : bool
        True: 2-D (and 1-D) sets padded with random permutations, as pbrt pads; False:
        one d-dimensional set per pixel from a sampler that makes all dimensions.
    progress : bool
        Show a progress bar over the pixels when the render is long.
    pool : int
        Realizations per set reused (with per-pixel toroidal shifts) by expensive samplers.

    Returns
    -------
    ndarray of float32, shape (height, width)
        Row 0 is the top of the image; values are linear radiance. Pixel ``(row, col)`` is
        pixel number ``row * width + col`` of the seed blocks.

    Notes
    -----
    See the module docstring for the sample layout, padding and decorrelation. The
    kernel casts rays in float32; the pixel mean is accumulated in double.

    Examples
    --------
    >>> from clsamp import render as rendering
    >>> img = rendering.render("ao", "jittered", spp=16, resolution=8, seed=1, progress=False)
    >>> img.shape, img.dtype
    ((8, 8), dtype('float32'))
    """
    check_bool(progress, "progress")
    scene = as_scene(scene)
    spp = check_int(spp, "spp", minimum=1, maximum=2**31)
    size = image_size(resolution)
    seed = check_seed(seed)
    pool = check_positive_int(pool, "pool")
    if not isinstance(pad, bool):
        raise InvalidArgumentError(f"'pad' must be True or False, got {pad!r}")
    runtime.check_host_bytes(4 * size[0] * size[1] + TILE_BYTES, f"a {size[0]} x {size[1]} render")
    sets = sample_plan(scene, sampler, spp, sampler_params, pad, pool)
    total = size[0] * size[1]
    dims = scene.sample_dimensions
    block = block_size(spp, dims)
    blocks = -(-total // block)
    if sampler == "random" and not sampler_params and not pad:
        return _render_random(scene, spp, size, seed, block, blocks)
    width = vector_width()
    spp_pad = -(-spp // width) * width
    # device bytes per block: float32 samples (padded to the vector width) and the output
    per_block = block * (4 * max(dims, 1) * spp_pad + 4)
    # host memory holds each tile's samples several times over (float64, permuted, float32)
    tiles = runtime.chunk_ranges(blocks, per_block, limit=TILE_BYTES)
    image = np.empty(total, dtype=np.float32)
    from tqdm import tqdm
    long = total * spp * scene.rays_per_sample() > 2**27
    with tqdm(total=total, desc=f"render {scene.name}", unit="px",
              disable=not (progress and long)) as bar:
        for b_lo, b_hi in tiles:
            pixels = range(b_lo * block, min(total, b_hi * block))
            host = np.full((len(pixels), max(dims, 1), spp_pad), 0.5, dtype=np.float32)
            pixel_samples(scene, sampler, spp, size, seed, pixels=pixels, pad=pad, _sets=sets,
                          _into=host)
            image[pixels.start:pixels.stop] = _launch(scene, host, pixels.start, len(pixels), size, spp,
                                                      width)
            bar.update(len(pixels))
    return image.reshape(size[1], size[0])


def render_task(scene, sampler, spp, resolution, seed, sampler_params):
    """One task of :func:`render_sweep`: the image of one (sampler, spp), without a progress bar.

    Parameters
    ----------
    scene, sampler, spp, resolution, seed, sampler_params
        As :func:`render` takes them.

    Returns
    -------
    ndarray of float32, shape (height, width)
    """
    return render(scene, sampler, spp, resolution, seed=seed, sampler_params=sampler_params,
                  progress=False)


def render_sweep(scene, samplers, spps, resolution, seed=0, sampler_params=None, reference=None,
                 client=None, checkpoint=None, progress=True):
    """Renders of ``scene`` for every sampler and sample count, here or on a Dask cluster.

    Parameters
    ----------
    scene : Scene, dict or path
    samplers : sequence of str
        Sampler names (``sampler_params[name]``, a dict, gives one its parameters).
    spps : sequence of int
    resolution, seed
        As :func:`render`.
    reference : ndarray, optional
        When given, the MSE of every render against it is returned too.
    client : dask.distributed.Client, optional
        One task a render (:mod:`clsamp.parallel`); the images are those :func:`render`
        makes in-process, bit for bit on workers of the same kind of device (the kernel
        casts rays in float32, so another kind of device agrees to the tolerance
        docs/design.md states).
    checkpoint : str or Path, optional
        A folder keeping every finished image.

    Returns
    -------
    images : dict
        ``{(sampler, spp): image}``.
    mse : dict
        ``{(sampler, spp): float}`` against ``reference`` (empty without one).
    """
    scene = as_scene(scene)
    for name, given in (("samplers", samplers), ("spps", spps)):
        if isinstance(given, (str, bytes)) or not hasattr(given, "__iter__"):
            raise InvalidArgumentError(f"'{name}' must be a list, got {given!r}")
    samplers, spps = list(samplers), list(spps)
    if sampler_params is not None and not isinstance(sampler_params, dict):
        raise InvalidArgumentError(
            f"'sampler_params' must be a dict {{sampler: params}}, got {sampler_params!r}")
    params = dict(sampler_params or {})
    if set(params) - set(samplers) or len(set(samplers)) < len(samplers) or len(set(spps)) < len(spps):
        raise InvalidArgumentError(
            "'samplers' and 'spps' must not repeat a value, and 'sampler_params' must name only "
            f"samplers of 'samplers'; got {samplers}, {spps}, {sorted(map(str, params))}")
    keys = [(str(name), check_int(spp, "spps", minimum=1, maximum=2**31))
            for name in samplers for spp in spps]
    if not keys:
        raise InvalidArgumentError("'samplers' and 'spps' must each hold at least one value")
    tasks = [(scene, name, spp, resolution, seed, params.get(name)) for name, spp in keys]
    images, _ = parallel.run(render_task, tasks, client=client, checkpoint=checkpoint, progress=progress,
                             desc=f"render {scene.name}")
    out = dict(zip(keys, images, strict=True))
    errors = {key: mse(image, reference) for key, image in out.items()} if reference is not None else {}
    return out, errors


def _render_random(scene, spp, size, seed, block, blocks):
    """``random`` with ``pad=False``, its draws made in the kernel: the same samples as
    :func:`pixel_samples` gives (the same Philox doubles, the same seeds per block), so the
    same image, without sample buffers."""
    total = size[0] * size[1]
    keys = np.array([philox.seed_key(derived_seed(seed, b, 0)) for b in range(blocks)],
                    dtype=np.uint32)
    image = np.empty(total, dtype=np.float32)
    for lo, hi in runtime.chunk_ranges(total, 4):
        image[lo:hi] = _launch(scene, None, lo, hi - lo, size, spp, keys=keys, block=block)
    return image.reshape(size[1], size[0])


def cache_folder():
    """Where reference renders are cached: ``$CLSAMP_CACHE``, else ``~/.cache/clsamp``."""
    env = os.environ.get("CLSAMP_CACHE")
    return Path(env) if env else Path.home() / ".cache" / "clsamp"


def reference_key(scene, resolution, spp, seed=REFERENCE_SEED):
    """The cache key of a reference render.

    Parameters
    ----------
    scene : Scene
    resolution, spp, seed
        As :func:`reference` takes them.

    Returns
    -------
    str
        The SHA-256 (hex) of the scene's content, image size, spp, seed, the reference's sampler
        and passes, and the renderer's version.
    """
    width, height = image_size(resolution)
    text = (f"render-{RENDER_VERSION}|{scene.content_hash()}|{width}x{height}|{spp}|{seed}|"
            f"{REFERENCE_SAMPLER}|{REFERENCE_PASSES}")
    return hashlib.sha256(text.encode()).hexdigest()


def reference_spp(spp, passes=None):
    """Check the total samples per pixel of a reference: :data:`REFERENCE_PASSES` passes of a
    power of two samples each (Sobol' nets).

    Parameters
    ----------
    spp : int
    passes : int, optional
        Passes instead of :data:`REFERENCE_PASSES`.

    Returns
    -------
    int
        ``spp``.

    Raises
    ------
    InvalidArgumentError
        Another ``spp``; the message names the nearest valid total.
    """
    passes = REFERENCE_PASSES if passes is None else passes
    spp = check_positive_int(spp, "spp", maximum=2**40)
    per = spp // passes
    if spp % passes or per & (per - 1):
        low = passes << max(0, (max(per, 1)).bit_length() - 1)
        nearest = min((low, 2 * low), key=lambda v: abs(v - spp))
        raise InvalidArgumentError(
            f"'spp'={spp}: a reference is {passes} passes of a power of two samples per pixel "
            f"each, so spp must be {passes} x 2^k; the nearest is {nearest}")
    return spp


def reference(scene, resolution, spp=None, progress=True, seed=REFERENCE_SEED, cache=True,
              return_noise=False):
    """A high-spp reference render and its own noise, cached as OpenEXR.

    The reference is the mean of :data:`REFERENCE_PASSES` independent renders with
    Owen-scrambled Sobol' (``"sobol:owen"``, padded as :func:`render` pads), each of
    ``spp / passes`` samples per pixel under its own derived seed. Every pass is unbiased
    (nested scrambling makes each point uniform), the passes are independent, and a
    scrambled net's error falls much faster than random sampling's, so the reference is far
    less noisy than ``random`` at the same cost. What noise is left is *measured*: the
    spread of the passes gives each pixel's standard error ``s / sqrt(passes)``, and the
    mean of its square is the MSE floor the reference adds to every MSE measured against
    it (``E[mse(image, ref)] = MSE(image) + floor`` for an image independent of it).
    :func:`compare` reports it beside the MSE.

    It is cached in :func:`cache_folder` under a name holding :func:`reference_key`
    (scene content, image size, spp, seed); a missing, unreadable or mismatching cache
    file is rendered again and rewritten atomically (channels ``Y`` and ``stderr``).

    Parameters
    ----------
    scene : Scene, dict or path
    resolution : int or (int, int)
        As :func:`render`.
    spp : int, optional
        Total samples per pixel: ``passes x 2^k`` (default: 16 passes of the power of two
        at or above 4 x ``scene.default_spp``).
    progress : bool
        Show a progress bar over the passes.
    seed : int
        Seed of the reference.
    cache : bool
        Read and write the cache (False: always render, write nothing).
    return_noise : bool
        Also return the per-pixel standard error.

    Returns
    -------
    image : ndarray of float32, shape (height, width)
    stderr : ndarray of float32, shape (height, width)
        Only with ``return_noise``.

    Warns
    -----
    UserWarning
        The cache cannot be written (the result is returned all the same).

    Examples
    --------
    >>> from clsamp import render as rendering
    >>> ref, stderr = rendering.reference("ao", 8, spp=256, progress=False, cache=False,
    ...                                   return_noise=True)
    >>> ref.shape, bool((stderr >= 0).all())
    ((8, 8), True)
    """
    check_bool(progress, "progress")
    check_bool(cache, "cache")
    check_bool(return_noise, "return_noise")
    scene = as_scene(scene)
    width, height = image_size(resolution)
    if spp is None:
        spp = REFERENCE_PASSES * (1 << (4 * scene.default_spp - 1).bit_length())
    spp = reference_spp(spp)
    seed = check_seed(seed)
    key = reference_key(scene, (width, height), spp, seed)
    path = cache_folder() / f"reference-{scene.name}-{width}x{height}px-{spp}spp-{key[:16]}.exr"
    result = None
    if cache and path.is_file():
        try:
            image, header = files.read_exr(path, with_header=True, channel_names=("Y", "stderr"))
            if image.shape == (height, width, 2) and _header_text(header.get("key")) == key:
                result = np.ascontiguousarray(image.transpose(2, 0, 1), dtype=np.float32)
        except Exception:  # a corrupt or foreign file: render again and overwrite it
            pass
    if result is None:
        result = _render_reference(scene, (width, height), spp, seed, progress)
        try:        # a cache that cannot be written costs the next run time, not this result
            if cache:
                files.write_exr(path, result.transpose(1, 2, 0), channel_names=("Y", "stderr"),
                                header={"key": key, "scene": scene.name, "spp": spp, "seed": seed,
                                        "sampler": f"{REFERENCE_SAMPLER} (reference, "
                                                   f"{REFERENCE_PASSES} passes)",
                                        "resolution": f"{width}x{height}"})
        except files.WriteError as error:
            warnings.warn(f"the reference render is not cached: {error}", UserWarning, stacklevel=2)
    return (result[0], result[1]) if return_noise else result[0]


def _render_reference(scene, size, spp, seed, progress):
    from tqdm import tqdm
    per = spp // REFERENCE_PASSES
    total = np.zeros((size[1], size[0]), dtype=np.float64)
    square = np.zeros_like(total)
    what = (f"reference {scene.name} {size[0]}x{size[1]}, {spp} spp (once; then read from "
            f"{cache_folder()})")
    for k in tqdm(range(REFERENCE_PASSES), desc=what, unit="pass", disable=not progress):
        image = render(scene, REFERENCE_SAMPLER, per, size, seed=derived_seed(seed, k, 0, PURPOSE_PASS),
                       progress=False).astype(np.float64)
        total += image
        square += image * image
    mean = total / REFERENCE_PASSES
    spread = np.maximum(square - REFERENCE_PASSES * mean * mean, 0.0) / (REFERENCE_PASSES - 1)
    return np.stack([mean, np.sqrt(spread / REFERENCE_PASSES)]).astype(np.float32)


def noise_floor(stderr):
    """The MSE a reference's own noise adds to any MSE measured against it: the mean of
    ``stderr**2``.

    Parameters
    ----------
    stderr : array_like
        The reference's per-pixel standard error (``reference(..., return_noise=True)``).

    Returns
    -------
    float
        In squared pixel values, as an MSE.

    Raises
    ------
    InvalidArgumentError
        An empty ``stderr``, or one with values that are negative or not finite.
    """
    try:
        stderr = np.asarray(stderr, dtype=np.float64)
    except (TypeError, ValueError):
        stderr = np.empty(0)
    if stderr.size == 0 or not np.all(np.isfinite(stderr)) or np.any(stderr < 0):
        raise InvalidArgumentError("'stderr' must be a non-empty array of finite values >= 0")
    return float(np.mean(stderr * stderr))


def _header_text(value):
    if isinstance(value, bytes):
        return value.decode(errors="replace")
    return None if value is None else str(value)


def _check_pair(image, ref):
    image = np.asarray(image)
    ref = np.asarray(ref)
    if image.shape != ref.shape:
        raise InvalidArgumentError(f"'image' and 'ref' must have the same shape, got {image.shape} "
                                   f"and {ref.shape}")
    for name, a in (("image", image), ("ref", ref)):
        if not np.issubdtype(a.dtype, np.floating) or not np.all(np.isfinite(a)) or not a.size:
            raise InvalidArgumentError(f"'{name}' must be a finite float image with pixels")
    return image.astype(np.float64), ref.astype(np.float64)


def mse(image, ref):
    """Mean squared error of an image against a reference, in float64.

    Parameters
    ----------
    image, ref : ndarray
        Finite float images of one shape.

    Returns
    -------
    float
        The mean of (image - ref)².

    Raises
    ------
    InvalidArgumentError
        Images of different shapes, not float, or not finite.
    """
    image, ref = _check_pair(image, ref)
    return float(np.mean((image - ref) ** 2))


def compare(image, ref, stderr=None):
    """MSE, PSNR (dB) and SSIM of an image against a reference (scikit-image).

    ``data_range`` is the reference's max - min (1 when the reference is constant). SSIM uses
    scikit-image's default 7 x 7 window, shrunk to the largest odd size the image allows; it
    is NaN for images smaller than 3 x 3.

    Parameters
    ----------
    image, ref : ndarray
        As :func:`mse` takes them.
    stderr : ndarray, optional
        The reference's per-pixel standard error (``reference(..., return_noise=True)``).

    Returns
    -------
    dict
        ``mse``, ``psnr`` and ``ssim``; with ``stderr`` also ``floor``, the MSE the reference's
        own noise adds (:func:`noise_floor`), and ``mse_excess = mse - floor``, an unbiased
        estimate of the image's MSE against the true image.

    Raises
    ------
    InvalidArgumentError
        Images :func:`mse` refuses, or a ``stderr`` of another shape or with invalid values.
    """
    from skimage.metrics import mean_squared_error, peak_signal_noise_ratio, structural_similarity
    image, ref = _check_pair(image, ref)
    data_range = float(ref.max() - ref.min()) or 1.0
    error = float(mean_squared_error(ref, image))
    psnr = float(peak_signal_noise_ratio(ref, image, data_range=data_range)) if error > 0 else math.inf
    side = min(ref.shape[:2])
    win = min(7, side if side % 2 else side - 1)
    ssim = (float(structural_similarity(ref, image, data_range=data_range, win_size=win,
                                        channel_axis=2 if ref.ndim == 3 else None))
            if win >= 3 else math.nan)
    out = {"mse": error, "psnr": psnr, "ssim": ssim}
    if stderr is not None:
        if np.shape(stderr) != ref.shape:
            raise InvalidArgumentError(f"'stderr' must have the reference's shape {ref.shape}, "
                                       f"got {np.shape(stderr)}")
        floor = noise_floor(stderr)
        out.update(floor=floor, mse_excess=error - floor)
    return out


def error_spectrum(image, reference, bins=None):
    """The power spectrum of a render's error image, radially averaged.

    The error e = image - reference is transformed with a 2-D FFT and its periodogram
    P(f) = |E(f)|^2 / (width height) averaged over rings of equal frequency |f| (cycles
    per pixel, 0 to 0.5). P is normalized so that white error of variance s^2 is flat at
    s^2, and its mean over all frequencies is the MSE (Parseval). Independent per-pixel
    sampling gives a flat (white) spectrum; samplers that decorrelate neighbouring pixels'
    errors (``zsobol``, Ahmed and Wonka 2020; Heitz and Belcour 2019) push the error
    power to high frequencies (blue noise), which the eye forgives.

    Parameters
    ----------
    image, reference : ndarray (height, width)
        The render and the reference (:func:`reference`).
    bins : int, optional
        Number of rings (default min(width, height) // 2).

    Returns
    -------
    frequencies : ndarray (bins,)
        The centre of each ring, in cycles per pixel.
    power : ndarray (bins,)
        The mean periodogram in each ring (NaN for an empty ring).

    Examples
    --------
    >>> import numpy as np
    >>> from clsamp import render as rendering
    >>> rng = np.random.default_rng(0)
    >>> ref = np.zeros((64, 64), np.float32)
    >>> f, p = rendering.error_spectrum(ref + rng.normal(0, 0.1, ref.shape).astype(np.float32), ref)
    >>> bool(abs(np.nanmean(p) - 0.01) < 0.002)
    True
    """
    image, reference = _check_pair(image, reference)
    if image.ndim != 2:
        raise InvalidArgumentError(f"'image' must be a gray image (height, width), got {image.shape}")
    height, width = image.shape
    if min(height, width) < 4:
        raise InvalidArgumentError(f"'image' must be at least 4 x 4 pixels, got {image.shape}")
    bins = min(width, height) // 2 if bins is None else check_positive_int(bins, "bins", maximum=65535)
    power = np.abs(np.fft.fft2(image - reference)) ** 2 / (width * height)
    fy = np.fft.fftfreq(height)[:, None]
    fx = np.fft.fftfreq(width)[None, :]
    radius = np.hypot(fx, fy)
    ring = np.minimum((radius / 0.5 * bins).astype(np.intp), bins)
    inside = ring < bins
    counts = np.bincount(ring[inside], minlength=bins)
    sums = np.bincount(ring[inside], weights=power[inside], minlength=bins)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(counts > 0, sums / np.maximum(counts, 1), np.nan)
    return (np.arange(bins) + 0.5) * 0.5 / bins, mean


def low_frequency_power(image, reference, cutoff=0.125):
    """How much of a render's error sits at low frequencies, relative to white error.

    The mean periodogram of the error image (as :func:`error_spectrum`) over the frequencies
    with 0 < |f| < ``cutoff`` cycles per pixel, divided by its mean over all frequencies (the
    MSE, by Parseval).

    Parameters
    ----------
    image, reference : ndarray (height, width)
        The render and the reference (:func:`reference`).
    cutoff : float, optional
        In (0, 0.5] cycles per pixel.

    Returns
    -------
    float
        1 up to noise for white (independent per-pixel) error; below 1 for blue error. NaN
        where the error is zero.

    Raises
    ------
    InvalidArgumentError
        Images :func:`mse` refuses, not gray or smaller than 4 x 4, or a ``cutoff`` outside
        (0, 0.5].
    """
    image, reference = _check_pair(image, reference)
    if image.ndim != 2 or min(image.shape) < 4:
        raise InvalidArgumentError(f"'image' must be a gray image of at least 4 x 4, got {image.shape}")
    cutoff = check_real(cutoff, "cutoff", minimum=0.0, maximum=0.5, open_minimum=True)
    height, width = image.shape
    power = np.abs(np.fft.fft2(image - reference)) ** 2
    radius = np.hypot(np.fft.fftfreq(height)[:, None], np.fft.fftfreq(width)[None, :])
    low = (radius < cutoff) & (radius > 0)       # the DC term is the bias, not noise
    if not low.any():
        raise InvalidArgumentError(f"'cutoff'={cutoff:g} holds no frequency of a {height} x {width} "
                                   f"image (the lowest is 1/{max(height, width)} cycles per pixel)")
    total = power.mean()
    return float(power[low].mean() / total) if total > 0 else math.nan


def save(path, image, sampler, spp, seed, scene=None, preview=True):
    """Write a render as OpenEXR with sampler, spp and seed in its header, and a tone-mapped PNG
    preview beside it.

    Parameters
    ----------
    path : str or Path
        The image's name, ending in ``.exr`` or ``.png``: both files are written from its
        stem, ``<stem>.exr`` and (``preview``) ``<stem>.png``, so neither overwrites the
        other.
    image : ndarray (height, width)
    sampler : str or Sampler
    spp, seed : int
        What made the image, for the header.
    scene : Scene, optional
        Its name goes in the header too.
    preview : bool
        Write the PNG.

    Returns
    -------
    list of Path
        The files written, the EXR first; both are renamed into place only once both are
        whole (:func:`clsamp.files.atomic_paths`).

    Raises
    ------
    InvalidArgumentError
        Another suffix.
    """
    path = Path(path)
    if path.suffix.lower() not in (".exr", ".png"):
        raise InvalidArgumentError(
            f"'path' {str(path)!r} must end in .exr or .png (a render writes <stem>.exr and a "
            f"<stem>.png preview), got {path.suffix or 'no suffix'!r}")
    header = {"sampler": sampler if isinstance(sampler, str) else repr(sampler), "spp": spp,
              "seed": seed}
    if scene is not None:
        header["scene"] = as_scene(scene).name
    written = [path.with_suffix(".exr")] + ([path.with_suffix(".png")] if preview else [])
    # the pair lands together: an interruption while the preview is drawn leaves neither
    with files.atomic_paths(*written) as temporary:
        files.write_exr(temporary[0], image, header)
        if preview:
            files.write_png(temporary[1], image)
    return written
