"""Gaussian blue noise (``gbn``): seconds to quality against its NumPy twin.

    python benchmarks/bench_gbn.py [--device all] [--quick] [--out FILE]

Cases: n = 1024 and 4096 (``--quick``: 1024 only), in 2-D and 4-D, one set (seed 1) on the
torus with the default sigma (0.5 mean spacings) and step. The quality asked of a set:

* 2-D: rho >= 0.75 and a low-frequency power (mean periodogram over the integer
  frequencies 0 < |w| < sqrt(n) / 2) at most a seventh of Poisson disk's, whose figure is
  measured in the same run (four rho = 0.75 dart-throwing sets of the same n);
* 4-D: rho >= 0.7 and a mean nearest-neighbour distance >= 0.8 d_max (white noise: rho
  about 0.1, mean 0.51 d_max).

The iterations are the first of 25, 50, 100, 200, 400 (``tol=0``: every iteration runs)
whose set has that quality; the row times that call on the device (median of 3) and the
NumPy twin's (``backend="numpy"``, once), which gives the same bits (checked). The peer
column is the twin; the ratio is twin seconds over device seconds.
"""

import math

from common import main, on_device, short_name, to_quality

import clsamp
from clsamp import spectral_stats
from clsamp.metrics import max_min_distance, nearest_neighbor_distances, relative_radius

LADDER = (25, 50, 100, 200, 400)


def low_frequency_power(points):
    """Mean periodogram power over the integer frequencies 0 < |w| < sqrt(n) / 2 (the
    issue's figure: Poisson disk about 0.07 at n = 1024, white noise 1)."""
    n = points.shape[-2]
    resolution = 2 * math.ceil(math.sqrt(n) / 2) + 2
    P = clsamp.power_spectrum(points, resolution=resolution, method="direct", progress=False)
    return spectral_stats.low_frequency_power(P, n)


def _quality(points, n, d, disk_power):
    """(met, description) of one set against the case's target."""
    rho = float(relative_radius(points))
    if d == 2:
        power = low_frequency_power(points)
        return (rho >= 0.75 and power <= disk_power / 7,
                f"rho {rho:.3f}, low-freq power {power:.4f} (Poisson disk {disk_power:.4f})")
    mean = float(nearest_neighbor_distances(points).mean()) / max_min_distance(n, d)
    return rho >= 0.7 and mean >= 0.8, f"rho {rho:.3f}, mean NN {mean:.3f} d_max"


def run(devices, quick):
    rows = []
    sizes = (1024,) if quick else (1024, 4096)
    disk = {n: low_frequency_power(clsamp.make_sampler("poisson_disk", seed=1).sample(n, realizations=4))
            for n in sizes}
    for device in devices:
        on_device(device)
        dev = short_name(device)
        for d in (2, 4):
            for n in sizes:
                rows.append(to_quality("gbn", d, n, LADDER,
                                       lambda pts, n=n, d=d: _quality(pts, n, d, disk[n]),
                                       dev, tol=0.0))
    return rows


if __name__ == "__main__":
    main(run, __doc__)
