"""The NumPy reference of kernels/render.cl: the same steps in float64, for checks."""

import math

import numpy as np


def camera_frame(scene):
    """The camera's position and orthonormal frame, as ``kernels/render.cl`` builds it.

    Parameters
    ----------
    scene : Scene
        Its camera's ``eye``, ``look_at`` and ``up``.

    Returns
    -------
    eye, forward, right, up : ndarray
        float64 3-vectors: the eye; the unit view direction; the unit vector forward x up;
        and right x forward, the true up (``up`` need not be orthogonal to the view).
    """
    cam = scene.camera
    eye = np.array(cam["eye"], dtype=np.float64)
    forward = np.array(cam["look_at"]) - eye
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, np.array(cam["up"], dtype=np.float64))
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    return eye, forward, right, up



def _concentric(u1, u2):
    a, b = 2.0 * u1 - 1.0, 2.0 * u2 - 1.0
    wide = np.abs(a) > np.abs(b)
    r = np.where(wide, a, b)
    with np.errstate(divide="ignore", invalid="ignore"):
        num = np.where(wide, b, a)
        den = np.where(wide, a, np.where(b == 0, 1.0, b))
        phi = np.where(wide, np.pi / 4 * (num / den), np.pi / 2 - np.pi / 4 * (num / den))
    zero = (a == 0) & (b == 0)
    return np.where(zero, 0.0, r * np.cos(phi)), np.where(zero, 0.0, r * np.sin(phi))


def _trace(scene, o, d, time, tmax, nearest):
    """NumPy twin of nearest_hit / occluded: (t, normal, albedo) or the occlusion mask."""
    best = np.broadcast_to(np.asarray(tmax, dtype=np.float64), o.shape[:-1]).copy()
    normal = np.zeros(o.shape)
    albedo = np.zeros(o.shape[:-1])
    blocked = np.zeros(o.shape[:-1], dtype=bool)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for s in scene.shapes:
            if s["type"] == "sphere":
                c = np.array(s["center"]) + np.array(s["velocity"]) * time[..., None]
                oc = o - c
                b = np.sum(oc * d, -1)
                cc = np.sum(oc * oc, -1) - s["radius"] ** 2
                disc = b * b - cc
                root = np.sqrt(np.maximum(disc, 0))
                t0 = -b - root
                t = np.where(t0 > 0, t0, -b + root)
                hit = (disc >= 0) & (t > 0)
                n = (oc + t[..., None] * d) / s["radius"]
            elif s["type"] == "plane":
                pn = np.array(s["normal"])
                den = d @ pn
                t = ((np.array(s["point"]) - o) @ pn) / den
                hit = (den != 0) & (t > 0)
                n = np.broadcast_to(pn, o.shape)
            else:
                ia = 1.0 / d
                a = (np.array(s["min"]) - o) * ia
                bb = (np.array(s["max"]) - o) * ia
                lo, hi = np.minimum(a, bb), np.maximum(a, bb)
                t = lo.max(-1)
                hit = (t <= hi.min(-1)) & (t > 0)
                onx = t == lo[..., 0]
                ony = ~onx & (t == lo[..., 1])
                n = np.stack([onx, ony, ~onx & ~ony], -1).astype(np.float64)
            if nearest:
                take = hit & (t < best)
                best = np.where(take, t, best)
                normal = np.where(take[..., None], n, normal)
                albedo = np.where(take, s["albedo"], albedo)
            else:
                blocked |= hit & (t < tmax)
    if not nearest:
        return blocked
    flip = np.where(np.sum(normal * d, -1) > 0, -1.0, 1.0)
    return best, normal * flip[..., None], albedo


def screen_window(scene, width, height):
    """Half the width and height of the screen window at distance 1 from the eye: the
    camera's fov spans the shorter side of the image, as in pbrt's perspective camera.

    Parameters
    ----------
    scene : Scene
        Its camera's ``fov``, in degrees.
    width, height : int
        The image's size in pixels.

    Returns
    -------
    (float, float)
        Half the window's width and half its height.
    """
    tan_half = math.tan(math.radians(scene.camera["fov"]) / 2)
    aspect = width / height
    return (tan_half * aspect, tan_half) if aspect > 1 else (tan_half, tan_half / aspect)


def render_reference(scene, samples, resolution, pixel0=0):
    """NumPy reference of ``render_pixels`` (float64): pixel values for the given samples.

    Follows ``kernels/render.cl`` step by step; for checks on small images (it holds every
    ray of the tile in memory).

    Parameters
    ----------
    scene : Scene
    samples : array_like
        (pixels, scene.sample_dimensions, spp) in [0, 1): each pixel's samples, their
        dimensions in the scene's order (``scene.sample_groups``).
    resolution : (int, int)
        The image's (width, height).
    pixel0 : int
        The number (row-major) of the first pixel of ``samples``.

    Returns
    -------
    ndarray
        float32 of shape (pixels,), as the kernel writes it: each pixel's mean radiance
        over its samples, computed in float64.
    """
    width, height = resolution
    samples = np.asarray(samples, dtype=np.float64)
    npix, dims, spp = samples.shape
    eye, forward, right, up = camera_frame(scene)
    cam = scene.camera
    half_w, half_h = screen_window(scene, width, height)
    pixel = pixel0 + np.arange(npix)
    col = (pixel % width).astype(np.float64)[:, None]
    row = (pixel // width).astype(np.float64)[:, None]
    offsets, k = {}, 0
    for g, w in scene.sample_groups:
        offsets[g] = k
        k += w

    def dim(name, j=0):
        return samples[:, offsets[name] + j, :]

    px, py = (dim("pixel"), dim("pixel", 1)) if "pixel" in offsets else (0.5, 0.5)
    sx = (2 * (col + px) / width - 1) * half_w
    sy = (1 - 2 * (row + py) / height) * half_h
    sx, sy = (np.broadcast_to(a, (npix, spp)) for a in (sx, sy))
    d = forward + sx[..., None] * right + sy[..., None] * up
    o = np.broadcast_to(eye, d.shape).copy()
    if "lens" in offsets:
        lens = cam["lens"]
        lx, ly = _concentric(dim("lens"), dim("lens", 1))
        focus = o + d * lens["focus_distance"]
        o = o + (lx * lens["aperture"])[..., None] * right + (ly * lens["aperture"])[..., None] * up
        d = focus - o
    d = d / np.linalg.norm(d, axis=-1, keepdims=True)
    if "time" in offsets:
        time = cam["shutter"][0] + (cam["shutter"][1] - cam["shutter"][0]) * dim("time")
    else:
        time = np.zeros(d.shape[:-1])
    t, n, albedo = _trace(scene, o, d, time, np.inf, nearest=True)
    hit = np.isfinite(t)
    with np.errstate(invalid="ignore"):
        x = o + t[..., None] * d + scene.epsilon * n
    if scene.ao_rays:
        sign = np.where(np.signbit(n[..., 2]), -1.0, 1.0)
        ia = -1.0 / (sign + n[..., 2])
        bb = n[..., 0] * n[..., 1] * ia
        b1 = np.stack([1 + sign * n[..., 0] ** 2 * ia, sign * bb, -sign * n[..., 0]], -1)
        b2 = np.stack([bb, sign + n[..., 1] ** 2 * ia, -n[..., 1]], -1)
        open_ = np.zeros(t.shape)
        for a in range(scene.ao_rays):
            hx, hy = _concentric(dim(f"ao{a}"), dim(f"ao{a}", 1))
            hz = np.sqrt(np.maximum(1 - hx * hx - hy * hy, 0))
            w = hx[..., None] * b1 + hy[..., None] * b2 + hz[..., None] * n
            open_ += ~_trace(scene, x, w, time, scene.ao_distance, nearest=False)
        ambient = scene.ambient * open_ / scene.ao_rays
    else:
        ambient = scene.ambient
    direct = 0.0
    if scene.light is not None:
        light = scene.light
        e1, e2 = np.array(light["edge1"]), np.array(light["edge2"])
        lu, lv = (dim("light"), dim("light", 1)) if "light" in offsets else (0.5, 0.5)
        lu, lv = np.broadcast_arrays(lu, lv, t)[:2]
        q = np.array(light["corner"]) + lu[..., None] * e1 + lv[..., None] * e2
        w = q - x
        dist2 = np.sum(w * w, -1)
        dist = np.sqrt(dist2)
        with np.errstate(invalid="ignore"):     # missed rays: inf - inf, masked below
            w = w / dist[..., None]
        cos_light = -(w @ np.cross(e1, e2))
        cos_surf = np.sum(n * w, -1)
        lit = (cos_light > 0) & (cos_surf > 0)
        shadow = _trace(scene, x, w, time, dist, nearest=False)
        with np.errstate(invalid="ignore"):
            direct = np.where(lit & ~shadow, light["emission"] * cos_light * cos_surf / dist2 / np.pi, 0)
    radiance = np.where(hit, albedo * (ambient + direct), scene.background)
    return radiance.mean(axis=1).astype(np.float32)
