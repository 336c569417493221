"""Run every capability's benchmark against its peer and print one table.

    python benchmarks/run.py [--device all] [--quick] [--out results.json] [--profile]
                             [--markdown FILE]

``--profile`` adds a table of where each row's time goes (one more call, profiled:
launch, kernel, transfer, host); ``--markdown`` writes the README's table from this run
(machine, versions, date and every row).

Each ``bench_<concern>.py`` listed in ``MODULES`` defines ``run(devices, quick)``.
A module that fails is reported and the others still run; the exit status is
non-zero if any failed (benchmarks never fail on time).
"""

import importlib
import os
import sys
import time
import traceback

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from common import enable_profile, finish, parser, select_devices  # noqa: E402

MODULES = (
    "bench_random",
    "bench_stratified",
    "bench_lowdiscrepancy",
    "bench_pmj",
    "bench_spectrum",
    "bench_metrics",
    "bench_convergence",
    "bench_families",
    "bench_poisson_disk",
    "bench_render",
    "bench_voronoi",
)


def main():
    args = parser(__doc__).parse_args()
    if args.profile:
        enable_profile()
    devices = select_devices(args.device)
    rows, failed = [], []
    for name in MODULES:
        t0 = time.perf_counter()
        try:
            module = importlib.import_module(name)
            rows.extend(module.run(devices, args.quick))
            print(f"[{name}: {time.perf_counter() - t0:.1f} s]", file=sys.stderr)
        except Exception:
            failed.append(name)
            traceback.print_exc()
    finish(args, rows)
    if failed:
        print("failed: " + ", ".join(failed), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
