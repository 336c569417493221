"""Run every capability's benchmark against its peer and print one table.

    python benchmarks/run.py [--device all] [--quick] [--out results.json] [--profile]
                             [--markdown FILE]

``--profile`` adds a table of where each row's time goes (one more call, profiled:
launch, kernel, transfer, host); ``--markdown`` writes the README's table from this run
(machine, versions, date and every row).

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
    full = [d for d in devices if d.fp64]
    partial = [d for d in devices if not d.fp64]
    rows, failed, refused = [], [], []
    for name in MODULES:
        t0 = time.perf_counter()
        try:
            module = importlib.import_module(name)
            if full:
                rows.extend(module.run(full, args.quick))
            for device in partial:      # without fp64 a module may refuse, by name
                try:
                    rows.extend(module.run([device], args.quick))
                except NoDeviceError as error:
                    refused.append(f"{name} on [{device.index}] {device.name}: {str(error)[:160]}")
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
