"""Point-set metrics against their peers, in one run:

- the L2-type discrepancies of n = 16384 points in d = 4 (quick: 4096) against
  ``scipy.stats.qmc.discrepancy(..., workers=-1)``; the quality column gives the relative
  difference to scipy and, in the full run, both errors against an 80-bit (long double)
  evaluation at n = 4096, which shows whose digits are right;
- the exact 2-D star discrepancy of n = 4096 and 65536 points (quick: 4096), against the
  NumPy twin (2-D prefix counts) where it fits in memory;
- the pair correlation function of 64 x 4096 points (quick: 16 x 1024), 100 radii up to
  3 mean spacings, against a vectorised NumPy estimator over periodic cKDTree pairs;
- nearest-neighbour distances of the same sets against cKDTree.query(k=2, boxsize=1);
- the float-float paths (``precision="float-float"``, what a device without fp64
  computes: the CD, the PCF, nearest neighbours) against the double ones on each device;
- the exact star discrepancy without fp64 (integer arithmetic, the double's bits) against
  the double sweep: under ``runtime.without_fp64()`` where the device has fp64, random and
  lattice sets, 2-D n = 1024 and 4096, 3-D n = 512 (quick: 1024 and 256).

Memory is the peak of the OpenCL buffers each call holds at once (common.device_memory).
"""

import math
from fractions import Fraction

import numpy as np
from common import Row, device_memory, main, on_device, short_name, timed

import clsamp
from clsamp import philox
from clsamp.metrics import l2, neighbors, star

SCIPY_METHODS = ("CD", "WD", "MD", "L2-star")


def _points(r, n, d, seed=1):
    return philox.uniform_block(seed, philox.Stream.POINTS, np.arange(r), n, d, 0)


def _mib(nbytes):
    return f"{nbytes / 2**20:.1f} MiB" if nbytes >= 2**20 else f"{nbytes / 2**10:.0f} KiB"


def longdouble_discrepancy(x, method):
    """The discrepancy in 80-bit arithmetic (numpy.longdouble, 64-bit mantissa) with the
    textbook terms, its sums combined exactly: about 1e-19 relative per term."""
    n, d = x.shape
    X = x.astype(np.longdouble)
    h = np.longdouble(0.5)
    a = np.abs(X - h)
    if method == "CD":
        single = np.prod(1 + h * a - h * a * a, axis=1)
    elif method == "WD":
        single = np.ones(n, dtype=np.longdouble)
    elif method == "MD":
        single = np.prod(np.longdouble(5) / 3 - a / 4 - a * a / 4, axis=1)
    else:
        single = np.prod(1 - X * X, axis=1)
    pairs = []
    for lo in range(0, n, 256):
        xi, ai = X[lo:lo + 256, None, :], a[lo:lo + 256, None, :]
        t = np.abs(xi - X[None])
        if method == "CD":
            g = 1 + h * ai + h * a[None] - h * t
        elif method == "WD":
            g = np.longdouble(1.5) - t + t * t
        elif method == "MD":
            g = np.longdouble(15) / 8 - ai / 4 - a[None] / 4 - 3 * t / 4 + t * t / 2
        else:
            g = 1 - np.maximum(xi, X[None])
        pairs.append(np.prod(g, axis=2).sum(axis=1))

    def exact(v):
        m, e = np.frexp(v)
        return Fraction(int(np.ldexp(m, 64))) * Fraction(2) ** (int(e) - 64)

    c0, c1, c2 = l2._constants(method, d, n)
    if method == "MD":          # l2 keeps 3 f for MD; the textbook f here
        c1 = c1 * 3**d
    value = float(c0 + c1 * sum(map(exact, single)) + c2 * sum(map(exact, np.concatenate(pairs))))
    return math.sqrt(value) if method in l2.ROOTED else value


def _pcf_peer(sets, radii, sigma, cut=neighbors.CUT):
    """The same estimator in vectorised NumPy over cKDTree's periodic pairs."""
    from scipy.spatial import cKDTree
    reach = radii[-1] + cut * sigma
    sums = np.zeros(len(radii))
    counts = 0.0
    for pts in sets:
        tree = cKDTree(pts, boxsize=1.0)
        pairs = tree.query_pairs(reach, output_type="ndarray")
        delta = np.abs(pts[pairs[:, 0]] - pts[pairs[:, 1]])
        s = np.sqrt(np.sum(np.minimum(delta, 1.0 - delta) ** 2, axis=1))
        t = radii[None, :] - s[:, None]
        sums += np.where(np.abs(t) <= cut * sigma, np.exp(-t * t / (2 * sigma * sigma)), 0.0).sum(axis=0)
        counts += len(pts) * (len(pts) - 1)
    d = sets.shape[-1]
    norm = neighbors.pcf_normalisation(radii, sigma, d)
    return 2.0 * sums / (math.sqrt(2 * math.pi) * sigma) / counts / norm


def _nn_peer(sets):
    from scipy.spatial import cKDTree
    return np.stack([cKDTree(p, boxsize=1.0).query(p, k=2)[0][:, 1] for p in sets])


def run(devices, quick):
    from scipy.stats import qmc
    rows = []
    n_disc = 4096 if quick else 16384
    x = _points(1, n_disc, 4)[0]
    check = None if quick else _points(1, 4096, 4, seed=2)[0]
    star_sizes = (4096,) if quick else (4096, 65536)
    r_pcf, n_pcf = (16, 1024) if quick else (64, 4096)
    sets = _points(r_pcf, n_pcf, 2, seed=3)
    radii = neighbors.RADII_SPAN * neighbors.mean_spacing(n_pcf, 2) * np.arange(1, 101) / 100
    sigma = neighbors.SIGMA_SPACING * neighbors.mean_spacing(n_pcf, 2)
    t_peer_pcf, g_peer = timed(lambda: _pcf_peer(sets, radii, sigma), repeats=1 if not quick else 2)
    t_peer_nn, nn_peer = timed(lambda: _nn_peer(sets), repeats=3)
    for device in [d for d in devices if d.fp64]:       # without fp64: the float-float rows only
        on_device(device)
        dev = short_name(device)
        for method in SCIPY_METHODS:
            t_ours, ours = timed(lambda m=method: clsamp.discrepancy(x, m), repeats=7)
            _, memory = device_memory(lambda m=method: clsamp.discrepancy(x, m))
            t_scipy, theirs = timed(lambda m=method: qmc.discrepancy(x, method=m, workers=-1),
                                    repeats=3, warmup=0)
            quality = f"vs scipy {abs(ours - theirs) / abs(ours):.1e} rel; mem {_mib(memory)}"
            if check is not None:
                ref = longdouble_discrepancy(check, method)
                ours_err = abs(clsamp.discrepancy(check, method) - ref) / ref
                scipy_err = abs(qmc.discrepancy(check, method=method, workers=-1) - ref) / ref
                quality += f"; n=4096 vs 80-bit: ours {ours_err:.0e}, scipy {scipy_err:.0e}"
            rows.append(Row(f"discrepancy {method}", f"{n_disc} x 4-D", dev, t_ours,
                            "scipy qmc.discrepancy workers=-1", t_scipy, quality))
        for n in star_sizes:
            pts = _points(1, n, 2, seed=4)[0]
            t_star, value = timed(lambda p=pts: clsamp.star_discrepancy(p), repeats=3 if n < 10**5 else 1)
            _, memory = device_memory(lambda p=pts: clsamp.star_discrepancy(p))
            peer, t_ref, quality = "", None, f"D* {value:.5g}; mem {_mib(memory)}"
            if n <= 4096:
                t_ref, ref = timed(lambda p=pts: star.star_discrepancy_reference(p), repeats=3)
                peer = "numpy prefix counts"
                quality += f"; equal to numpy: {ref == value}"
            rows.append(Row("star discrepancy exact 2-D", f"{n}", dev, t_star, peer, t_ref, quality))
        t_pcf, (_, g) = timed(lambda: clsamp.pair_correlation(sets, radii, sigma), repeats=3)
        _, memory = device_memory(lambda: clsamp.pair_correlation(sets, radii, sigma))
        rows.append(Row("pair correlation", f"{r_pcf}x{n_pcf}, 100 radii", dev, t_pcf,
                        "numpy + periodic cKDTree", t_peer_pcf,
                        f"max |diff| {np.max(np.abs(g - g_peer)):.1e}; mem {_mib(memory)}"))
        t_nn, nn = timed(lambda: clsamp.nearest_neighbor_distances(sets), repeats=5)
        _, memory = device_memory(lambda: clsamp.nearest_neighbor_distances(sets))
        rows.append(Row("nearest neighbours", f"{r_pcf}x{n_pcf}", dev, t_nn,
                        "cKDTree.query k=2 boxsize=1", t_peer_nn,
                        f"max |diff| {np.max(np.abs(nn - nn_peer)):.1e}; mem {_mib(memory)}"))
    return rows + _float_float_rows(devices, quick) + star_without_fp64_rows(devices, quick)


def _float_float_rows(devices, quick):
    """The float-float paths (what a device without fp64 computes) against the double ones
    on the same device; errors against the NumPy twins."""
    rows = []
    x = _points(1, 1024 if quick else 4096, 4, seed=5)[0]
    sets = _points(2, 1024 if quick else 4096, 2, seed=6)
    cases = [("discrepancy CD", f"{len(x)} x 4-D", lambda p: clsamp.discrepancy(x, "CD", precision=p),
              l2.discrepancy_reference(x, "CD")),
             ("pair correlation", f"{len(sets)}x{sets.shape[1]}, 100 radii",
              lambda p: clsamp.pair_correlation(sets, precision=p)[1],
              clsamp.pair_correlation(sets, backend="numpy")[1]),
             ("nearest neighbours", f"{len(sets)}x{sets.shape[1]}",
              lambda p: clsamp.nearest_neighbor_distances(sets, precision=p),
              clsamp.nearest_neighbor_distances(sets, backend="numpy"))]
    for device in devices:
        on_device(device)
        for case, size, fn, ref in cases:
            t_ff, ff = timed(lambda fn=fn: fn("float-float"), repeats=3)
            quality = f"max err {np.max(np.abs(np.asarray(ff) - ref)):.1e}"
            if device.fp64:
                t_d, dbl = timed(lambda fn=fn: fn("double"), repeats=3)
                quality += f"; double {np.max(np.abs(np.asarray(dbl) - ref)):.1e}"
                rows.append(Row(f"{case} float-float", size, short_name(device), t_ff, "clsamp in double",
                                t_d, quality))
            else:
                rows.append(Row(f"{case} float-float", size, short_name(device), t_ff,
                                quality=quality + "; double: no fp64 on this device"))
    return rows


def star_without_fp64_rows(devices, quick):
    """The exact star discrepancy's integer path (what a device without fp64 computes)
    against the double sweep on the same device; the quality column says whether the bits
    are the double's."""
    from clsamp import runtime
    rows = []
    cases = [(2, 1024), (3, 256)] if quick else [(2, 1024), (2, 4096), (3, 512)]
    for device in devices:
        on_device(device)
        for name in ("random", "lattice"):
            for d, n in cases:
                pts = clsamp.make_sampler(name, d=d, seed=7).sample(n)
                size = f"{name} {n} x {d}-D"
                if not device.fp64:
                    t_int, _ = timed(lambda p=pts: clsamp.star_discrepancy(p), repeats=3)
                    rows.append(Row("star discrepancy exact, integer", size, short_name(device),
                                    t_int, quality="double: no fp64 on this device"))
                    continue

                def integer(p=pts):
                    with runtime.without_fp64():
                        return clsamp.star_discrepancy(p)
                t_int, value = timed(integer, repeats=5)
                t_d, want = timed(lambda p=pts: clsamp.star_discrepancy(p), repeats=5)
                rows.append(Row("star discrepancy exact, integer", size, short_name(device), t_int,
                                "clsamp in double", t_d, f"same bits: {value == want}"))
    return rows


if __name__ == "__main__":
    main(run, __doc__)
