"""The renderer: rays per second, what each effect costs, and MSE per second per sampler.

    python benchmarks/bench_render.py [--device all] [--quick] [--out FILE]

Cases, on each device:
- ``rays/s <scene>``: the kernel alone on pre-made float32 samples (every shipped scene;
  the upload included, sampling not), against
  the NumPy reference renderer on the same samples (a smaller image: it holds every ray
  in memory). Rays = camera rays + AO rays + shadow rays.
- ``combined -<effect>``: the combined scene with one effect taken out, full render
  (sampling included), against the scene with every effect: what the effect costs and
  what skipping it saves (ratio < 1: the effect is expensive).
- ``sampler <name>``: the AO scene at its 128 spp, full render against the cached reference
  (MSE); the quality column also gives MSE x seconds (lower is better), the peer is
  the random sampler.
- ``zsobol``: the AO scene at 256 x 256 (quick 64 x 64), 64 spp, against ``sobol:owen`` at the
  same size (target: at most 1.2x its time), with the MSE and the low-frequency share of the
  error (1 for white error, below 1 for blue) of both.

Sizes: 192 x 192 pixels (``--quick``: 48 x 48) at 96 spp for rays/s, the AO scene's 128 for
the samplers, 64 spp
for the effects; the reference at 8192 spp (quick: 2048).
"""

import time

from common import Row, main, on_device, short_name, timed

import clsamp
from clsamp import render as rendering
from clsamp.scene import Scene, shipped_scenes

SAMPLERS = (("random", None), ("jittered", {"strata": (16, 8)}), ("latin_hypercube", None),
            ("correlated_multijittered", None), ("sobol:owen", None), ("halton:owen", None),
            ("poisson_disk", None), ("ccvt", None))


def _rays(scene, resolution, spp):
    return resolution * resolution * spp * scene.rays_per_sample()


def run(devices, quick):
    rows = []
    res = 48 if quick else 192
    small = 16 if quick else 32
    ref_spp = 2048 if quick else 8192
    known = set(clsamp.sampler_names())
    for device in devices:
        on_device(device)
        dev = short_name(device)
        # rays per second: kernel alone, against the NumPy renderer
        for name in shipped_scenes():
            scene = Scene.from_file(name)
            spp = 96
            samples = rendering.pixel_samples(scene, "random", spp, res, seed=1)
            f32 = rendering.float32_samples(samples)
            seconds, _ = timed(lambda: rendering.render_samples(scene, f32, res), repeats=5)  # noqa: B023
            few = samples[:small * small]
            t_np, _ = timed(lambda: rendering.render_samples(scene, few, res, backend="numpy"),
                            repeats=1, warmup=0)
            t_np *= (res * res) / (small * small)    # per the same number of rays
            rate = _rays(scene, res, spp) / seconds
            rows.append(Row(f"rays/s {name}", f"{res}^2x{spp}spp", dev, seconds,
                            "numpy reference (scaled)", t_np,
                            f"{rate / 1e6:.1f} Mrays/s, {scene.sample_dimensions} dims"))
        # each effect on and off
        combined = Scene.from_file("combined").to_dict()
        spp = 64

        def full(data):
            scene = Scene.from_dict(data)
            rendering.render(scene, "random", spp, 8, seed=1, progress=False)   # build first
            return timed(lambda: rendering.render(scene, "random", spp, res, seed=1, progress=False),
                         repeats=3)[0], scene

        t_all, scene_all = full(combined)
        rows.append(Row("combined (all effects)", f"{res}^2x{spp}spp", dev, t_all, quality=
                        f"{scene_all.sample_dimensions} dims, "
                        f"{_rays(scene_all, res, spp) / t_all / 1e6:.1f} Mrays/s"))
        for effect in scene_all.effects:
            data = dict(combined, effects=[e for e in combined["effects"] if e != effect])
            seconds, scene = full(data)
            rows.append(Row(f"combined -{effect}", f"{res}^2x{spp}spp", dev, seconds,
                            "combined (all effects)", t_all,
                            f"{scene.sample_dimensions} dims, saves {1 - seconds / t_all:.0%}"))
        # MSE per second for each sampler at equal spp
        ao = Scene.from_file("ao")
        t0 = time.perf_counter()
        ref = rendering.reference(ao, res, spp=ref_spp, progress=False)
        ref_seconds = time.perf_counter() - t0
        rows.append(Row("reference ao", f"{res}^2x{ref_spp}spp", dev, ref_seconds,
                        quality=f"{rendering.REFERENCE_SAMPLER} x {rendering.REFERENCE_PASSES} passes "
                        "(cached after the first run)"))
        t_random = None
        for name, params in SAMPLERS:
            if name.partition(":")[0] not in known:
                continue
            rendering.render(ao, name, ao.default_spp, 8, seed=4, sampler_params=params, progress=False)
            seconds, image = timed(lambda: rendering.render(  # noqa: B023
                ao, name, ao.default_spp, res, seed=4, sampler_params=params, progress=False),
                repeats=3)
            mse = rendering.mse(image, ref)
            if name == "random":
                t_random = seconds
            rows.append(Row(f"sampler {name}", f"{res}^2x{ao.default_spp}spp", dev, seconds,
                            "random" if t_random else "", t_random,
                            f"MSE {mse:.3g}, MSE x s {mse * seconds:.3g}"))
        rows.append(_zsobol(ao, dev, quick))
    return rows


def _zsobol(ao, dev, quick):
    side, spp = (64, 64) if quick else (256, 64)
    ref = rendering.reference(ao, side, spp=1024 if quick else 4096, progress=False)
    out = {}
    for name in ("sobol:owen", "zsobol"):
        rendering.render(ao, name, spp, 8, seed=4, progress=False)            # build first
        seconds, image = timed(lambda: rendering.render(ao, name, spp, side, seed=4,  # noqa: B023
                                                        progress=False), repeats=3)
        out[name] = (seconds, rendering.mse(image, ref), rendering.low_frequency_power(image, ref))
    (t_z, mse_z, low_z), (t_o, mse_o, low_o) = out["zsobol"], out["sobol:owen"]
    return Row("zsobol AO render", f"{side}^2x{spp}spp", dev, t_z, "sobol:owen render", t_o,
               f"MSE {mse_z:.3g} vs {mse_o:.3g}; low-freq share {low_z:.2f} vs {low_o:.2f}",
               extra={"time_over_sobol_owen": t_z / t_o})


if __name__ == "__main__":
    main(run, __doc__)
