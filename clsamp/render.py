"""The renderer: a scene, a sampler and a number of samples per pixel in, an image out.

``render(scene, sampler, spp, resolution, seed)`` ray-casts a :class:`~clsamp.scene.Scene`
with ``kernels/render.cl`` and returns a float32 image of shape (resolution, resolution)
(one channel: the scenes are gray). ``reference`` renders (and caches) a high-spp
reference, ``compare`` and ``mse`` measure an image against it.

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
from pathlib import Path

import numpy as np

from . import io, parallel, philox, runtime
from .errors import InvalidArgumentError
from .pixel_sampling import (  # noqa: F401  (block_size, float32_samples: public here too)
    DEFAULT_POOL,
    PURPOSE_PASS,
    block_size,
    derived_seed,
    float32_samples,
    pixel_samples,
    sample_plan,
)
from .render_numpy import camera_frame, render_reference
from .scene import Scene
from .validation import check_int, check_positive_int, check_seed

TILE_BYTES = 128 * 2**20            # float32 sample bytes of one tile at most (host memory)
REFERENCE_PASS = 256                # spp per pass of a reference render
REFERENCE_SEED = 0x5EED_0F_2EF
RENDER_VERSION = "1"                # bump when the renderer's output changes (cache key)


# -- the kernel and its NumPy reference ------------------------------------------------------
def _scene_arrays(scene):
    """The float32 buffers of render.cl: camera, shading, spheres, planes, boxes, light."""
    eye, forward, right, up = camera_frame(scene)
    cam = scene.camera
    lens = cam.get("lens") or {"aperture": 0.0, "focus_distance": 1.0}
    camera = np.concatenate([eye, forward, right, up, [math.tan(math.radians(cam["fov"]) / 2),
                             lens["aperture"], lens["focus_distance"], *cam["shutter"]]])
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
    """Samples per vector lane group in render.cl: 8 on CPU devices (PoCL vectorizes explicit
    vectors only), 1 on GPUs (one sample per lane of a warp is the natural width there)."""
    return 8 if runtime.current_device().type == "cpu" else 1


def render_samples(scene, samples, resolution, pixel0=0, backend="opencl", width=None):
    """Render given samples: float32 pixel values for pixels [pixel0, pixel0 + len(samples)).

    ``samples`` has shape (pixels, scene.sample_dimensions, spp) in [0, 1) (as from
    :func:`pixel_samples`); float64 samples are rounded toward zero to float32 first on
    both backends, float32 samples are taken as they are. ``backend="numpy"`` is the
    NumPy reference (float64 ray math); ``width`` overrides the kernel's vector width
    (1, 4 or 8).
    """
    samples = np.asarray(samples)
    npix, dims, spp = samples.shape
    if dims != scene.sample_dimensions:
        raise InvalidArgumentError(f"'samples' must have {scene.sample_dimensions} dimensions "
                                   f"(axis 1), got {dims}")
    f32 = samples if samples.dtype == np.float32 else float32_samples(samples)
    if backend == "numpy":
        return render_reference(scene, f32.astype(np.float64), resolution, pixel0)
    spp_pad = -(-spp // (width or vector_width())) * (width or vector_width())
    host = np.full((npix, max(dims, 1), spp_pad), 0.5, dtype=np.float32)
    host[:, :dims, :spp] = f32
    return _launch(scene, host, pixel0, npix, resolution, spp, width)


def _launch(scene, host, pixel0, npix, resolution, spp, width=None, keys=None, block=1):
    """Run render_pixels on ``host`` samples (npix, dims, spp_pad) float32, or, with
    ``keys`` ((blocks, 2) uint32 seeds of the seed blocks), on Philox draws made in the kernel."""
    import pyopencl.array as cla
    width = width or vector_width()
    runtime.require_fp64()
    queue = runtime.queue()
    spp_pad = -(-spp // width) * width
    arrays = _scene_arrays(scene)
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
           np.uint32(pixel0), np.uint32(npix), np.uint32(resolution), np.uint32(spp),
           np.uint32(spp_pad), camera.data, shading.data, spheres.data, np.uint32(counts[0]),
           planes.data, np.uint32(counts[1]), boxes.data, np.uint32(counts[2]), light.data,
           keys_d.data, np.uint32(block))
    return out.get()


# -- the public entry points ----------------------------------------------------------------
def _as_scene(scene):
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, dict):
        return Scene.from_dict(scene)
    if isinstance(scene, (str, os.PathLike)):
        return Scene.from_file(scene)
    raise InvalidArgumentError(f"'scene' must be a Scene, a dict or a scene file, got {scene!r}")


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
        seed block by copying it.
    spp : int
        Samples per pixel (>= 1); the sampler must be able to make spp points
        (jittered in 2-D needs k^2 or its ``strata`` product).
    resolution : int
        The image is resolution x resolution pixels.
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
    ndarray of float32, shape (resolution, resolution)
        Row 0 is the top of the image; values are linear radiance.

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
    scene = _as_scene(scene)
    spp = check_int(spp, "spp", minimum=1, maximum=2**31)
    resolution = check_positive_int(resolution, "resolution", maximum=65535)
    seed = check_seed(seed)
    pool = check_positive_int(pool, "pool")
    if not isinstance(pad, bool):
        raise InvalidArgumentError(f"'pad' must be True or False, got {pad!r}")
    runtime.check_host_bytes(4 * resolution * resolution + TILE_BYTES,
                             f"a {resolution} x {resolution} render")
    sets = sample_plan(scene, sampler, spp, sampler_params, pad, pool)
    total = resolution * resolution
    dims = scene.sample_dimensions
    block = block_size(spp, dims)
    blocks = -(-total // block)
    if sampler == "random" and not sampler_params and not pad:
        return _render_random(scene, spp, resolution, seed, block, blocks)
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
            pixel_samples(scene, sampler, spp, resolution, seed, pixels=pixels, pad=pad, _sets=sets,
                          _into=host)
            image[pixels.start:pixels.stop] = _launch(scene, host, pixels.start, len(pixels),
                                                      resolution, spp, width)
            bar.update(len(pixels))
    return image.reshape(resolution, resolution)


def render_task(scene, sampler, spp, resolution, seed, sampler_params):
    """One task of :func:`render_sweep`: the image of one (sampler, spp)."""
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
    scene = _as_scene(scene)
    params = dict(sampler_params or {})
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


def _render_random(scene, spp, resolution, seed, block, blocks):
    """``random`` with ``pad=False``, its draws made in the kernel: the same samples as
    :func:`pixel_samples` gives (the same Philox doubles, the same seeds per block), so the
    same image, without sample buffers."""
    total = resolution * resolution
    keys = np.array([philox.seed_key(derived_seed(seed, b, 0)) for b in range(blocks)],
                    dtype=np.uint32)
    image = np.empty(total, dtype=np.float32)
    for lo, hi in runtime.chunk_ranges(total, 4):
        image[lo:hi] = _launch(scene, None, lo, hi - lo, resolution, spp, keys=keys, block=block)
    return image.reshape(resolution, resolution)


def cache_folder():
    """Where reference renders are cached: ``$CLSAMP_CACHE``, else ``~/.cache/clsamp``."""
    env = os.environ.get("CLSAMP_CACHE")
    return Path(env) if env else Path.home() / ".cache" / "clsamp"


def reference_key(scene, resolution, spp, seed=REFERENCE_SEED):
    """The cache key of a reference: SHA-256 of the scene's content, resolution, spp, seed."""
    text = f"render-{RENDER_VERSION}|{scene.content_hash()}|{resolution}|{spp}|{seed}"
    return hashlib.sha256(text.encode()).hexdigest()


def reference(scene, resolution, spp=None, progress=True, seed=REFERENCE_SEED, cache=True):
    """A high-spp reference render, cached as OpenEXR.

    The reference is the mean of passes of :data:`REFERENCE_PASS` samples per pixel
    from the ``random`` sampler with all dimensions at once (``pad=False``), each pass
    with its own derived seed: an unbiased estimate whose variance is 1/spp of one
    sample's. It is cached in :func:`cache_folder` under a name holding
    :func:`reference_key` (scene content, resolution, spp, seed); a missing, unreadable or
    mismatching cache file is rendered again and rewritten atomically.

    Parameters
    ----------
    scene : Scene, dict or path
    resolution : int
    spp : int, optional
        Samples per pixel (default 64 x ``scene.default_spp``).
    progress : bool
        Show a progress bar over the passes.
    seed : int
        Seed of the reference.
    cache : bool
        Read and write the cache (False: always render, write nothing).

    Returns
    -------
    ndarray of float32, shape (resolution, resolution)
    """
    scene = _as_scene(scene)
    resolution = check_positive_int(resolution, "resolution", maximum=65535)
    spp = 64 * scene.default_spp if spp is None else check_positive_int(spp, "spp", maximum=2**40)
    seed = check_seed(seed)
    key = reference_key(scene, resolution, spp, seed)
    path = cache_folder() / f"reference-{scene.name}-{resolution}px-{spp}spp-{key[:16]}.exr"
    if cache and path.is_file():
        try:
            image, header = io.read_exr(path, with_header=True)
            if image.shape == (resolution, resolution) and _header_text(header.get("key")) == key:
                return np.ascontiguousarray(image, dtype=np.float32)
        except Exception:  # a corrupt or foreign file: render again and overwrite it
            pass
    from tqdm import tqdm
    total = np.zeros((resolution, resolution), dtype=np.float64)
    passes = -(-spp // REFERENCE_PASS)
    for k in tqdm(range(passes), desc=f"reference {scene.name}", unit="pass", disable=not progress):
        n = min(REFERENCE_PASS, spp - k * REFERENCE_PASS)
        image = render(scene, "random", n, resolution, seed=derived_seed(seed, k, 0, PURPOSE_PASS),
                       pad=False, progress=False)
        total += n * image.astype(np.float64)
    result = (total / spp).astype(np.float32)
    if cache:
        io.write_exr(path, result, {"key": key, "scene": scene.name, "sampler": "random (reference)",
                                    "spp": spp, "seed": seed, "resolution": resolution})
    return result


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
        if not np.issubdtype(a.dtype, np.floating) or not np.all(np.isfinite(a)):
            raise InvalidArgumentError(f"'{name}' must be a finite float image")
    return image.astype(np.float64), ref.astype(np.float64)


def mse(image, ref):
    """Mean squared error of ``image`` against ``ref`` (float64 arithmetic)."""
    image, ref = _check_pair(image, ref)
    return float(np.mean((image - ref) ** 2))


def compare(image, ref):
    """MSE, PSNR (dB) and SSIM of ``image`` against the reference ``ref`` (scikit-image).

    ``data_range`` is the reference's max - min (1 when the reference is constant). SSIM
    uses scikit-image's default 7 x 7 window, shrunk to the largest odd size the image
    allows; it is NaN for images smaller than 3 x 3.
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
    return {"mse": error, "psnr": psnr, "ssim": ssim}


def save(path, image, sampler, spp, seed, scene=None, preview=True):
    """Write ``image`` as OpenEXR with sampler, spp and seed in the header, and a
    tone-mapped PNG preview beside it.

    Parameters
    ----------
    path : str or Path
        The image's name, ending in ``.exr`` or ``.png``: both files are written from its
        stem, ``<stem>.exr`` and (``preview``) ``<stem>.png``, so neither overwrites the
        other.

    Returns
    -------
    list of Path
        The files written, the EXR first.

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
        header["scene"] = scene.name
    written = [io.write_exr(path.with_suffix(".exr"), image, header)]
    if preview:
        written.append(io.write_png(path.with_suffix(".png"), image))
    return [Path(p) for p in written]
