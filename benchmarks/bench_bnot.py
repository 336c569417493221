"""Blue noise through optimal transport (``bnot``): seconds to quality against its NumPy twin.

    python benchmarks/bench_bnot.py [--device all] [--quick] [--out FILE]

Cases: n = 1024 and 4096 (``--quick``: 256 only, CI-sized), 2-D (the method's domain, the unit
torus), one set (seed 1) with the default 256 density points a site. The quality asked of
a set is gbn's in 2-D: rho >= 0.75 and a low-frequency power (mean periodogram over the
integer frequencies 0 < |w| < sqrt(n) / 2) at most a seventh of Poisson disk's, whose
figure is measured in the same run (four rho = 0.75 dart-throwing sets of the same n).

The iterations are the first of 8, 16, 32, 64 (``tol=0``: every iteration runs until
the cost stops falling) whose set has that quality; the row times that call on the
device (median of 3) and the NumPy twin's (``backend="numpy"``, once), which gives the
same bits (checked). The peer column is the twin; the ratio is twin seconds over device
seconds. The rows "bnot exact to quality" do the same with ``cells="exact"`` (the power
cells as polygons of the uniform density), over 8, 16, 32, 64, 128 iterations.
"""

from bench_gbn import _quality, low_frequency_power
from common import main, on_device, short_name, to_quality

import clsamp

LADDER = (8, 16, 32, 64)
EXACT_LADDER = (8, 16, 32, 64, 128)


def run(devices, quick):
    rows = []
    sizes = (256,) if quick else (1024, 4096)
    disk = {n: low_frequency_power(clsamp.make_sampler("poisson_disk", seed=1).sample(n, realizations=4))
            for n in sizes}
    for device in devices:
        on_device(device)
        dev = short_name(device)
        for n in sizes:
            rows.append(to_quality("bnot", 2, n, LADDER,
                                   lambda pts, n=n: _quality(pts, n, 2, disk[n]), dev, tol=0.0))
            rows.append(to_quality("bnot", 2, n, EXACT_LADDER,
                                   lambda pts, n=n: _quality(pts, n, 2, disk[n]), dev,
                                   title="bnot exact to quality", tol=0.0, cells="exact",
                                   progress=False))
    return rows


if __name__ == "__main__":
    main(run, __doc__)
