"""UTK's samplers (utk-team/utk) built from their source, timed in the same run as clsamp's.

    scripts/build-utk-peers.sh UTK_SRC SOT_SRC DIR
    CLSAMP_UTK_BIN=DIR python benchmarks/bench_utk.py [--device all] [--quick] [--out FILE]

Optional: without ``CLSAMP_UTK_BIN`` (a folder holding ``utk_sot``,
``utk_periodic_bnot``, ``utk_periodic_bnot_uniform``, ``utk_faure``,
``utk_niederreiter``) the module prints why and gives no rows, and a peer whose binary is
missing gives none; ``benchmarks/run.py`` runs it all the same. Each UTK binary
(``scripts/utk/utk_peer.cpp``) times one call of the sampler's ``generateSamples`` by its
own clock, so process start and file I/O are not counted; its points come back for the
quality figures. The machine may be shared, so the two sides are timed close together:
for ``sot`` and the nets clsamp's and UTK's calls alternate (each column the median of
its calls; each clsamp call timed after ``common.WARM`` seconds of untimed ones), for
PeriodicBNOT clsamp's calls follow UTK's. Even so a loaded machine bends
the ratios: UTK's SOT runs OpenMP threads, which slowed 22x at a load of 10 on two cores
where clsamp's sot slowed 2.2x (docs/performance.md); compare runs at low load.

Cases (``--quick``: n = 1024 only):

* ``sot`` against UTK's ``SOT`` (Paulin et al.'s code: points in the ball, mapped to the
  cube), n = 1024 and 4096, 2-D and 4-D. Each side at the first setting of its ladder
  whose set reaches ``bench_sot``'s quality (2-D: low-frequency power at most half of
  Poisson disk's; 4-D: mean nearest-neighbour distance in the cube at least 1.2 times
  white noise's, both measured in the run): clsamp's batches of 32 directions
  (``bench_sot.LADDER``), UTK's iterations of 64 directions (its default batch) on the
  same ladder continued up to 4096 (its default); then clsamp climbs on until its set is
  also equal or better than UTK's on both figures (rho, and the power or the mean
  nearest-neighbour distance), and that setting is timed.
* ``gbn``, ``ccvt`` and ``bnot`` (where registered) against UTK's ``PeriodicBNOT``, n =
  1024 and 4096, 2-D, two peers: UTK's sampler as shipped (its start is drawn in
  [0, 0.1)^2, which its default 20 outer iterations leave clustered) and the same code
  from a uniform start (``utk_periodic_bnot_uniform``), each one call at UTK's defaults
  (stopped after 600 s: the row then says so and its ratio is a lower bound).
  ``gbn`` at the first of ``bench_gbn.LADDER`` whose set has the uniform start's rho and
  low-frequency power or better (without it: ``bench_gbn``'s quality), ``ccvt`` and
  ``bnot`` at their defaults, ``bnot`` with ``cells="exact"`` ("bnot exact") at the
  first of ``bench_bnot.EXACT_LADDER`` whose set has the uniform start's rho and power
  (as gbn); clsamp's calls follow UTK's (median of 3 after a warm-up; ``bnot`` once).
* ``faure`` and ``niederreiter`` against UTK's ``Faure`` and ``Niederreiter``
  (unscrambled, the first n points) in 2-D and 4-D: n = 1024, 4096 and 65536 (Faure in
  4-D, base 5: 625, 3125 and 78125; ``--quick``: the first); the quality column says
  whether the points are the same.

Quality: rho (:func:`clsamp.metrics.relative_radius`, on the torus) and the low-frequency
power (:func:`clsamp.spectral_stats.low_frequency_power` of the periodogram) of each set,
clsamp's first, UTK's after "|". Ratio: UTK seconds over clsamp seconds (> 1: clsamp
faster).
"""

import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np
from bench_bnot import EXACT_LADDER as BNOT_EXACT_LADDER
from bench_gbn import LADDER as GBN_LADDER
from bench_gbn import low_frequency_power
from bench_sot import LADDER as SOT_LADDER
from bench_sot import _mean_nn
from common import WARM, Row, main, on_device, short_name, timed

import clsamp
from clsamp.metrics import relative_radius

ENV = "CLSAMP_UTK_BIN"
BINARIES = {"SOT": "utk_sot", "PeriodicBNOT": "utk_periodic_bnot",
            "PeriodicBNOT uniform": "utk_periodic_bnot_uniform", "Faure": "utk_faure",
            "Niederreiter": "utk_niederreiter"}
PEER_NAMES = {"PeriodicBNOT": "UTK PeriodicBNOT",
              "PeriodicBNOT uniform": "UTK PeriodicBNOT, uniform start"}
UTK_SOT_BATCH = 64                                   # UTK's default directions a batch
UTK_SOT_LADDER = SOT_LADDER + (768, 1024, 1536, 2048, 3072, 4096)
LONG = 10.0          # seconds: a call longer than this is timed once a side, not three times
BNOT_LIMIT = 600.0   # seconds: a PeriodicBNOT call stopped here gives a lower bound


def utk_binaries():
    """{UTK sampler: path} of the built binaries under $CLSAMP_UTK_BIN; None where it is
    unset or not a folder."""
    folder = os.environ.get(ENV)
    if not folder or not os.path.isdir(folder):
        return None
    found = {}
    for sampler, name in BINARIES.items():
        path = os.path.join(folder, name)
        if os.path.isfile(path) and os.access(path, os.X_OK):
            found[sampler] = path
    return found


def utk_sample(binary, n, d, seed=1, *params, limit=None):
    """(seconds of UTK's generateSamples, points (n, d)) from one run of ``binary``; (None,
    None) where it ran past ``limit`` seconds (it is then stopped)."""
    with tempfile.TemporaryDirectory(prefix="clsamp-utk-") as tmp:
        out = os.path.join(tmp, "points.bin")
        try:
            subprocess.run([binary, str(n), str(d), str(seed), out, *map(str, params)],
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, check=True,
                           timeout=limit)
        except subprocess.TimeoutExpired:
            return None, None
        data = np.fromfile(out, dtype=np.float64)
    seconds, count, dim = data[0], int(data[1]), int(data[2])
    return float(seconds), data[3:].reshape(count, dim)


def outside(points):
    """How many of UTK's points lie outside [0, 1)^d (its SOT maps the ball to the cube,
    which can land a hair past 1 in 4-D)."""
    return int(np.count_nonzero(((points < 0) | (points >= 1)).any(axis=1)))


def into_cube(points):
    """``points`` clamped into [0, 1)^d, so that clsamp's metrics take them."""
    return np.clip(points, 0.0, 1.0 - 2.0 ** -53)


def interleaved(clsamp_fn, utk_fn, repeats):
    """Median seconds of clsamp's calls and UTK's, called alternately ``repeats`` times each;
    the last points of each. Each timed clsamp call comes after ``WARM`` seconds of
    untimed ones (at least one), as ``common.timed``'s rows over the twins: UTK's run
    leaves clsamp's process idle, and a CPU device's first work after a pause runs slower
    (docs/performance.md, "Warm calls before the timed ones")."""
    t_cl, t_utk = [], []
    for _ in range(repeats):
        warm = time.perf_counter()
        pts = clsamp_fn()
        while time.perf_counter() - warm < WARM:
            pts = clsamp_fn()
        t0 = time.perf_counter()
        pts = clsamp_fn()
        t_cl.append(time.perf_counter() - t0)
        seconds, ref = utk_fn()
        t_utk.append(seconds)
    return statistics.median(t_cl), pts, statistics.median(t_utk), ref


def _figures(points):
    """rho and low-frequency power of a 2-D set."""
    return float(relative_radius(points)), low_frequency_power(points)


def _describe(points, n, d):
    if d == 2:
        rho, power = _figures(points)
        return f"rho {rho:.3f}, power {power:.4f}"
    return f"rho {float(relative_radius(points)):.3f}, mean NN {_mean_nn(points, n, d):.3f} d_max"


def _first(ladder, make, met):
    """The first setting of ``ladder`` whose points ``make(setting)`` are ``met``: (setting,
    points, reached), the last rung's where none is."""
    for setting in ladder:
        pts = make(setting)
        if met(pts):
            return setting, pts, True
    return setting, pts, False


def _sot_figures(points, n, d):
    """(rho, low-frequency power) in 2-D; (rho, -mean NN / d_max) in 4-D: smaller second
    figure is better in both."""
    if d == 2:
        return _figures(points)
    return float(relative_radius(points)), -_mean_nn(points, n, d)


def _sot_rows(binary, sizes, targets, dev):
    rows = []
    for d in (2, 4):
        for n in sizes:
            target = targets[n, d]
            if d == 2:
                goal = f"power <= {target / 2:.4f}"

                def met(pts, target=target):
                    return low_frequency_power(pts) <= target / 2
            else:
                goal = f"mean NN >= {1.2 * target:.3f} d_max"

                def met(pts, n=n, d=d, target=target):
                    return _mean_nn(pts, n, d) >= 1.2 * target

            def make(b, n=n, d=d):
                return clsamp.make_sampler("sot", d=d, seed=1, iterations=b).sample(n)
            batches, _, ok_cl = _first(SOT_LADDER, make, met)
            last = {}                        # UTK's last call: seconds, points outside

            def utk(it, n=n, d=d, last=last):
                seconds, points = utk_sample(binary, n, d, 1, it, UTK_SOT_BATCH)
                last.update(seconds=seconds, outside=outside(points))
                return seconds, into_cube(points)
            iterations, ref, ok_utk = _first(UTK_SOT_LADDER, lambda it: utk(it)[1], met)
            theirs = _sot_figures(ref, n, d)

            def as_good(pts, n=n, d=d, theirs=theirs):
                mine = _sot_figures(pts, n, d)
                return mine[0] >= theirs[0] and mine[1] <= theirs[1]
            batches, _, _ = _first(SOT_LADDER[SOT_LADDER.index(batches):], make, as_good)
            sampler = clsamp.make_sampler("sot", d=d, seed=1, iterations=batches)
            t_cl, pts, t_utk, ref = interleaved(
                lambda s=sampler, n=n: s.sample(n), lambda it=iterations: utk(it),
                1 if last["seconds"] > LONG else 3)
            mine, theirs = _sot_figures(pts, n, d), _sot_figures(ref, n, d)
            better = "yes" if mine[0] >= theirs[0] and mine[1] <= theirs[1] else "no"
            # UTK's OpenMP threads spin: other load on the cores slows them several-fold
            # (docs/performance.md), so the row says what the machine carried
            load = os.getloadavg()[0]
            clamped = f" ({last['outside']} outside the cube, clamped)" if last["outside"] else ""
            text = (f"{goal}: {_describe(pts, n, d)}{'' if ok_cl else ' (not reached)'} | "
                    f"UTK {iterations} it x {UTK_SOT_BATCH}: {_describe(ref, n, d)}"
                    f"{'' if ok_utk else ' (not reached)'}"
                    f"{clamped}; equal or better: {better}; load average {load:.2f}")
            rows.append(Row("sot vs UTK SOT", f"{n}x{d}D, {batches} batches x 32", dev, t_cl,
                            "UTK SOT", t_utk, text,
                            {"batches": batches, "utk_iterations": iterations,
                             "reached": ok_cl, "utk_reached": ok_utk,
                             "equal_or_better": better == "yes", "load": load}))
    return rows


def _bnot_rows(binaries, sizes, disk, dev):
    """Per n: UTK's PeriodicBNOT as shipped and from a uniform start (one call each, its
    defaults), then gbn (at the first of bench_gbn's ladder matching the uniform start's
    rho and power), ccvt and bnot (defaults), one after the other."""
    rows = []
    for n in sizes:
        peers = []
        for peer in ("PeriodicBNOT", "PeriodicBNOT uniform"):
            if peer in binaries:
                seconds, ref = utk_sample(binaries[peer], n, 2, 1, limit=BNOT_LIMIT)
                peers.append((PEER_NAMES[peer], seconds, None if ref is None else _figures(ref)))
        if not peers:
            continue
        # the uniform start's figures where it finished, else bench_gbn's quality
        uniform = [f for peer, _, f in peers if peer == PEER_NAMES["PeriodicBNOT uniform"]]
        goal = uniform[0] if uniform and uniform[0] is not None else (0.75, disk[n] / 7)
        ours = []
        iterations, _, ok = _first(GBN_LADDER, lambda it, n=n: clsamp.make_sampler(
            "gbn", seed=1, iterations=it, tol=0.0).sample(n), lambda pts: _at_least(pts, goal))
        ours.append(("gbn", f"{iterations} it{'' if ok else ' (quality not reached)'}",
                     clsamp.make_sampler("gbn", seed=1, iterations=iterations, tol=0.0), 3))
        ours.append(("ccvt", "default", clsamp.make_sampler("ccvt", seed=1, progress=False), 3))
        if "bnot" in clsamp.sampler_names():
            ours.append(("bnot", "default", clsamp.make_sampler("bnot", seed=1, progress=False), 1))
            iterations, _, ok = _first(BNOT_EXACT_LADDER, lambda it, n=n: clsamp.make_sampler(
                "bnot", seed=1, iterations=it, tol=0.0, cells="exact", progress=False).sample(n),
                lambda pts: _at_least(pts, goal))
            ours.append(("bnot exact", f"{iterations} it{'' if ok else ' (quality not reached)'}",
                         clsamp.make_sampler("bnot", seed=1, iterations=iterations, tol=0.0,
                                             cells="exact", progress=False), 3))
        for name, setting, sampler, repeats in ours:
            seconds, pts = timed(lambda s=sampler, n=n: s.sample(n), repeats=repeats)
            figures = _figures(pts)
            for peer, utk_seconds, utk_figures in peers:
                mine = f"rho {figures[0]:.3f}, power {figures[1]:.4f} | "
                if utk_figures is None:
                    text = mine + f"UTK stopped unfinished at {BNOT_LIMIT:.0f} s: ratio a lower bound"
                    utk_seconds, better = BNOT_LIMIT, None
                else:
                    better = _at_least(pts, utk_figures, figures)
                    text = mine + (f"UTK rho {utk_figures[0]:.3f}, power {utk_figures[1]:.4f}; "
                                   f"equal or better: {'yes' if better else 'no'}")
                # a peer stopped at the limit gives a lower bound, not a ratio: the summary
                # leaves it out, as it does a row below the peer's quality
                rows.append(Row(f"{name} vs {peer}", f"{n}x2D, {setting}", dev, seconds, peer,
                                utk_seconds, text, {"equal_or_better": better,
                                                    "peer_unconverged": utk_figures is None}))
    return rows


def _at_least(pts, goal, figures=None):
    """Whether a 2-D set has rho and low-frequency power at least as good as ``goal``."""
    rho, power = _figures(pts) if figures is None else figures
    return rho >= goal[0] and power <= goal[1]


def _same(pts, ref):
    """Whether clsamp's points and UTK's are the same: in order, as a set, or neither."""
    if pts.shape != ref.shape:
        return f"UTK gave {ref.shape}"
    err = float(np.abs(pts - ref).max())
    if err <= 2.0 ** -40:
        return "same points as UTK" + (f" (within {err:.1e})" if err else "")
    set_err = float(np.abs(pts[np.lexsort(pts.T[::-1])] - ref[np.lexsort(ref.T[::-1])]).max())
    if set_err <= 2.0 ** -40:
        return "same set as UTK, another order" + (f" (within {set_err:.1e})" if set_err else "")
    return f"differs from UTK by up to {err:.3g}"


def _compare(name, pts, ref):
    """_same, and for Niederreiter (UTK: natural order from index 1; clsamp: Gray code
    from 0) whether clsamp's points 1..n-1 are UTK's first n-1 as a set."""
    same = _same(pts, ref)
    if name == "niederreiter" and same.startswith("differs") and len(pts) > 1:
        if _same(pts[1:], ref[:-1]).startswith("same"):
            return ("the same net: UTK's first n-1 points are clsamp's 1..n-1 as a set "
                    "(UTK from index 1 in natural order, clsamp from 0 in Gray order)")
    return same


def _net_rows(binaries, quick, dev):
    """Faure in base 2 (d = 2) and 5 (d = 4) at powers of its base (nets); Niederreiter at
    powers of 2."""
    rows = []
    sizes = {("faure", 2): (1024, 4096, 65536), ("faure", 4): (625, 3125, 78125),
             ("niederreiter", 2): (1024, 4096, 65536), ("niederreiter", 4): (1024, 4096, 65536)}
    for name, peer in (("faure", "Faure"), ("niederreiter", "Niederreiter")):
        if peer not in binaries:
            continue
        for d in (2, 4):
            for n in sizes[name, d][:1 if quick else 3]:
                sampler = clsamp.make_sampler(name, d=d)
                t_cl, pts, t_utk, ref = interleaved(
                    lambda s=sampler, n=n: s.sample(n),
                    lambda n=n, d=d: utk_sample(binaries[peer], n, d), 5)
                rows.append(Row(f"{name} vs UTK {peer}", f"{n}x{d}D", dev, t_cl, f"UTK {peer}",
                                t_utk, _compare(name, pts, ref)))
    return rows


def run(devices, quick):
    binaries = utk_binaries()
    if binaries is None:
        print(f"bench_utk: skipped: set {ENV} to a folder of UTK samplers built by "
              "scripts/build-utk-peers.sh", file=sys.stderr)
        return []
    missing = sorted(set(BINARIES.values()) - {os.path.basename(p) for p in binaries.values()})
    if missing:
        print(f"bench_utk: not built, so not timed: {', '.join(missing)}", file=sys.stderr)
    sizes = (1024,) if quick else (1024, 4096)
    disk = {n: low_frequency_power(clsamp.make_sampler("poisson_disk", seed=1).sample(n, realizations=4))
            for n in sizes}
    targets = {}
    for n in sizes:
        targets[n, 2] = disk[n]
        targets[n, 4] = _mean_nn(clsamp.make_sampler("random", d=4, seed=1).sample(n), n, 4)
    rows = []
    for device in devices:
        on_device(device)
        dev = short_name(device)
        rows += _net_rows(binaries, quick, dev)
        if "SOT" in binaries:
            rows += _sot_rows(binaries["SOT"], sizes, targets, dev)
        rows += _bnot_rows(binaries, sizes, disk, dev)
    return rows


if __name__ == "__main__":
    main(run, __doc__)
