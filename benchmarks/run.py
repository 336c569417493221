"""Run every capability's benchmark against its peer and print one table.

    python benchmarks/run.py [--device all] [--quick] [--out results.json] [--profile]
                             [--markdown FILE]

``--profile`` adds a table of where each row's time goes (one more call, profiled:
launch, kernel, transfer, host); ``--markdown README.md`` writes the README's summary from
this run (one line per capability and outside peer) and the full table (machine, versions,
date and every row) to docs/benchmarks.md; ``--markdown FILE`` for another file writes the
full table there.

Each ``bench_<concern>.py`` listed in ``MODULES`` defines ``run(devices, quick)``.
A module that fails is reported and the others still run; the exit status is
non-zero if any failed (benchmarks never fail on time). With ``--device all`` a device
without fp64 runs each module alone; one that refuses there (NoDeviceError: spectra,
metrics, ...) is listed as refused, not failed.
"""

import importlib
import os
import sys
import time
import traceback

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from common import enable_profile, finish, parser, select_devices  # noqa: E402

from clsamp.errors import NoDeviceError  # noqa: E402

MODULES = (
    "bench_random",
    "bench_stratified",
    "bench_lowdiscrepancy",
    "bench_digital_nets",
    "bench_pmj",
    "bench_spectrum",
    "bench_metrics",
    "bench_convergence",
    "bench_families",
    "bench_cubature",
    "bench_poisson_disk",
    "bench_render",
    "bench_voronoi",
    "bench_gbn",
    "bench_bnot",
    "bench_sample_elimination",
    "bench_sot",
    "bench_dither",
    "bench_optimizer_memory",
    "bench_shapes",
    "bench_utk",        # UTK's samplers where built (CLSAMP_UTK_BIN); no rows otherwise
)


def main():
    args = parser(__doc__).parse_args()
    if args.profile:
        enable_profile()
    devices = select_devices(args.device)
    full = [d for d in devices if d.fp64]
    partial = [d for d in devices if not d.fp64]
    rows, failed, refused = [], [], []
    for name in MODULES:
        t0 = time.perf_counter()
        try:
            module = importlib.import_module(name)
            mine = []
            if full:
                mine.extend(module.run(full, args.quick))
            for device in partial:      # without fp64 a module may refuse, by name
                try:
                    mine.extend(module.run([device], args.quick))
                except NoDeviceError as error:
                    refused.append(f"{name} on [{device.index}] {device.name}: {str(error)[:160]}")
            for row in mine:
                row.capability = name.removeprefix("bench_")
            rows.extend(mine)
            print(f"[{name}: {time.perf_counter() - t0:.1f} s]", file=sys.stderr)
        except Exception:
            failed.append(name)
            traceback.print_exc()
    finish(args, rows)
    for line in refused:
        print(f"refused (documented): {line}")
    if failed:
        print("failed: " + ", ".join(failed), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
