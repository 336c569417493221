"""Digital nets against their peers in the same run.

    python benchmarks/bench_digital_nets.py [--device all] [--quick] [--out FILE]

Cases: LMS-scrambled Sobol' (``sobol:lms``, ``sobol:lms+shift``: Matoušek's linear matrix
scrambling, without and with the digital shift) against scipy's ``Sobol(scramble=True)``
(the same LMS + shift; a fresh engine per call, so both draw the first n points and
scramble once) at 2^20 points in 16 dimensions (``--quick``: 2^16); ``niederreiter`` and
``niederreiter:lms+shift`` against qmcpy's ``DigitalNetB2`` given the same Niederreiter
matrices (Gray-code order, unrandomized and LMS + digital shift), and ``faure`` against
qmcpy's ``Faure`` (17^5 points in 16 dimensions, base 17; ``--quick``: 17^3). The quality
column says whether the unrandomized points equal the peer's. Times are for ``sample()``
returning host float64 arrays.
"""

import numpy as np
from common import Row, copy_bandwidth, main, on_device, short_name, timed
from scipy.stats import qmc

import clsamp
from clsamp import generating_matrices as gm

D = 16


def _qmcpy():
    try:
        import qmcpy
    except ImportError:
        return None
    return qmcpy


def _agreement(ours, theirs):
    if np.array_equal(ours, theirs):
        return "equals peer"
    return f"peer within {np.max(np.abs(ours - theirs)):.1e}"


def _peers(quick):
    """(case, n) -> (peer name, seconds, points or None): measured once, before any device."""
    n2 = 2**16 if quick else 2**20
    nf = 17**3 if quick else 17**5
    peers = {}
    seconds, _ = timed(lambda: qmc.Sobol(D, scramble=True, seed=1).random(n2), repeats=3)
    for case in ("sobol:lms", "sobol:lms+shift"):
        peers[case, n2] = ("scipy Sobol scrambled (LMS+shift)", seconds, None)
    qmcpy = _qmcpy()
    if qmcpy is not None:
        columns = gm.columns_base2(gm.niederreiter_matrices(D)).astype(np.uint64)
        for case, randomize in (("niederreiter", "FALSE"), ("niederreiter:lms+shift", "LMS DS")):
            def draw(randomize=randomize):
                net = qmcpy.DigitalNetB2(D, randomize=randomize, generating_matrices=columns,
                                         msb=True, t=32, order="GRAY", seed=1)
                return net(n2, warn=False)
            seconds, points = timed(draw, repeats=3)
            peers[case, n2] = (f"qmcpy DigitalNetB2 {randomize}", seconds, points)
        seconds, points = timed(lambda: qmcpy.Faure(D, randomize="FALSE")(nf, warn=False),
                                repeats=1 if not quick else 3)
        peers["faure", nf] = ("qmcpy Faure", seconds, points)
    return peers


def run(devices, quick):
    rows = []
    peers = _peers(quick)
    for device in devices:
        on_device(device)
        dev = short_name(device)
        for (case, n), (peer, peer_seconds, peer_points) in peers.items():
            sampler = clsamp.make_sampler(case, d=D, seed=1)
            seconds, points = timed(lambda: sampler.sample(n), repeats=5, min_time=2.0)
            quality = f"{n * D / seconds / 1e6:.0f} M coords/s"
            if sampler.randomize is None and peer_points is not None:
                quality = f"{_agreement(points, peer_points)}, {quality}"
            rows.append(Row(case, f"{n}x{D}D", dev, seconds, peer, peer_seconds, quality,
                            output_bytes=points.nbytes, copy_gbs=copy_bandwidth(points.nbytes)))
    return rows


if __name__ == "__main__":
    main(run, __doc__)
