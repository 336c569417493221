"""Sliced optimal transport (``sot``): seconds to quality against its NumPy twin.

    python benchmarks/bench_sot.py [--device all] [--quick] [--out FILE]

Cases: n = 1024 and 4096 (``--quick``: 1024 only), in 2-D and 4-D, one set (seed 1) with
the defaults (32 directions a batch, step d). The quality asked of a set:

* 2-D: a low-frequency power (mean periodogram over the integer frequencies
  0 < |w| < sqrt(n) / 2) at most half of Poisson disk's, whose figure is measured in the
  same run (four rho = 0.75 dart-throwing sets of the same n);
* 4-D: a mean nearest-neighbour distance in the cube at least 1.2 times white noise's
  (measured in the same run, seed 1).

The batches are the first of ``LADDER`` (16 to 512, steps of 1.5 and 4/3) whose set has
that quality; the row times that call on the device (median of 3) and the NumPy twin's
(``backend="numpy"``, once), which gives the same bits (checked). The peer column is the
twin; the ratio is twin seconds over device seconds.
"""

from bench_gbn import low_frequency_power
from common import main, on_device, short_name, to_quality

import clsamp
from clsamp.metrics import max_min_distance, nearest_neighbor_distances

LADDER = (16, 24, 32, 48, 64, 96, 128, 192, 256, 384, 512)


def _mean_nn(points, n, d):
    return float(nearest_neighbor_distances(points, periodic=False).mean()) / max_min_distance(n, d)


def _quality(points, n, d, target):
    """(met, description) of one set against the case's target."""
    if d == 2:
        power = low_frequency_power(points)
        return power <= target / 2, f"low-freq power {power:.4f} (Poisson disk {target:.4f})"
    mean = _mean_nn(points, n, d)
    return mean >= 1.2 * target, f"mean NN {mean:.3f} d_max (white noise {target:.3f})"


def run(devices, quick):
    rows = []
    sizes = (1024,) if quick else (1024, 4096)
    target = {}
    for n in sizes:
        target[n, 2] = low_frequency_power(
            clsamp.make_sampler("poisson_disk", seed=1).sample(n, realizations=4))
        target[n, 4] = _mean_nn(clsamp.make_sampler("random", d=4, seed=1).sample(n), n, 4)
    for device in devices:
        on_device(device)
        dev = short_name(device)
        for d in (2, 4):
            for n in sizes:
                rows.append(to_quality("sot", d, n, LADDER,
                                       lambda pts, n=n, d=d: _quality(pts, n, d, target[n, d]),
                                       dev, unit="batches"))
    return rows


if __name__ == "__main__":
    main(run, __doc__)
