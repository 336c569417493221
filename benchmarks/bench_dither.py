"""Dither masks (``clsamp.dither_mask``, void and cluster): seconds against the NumPy twin.

    python benchmarks/bench_dither.py [--device all] [--quick] [--out FILE]

Cases: 64 x 64 (``--quick``: this one only), 128 x 128, 256 x 256, a 16^3 and a 32^3 mask,
and spatiotemporal 64 x 64 x 16 and 32 x 32 x 32 masks (sigma 1.9, seed 1). Each is timed
on the device (``kernels/dither.cl``: one work-item walks the N sequential steps with two
tournament trees; median of 3) against the NumPy twin (``backend="numpy"``: an argmax over
the mask a step; median of 3, once from 2^15 pixels on), which gives the same ranks
(checked). A device that does not run the kernel (not a CPU, no fp64, a loop limit, or
memory of its own) runs the twin and has no rows. The quality column gives the mean power of the
thresholds at integer frequencies 0 < |k| < size / 8 (white noise 1), over the mask's
space axes (each frame of a spatiotemporal mask) and, for a spatiotemporal mask, each
pixel's sequence over time at 1 and 2 cycles.
"""

import numpy as np
from common import WARM, Row, main, on_device, short_name, timed

import clsamp
from clsamp.samplers import dither


def _low(mask, axes, below):
    """Mean power of the thresholds over ``axes`` at integer frequencies 0 < |k| < below."""
    power = dither.mask_spectrum(mask, axes=axes)
    grids = np.meshgrid(*[np.fft.fftfreq(mask.shape[a]) * mask.shape[a] for a in axes],
                        indexing="ij")
    f = np.sqrt(sum(g * g for g in grids))
    return float(power[(f > 0) & (f < below)].mean())


def _quality(mask, size, temporal):
    space = tuple(range(1 if temporal else 0, mask.ndim))
    text = f"low-freq power {_low(mask, space, max(2, size / 8)):.4f} (white noise 1)"
    if temporal:
        text += f", in time {float(dither.mask_spectrum(mask, axes=(0,))[1:3].mean()):.3f}"
    return text


def run(devices, quick):
    rows = []
    cases = [(64, 2, None)] if quick else [(64, 2, None), (128, 2, None), (256, 2, None),
                                            (16, 3, None), (32, 3, None), (64, 2, 16),
                                            (32, 2, 32)]
    for device in devices:
        on_device(device)
        if not dither._device_runs_it():
            continue
        dev = short_name(device)
        for size, d, temporal in cases:
            def mask(backend, size=size, d=d, temporal=temporal):
                return clsamp.dither_mask(size, d=d, seed=1, temporal=temporal, backend=backend)
            pixels = size ** d * (temporal or 1)
            t_cl, out = timed(lambda: mask("opencl"), repeats=3, warm_time=WARM)  # noqa: B023
            t_np, ref = timed(lambda: mask("numpy"), repeats=3 if pixels < 1 << 15 else 1,  # noqa: B023
                              warmup=0)
            same = "bit-identical" if np.array_equal(out, ref) else "DIFFERS"
            shape = " x ".join(map(str, out.shape))
            rows.append(Row("dither_mask" + (" spatiotemporal" if temporal else ""), shape, dev,
                            t_cl, "numpy twin", t_np,
                            f"{_quality(out, size, temporal)}, {same}"))
    return rows


if __name__ == "__main__":
    main(run, __doc__)
