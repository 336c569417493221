"""Which samples each pixel of a render gets: the plan, the seeds and the padding.

Sample dimensions (docs/design.md, "Rendering")
-------------------------------------------------
Each pixel sample has exactly the dimensions of the scene's effects, in the fixed order
pixel 2, lens 2, time 1, 2 per AO ray, light 2 (``scene.sample_groups``). With
``pad=True`` (the default) the sampler is asked, for each pixel, for one set of ``spp``
2-D points per pair of dimensions (a 1-D set for time: ``d=1`` where the sampler has
it, else the first coordinate of a 2-D set), and the sets are *padded* as pbrt pads
(Pharr et al., PBR 3rd ed., 7.2.3): the samples of every set are reordered by an
independent, exactly uniform random permutation, so that no correlation links the
order of one set to another's (Fisher–Yates on the Philox stream ``PIXEL``,
realization = pixel number, permutation = set number; see :mod:`clsamp.permutation`).
A pixel sample made of a single set is not permuted: its order cannot change the
pixel's mean. With ``pad=False`` the sampler makes all ``d = scene.sample_dimensions``
dimensions at once (random, latin_hypercube, halton, sobol, ...), unpermuted;
``random`` with ``pad=False`` (the reference's sampler) draws the very same Philox
numbers inside the kernel instead of through a sample buffer.

Decorrelation across pixels
---------------------------
Every pixel uses its own independent realization of the sampler. Pixels are grouped
in *seed blocks* of :func:`block_size` consecutive pixels (row-major); the sampler of
set ``g`` in block ``b`` is created with the seed ``philox(seed, PIXEL, index=b,
realization=g)`` and pixel ``b * B + k`` takes its realization ``k``. The block size
follows only from ``spp`` and the dimensions, never from the device, so the same seed
gives the same samples on every device, and the same image up to float rounding
(the ray math is float32; on one device the image is bit-identical run to run).

*Expensive* samplers (``Sampler.expensive``: optimizers and dart throwing) cannot afford
one realization per pixel. For them a pool of ``pool`` realizations (default
:data:`DEFAULT_POOL`) per set is made once (seeded per set),
and pixel ``p`` takes pool member ``j(p)`` shifted by its own random toroidal vector
``u(p)``: ``x -> (x + u) mod 1`` (Cranley–Patterson). The shift keeps the set's
blue-noise and stratification on the torus and makes each pixel's estimate unbiased
(every point uniform); ``j`` and ``u`` are Philox draws keyed by (seed, pixel, set),
so pixels sharing a pool member still see different point positions.

*Pixel-indexed* samplers (``pixel_indexed = True``: ``zsobol``) decorrelate pixels
themselves, by handing each pixel its part of one sequence: set ``g`` is one sampler for
the whole image (seed ``philox(seed, PIXEL, index=0xFFFFFFFE, realization=g)``, made
for the image's size by ``for_image``), pixel p takes its realization p, and its sets
are not permuted (pbrt does not pad its ZSobolSampler either: each pair of dimensions
has its own digit permutations and scrambles).
"""

import numpy as np

from . import permutation, philox
from .errors import InvalidArgumentError
from .geometry import torus
from .samplers import Sampler, make_quiet_sampler, sampler_class
from .scene import as_scene
from .validation import check_image_size, check_positive_int, check_seed

DEFAULT_POOL = 8                    # realizations per set of an expensive sampler
MAX_BLOCK = 1024                    # pixels per seed block at most
BLOCK_BYTES = 64 * 2**20            # float64 sample bytes of one block at most
_IMAGE_INDEX = 0xFFFFFFFE           # derived-seed index of a pixel-indexed sampler's one seed

_SEED_BLOCK = 0x40000000            # Philox block word of derived seeds (above every perm << 8)
PURPOSE_SEED, PURPOSE_POOL, PURPOSE_SHIFT, PURPOSE_PASS = 0, 1, 2, 3


# -- randomness of the renderer ----------------------------------------------------------
def _words(seed, index, realization, purpose):
    """Four Philox words per (index, realization) on the PIXEL stream, one block per purpose."""
    index, realization = np.broadcast_arrays(np.asarray(index, dtype=np.uint32),
                                             np.asarray(realization, dtype=np.uint32))
    counter = np.stack([index, realization,
                        np.full(index.shape, _SEED_BLOCK + purpose, dtype=np.uint32),
                        np.full(index.shape, philox.Stream.PIXEL, dtype=np.uint32)], axis=-1)
    return philox.philox4x32(counter, np.stack(philox.seed_key(seed)))


def _shifts(seed, index, realization, d):
    """A toroidal shift in d dimensions per (index, realization): two components a Philox
    block, the first two from the ``PURPOSE_SHIFT`` block, any more from the blocks after
    ``PURPOSE_PASS`` (a pooled set of more than 2 dimensions, ``pad=False``)."""
    parts = []
    for k in range(-(-d // 2)):
        w = _words(seed, index, realization, PURPOSE_SHIFT if k == 0 else PURPOSE_PASS + k)
        parts += [philox.words_to_unit(w[:, 0], w[:, 1]), philox.words_to_unit(w[:, 2], w[:, 3])]
    return np.stack(parts, axis=-1)[:, :d]


def derived_seed(seed, index, realization, purpose=PURPOSE_SEED):
    """A 64-bit seed drawn from (seed, index, realization): the seed of one sampler of a render.

    Parameters
    ----------
    seed : int
        The render's seed.
    index, realization : int
        32-bit counters (a seed block and a set, for instance).
    purpose : int, optional
        Which draw (``PURPOSE_SEED``, ``PURPOSE_POOL``, ``PURPOSE_SHIFT``, ``PURPOSE_PASS``),
        each from its own Philox block.

    Returns
    -------
    int
        In [0, 2^64).
    """
    w = _words(seed, index, realization, purpose)
    return int(w[..., 0]) | (int(w[..., 1]) << 32)


def block_size(spp, dimensions):
    """Pixels per seed block: a power of two up to 1024, smaller when one block's float64
    samples would pass 64 MiB. It follows from ``spp`` and ``dimensions`` only, never from the
    device, so a seed gives the same samples on every device.

    Parameters
    ----------
    spp : int
    dimensions : int
        The scene's sample dimensions.

    Returns
    -------
    int
    """
    per_pixel = 8 * spp * max(1, dimensions)
    b = MAX_BLOCK
    while b > 1 and b * per_pixel > BLOCK_BYTES:
        b //= 2
    return b


def float32_samples(x):
    """Samples as the kernel reads them: float64 rounded toward zero to float32, so they stay
    in [0, 1) (round-to-nearest could give 1.0).

    Parameters
    ----------
    x : ndarray of float64
        In [0, 1).

    Returns
    -------
    ndarray of float32
        Of ``x``'s shape.
    """
    f = x.astype(np.float32)
    up = f > x
    f[up] = np.nextafter(f[up], np.float32(0))
    return f


# -- the plan: which sampler makes which dimensions ------------------------------------------
class _Set:
    """One sampler set of a pixel: dimensions [offset, offset + width) from a d-D sampler."""

    def __init__(self, offset, width, d, factory, pooled):
        self.offset, self.width, self.d, self.factory, self.pooled = offset, width, d, factory, pooled
        self.pool = None
        self.indexed = False    # a pixel-indexed sampler (zsobol): one sampler, realization = pixel


def _sampler_factory(sampler, sampler_params):
    """(name, make(d, seed) -> Sampler, supports(d) -> bool, expensive)."""
    if isinstance(sampler, Sampler):
        if sampler_params:
            raise InvalidArgumentError("'sampler_params' can only be given with a sampler name, "
                                       "not with a Sampler object")
        base = sampler

        def make(d, seed):
            if d != base.d:
                raise InvalidArgumentError(
                    f"'sampler' has d={base.d}; this render needs d={d} (pairs of dimensions "
                    "with pad=True, scene.sample_dimensions with pad=False)")
            return base.with_seed(seed)

        return base.label, make, lambda d: d == base.d, base.expensive
    if not isinstance(sampler, str):
        raise InvalidArgumentError(f"'sampler' must be a sampler name or a Sampler, got {sampler!r}")
    if sampler_params is not None and not isinstance(sampler_params, dict):
        raise InvalidArgumentError(f"'sampler_params' must be a dict, got {sampler_params!r}")
    params = dict(sampler_params or {})
    for key in params:
        if not isinstance(key, str) or key in ("d", "seed"):
            raise InvalidArgumentError(
                f"'sampler_params' key {key!r}: the keys are the sampler's parameters by name, "
                "other than 'd' (the scene's dimensions) and 'seed' (the render's)")
    cls = sampler_class(sampler)        # raises, naming the unknown sampler and the known ones

    def make(d, seed):      # without a progress bar of its own (bnot's): the render has one
        return make_quiet_sampler(sampler, d=d, seed=seed, **dict(params))

    def supports(d):
        try:
            make(d, 0)
            return True
        except InvalidArgumentError:
            return False

    return sampler, make, supports, cls.expensive


def sample_plan(scene, sampler, spp, sampler_params, pad, pool):
    """The sets one pixel sample is made of: one per group of the scene's dimensions (``pad``)
    or one for all of them, each with its factory, dimension and whether the sampler is
    pixel-indexed or pooled.

    Parameters
    ----------
    scene, sampler, spp, sampler_params, pad, pool
        As :func:`pixel_samples` takes them.

    Returns
    -------
    list
        The sets, in the order of the scene's dimensions.

    Raises
    ------
    InvalidArgumentError
        An ``spp`` the sampler cannot make in a set's dimension (naming the nearest valid
        one), an unknown sampler, or ``sampler_params`` with a Sampler object.
    """
    name, make, supports, expensive = _sampler_factory(sampler, sampler_params)
    sets, offset = [], 0
    if pad:
        for _, width in scene.sample_groups:
            d = width
            if width == 1 and not supports(1):
                d = 2          # a 2-D-only sampler: time is the first coordinate of a 2-D set
            sets.append(_Set(offset, width, d, make, expensive))
            offset += width
    elif scene.sample_dimensions:
        sets.append(_Set(0, scene.sample_dimensions, scene.sample_dimensions, make, expensive))
    for s in sets:
        probe = make(s.d, 0)
        s.indexed = probe.pixel_indexed
        valid = probe.valid_n(spp)
        if valid != spp:
            raise InvalidArgumentError(
                f"'spp'={spp}: sampler {name!r} cannot make {spp} points in d={s.d} "
                f"(the renderer asks for one {s.d}-D set of spp points per pixel"
                f"{' and pair of dimensions' if pad else ''}); the nearest valid spp is {valid}")
        if spp > probe.max_n:
            raise InvalidArgumentError(f"'spp'={spp} exceeds what sampler {name!r} can make "
                                       f"({probe.max_n})")
    for s in sets:
        if s.pooled:
            s.pool_size = pool
    return sets


def image_size(resolution, name="resolution"):
    """The size of an image (:func:`clsamp.validation.check_image_size`).

    Parameters
    ----------
    resolution : int or (int, int)
        A side, or (width, height).
    name : str, optional
        The argument's name, for the message.

    Returns
    -------
    (int, int)
        (width, height).

    Raises
    ------
    InvalidArgumentError
        Not a positive size up to 65535 pixels a side.
    """
    return check_image_size(resolution, name)


def pixel_samples(scene, sampler, spp, resolution, seed=0, sampler_params=None, pad=True,
                  pixels=None, pool=DEFAULT_POOL, _sets=None, _into=None):
    """The samples the renderer feeds the kernel, in [0, 1).

    Parameters
    ----------
    scene, sampler, spp, resolution, seed, sampler_params, pad, pool
        As :func:`clsamp.render.render` takes them.
    pixels : range, optional
        Row-major pixel numbers (pixel ``row * width + col``), starting on a seed-block
        boundary (:func:`block_size`) unless it is the whole image; all pixels by default.

    Returns
    -------
    ndarray of float64, shape (pixels, scene.sample_dimensions, spp)

    Raises
    ------
    InvalidArgumentError
        Arguments :func:`clsamp.render.render` refuses, or ``pixels`` not starting on a
        seed-block boundary.
    """
    width, height = image_size(resolution)
    spp = check_positive_int(spp, "spp", maximum=2**31)
    seed = check_seed(seed)
    total = width * height
    if _sets is None:           # (render checked these, and passes its plan)
        scene = as_scene(scene)
        pool = check_positive_int(pool, "pool")
        if not isinstance(pad, bool):
            raise InvalidArgumentError(f"'pad' must be True or False, got {pad!r}")
    pixels = range(total) if pixels is None else pixels
    if not isinstance(pixels, range) or pixels.step != 1 or pixels.start < 0 or pixels.stop > total:
        raise InvalidArgumentError(
            f"'pixels' must be a range of step 1 within the image's {total} pixels, got {pixels!r}")
    sets = _sets if _sets is not None else sample_plan(scene, sampler, spp, sampler_params, pad, pool)
    dims = scene.sample_dimensions
    # _into: the kernel's float32 buffer (pixels, >= dims, >= spp), filled set by set
    out = np.empty((len(pixels), dims, spp), dtype=np.float64) if _into is None else _into
    if not dims or not len(pixels):
        return out
    block = block_size(spp, dims)
    if pixels.start % block:
        raise InvalidArgumentError(f"'pixels' must start on a seed block boundary ({block}), "
                                   f"got {pixels!r}")
    lo, hi = pixels.start, pixels.stop
    perms = None
    if pad and sum(not s.indexed for s in sets) > 1:   # one set alone: its order cannot change the mean
        perms = permutation.random_permutations_device(
            seed, philox.Stream.PIXEL, range(lo, hi), spp, range(len(sets))).get()
    for g, s in enumerate(sets):
        if s.pooled:
            if s.pool is None:
                count = min(s.pool_size, total)
                s.pool = s.factory(s.d, derived_seed(seed, 0xFFFFFFFF, g)).sample(
                    spp, realizations=count)
            w = _words(seed, np.arange(lo, hi), g, PURPOSE_POOL)
            # Lemire's multiply-shift: bias below pool / 2^32, negligible and deterministic
            choice = ((w[:, 0].astype(np.uint64) * np.uint64(len(s.pool))) >> np.uint64(32)).astype(np.intp)
            points = torus.shift(s.pool[choice], _shifts(seed, np.arange(lo, hi), g, s.d)[:, None, :])
        elif s.indexed:          # one sampler for the image; its realizations are the pixels
            points = s.factory(s.d, derived_seed(seed, _IMAGE_INDEX, g)).for_image(width, height).sample(
                spp, realizations=range(lo, hi))
        else:
            points = np.empty((hi - lo, spp, s.d))
            for b in range(lo // block, -(-hi // block)):
                b_lo, b_hi = max(lo, b * block), min(hi, (b + 1) * block)
                sampler_b = s.factory(s.d, derived_seed(seed, b, g))
                # realization k of block b is pixel b * block + k
                points[b_lo - lo:b_hi - lo] = sampler_b.sample(
                    spp, realizations=range(b_lo - b * block, b_hi - b * block))
        if perms is not None and not s.indexed:
            flat = perms[:, g, :].astype(np.intp) + (np.arange(hi - lo, dtype=np.intp) * spp)[:, None]
            points = points.reshape(-1, s.d)[flat.ravel()].reshape(hi - lo, spp, s.d)
        columns = points[:, :, :s.width].transpose(0, 2, 1)
        if _into is None:
            out[:, s.offset:s.offset + s.width, :] = columns
        else:
            out[:, s.offset:s.offset + s.width, :spp] = float32_samples(columns)
    return out
