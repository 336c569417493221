"""The stratified family: OpenCL kernels against their NumPy references and
scipy.stats.qmc.LatinHypercube, and the permutations against NumPy's shuffle.

    python benchmarks/bench_stratified.py [--device all] [--quick] [--out FILE]

Cases: one set of 2^20 2-D points and 64 realizations of 4096 (``--quick``: 2^16 and
16 x 4096). Times are for ``sample()`` returning host arrays (the transfer included).
Every row also gives clsamp's output GB/s (the array returned, over its seconds) and its
share of ``np.copyto``'s GB/s for the same bytes, measured in the same run.
The NumPy references of the shuffling samplers run Fisher–Yates in a Python loop,
so they are timed once, without warm-up.
"""

import numpy as np
from common import Row, copy_bandwidth, main, on_device, short_name, timed
from scipy.stats import qmc

import clsamp
from clsamp import permutation
from clsamp.philox import Stream

SAMPLERS = ("regular", "jittered", "uncorrelated_jitter", "latin_hypercube", "multijittered",
            "correlated_multijittered")


def _stratified(name, points):
    """Whether every realization is stratified as the sampler promises (2-D)."""
    r, n, _ = points.shape
    k = int(round(np.sqrt(n)))
    if name in ("latin_hypercube", "multijittered", "correlated_multijittered"):
        slabs = np.floor(points * n).astype(np.int64)
        ok = all(np.unique(slabs[i, :, j]).size == n for i in range(r) for j in range(2))
        if name == "latin_hypercube":
            return ok
    else:
        ok = True
    cell = np.floor(points * k).astype(np.int64) @ np.array([1, k])
    return ok and all(np.unique(cell[i]).size == n for i in range(r))


def run(devices, quick):
    rows = []
    cases = [(2**16, 1), (4096, 16)] if quick else [(2**20, 1), (4096, 64)]
    peers = {}
    for n, r in cases:
        # scipy draws one set per call; 64 realizations are 64 calls of one engine
        engine = qmc.LatinHypercube(d=2, seed=1)
        peers[(n, r)] = timed(lambda: [engine.random(n) for _ in range(r)], repeats=3)[0]
        rng = np.random.default_rng(1)
        peers[("perm", n, r)] = timed(lambda: [rng.permutation(n) for _ in range(2 * r)],
                                      repeats=3)[0]
    for device in devices:
        on_device(device)
        dev = short_name(device)
        for n, r in cases:
            size = f"{r}x{n}x2D"
            copy = copy_bandwidth(r * n * 2 * 8)
            for name in SAMPLERS:
                cl = clsamp.make_sampler(name, d=2, seed=1)
                ref = clsamp.make_sampler(name, d=2, seed=1, backend="numpy")
                t_cl, a = timed(lambda: cl.sample(n, realizations=r), repeats=5)
                t_ref, b = timed(lambda: ref.sample(n, realizations=r), repeats=1, warmup=0)
                same = "bit-identical" if np.array_equal(a, b) else "DIFFERS"
                strat = "stratified" if _stratified(name, a) else "NOT STRATIFIED"
                rate = f"{r * n / t_cl / 1e6:.1f} Mpts/s"
                rows.append(Row(name, size, dev, t_cl, "numpy reference", t_ref,
                                f"{same}, {strat}, {rate}", output_bytes=a.nbytes, copy_gbs=copy))
                # scipy has no jittered or multi-jittered sampler: its LatinHypercube is
                # the stratified peer of them all (the like-for-like one for latin_hypercube)
                rows.append(Row(name, size, dev, t_cl, "scipy LatinHypercube", peers[(n, r)], rate,
                                output_bytes=a.nbytes, copy_gbs=copy))
            t_p, p = timed(lambda: permutation.random_permutations_device(
                1, Stream.PERMUTATION, r, n, 2).get(), repeats=5)
            ok = np.array_equal(np.sort(p, axis=-1), np.broadcast_to(np.arange(n), p.shape))
            rows.append(Row("random_permutations", f"{r}x2x{n}", dev, t_p,
                            "numpy Generator.permutation", peers[("perm", n, r)],
                            "permutations" if ok else "NOT PERMUTATIONS",
                            output_bytes=p.nbytes, copy_gbs=copy_bandwidth(p.nbytes)))
    return rows


if __name__ == "__main__":
    main(run, __doc__)
