"""The blue-noise optimizers' peak memory against n: the issue's "memory linear in n".

    python benchmarks/bench_optimizer_memory.py [--device all] [--quick] [--out FILE]

Each optimizer makes one 2-D set (seed 1) at n = 8192, 16384, 32768 and 65536 (``--quick``:
8192 and 16384), each n in a fresh Python process on the device: a warm-up call of 64
points (the kernels built, the runtime's pools made) and one of n points (the kernels a
call at n builds once, such as PoCL's for another work-group size), the memory they freed
handed back to the system (glibc's ``malloc_trim``), then the measured call. Its peak is
the process's resident high-water mark (``VmHWM`` in ``/proc/self/status``), set back to
the resident memory of the moment (``VmRSS``) just before the call (``5`` written to
``/proc/self/clear_refs``, Linux 4.0 on; where that is refused, the mark includes the
warm-up's peak). Not ``getrusage``'s ``ru_maxrss``: on Linux a child started by
``subprocess`` inherits its parent's peak there, gigabytes in a full run of
``benchmarks/run.py``. Without ``/proc`` (not Linux) the module gives no rows.

The optimizers, with few iterations (an iteration's arrays are made in the first and
reused, so the peak does not grow with the iterations; docs/performance.md gives the
measurements over more):

* ``gbn``, 5 iterations, ``tol=0``;
* ``sot``, 16 batches of 32 directions;
* ``bnot`` with exact cells, 4 iterations;
* ``bnot`` with density points (256 a site), 1 iteration;
* ``sample_elimination``, 5 candidates a point.

A row gives the call's seconds and, in its quality column, the peak, the part above the
resident memory before the call, and the growth of both over the previous n (one
doubling). The issue's bound, 2.2x a doubling, is judged on the part above, what the call
itself holds at its peak, which grows about 2x a doubling where memory is linear in n:
the peak includes the process's own 270 MiB or so (Python, NumPy, PoCL), under which a
quadratic call would grow by less than 2.2x at these n. There is no
peer: the rows stay in the full table (docs/benchmarks.md). The memory is the host's: on a
GPU the device's buffers are not in it.
"""

import json
import os
import subprocess
import sys

from common import Row, main, on_device, short_name

from clsamp import runtime

#: (case, sampler, keyword arguments) of each optimizer measured
OPTIMIZERS = (
    ("gbn", "gbn", {"iterations": 5, "tol": 0.0}),
    ("sot", "sot", {"iterations": 16}),
    ("bnot exact", "bnot", {"cells": "exact", "iterations": 4, "progress": False}),
    ("bnot with density points", "bnot", {"iterations": 1, "progress": False}),
    ("sample_elimination", "sample_elimination", {}),
)
SIZES = (8192, 16384, 32768, 65536)
QUICK_SIZES = (8192, 16384)
BOUND = 2.2           # the largest growth a doubling of n (of the part above)
WARM_UP = 64          # points of the call before the measured one
TIMEOUT = 1800        # seconds one child process may take
MIN_ABOVE = 4.0       # MiB above the call's start from which its growth is given (below
                      # it the allocator's reuse of freed memory decides the figure)


def measure(device_index, name, n, params):
    """One child process: ``name`` with ``params`` makes a warm-up set, then n points.

    Returns
    -------
    dict
        ``seconds`` of the measured call; ``base``, the resident memory before it, and
        ``peak``, the resident high-water mark of the call, in MiB.
    """
    env = dict(os.environ, CLSAMP_DEVICE=str(device_index))
    done = subprocess.run([sys.executable, os.path.abspath(__file__), "--child", name, str(n),
                           json.dumps(params)], env=env, capture_output=True, text=True,
                          timeout=TIMEOUT, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"{name} at n = {n}: the child process failed:\n{done.stderr}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def _status_mib(field):
    """A memory field of ``/proc/self/status`` (``VmRSS``, ``VmHWM``) in MiB."""
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith(field + ":"):
                return int(line.split()[1]) / 1024      # kB
    raise RuntimeError(f"/proc/self/status has no {field}")


def _child(name, n, params):
    """The measurement inside the child process; prints its dict as JSON."""
    import ctypes
    import gc
    import time

    import clsamp
    sampler = clsamp.make_sampler(name, seed=1, **params)
    sampler.sample(WARM_UP)
    # a first call at n builds what a call at n builds once (PoCL compiles a kernel for
    # each work-group size it meets: 20 MiB and 0.2 s inside a measured gbn call at
    # 65536 points, where the warm-up's 64 points had used another size); the memory it
    # freed is then handed back to the system, so the measured call finds none to reuse
    sampler.sample(n)
    gc.collect()
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):    # not glibc: freed memory may be reused
        pass
    base = _status_mib("VmRSS")
    try:
        with open("/proc/self/clear_refs", "w") as refs:  # the high-water mark := VmRSS
            refs.write("5")
    except OSError:          # not allowed here: the mark then includes the warm-up's peak
        pass
    start = time.perf_counter()
    sampler.sample(n)
    seconds = time.perf_counter() - start
    print(json.dumps({"seconds": seconds, "base": base, "peak": _status_mib("VmHWM")}))


def run(devices, quick):
    rows = []
    if not os.path.exists("/proc/self/status"):
        print("bench_optimizer_memory: no /proc/self/status here (not Linux), no rows",
              file=sys.stderr)
        return rows
    sizes = QUICK_SIZES if quick else SIZES
    for device in devices:
        on_device(device)
        runtime.require_fp64()      # the optimizers need it; run.py lists a refusal as such
        dev = short_name(device)
        for case, name, params in OPTIMIZERS:
            last = None
            for n in sizes:
                got = measure(device.index, name, n, params)
                peak, above = got["peak"], got["peak"] - got["base"]
                text = f"peak RSS {peak:.0f} MiB, {above:.1f} MiB above the RSS before the call"
                extra = {"peak_mib": peak, "above_mib": above}
                if last is not None:
                    growth = peak / last[0]
                    text += f"; {growth:.2f}x the peak at n/2"
                    extra.update(growth=growth)
                    if last[1] >= MIN_ABOVE:
                        # the bound on what the call holds: the process's own ~270 MiB
                        # (Python, NumPy, PoCL) would hide any growth in the peak
                        above_growth = above / last[1]
                        extra.update(above_growth=above_growth, within_bound=above_growth <= BOUND)
                        text += (f", {above_growth:.2f}x the part above (bound {BOUND}x: "
                                 f"{'within' if above_growth <= BOUND else 'over'})")
                rows.append(Row(f"{case} memory", f"{n}x2D", dev, got["seconds"],
                                quality=text, extra=extra))
                last = (peak, above)
    return rows


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        _child(sys.argv[2], int(sys.argv[3]), json.loads(sys.argv[4]))
    else:
        main(run, __doc__)
