"""pmj02 and pmj02bn against NumPy implementations of the same algorithms and scipy's Sobol.

    python benchmarks/bench_pmj.py [--device all] [--quick] [--out FILE]

Cases: 2^20 points x 16 realizations (``--quick``: 2^16 x 16). The peers: for ``pmj02``, the
same level-by-level construction vectorized in NumPy with ``default_rng`` bits (what a NumPy
user would write; not clsamp's bits); for ``pmj02bn``, clsamp's NumPy reference (a Python
loop: the sequential algorithm has no vectorized form) at 2^12 x 1, against the kernel at
the same size; and ``scipy.stats.qmc.Sobol(2, scramble=True)`` for scale, one engine per
realization. Times are for ``sample()`` returning host float64 arrays.
"""

import numpy as np
from common import Row, main, on_device, short_name, timed
from scipy.stats import qmc

import clsamp
from clsamp.errors import NoDeviceError
from clsamp.samplers import pmj


def numpy_pmj02(n, realizations, seed=1):
    """The pmj02 construction in NumPy: (realizations, n, 2) float64."""
    rng = np.random.default_rng(seed)
    x = rng.integers(0, 2**53, size=(realizations, n, 2), dtype=np.uint64)
    masks = pmj.xor_masks()
    m, size = 0, 1
    while size < n:
        count = min(size, n - size)
        i = np.arange(count, dtype=np.uint32)
        low = np.uint64(52 - m)
        keep = np.uint64((1 << (52 - m)) - 1)
        for axis in range(2):
            source = x[:, i ^ masks[axis, m], axis]
            x[:, size:size + count, axis] = (((source >> low) ^ np.uint64(1)) << low) \
                | (x[:, size:size + count, axis] & keep)
        m, size = m + 1, size * 2
    return x.astype(np.float64) * 2.0**-53


def _sobol(n, realizations):
    return [qmc.Sobol(2, scramble=True, seed=k).random(n) for k in range(realizations)]


def run(devices, quick):
    rows = []
    n, r = (2**16, 16) if quick else (2**20, 16)
    small = 2**12
    numpy_seconds, _ = timed(lambda: numpy_pmj02(n, r), repeats=3)
    sobol_seconds, _ = timed(lambda: _sobol(n, r), repeats=3)
    reference = clsamp.make_sampler("pmj02bn", seed=1, backend="numpy")
    loop_seconds, _ = timed(lambda: reference.sample(small), repeats=1, warmup=0)
    for device in devices:
        on_device(device)
        dev = short_name(device)
        plain = clsamp.make_sampler("pmj02", seed=1)
        seconds, _ = timed(lambda: plain.sample(n, realizations=r), repeats=5, min_time=2.0)
        rate = f"{n * r / seconds / 1e6:.1f} M points/s"
        rows.append(Row("pmj02", f"{n}x{r}", dev, seconds, "NumPy, same algorithm",
                        numpy_seconds, rate))
        rows.append(Row("pmj02", f"{n}x{r}", dev, seconds, "scipy Sobol scrambled", sobol_seconds,
                        rate))
        blue = clsamp.make_sampler("pmj02bn", seed=1)
        try:
            blue.sample(16)
        except NoDeviceError as error:      # documented refusals (Mesa's rusticl)
            print(f"pmj02bn on {dev}: {error}")
            continue
        seconds, _ = timed(lambda: blue.sample(n, realizations=r), repeats=1, warmup=1)
        rows.append(Row("pmj02bn", f"{n}x{r}", dev, seconds, "scipy Sobol scrambled",
                        sobol_seconds, f"{n * r / seconds / 1e6:.2f} M points/s"))
        seconds, _ = timed(lambda: blue.sample(small), repeats=3)
        rows.append(Row("pmj02bn", f"{small}x1", dev, seconds, "NumPy reference (loop)",
                        loop_seconds, f"{small / seconds / 1e6:.2f} M points/s"))
    return rows


if __name__ == "__main__":
    main(run, __doc__)
