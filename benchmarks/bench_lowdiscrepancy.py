"""The low-discrepancy family against scipy.stats.qmc in the same run.

    python benchmarks/bench_lowdiscrepancy.py [--device all] [--quick] [--out FILE]

Cases: 2^20 and 2^22 points in 2 and 16 dimensions (``--quick``: 2^16 in 2 and 16), every
randomization of ``sobol`` and ``halton``; and ``halton:owen`` (nested uniform scrambling,
a uniformly random permutation per digit-tree node) with 16 realizations of 2^20 points
in 2 and 16 dimensions (``--quick``: 2^16), against 16 scrambled scipy engines. The peers
are scipy's ``Sobol(scramble=True)`` (a linear matrix scramble plus a digital shift, scipy
#15398: weaker than Owen's nested scrambling) and ``Halton(scramble=True)``; with
``randomize=None`` the unscrambled scipy engines. Times are for ``sample()`` returning host
float64 arrays. The quality column says how close the unscrambled points are to scipy's
(bit for bit, or in ulps). Every row also gives clsamp's output GB/s and its share of
``np.copyto``'s GB/s for the same bytes, measured in the same run (issue 20's mark: half
the copy's at 2^22 points in 16 dimensions). Cases are named as ``make_sampler`` spells
them (``"sobol"``, ``"halton:owen"``).
"""

import numpy as np
from common import Row, copy_bandwidth, main, on_device, short_name, timed
from scipy.stats import qmc

import clsamp

RANDOMIZE = {"sobol": (None, "shift", "xor", "owen"),
             "halton": (None, "shift", "xor", "owen", "permute")}


def _scipy_engine(name, d, scramble):
    if name == "sobol":
        return qmc.Sobol(d, scramble=scramble, seed=1)
    return qmc.Halton(d, scramble=scramble, seed=1)


def _scipy_time(name, d, n, scramble):
    # a fresh engine per call, so every timed call draws the first n points as clsamp does
    return timed(lambda: _scipy_engine(name, d, scramble).random(n), repeats=3)


def _agreement(ours, theirs):
    """Bit-identical, or the largest difference in ulps (scipy sums Halton digits in floating
    point; clsamp rounds the exact rational once)."""
    if np.array_equal(ours, theirs):
        return "equals scipy"
    ulps = np.max(np.abs(ours - theirs) / np.spacing(np.maximum(np.abs(ours), 2.0**-1022)))
    return f"scipy within {ulps:.0f} ulp"


def run(devices, quick):
    rows = []
    sizes = [2**16] if quick else [2**20, 2**22]
    dims = (2, 16)
    peers = {}
    for name in RANDOMIZE:
        for d in dims:
            for n in sizes:
                for scramble in (False, True):
                    peers[(name, d, n, scramble)] = _scipy_time(name, d, n, scramble)
    for device in devices:
        on_device(device)
        dev = short_name(device)
        for name, variants in RANDOMIZE.items():
            for d in dims:
                for n in sizes:
                    copy = copy_bandwidth(n * d * 8)
                    for randomize in variants:
                        sampler = clsamp.make_sampler(name, d=d, seed=1, randomize=randomize)
                        seconds, points = timed(lambda: sampler.sample(n), repeats=5, min_time=2.0)
                        peer_seconds, peer_points = peers[(name, d, n, randomize is not None)]
                        rate = f"{n * d / seconds / 1e6:.0f} M coords/s"
                        if randomize is None:
                            quality = f"{_agreement(points, peer_points)}, {rate}"
                            peer = f"scipy {name.title()} unscrambled"
                        else:
                            quality = rate
                            peer = f"scipy {name.title()} scrambled"
                        case = name if randomize is None else f"{name}:{randomize}"
                        rows.append(Row(case, f"{n}x{d}D", dev, seconds, peer, peer_seconds,
                                        quality, output_bytes=points.nbytes, copy_gbs=copy))
    rows.extend(_owen_realizations(devices, quick))
    return rows


def _owen_realizations(devices, quick, realizations=16):
    """halton:owen, several realizations in one call, against as many scipy engines."""
    rows = []
    n = 2**16 if quick else 2**20
    for d in (2, 16):
        peer_seconds, _ = timed(lambda: [qmc.Halton(d, scramble=True, seed=s).random(n)
                                         for s in range(realizations)], repeats=3)
        for device in devices:
            on_device(device)
            sampler = clsamp.make_sampler("halton", d=d, seed=1, randomize="owen")
            seconds, points = timed(lambda: sampler.sample(n, realizations=realizations),
                                    repeats=5, min_time=2.0)
            copy = copy_bandwidth(points.nbytes)
            rate = n * d * realizations / seconds / 1e6
            peer_rate = n * d * realizations / peer_seconds / 1e6
            rows.append(Row("halton:owen", f"{n}x{d}D x{realizations}", short_name(device), seconds,
                            "scipy Halton scrambled", peer_seconds,
                            f"{rate:.1f} M coords/s (scipy {peer_rate:.1f})",
                            output_bytes=points.nbytes, copy_gbs=copy))
    return rows


if __name__ == "__main__":
    main(run, __doc__)
