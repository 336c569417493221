"""The ``random`` sampler: OpenCL kernel against its NumPy reference and NumPy's own generator.

    python benchmarks/bench_random.py [--device all] [--quick] [--out FILE]

Every row also gives clsamp's output GB/s (the float64 points ``sample()`` returns, over
its seconds) and its share of ``np.copyto``'s GB/s for the same bytes, measured in the
same run.
"""

import numpy as np
from common import Row, copy_bandwidth, main, on_device, short_name, timed

import clsamp


def run(devices, quick):
    rows = []
    cases = [(2**16, 1, 2), (4096, 16, 2)] if quick else [(2**20, 1, 2), (4096, 64, 2), (2**20, 1, 16)]
    for device in devices:
        on_device(device)
        for n, r, d in cases:
            cl = clsamp.make_sampler("random", d=d, seed=1)
            ref = clsamp.make_sampler("random", d=d, seed=1, backend="numpy")
            # calls of a few ms: the first ones after the build fault the output pool's
            # pages in and wake PoCL's threads, so more warm-up calls and repeats
            t_cl, a = timed(lambda: cl.sample(n, realizations=r), repeats=31, warmup=3)
            t_ref, b = timed(lambda: ref.sample(n, realizations=r), repeats=3)
            same = "bit-identical" if np.array_equal(a, b) else "DIFFERS"
            copy = copy_bandwidth(a.nbytes)
            rows.append(Row("random", f"{r}x{n}x{d}D", short_name(device), t_cl,
                            "numpy reference", t_ref, same, output_bytes=a.nbytes, copy_gbs=copy))
            rng = np.random.default_rng(1)
            t_np, _ = timed(lambda: rng.random((r, n, d)), repeats=31, warmup=3)
            rows.append(Row("random", f"{r}x{n}x{d}D", short_name(device), t_cl,
                            "numpy default_rng", t_np, f"{r * n / t_cl / 1e6:.1f} Mpts/s",
                            output_bytes=a.nbytes, copy_gbs=copy))
    return rows


if __name__ == "__main__":
    main(run, __doc__)
