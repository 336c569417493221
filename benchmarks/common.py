"""What every benchmark shares: device selection, timing, the table and the JSON.

A benchmark module ``bench_<concern>.py`` defines ``run(devices, quick) -> list[Row]``;
``benchmarks/run.py`` runs them all. Timings are the median of repeats after one
warm-up call; peers are timed in the same run, so ratios compare like with like.
Benchmarks never fail on time. A generator's row may also carry its output bytes and
np.copyto's GB/s for the same size (:func:`copy_bandwidth`, measured in the same run):
the tables then show its output GB/s and its share of the copy's.
"""

import argparse
import dataclasses
import json
import os
import platform
import statistics
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import clsamp  # noqa: E402
from clsamp import runtime  # noqa: E402


@dataclasses.dataclass
class Row:
    """One line of the table: clsamp's time against its peer's on one case."""

    case: str
    size: str
    device: str
    seconds: float
    peer: str = ""
    peer_seconds: float | None = None
    quality: str = ""          # e.g. "max err 3e-12", "N·E 0.1641", "MSE 8.5e-4"
    extra: dict = dataclasses.field(default_factory=dict)
    output_bytes: int | None = None     # bytes one timed call returns (a generator's output)
    copy_gbs: float | None = None       # copy_bandwidth(output_bytes), measured in the same run
    capability: str = ""       # the bench_<capability>.py module that measured it

    @property
    def ratio(self):
        """Peer seconds over clsamp seconds: > 1 means clsamp is faster."""
        if self.peer_seconds is None or self.seconds <= 0:
            return None
        return self.peer_seconds / self.seconds

    @property
    def gbs(self):
        """clsamp's output GB/s (1e9 bytes a second): output bytes over seconds."""
        if self.output_bytes is None or self.seconds <= 0:
            return None
        return self.output_bytes / self.seconds / 1e9

    @property
    def copy_fraction(self):
        """Output GB/s over np.copyto's GB/s for the same bytes: 1 writes as fast as a copy."""
        if self.gbs is None or not self.copy_gbs:
            return None
        return self.gbs / self.copy_gbs

    def __post_init__(self):
        if _PROFILE["on"] and _PROFILE["last"] is not None and "profile" not in self.extra:
            self.extra["profile"] = _PROFILE["last"]
        _PROFILE["last"] = None

    def as_dict(self):
        d = dataclasses.asdict(self)
        d["ratio"] = self.ratio
        d["gbs"] = self.gbs
        d["copy_fraction"] = self.copy_fraction
        return d


# --profile: where one more call of each timed function spends its time
_PROFILE = {"on": False, "last": None}


def enable_profile():
    """Profile every timed call from now on (before any device is used)."""
    runtime.enable_profiling()
    _PROFILE["on"] = True


def profile(fn):
    """Where one call of ``fn`` spends its time: a dict of seconds, or None if it used no OpenCL.

    The call is serialized: every kernel launch and copy is waited for before the next
    command, so the device intervals below never overlap and add up to at most the wall
    time (this call is one more, apart from the timed ones). ``launch``: per kernel, the
    device's QUEUED..START (submitting, argument setup, scheduling); ``kernel``: its
    START..END; ``transfer``: START..END of every copy and map (``enqueue_copy``,
    ``enqueue_map_buffer``: reads, writes, the zero-copy output's map); ``host``: the rest
    of the wall time (NumPy work, Python). Launches through ``pyopencl.Kernel.__call__``
    and ``enqueue_nd_range_kernel`` are seen.
    """
    import pyopencl as cl
    kernels, copies = [], []
    originals = (cl.Kernel.__call__, cl.enqueue_nd_range_kernel, cl.enqueue_copy,
                 cl.enqueue_map_buffer)

    def seen(events, event):
        if event is not None:
            event.wait()
            events.append(event)
        return event

    def call(self, *args, **kwargs):
        return seen(kernels, originals[0](self, *args, **kwargs))

    def nd_range(*args, **kwargs):
        return seen(kernels, originals[1](*args, **kwargs))

    def copy(*args, **kwargs):
        return seen(copies, originals[2](*args, **kwargs))

    def map_buffer(*args, **kwargs):
        result = originals[3](*args, **kwargs)
        seen(copies, result[1])
        return result

    cl.Kernel.__call__, cl.enqueue_nd_range_kernel = call, nd_range
    cl.enqueue_copy, cl.enqueue_map_buffer = copy, map_buffer
    try:
        t0 = time.perf_counter()
        fn()
        wall = time.perf_counter() - t0
    finally:
        cl.Kernel.__call__, cl.enqueue_nd_range_kernel, cl.enqueue_copy, cl.enqueue_map_buffer = originals
    if not kernels and not copies:
        return None

    def seconds(events, first, last):
        return sum(max(0, getattr(e.profile, last) - getattr(e.profile, first)) for e in events) * 1e-9

    launch = seconds(kernels, "queued", "start")
    kernel, transfer = seconds(kernels, "start", "end"), seconds(copies, "start", "end")
    return {"wall": wall, "launches": len(kernels), "launch": launch, "kernel": kernel,
            "transfer": transfer, "host": max(0.0, wall - launch - kernel - transfer)}


#: seconds :func:`timed` waits before its first call: after a NumPy call that goes to
#: OpenBLAS (a quality check's spectrum, the last peer), OpenBLAS's worker threads spin
#: for a while before they sleep, and a CPU OpenCL device's work items, timed then, would
#: share a core with them (docs/performance.md, "Timings after a BLAS call")
SETTLE = 0.25

#: seconds of untimed calls (``warm_time``) before the timed ones of the rows that ask for
#: them, both sides alike: after a pause, a 2-core VM runs the first tenth of a second or
#: so of a CPU device's calls slower than the rest
#: (docs/performance.md, "Warm calls before the timed ones")
WARM = 0.2


def timed(fn, repeats=5, warmup=1, min_time=0.0, warm_time=0.0):
    """Median seconds of ``fn()`` over ``repeats`` calls after ``warmup`` calls, and more
    untimed calls until ``warm_time`` seconds of them have passed; and its last result.

    Both sides of a row start on a quiet machine: :data:`SETTLE` seconds of sleep come first.
    With ``--profile`` one more call is profiled (:func:`profile`) and the next :class:`Row`
    made carries the breakdown (calls that use no OpenCL, a peer's, leave none)."""
    result = None
    time.sleep(SETTLE)
    warm_start = time.perf_counter()
    for _ in range(warmup):
        result = fn()
    while time.perf_counter() - warm_start < warm_time:
        result = fn()
    times = []
    start_all = time.perf_counter()
    for i in range(repeats):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
        if min_time and i >= 1 and time.perf_counter() - start_all > min_time:
            break
    if _PROFILE["on"]:
        breakdown = profile(fn)
        if breakdown is not None:
            _PROFILE["last"] = breakdown
    return statistics.median(times), result


def to_quality(name, d, n, ladder, quality, device, unit="iterations", title=None, **params):
    """An iterating sampler timed where it first reaches a quality: climb ``ladder`` (its
    ``iterations``) until ``quality(points)`` gives (True, text), then time that setting
    against its NumPy twin (which must give the same bits), each side after :data:`WARM`
    seconds of untimed calls.

    Returns
    -------
    Row
        ``title`` (default "<name> to quality"); its extra holds the iterations and whether
        the quality was met.
    """
    import numpy as np
    for iterations in ladder:
        sampler = clsamp.make_sampler(name, d=d, seed=1, iterations=iterations, **params)
        met, text = quality(sampler.sample(n))
        if met:
            break
    t_cl, pts = timed(lambda: sampler.sample(n), repeats=3, warm_time=WARM)
    twin = clsamp.make_sampler(name, d=d, seed=1, iterations=iterations, backend="numpy", **params)
    t_np, ref = timed(lambda: twin.sample(n), repeats=1, warmup=0, warm_time=WARM)
    same = "bit-identical" if np.array_equal(ref, pts) else "DIFFERS"
    reached = "" if met else f"quality not reached in {iterations} {unit}: "
    label = "it" if unit == "iterations" else unit
    return Row(title or f"{name} to quality", f"{n}x{d}D, {iterations} {label}", device, t_cl,
               "numpy twin", t_np,
               f"{reached}{text}, {same}", {"iterations": iterations, "reached": met})


def copy_bandwidth(nbytes, repeats=None):
    """GB/s (1e9 bytes a second) of ``np.copyto(dst, src)`` for float64 arrays of ``nbytes``.

    The bytes counted are the ``nbytes`` written, as a generator's output GB/s counts its
    output, so their ratio says how near the generator writes to the rate at which this
    machine copies that much memory (reading as much again). Both arrays are allocated and
    written before timing, so no page fault is timed; the time is :func:`timed`'s median
    (``repeats``: by default more for small arrays, which copy within the caches in
    microseconds)."""
    import numpy as np
    n = max(1, int(nbytes) // 8)
    src, dst = np.full(n, 0.5), np.full(n, 0.25)
    if repeats is None:
        repeats = max(5, min(101, 2**28 // (8 * n)))
    seconds, _ = timed(lambda: np.copyto(dst, src), repeats=repeats, min_time=1.0)
    return 8 * n / seconds / 1e9


# The machine gauge: a fixed single-threaded workload, also timed when the figures of peers
# that cannot run here (Balzer et al.'s CCVT) were taken on the project machine
GAUGE_RADIUS = 0.01215
GAUGE_PUBLISHED = 2.98   # the gauge's seconds then (docs/performance.md, first section)


def machine_gauge():
    """Seconds of ``scipy.stats.qmc.PoissonDisk(d=2, radius=0.01215, seed=1).fill_space()``
    now, to set beside GAUGE_PUBLISHED.

    A row whose peer is a published figure, not code run in the same process, compares
    like with like only while the machine runs at the speed it ran at then, and a shared
    VM drifts. The gauge says when a ratio to a published figure is fair (near
    GAUGE_PUBLISHED); it is no conversion factor, since the gauge and the timed code do not
    slow by the same factor (docs/performance.md gives an evening of both)."""
    from scipy.stats import qmc
    engine = qmc.PoissonDisk(d=2, radius=GAUGE_RADIUS, seed=1)
    t0 = time.perf_counter()
    engine.fill_space()
    return time.perf_counter() - t0


def select_devices(spec):
    """``None`` -> the default device; ``"all"`` -> every device whose compiler works (those
    without fp64 included: run.py reports what they refuse), but a simulator (Oclgrind:
    its times say nothing of a device; tests/test_oclgrind.py runs it); else one index/name,
    or several separated by commas (``"0,3"``: PoCL and Intel's runtime side by side)."""
    if spec == "all":
        usable = []
        for device in runtime.devices():
            if device.simulator:
                print(f"skipping {device}: a simulator, not timed", file=sys.stderr)
            elif not runtime.compiles(device.index):
                print(f"skipping {device}: its compiler fails", file=sys.stderr)
            else:
                usable.append(device)
        return usable
    if spec is None:
        return [runtime.current_device()]
    return [runtime.use_device(part.strip()) for part in spec.split(",")]


def on_device(device):
    """Make ``device`` current (benchmarks loop over devices)."""
    return runtime.use_device(device.index)


def short_name(device):
    """``[index] name (type, implementation)``: Intel's CPU runtime names its device by the
    CPU alone ("AMD EPYC"), so the implementation tells it from PoCL's."""
    words = device.platform.replace("(R)", "").split() or ["?"]
    implementation = "PoCL" if device.platform == "Portable Computing Language" else words[0]
    return f"[{device.index}] {device.name[:28]} ({device.type}, {implementation})"


def print_tables(rows, file=sys.stdout):
    """One table per device, then (with several) a cross-device summary of clsamp's seconds."""
    devices = list(dict.fromkeys(r.device for r in rows))
    if len(devices) <= 1:
        print_table(rows, file)
        return
    for device in devices:
        print(f"\n{device}:", file=file)
        print_table([r for r in rows if r.device == device], file)
    headers = ("case", "size", *devices, f"vs {devices[0]}")
    lines = [(case, size, *("-" if t is None else f"{t:.4g}" for t in times),
              " ".join("-" if None in (times[0], t) else f"{times[0] / t:.2f}x" for t in times[1:]))
             for case, size, times in across_devices(rows, devices)]
    widths = [max(len(h), *(len(line[i]) for line in lines)) if lines else len(h)
              for i, h in enumerate(headers)]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    print("\nacross devices (clsamp seconds; the last column: the first device's time over each "
          "other's, > 1 means that one is faster):", file=file)
    print(fmt.format(*headers), file=file)
    print(fmt.format(*("-" * w for w in widths)), file=file)
    for line in lines:
        print(fmt.format(*line), file=file)


def across_devices(rows, devices):
    """(case, size, clsamp seconds on each of ``devices``, None where it did not run) for
    every case two or more of them ran (a device without fp64 refuses the analyses), once
    each: a case's several peers repeat its clsamp time, and the first row's is taken."""
    seconds = {}
    for r in rows:
        seconds.setdefault((r.case, r.size, r.device), r.seconds)
    out = []
    for case, size in dict.fromkeys((r.case, r.size) for r in rows):
        times = [seconds.get((case, size, d)) for d in devices]
        if sum(t is not None for t in times) >= 2:
            out.append((case, size, times))
    return out


def _fastest_index(times):
    return min((k for k, t in enumerate(times) if t is not None), key=times.__getitem__)


def cross_device_markdown(rows):
    """The run's cases side by side on every device it timed (docs/benchmarks.md), each with
    the first device's seconds over each other's and which device is fastest; "" with one
    device."""
    devices = list(dict.fromkeys(r.device for r in rows))
    if len(devices) <= 1:
        return ""
    headers = ("case", "size", *(f"{d} s" for d in devices),
               *(f"{devices[0]} s / {d} s" for d in devices[1:]), "fastest")
    lines = ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers)]
    for case, size, times in across_devices(rows, devices):
        cells = (case, size, *("-" if t is None else f"{t:.3g}" for t in times),
                 *("-" if None in (times[0], t) else f"{times[0] / t:.2f}×" for t in times[1:]),
                 devices[_fastest_index(times)])
        lines.append("| " + " | ".join(str(c).replace("|", "\\|") for c in cells) + " |")
    return "\n".join(lines) + "\n"


def implementation_summary(rows):
    """The README's side-by-side line per capability: on how many cases each device was the
    fastest (of those that ran the case), and the range of the first device's seconds over
    each other's; "" with one device."""
    devices = list(dict.fromkeys(r.device for r in rows))
    if len(devices) <= 1:
        return ""
    groups = {}
    capability = {(r.case, r.size): r.capability or "-" for r in rows}
    for case, size, times in across_devices(rows, devices):
        groups.setdefault(capability[(case, size)], []).append(times)
    head = ("| capability | cases | " + " | ".join(f"fastest on {d}" for d in devices) + " | "
            + " | ".join(f"{devices[0]} s / {d} s" for d in devices[1:]) + " |")
    lines = [head, "|" + "---|" * (1 + 2 * len(devices))]
    for name, cases in groups.items():
        wins = [sum(1 for t in cases if _fastest_index(t) == k) for k in range(len(devices))]
        spans = []
        for k in range(1, len(devices)):
            ratios = [t[0] / t[k] for t in cases if None not in (t[0], t[k])]
            spans.append("-" if not ratios else f"{ratios[0]:.3g}×" if len(ratios) == 1
                         else f"{min(ratios):.3g}× – {max(ratios):.3g}×")
        lines.append(f"| {name} | {len(cases)} | " + " | ".join(map(str, wins)) + " | "
                     + " | ".join(spans) + " |")
    return "\n".join(lines) + "\n"


def _bandwidth_cells(r):
    """The output GB/s, np.copyto's GB/s and their fraction of a row ("-" where it has none)."""
    return ("-" if r.gbs is None else f"{r.gbs:.3g}",
            "-" if r.copy_gbs is None else f"{r.copy_gbs:.3g}",
            "-" if r.copy_fraction is None else f"{100 * r.copy_fraction:.0f}%")


BANDWIDTH_HEADERS = ("GB/s", "copyto GB/s", "of copyto")


def print_table(rows, file=sys.stdout):
    # the bandwidth columns only where some row has them, so other tables read as before
    bandwidth = any(r.gbs is not None for r in rows)
    headers = ("case", "size", "device", "clsamp s", "peer", "peer s", "ratio",
               *(BANDWIDTH_HEADERS if bandwidth else ()), "quality")
    lines = []
    for r in rows:
        lines.append((r.case, r.size, r.device, f"{r.seconds:.4g}", r.peer or "-",
                      "-" if r.peer_seconds is None else f"{r.peer_seconds:.4g}",
                      "-" if r.ratio is None else f"{r.ratio:.2f}x",
                      *(_bandwidth_cells(r) if bandwidth else ()), r.quality))
    widths = [max(len(h), *(len(line[i]) for line in lines)) if lines else len(h)
              for i, h in enumerate(headers)]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    print(fmt.format(*headers), file=file)
    print(fmt.format(*("-" * w for w in widths)), file=file)
    for line in lines:
        print(fmt.format(*line), file=file)


def print_profile(rows, file=sys.stdout):
    """The --profile table: per row, where one call's time went."""
    headers = ("case", "size", "device", "wall s", "launches", "launch s", "kernel s",
               "transfer s", "host s")
    lines = []
    for r in rows:
        p = r.extra.get("profile")
        if p is None:
            continue
        lines.append((r.case, r.size, r.device, f"{p['wall']:.4g}", str(p["launches"]),
                      f"{p['launch']:.3g}", f"{p['kernel']:.4g}", f"{p['transfer']:.3g}",
                      f"{p['host']:.3g}"))
    if not lines:
        return
    widths = [max(len(h), *(len(line[i]) for line in lines)) for i, h in enumerate(headers)]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    print("\nwhere the time goes (one more call of each, profiled):", file=file)
    print(fmt.format(*headers), file=file)
    print(fmt.format(*("-" * w for w in widths)), file=file)
    for line in lines:
        print(fmt.format(*line), file=file)


def markdown_table(rows):
    """The full benchmark table from one run (docs/benchmarks.md): machine, versions, date,
    then the rows."""
    m = machine()
    cpu = m["processor"]
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    versions = ", ".join(f"{k} {m[k]}" for k in ("clsamp", "numpy", "pyopencl", "python"))
    peers = []
    for module in ("scipy", "finufft", "bridson", "qmcpy"):
        try:
            peers.append(f"{module} {__import__(module).__version__}")
        except Exception:
            continue
    if os.environ.get("CLSAMP_UTK_BIN"):
        peers.append(f"UTK's samplers from {os.environ['CLSAMP_UTK_BIN']} (built as "
                     "docs/performance.md, \"UTK's samplers built from source (issues 37 and 38)\", says)")
    command = " ".join(["python", "benchmarks/" + os.path.basename(sys.argv[0]), *sys.argv[1:]])
    lines = [measured_line(command, cpu, m, versions, peers), ""]
    bandwidth = any(r.gbs is not None for r in rows)
    headers = ("case", "size", "device", "clsamp s", "peer", "peer s", "ratio",
               *(BANDWIDTH_HEADERS if bandwidth else ()), "quality")
    lines += ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers)]
    for r in rows:
        cells = (r.case, r.size, r.device, f"{r.seconds:.3g}", r.peer or "-",
                 "-" if r.peer_seconds is None else f"{r.peer_seconds:.3g}",
                 "-" if r.ratio is None else f"{r.ratio:.2f}×",
                 *(_bandwidth_cells(r) if bandwidth else ()), r.quality)
        lines.append("| " + " | ".join(str(c).replace("|", "\\|") for c in cells) + " |")
    side_by_side = cross_device_markdown(rows)
    if side_by_side:
        lines += ["", "## Side by side: clsamp's seconds on each device of the run", "",
                  side_by_side.rstrip("\n")]
    return "\n".join(lines) + "\n"


def measured_line(command, cpu, m, versions, peers):
    """The first line of both tables: when, by which command, on what."""
    return (f"Measured {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())} in one run of "
            f"`{command}` on {cpu} ({m['cpus']} CPUs); {versions}"
            + (f"; peers {', '.join(peers)}" if peers else "") + "; devices: "
            + "; ".join(m["devices"]) + ".")


# Comparisons inside clsamp (its NumPy twins, another of its samplers or settings, its
# double path against float-float, its launch shapes, a published figure): the full table
# has them, the summary keeps the outside peers.
INTERNAL_PEERS = ("numpy reference", "numpy, same algorithm", "numpy twin", "combined", "random",
                  "sobol:owen render", "balzer", "clsamp ", "double (same device)", "gpu shape",
                  "host shape")


def summary_table(rows, measured):
    """The README's summary of one run: one line per capability and outside peer, with how
    many cases and the range of the ratios (peer seconds / clsamp seconds), under the
    ``measured`` line of the full table (docs/benchmarks.md). Rows against clsamp itself
    (:data:`INTERNAL_PEERS`), rows whose peer stopped without its result
    (``extra["peer_unconverged"]``: the ratio a lower bound) and rows below the peer's
    quality (``extra["equal_or_better"]`` False) stay in the full table only."""
    groups = {}
    for r in rows:
        if (r.ratio is None or r.peer in ("", "-") or r.peer.lower().startswith(INTERNAL_PEERS)
                or r.extra.get("peer_unconverged") or r.extra.get("equal_or_better") is False):
            continue
        groups.setdefault((r.capability or "-", r.peer), []).append(r.ratio)
    lines = [measured, "", "| capability | peer | cases | ratio, peer s / clsamp s (> 1: clsamp faster) |",
             "|---|---|---|---|"]
    for (capability, peer), ratios in groups.items():
        low, high = min(ratios), max(ratios)
        span = f"{low:.3g}×" if len(ratios) == 1 else f"{low:.3g}× – {high:.3g}×"
        lines.append(f"| {capability} | {peer.replace('|', chr(92) + '|')} | {len(ratios)} | {span} |")
    side_by_side = implementation_summary(rows)
    if side_by_side:
        lines += ["", "The same run's cases on each OpenCL implementation (cases where each was "
                  "the fastest; seconds of the first over the second, > 1: the second is faster):",
                  "", side_by_side.rstrip("\n")]
    lines += ["", "Every row of the run, with sizes, devices, times and quality figures: "
              "[docs/benchmarks.md](docs/benchmarks.md)."]
    return "\n".join(lines) + "\n"


def machine():
    """What the numbers were measured on."""
    import numpy
    import pyopencl
    return {"python": platform.python_version(), "machine": platform.machine(),
            "processor": platform.processor() or platform.machine(), "cpus": os.cpu_count(),
            "numpy": numpy.__version__, "pyopencl": pyopencl.VERSION_TEXT,
            "clsamp": clsamp.__version__,
            "devices": [str(d) for d in runtime.devices()]}


def write_json(path, rows):
    from clsamp.files import write_text
    write_text(path, json.dumps({"machine": machine(), "rows": [r.as_dict() for r in rows]},
                                indent=2, default=str))


def parser(description):
    p = argparse.ArgumentParser(description=description)
    p.add_argument("--device", default=None,
                   help="'all', an index or a name substring, or several separated by commas")
    p.add_argument("--quick", action="store_true", help="CI-sized problems")
    p.add_argument("--out", default=None, help="write the rows as JSON here")
    p.add_argument("--profile", action="store_true",
                   help="also print where each row's time goes (launch, kernel, transfer, host)")
    p.add_argument("--markdown", default=None, metavar="FILE",
                   help="write this run's tables (markdown): into a file with the table "
                        "markers (README.md) the summary between them and the full table to "
                        "docs/benchmarks.md beside it; into any other FILE the full table")
    return p


def main(run, description):
    """Entry point shared by the bench_*.py scripts."""
    args = parser(description).parse_args()
    if args.profile:
        enable_profile()
    rows = run(select_devices(args.device), args.quick)
    finish(args, rows)
    return rows


def finish(args, rows):
    """Print the tables (and the profile); write the JSON and the markdown when asked."""
    print_tables(rows)
    if args.profile:
        print_profile(rows)
    if args.out:
        write_json(args.out, rows)
    if args.markdown:
        write_markdown(args.markdown, rows)


FULL_TABLE = "docs/benchmarks.md"     # beside a README with the markers


def write_markdown(path, rows):
    """Write the run's tables: into a file with the table markers (README.md) the summary,
    and the full table to docs/benchmarks.md beside it; into any other file the full table."""
    from clsamp.files import write_text
    full = markdown_table(rows)
    text = with_table(path, None)
    if text is None:
        write_text(path, full)
        print(f"wrote {path}", file=sys.stderr)
        return
    beside = os.path.join(os.path.dirname(os.path.abspath(path)), *FULL_TABLE.split("/"))
    write_text(beside, "# clsamp's benchmarks: every row of one run\n\n"
               "Written by `python benchmarks/run.py --markdown README.md`, which puts the "
               "summary in the README. Ratio = peer seconds / clsamp seconds.\n\n" + full)
    write_text(path, with_table(path, summary_table(rows, full.splitlines()[0])))
    print(f"wrote {path} and {beside}", file=sys.stderr)


TABLE_BEGIN = "<!-- benchmarks/run.py --markdown: begin -->"
TABLE_END = "<!-- benchmarks/run.py --markdown: end -->"


def with_table(path, table):
    """The text to write to ``path``: the table alone, or, where ``path`` is a file holding
    the two markers (README.md), that file with the table between them, the rest kept.
    With ``table`` None: None unless ``path`` holds the markers."""
    try:
        with open(path) as f:
            text = f.read()
    except OSError:
        return table
    if TABLE_BEGIN not in text or TABLE_END not in text:
        return table
    if table is None:
        return text
    head, rest = text.split(TABLE_BEGIN, 1)
    _, tail = rest.split(TABLE_END, 1)
    return f"{head}{TABLE_BEGIN}\n{table}{TABLE_END}{tail}"


def device_memory(fn):
    """(result of ``fn()``, the peak bytes of OpenCL buffers it held at once).

    Every buffer made during the call (``pyopencl.Buffer``, which ``pyopencl.array`` and
    clsamp's runtime use) is counted from its creation until it is freed; buffers that
    lived before the call are not. On a GPU this is device memory; on PoCL the same bytes
    are host memory.
    """
    import weakref

    import pyopencl as cl
    live, peak = [0], [0]
    original = cl.Buffer

    class Counted(original):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            size = self.size
            live[0] += size
            peak[0] = max(peak[0], live[0])
            weakref.finalize(self, lambda: live.__setitem__(0, live[0] - size))

    cl.Buffer = Counted
    try:
        result = fn()
    finally:
        cl.Buffer = original
    return result, peak[0]
