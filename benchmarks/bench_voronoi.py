"""Lloyd relaxation and CCVT: seconds and quality against a scipy cKDTree Lloyd and the
published figures of Balzer et al.'s single-threaded CCVT code.

    python benchmarks/bench_voronoi.py [--device all] [--quick] [--out FILE]

Cases (``--quick`` in brackets):

* Lloyd, 1024 sites, 512^2 density points [256 sites, 128^2]: seconds per iteration
  (the difference of an 11- and a 1-iteration run over 10, for both) against a periodic Lloyd
  iteration with ``scipy.spatial.cKDTree(boxsize=1)`` on the same density grid (tree of
  the sites, nearest-site query, centroids unwrapped relative to the site); both from
  the same starting sites, N*E after 10 iterations of each. Then 3-D and 4-D, 1024 sites
  and 256 density points per site (64^3, 23^4) [3-D only, 256 sites x 64]: seconds per
  iteration (the difference of a 4- and a 1-iteration run) against the same cKDTree Lloyd
  in d dimensions, and the energy E (not normalized: N*E is a 2-D figure) of both after 3.
* CCVT until no exchange improves: 1024 sites x 1024 points per site, then 256 x 1024
  and 4096 x 256 (Balzer's other two cases), and 256, 1024, 4096 sites x 256 for the
  growth with n at one p [256 x 64, 1024 x 64, 4096 x 16]: seconds (all of it: density,
  start, optimization; the start's share named), iterations, N*E and rho. Balzer's three
  cases again with ``relax=8`` (the sites relaxed before the partition: faster and lower
  in energy, but more regular; see :class:`clsamp.samplers.ccvt.CCVTSampler`).
  ``BALZER`` holds the seconds Balzer's code took for its three cases, built on the
  project machine (docs/performance.md, "CCVT: start and optimization", gives them with
  its N*E and rho). Those are published figures, not code run here, and the machine's
  speed drifts from hour to hour, so the full run also times the machine gauge
  (:func:`common.machine_gauge`) before and after the CCVT cases and the rows with a
  published peer give it: their ratio compares like with like when the gauge is near
  GAUGE_PUBLISHED, what it took when the figures were taken.

N*E of a set is :func:`clsamp.metrics.normalized_energy`: n times the mean squared
toroidal distance to the nearest point over a regular grid of 4096 points per site,
0.160375 for the hexagonal lattice, 1/pi for white noise; the same figure for the CCVT,
the Lloyd sets and the cKDTree Lloyd. A CCVT row also gives its own objective, the
capacity-constrained energy over its density points ("capacity N*E"), which is never
lower. Which of the two Balzer's published N*E is, its source does not say.
"""

import numpy as np
from common import GAUGE_PUBLISHED, Row, machine_gauge, main, on_device, short_name, timed

from clsamp import metrics
from clsamp.geometry import integer_torus as it
from clsamp.geometry import voronoi
from clsamp.samplers import lloyd
from clsamp.samplers.ccvt import ccvt_optimize, density, start
from clsamp.samplers.optimizer import initial_sites

BALZER = {(1024, 1024): 4.9, (256, 1024): 1.0, (4096, 256): 4.5}


def ckdtree_lloyd(sites, g, iterations):
    """Periodic Lloyd with scipy's cKDTree on the g^d grid of cell centres, d the sites':
    (sites, [energy after each iteration])."""
    from scipy.spatial import cKDTree
    d = sites.shape[1]
    c = (np.arange(g) + 0.5) / g
    density = np.stack(np.meshgrid(*[c] * d), -1).reshape(-1, d)
    sites = np.array(sites, dtype=np.float64)
    energies = []
    n = len(sites)
    for _ in range(iterations + 1):
        dist, label = cKDTree(sites, boxsize=1.0).query(density, k=1)
        energies.append(float(np.mean(dist * dist)))
        if len(energies) == iterations + 1:
            break
        off = density - sites[label]
        off -= np.round(off)
        count = np.bincount(label, minlength=n)
        full = count > 0
        for axis in range(d):
            shift = np.bincount(label, weights=off[:, axis], minlength=n)
            sites[full, axis] = (sites[full, axis] + shift[full] / count[full]) % 1.0
        sites[sites >= 1.0] = 0.0        # -tiny % 1.0 rounds to 1.0, outside cKDTree's box
    return sites, energies[1:]


def ccvt_start(sites, points, p, relax):
    """The whole start of a CCVT run: the sites relaxed (``relax`` steps), then the exact
    partition."""
    relaxed, weight = start.start_sites(sites, p, steps=relax)
    return start.start_partition(relaxed, points, p, "opencl", weight)


def lloyd_row(dev, d, n, density_per_site, steps, peer):
    """Seconds per Lloyd iteration in d dimensions (the difference of a ``steps + 1``- and a
    1-iteration run) against the cKDTree Lloyd's (``peer``: its seconds per iteration and
    its energy after ``steps``, measured once for all devices), with both energies."""
    begin = it.to_unit(initial_sites(1, np.arange(1), n, d=d))
    lloyd.lloyd_relax(begin, density_per_site, 1)          # build the kernels
    t1, _ = timed(lambda: lloyd.lloyd_relax(begin, density_per_site, 1), repeats=1)
    tn, (_, info) = timed(lambda: lloyd.lloyd_relax(begin, density_per_site, steps + 1), repeats=1)
    g = voronoi.density_side(n, density_per_site, d)
    return Row(f"lloyd iteration {d}-D", f"{n} sites, {g}^{d} density", dev,
               max(tn - t1, 1e-9) / steps, "scipy cKDTree Lloyd", peer[0],
               f"E after {steps}: {info.energy_history[0, steps - 1]:.6g} (cKDTree {peer[1]:.6g})")


def ckdtree_peer(d, n, density_per_site, steps):
    """The cKDTree Lloyd's seconds per iteration and its energy after ``steps``."""
    begin = it.to_unit(initial_sites(1, np.arange(1), n, d=d))[0]
    g = voronoi.density_side(n, density_per_site, d)
    t1, _ = timed(lambda: ckdtree_lloyd(begin, g, 1), repeats=1)
    tn, (_, e) = timed(lambda: ckdtree_lloyd(begin, g, steps + 1), repeats=1)
    return max(tn - t1, 1e-9) / steps, e[steps - 1]


def run(devices, quick):
    rows = []
    n_lloyd, g = (256, 128) if quick else (1024, 512)
    per_site = g * g // n_lloyd
    begin = it.to_unit(initial_sites(1, np.arange(1), n_lloyd))
    t_kd1, (_, e_kd) = timed(lambda: ckdtree_lloyd(begin[0], g, 1), repeats=3)
    t_kd11, (kd_sites, e_kd10) = timed(lambda: ckdtree_lloyd(begin[0], g, 11), repeats=3)
    t_kd = max(t_kd11 - t_kd1, 1e-9) / 10
    cases = ([(256, 64), (1024, 64), (4096, 16)] if quick
             else [(1024, 1024), (256, 1024), (4096, 256), (256, 256), (1024, 256)])
    # the default start, then Balzer's three cases from relaxed sites
    ccvt_cases = [(n, p, 0) for n, p in cases] + [(n, p, start.RELAX_STEPS) for n, p in cases[:3]]
    gauges = [] if quick else [machine_gauge()]
    ccvt_rows = []
    higher = [(3, 256, 64)] if quick else [(3, 1024, 256), (4, 1024, 256)]
    peers = {case: ckdtree_peer(*case, 3) for case in higher}
    for device in devices:
        on_device(device)
        dev = short_name(device)
        lloyd.lloyd_relax(begin, per_site, 1)              # build the kernels
        t1, _ = timed(lambda: lloyd.lloyd_relax(begin, per_site, 1), repeats=3)
        t11, (relaxed, info) = timed(lambda: lloyd.lloyd_relax(begin, per_site, 11), repeats=3)
        per = max(t11 - t1, 1e-9) / 10
        ne = n_lloyd * info.energy_history[0]
        rows.append(Row("lloyd iteration", f"{n_lloyd} sites, {g}^2 density", dev, per,
                        "scipy cKDTree Lloyd", t_kd,
                        f"N*E after 10: {ne[9]:.5f} (cKDTree {n_lloyd * e_kd10[9]:.5f}); "
                        f"after 1: {ne[0]:.5f} ({n_lloyd * e_kd[0]:.5f}); set N*E after "
                        f"11: {metrics.normalized_energy(relaxed[0]):.5f} "
                        f"(cKDTree {metrics.normalized_energy(kd_sites):.5f})"))
        rows += [lloyd_row(dev, *case, 3, peers[case]) for case in higher]
        for n, p, relax in ccvt_cases:
            sites = initial_sites(1, np.arange(1), n)
            ccvt_optimize(it.to_unit(initial_sites(2, np.arange(1), 16)),
                          points_per_site=16, iterations=5)          # build the kernels
            seconds, (points, res) = timed(lambda: ccvt_optimize(  # noqa: B023
                it.to_unit(sites), points_per_site=p, iterations=2000, seed=1,  # noqa: B023
                relax=relax), repeats=1 if quick else 3, warmup=1)  # noqa: B023
            dense = density.density_points_device(1, np.arange(1), n * p).get()
            start_seconds, _ = timed(lambda: ccvt_start(sites, dense, p, relax),  # noqa: B023
                                     repeats=1, warmup=0)
            capacity = n * res.energy_history[0, -1]
            ne = metrics.normalized_energy(points[0])
            rho = metrics.relative_radius(points[0])
            peer = BALZER.get((n, p))
            name = f"ccvt relax={relax}" if relax else "ccvt"
            ccvt_rows.append(Row(name, f"{n} x {p}", dev, seconds,
                                 "Balzer et al. (published here)" if peer else "", peer,
                                 f"{int(res.iterations[0])} iterations, "
                                 f"{'converged' if res.converged[0] else 'NOT converged'}, "
                                 f"N*E {ne:.5f} (capacity N*E {capacity:.5f}), rho {rho:.3f}; "
                                 f"start {start_seconds:.2f} s; "
                                 f"{seconds / (n * p) * 1e9:.0f} ns per density point",
                                 extra={"iterations": int(res.iterations[0]), "ne": float(ne),
                                        "capacity_ne": float(capacity), "rho": float(rho),
                                        "start_seconds": start_seconds, "relax": relax}))
    if not quick:
        gauges.append(machine_gauge())
        for row in ccvt_rows:
            if row.peer_seconds is not None:
                row.quality += (f"; machine gauge {gauges[0]:.2f} s before, {gauges[1]:.2f} s "
                                f"after ({GAUGE_PUBLISHED} s when the peer was timed)")
                row.extra["gauge_seconds"] = gauges
    return rows + ccvt_rows


if __name__ == "__main__":
    main(run, __doc__)
