"""Hash the outputs of every sampler and randomization, a convergence sweep, a family sweep,
an integration and three renders, to show that a refactoring keeps the bits.

    python scripts/bit_hashes.py > before.txt      # on the old tree
    python scripts/bit_hashes.py > after.txt       # on the new one
    diff before.txt after.txt                      # nothing: the same bits

Each line is ``case  sha256[:16]`` of the output's bytes, on the default device. Samplers are
hashed at 2^20 points a set (n rounded to the nearest valid n) in 2-D and in their highest
listed dimension up to 4-D; the expensive ones (dart throwing, optimizers) at small n.
"""

import argparse
import hashlib
import sys

import numpy as np

import clsamp
from clsamp.render import Scene, render

N = 1 << 20
SMALL = {"ccvt": 1024, "lloyd": 1024, "poisson_disk": 1024, "pmj02bn": 4096, "gbn": 1024}


def digest(array):
    return hashlib.sha256(np.ascontiguousarray(array).tobytes()).hexdigest()[:16]


def sampler_cases(quick):
    for name in clsamp.sampler_names():
        cls = clsamp.samplers.sampler_class(name)
        dims = cls.dimensions or (1, 2, 4)
        for d in sorted({min(dims), 2, max(x for x in dims if x <= 4)} & set(dims)):
            for randomize in cls.randomizations:
                params = {} if randomize is None else {"randomize": randomize}
                sampler = clsamp.make_sampler(name, d=d, seed=7, **params)
                n = sampler.valid_n(SMALL.get(name, N) >> (6 if quick else 0))
                yield f"{sampler.label} d={d} n={n}", sampler, n


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="64x fewer points a set")
    args = parser.parse_args(argv)
    out = sys.stdout
    for case, sampler, n in sampler_cases(args.quick):
        out.write(f"{case:44s} {digest(sampler.sample(n, realizations=2, start=0))}\n")
        if sampler.accepts_start and sampler.sequence:
            out.write(f"{case + ' start=5':44s} {digest(sampler.sample(64, start=5))}\n")
        out.flush()
    r = clsamp.convergence("jittered", "disk", [16, 64, 256], realizations=64, seed=3)
    out.write(f"{'convergence jittered disk':44s} {digest(np.stack([r.mse, r.mean, r.variance]))}\n")
    r = clsamp.convergence("sobol:owen", "gaussian", [16, 64, 256], realizations=64, seed=3)
    out.write(f"{'convergence sobol:owen gaussian':44s} {digest(np.stack([r.mse, r.mean]))}\n")
    f = clsamp.convergence("jittered", "random_heavisides", [16, 64], realizations=8, members=16, seed=3)
    out.write(f"{'family jittered random_heavisides':44s} {digest(f.mse)}\n")
    res = clsamp.integrate(lambda x: np.exp(-np.sum(x * x, axis=1)), 3, abs_tol=1e-5)
    out.write(f"{'integrate gaussian 3-D':44s} {digest(np.array([res.estimate, res.half_width]))}\n")
    scene = Scene.from_file("ao")
    for sampler, spp in (("jittered", 16), ("zsobol", 16), ("poisson_disk", 16), ("sobol:owen", 16)):
        img = render(scene, sampler, spp=spp, resolution=32, seed=1)
        out.write(f"{'render ao ' + sampler:44s} {digest(img)}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
