"""Launch shapes (clsamp.runtime.shapes): what each device's shape gains over the others.

    python benchmarks/bench_shapes.py [--device all] [--quick] [--out FILE]

On each device the samplers and the renderer whose launches the shape decides are timed
at the device's own shape (what ``runtime.shape()`` gives it: measured once, or a GPU's
default) and, as peers in the same run, at the GPU's shape (one point a work-item, groups
of 128, one sample a renderer lane, everything on the device) and at the host's unmeasured
shape (16 points an item, blocks of 256, groups of 64, the CPU sort, the host BLAS). The
shapes take turns call by call (medians), so a busy machine's drift falls on all alike.
Every shape gives the same bits (the quality column checks it).
"""

import dataclasses
import statistics
import time

import numpy as np
from common import Row, main, on_device, short_name

import clsamp
from clsamp import runtime

CASES = (("random", {"d": 2}, 2**20, 4), ("sobol", {"d": 4}, 2**20, 4),
         ("sobol:owen", {"d": 4}, 2**18, 4), ("halton:permute", {"d": 4}, 2**18, 4),
         ("jittered", {"d": 2}, 2**20, 4), ("sot", {"d": 2, "iterations": 64}, 4096, 1))
QUICK = (("random", {"d": 2}, 2**18, 2), ("sobol", {"d": 4}, 2**18, 2),
         ("halton:permute", {"d": 4}, 2**16, 2), ("sot", {"d": 2, "iterations": 16}, 1024, 1))


def _sampler(label, params):
    name, _, randomize = label.partition(":")
    return clsamp.make_sampler(name, seed=1, **params, **({"randomize": randomize} if randomize else {}))


def _sampling(label, params, n, r):
    sampler = _sampler(label, params)
    return lambda: sampler.sample(n, realizations=r)


def _render(n):
    from clsamp import render as rendering
    from clsamp.scene import Scene
    scene = Scene.from_file("ao")
    return lambda: rendering.render(scene, "random", 64, n, seed=1, progress=False)


def _interleaved(fn, shapes, rounds):
    """Median seconds of ``fn`` at each shape, the shapes taking turns round by round (after
    one untimed call each, which builds), so a busy machine's drift falls on all alike; and
    each shape's last result."""
    results = {}
    for key, shape in shapes.items():
        with runtime.forced_shape(shape):
            results[key] = fn()
    times = {key: [] for key in shapes}
    for _ in range(rounds):
        for key, shape in shapes.items():
            with runtime.forced_shape(shape):
                t0 = time.perf_counter()
                results[key] = fn()
                times[key].append(time.perf_counter() - t0)
    return {key: statistics.median(t) for key, t in times.items()}, results


def run(devices, quick):
    rows = []
    for device in devices:
        on_device(device)
        own = runtime.shape()
        others = {"gpu shape": runtime.shapes.gpu_shape(runtime.current_device()),
                  "host shape": runtime.shapes.host_shape(runtime.current_device())}
        shape_text = (f"{own.source}: {own.points_per_item} pts/item, block {own.block}, "
                      f"local {own.local}, vw {own.vector_width}")
        jobs = [(f"{label} r={r}", f"{r}x{n}x{params['d']}D", _sampling(label, params, n, r))
                for label, params, n, r in (QUICK if quick else CASES)]
        jobs.append(("render ao, random 64 spp", f"{32 if quick else 96}^2 px",
                     _render(32 if quick else 96)))
        shapes = {"own": own, **others}
        for case, size, fn in jobs:
            seconds, results = _interleaved(fn, shapes, rounds=5 if quick else 9)
            want = results["own"]
            for peer in others:
                got = results[peer]
                if case.startswith("render"):
                    same = f"max diff {np.abs(got - want).max():.1e}"
                else:
                    same = "bit-identical" if np.array_equal(got, want) else "DIFFERS"
                rows.append(Row(f"{case} at own shape", size, short_name(device), seconds["own"],
                                peer, seconds[peer], f"{same}; {shape_text}",
                                {"shape": dataclasses.asdict(own)}))
    return rows


if __name__ == "__main__":
    main(run, __doc__)
