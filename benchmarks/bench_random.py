"""The ``random`` sampler: OpenCL kernel against its NumPy reference and NumPy's own generator."""

import numpy as np
from common import Row, main, on_device, short_name, timed

import clsamp


def run(devices, quick):
    rows = []
    cases = [(2**16, 1, 2), (4096, 16, 2)] if quick else [(2**20, 1, 2), (4096, 64, 2), (2**20, 1, 16)]
    for device in devices:
        on_device(device)
        for n, r, d in cases:
            cl = clsamp.make_sampler("random", d=d, seed=1)
            ref = clsamp.make_sampler("random", d=d, seed=1, backend="numpy")
            t_cl, a = timed(lambda: cl.sample(n, realizations=r), repeats=5)
            t_ref, b = timed(lambda: ref.sample(n, realizations=r), repeats=3)
            same = "bit-identical" if np.array_equal(a, b) else "DIFFERS"
            rows.append(Row("random", f"{r}x{n}x{d}D", short_name(device), t_cl,
                            "numpy reference", t_ref, same))
            rng = np.random.default_rng(1)
            t_np, _ = timed(lambda: rng.random((r, n, d)), repeats=5)
            rows.append(Row("random", f"{r}x{n}x{d}D", short_name(device), t_cl,
                            "numpy default_rng", t_np, f"{r * n / t_cl / 1e6:.1f} Mpts/s"))
    return rows


if __name__ == "__main__":
    main(run, __doc__)
