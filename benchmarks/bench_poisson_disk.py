"""Poisson disk by parallel dart throwing against scipy.stats.qmc.PoissonDisk and the
`bridson` package, and the fixed-n sizes that the tour and the convergence sweep use.

    python benchmarks/bench_poisson_disk.py [--device all] [--quick] [--out FILE]

Cases:

* maximal sets at r = 0.01215 (about 4.7k points) and r = 0.006077 (about 19k; not with
  ``--quick``), on the unit torus. Peers, timed in the same run, in the unit square (they
  are not periodic): ``scipy.stats.qmc.PoissonDisk(d=2, radius=r).fill_space()`` (Bridson
  sampling with 30 candidates per active point; not maximal) and ``bridson``'s
  ``poisson_disc_samples(1, 1, r, k=30)`` (pure Python; skipped if not installed). The
  quality column gives the points, the relative radius rho (clsamp: toroidal) and the
  fraction of a 1024^2 probe grid farther than r from every point (0 = maximal; the
  peers' probes are taken 2r inside the square's edges, where they are not penalized
  for the boundary).
* fixed n at rho = 0.75: 256 x 8 and 1024 x 128 realizations (the tour's sizes) and the
  convergence sweep n = 16, 64, 256, 1024 with 128 realizations each, against the NumPy
  reference for the smallest (which gives the same bits).
* other dimensions (:func:`run_dimensions`): one set of n = 1024 and 4096 (1024 only with
  ``--quick``) in 4-D (the void-tracking grid, rho = 0.75) and 8-D (darts into the whole
  torus, the default rho = 0.65), and a maximal 4-D set at r = 0.15 with the fraction of
  200k random probes farther than r from every point.
"""

import random

import numpy as np
from common import Row, main, on_device, short_name, timed
from scipy.spatial import cKDTree
from scipy.stats import qmc

import clsamp
from clsamp.metrics import min_distance, relative_radius

try:
    import bridson
except ImportError:     # an optional peer: say so in the table, do not fail
    bridson = None

RADII = (0.01215, 0.006077)
PROBES = 1024


def _void_fraction(points, radius, periodic, margin=0.0):
    """Fraction of a PROBES^2 grid of probes farther than r from every point."""
    axis = (np.arange(PROBES) + 0.5) / PROBES
    axis = axis[(axis >= margin) & (axis <= 1.0 - margin)]
    probes = np.stack(np.meshgrid(axis, axis, indexing="ij"), axis=-1).reshape(-1, 2)
    tree = cKDTree(points, boxsize=1.0 if periodic else None)
    dist, _ = tree.query(probes, k=1)
    return float(np.mean(dist >= radius))


def _peer_quality(points, radius):
    points = np.asarray(points, dtype=np.float64)
    dist, _ = cKDTree(points).query(points, k=2)
    ratio = float(dist[:, 1].min()) / radius
    void = _void_fraction(points, radius, periodic=False, margin=2 * radius)
    return f"{len(points)} pts, min dist {ratio:.3f} r (square), void {void:.2%}"


def run(devices, quick):
    rows = []
    radii = RADII[:1] if quick else RADII
    peers = {}
    for radius in radii:
        engine = qmc.PoissonDisk(d=2, radius=radius, seed=1)
        t, pts = timed(lambda: (engine.reset(), engine.fill_space())[1], repeats=1, warmup=0)
        peers[("scipy", radius)] = (t, _peer_quality(pts, radius))
        if bridson is not None:
            rng = random.Random(1)
            t, pts = timed(lambda: bridson.poisson_disc_samples(1.0, 1.0, radius, k=30,
                                                                 random=rng.random),
                           repeats=1, warmup=0)
            peers[("bridson", radius)] = (t, _peer_quality(pts, radius))
    for device in devices:
        on_device(device)
        dev = short_name(device)
        for radius in radii:
            sampler = clsamp.make_sampler("poisson_disk", radius=radius, seed=1)
            t_cl, (pts, info) = timed(lambda: sampler.sample(return_info=True),  # noqa: B023
                                      repeats=7)
            assert min_distance(pts) >= radius
            void = _void_fraction(pts, radius, periodic=True)
            quality = (f"{len(pts)} pts, rho {relative_radius(pts):.4f}, void {void:.2%}, "
                       f"{info.rounds} rounds, {info.darts} darts")
            size = f"maximal r={radius}"
            t_s, q_s = peers[("scipy", radius)]
            rows.append(Row("poisson_disk", size, dev, t_cl, "scipy PoissonDisk.fill_space", t_s,
                            f"{quality} | peer: {q_s}", {"points": len(pts)}))
            if bridson is not None:
                t_b, q_b = peers[("bridson", radius)]
                rows.append(Row("poisson_disk", size, dev, t_cl, "bridson (k=30)", t_b,
                                f"{quality} | peer: {q_b}", {"points": len(pts)}))
            else:
                rows.append(Row("poisson_disk", size, dev, t_cl, "bridson: not installed", None,
                                quality))
        sampler = clsamp.make_sampler("poisson_disk", rho=0.75, seed=1)
        reference = clsamp.make_sampler("poisson_disk", rho=0.75, seed=1, backend="numpy")
        sweep = 0.0
        for n, r in ((256, 8), (16, 128), (64, 128), (256, 128), (1024, 128)):
            t_cl, (pts, info) = timed(lambda: sampler.sample(n, realizations=r, return_info=True),
                                      repeats=3)
            rho = relative_radius(pts)
            quality = (f"rho min {rho.min():.4f} mean {rho.mean():.4f}, {n} pts each, "
                       f"{info.redraws} redraws")
            if r == 128:
                sweep += t_cl
            if (n, r) == (256, 8):
                t_ref, ref = timed(lambda: reference.sample(n, realizations=r), repeats=1, warmup=0)
                same = "bit-identical" if np.array_equal(ref, pts) else "DIFFERS"
                rows.append(Row("poisson_disk rho=0.75", f"{r}x{n}x2D", dev, t_cl,
                                "numpy reference", t_ref, f"{same}, {quality}"))
            else:
                rows.append(Row("poisson_disk rho=0.75", f"{r}x{n}x2D", dev, t_cl, "", None,
                                quality))
        rows.append(Row("poisson_disk rho=0.75", "sweep 16..1024 x128", dev, sweep, "", None,
                        "sum of the four sizes above"))
    return rows + run_dimensions(devices, quick)


def run_dimensions(devices, quick):
    """The 4-D and 8-D cases of the module docstring, one row each per device."""
    rows = []
    ns = (1024,) if quick else (1024, 4096)
    for device in devices:
        on_device(device)
        dev = short_name(device)
        for d in (4, 8):
            sampler = clsamp.make_sampler("poisson_disk", d=d, seed=1)
            for n in ns:
                t_cl, (pts, info) = timed(lambda: sampler.sample(n, return_info=True),  # noqa: B023
                                          repeats=3)
                assert min_distance(pts) >= info.radius
                rows.append(Row(f"poisson_disk rho={sampler.rho}", f"1x{n}x{d}D", dev, t_cl, "",
                                None, f"rho {relative_radius(pts):.4f}, {info.rounds} rounds, "
                                f"{info.darts} darts"))
        radius = 0.15
        sampler = clsamp.make_sampler("poisson_disk", d=4, radius=radius, seed=1)
        t_cl, (pts, info) = timed(lambda: sampler.sample(return_info=True), repeats=3)
        probes = np.random.default_rng(0).random((200_000, 4))
        void = float(np.mean(cKDTree(pts, boxsize=1.0).query(probes, k=1)[0] >= radius))
        rows.append(Row("poisson_disk", f"maximal 4D r={radius}", dev, t_cl, "", None,
                        f"{len(pts)} pts, rho {relative_radius(pts):.4f}, void {void:.2%} of "
                        f"200k probes, {info.rounds} rounds, {info.darts} darts"))
    return rows


if __name__ == "__main__":
    main(run, __doc__)
