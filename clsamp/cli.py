"""The ``clsamp`` command line: one entry point, one subcommand per capability.

Each subcommand is a pair of functions, ``_add_<name>(subparsers)`` that declares
its arguments and ``_run_<name>(args)`` that does the work; ``_COMMANDS`` lists them
in the order ``clsamp --help`` shows them. A ``_run_`` checks every name and output path
it was given before any work, so that a typo costs a line, not a finished sweep.
"""

import argparse
import sys
from pathlib import Path

from .cli_source import add_source, parse_params, points_from_source
from .errors import ClsampError, InvalidArgumentError

TEXT_POINTS = (".txt", ".dat", ".pts")      # one point a line, as UTK and PSA read them
FIGURES = (".png", ".pdf", ".svg")
PLOTTED_SETS = 8                            # sample --plot draws the first realizations
FOLDERS = "missing folders are created"    # the outputs' rule, said in --help and the README


def _output(value, accepted, command, option="-o"):
    """The output path ``value`` if its suffix is one ``command`` writes and it can be
    written (:func:`clsamp.files.check_output`); refused, before any work, otherwise."""
    from .files import check_output
    path = Path(value)
    if path.suffix.lower() not in accepted:
        got = repr(path.suffix) if path.suffix else "no suffix"
        raise InvalidArgumentError(
            f"'{option}' {value!r}: clsamp {command} writes {', '.join(accepted)}; got {got}")
    return check_output(path, f"'{option}'")


def _distinct(paths):
    """Refuse outputs that would overwrite each other, or that cannot be written."""
    from .files import check_output
    seen = {}
    for option, path in paths:
        check_output(path, f"'{option}'")
        key = Path(path).resolve()
        if key in seen:
            raise InvalidArgumentError(
                f"'{option}' {str(path)!r} would overwrite the output of '{seen[key]}'")
        seen[key] = option


def _nearest(names, known):
    """"; did you mean 'x'?" for the first of ``names`` close to one of ``known``, or ""."""
    import difflib
    close = [c for name in names for c in difflib.get_close_matches(name, list(known), n=1)]
    return f"; did you mean {close[0]!r}?" if close else ""


def _integrands(names, option):
    """'family' or 'integrand': what every name of ``--integrand`` or ``--family`` (``option``)
    is, resolved before any work; an unknown name is refused with the nearest known one."""
    from .families import family_names, is_family, make_family
    from .integrands import integrand_names
    for name in names:
        if option == "--family" and name.strip().lower() in integrand_names():
            raise InvalidArgumentError(f"'--family' {name!r} is an integrand; give it to '--integrand'")
        if option == "--family" or is_family(name):
            make_family(name, members=1)                # refused with the nearest family
        elif name.strip().lower() not in integrand_names():
            hint = _nearest([name.strip().lower()], integrand_names() + family_names()) or "."
            known = f"Integrands: {', '.join(integrand_names())}; families: {', '.join(family_names())}"
            raise InvalidArgumentError(f"unknown integrand or family {name!r}{hint} {known}")
    if len({is_family(name) for name in names}) > 1:
        raise InvalidArgumentError(
            "'--integrand' mixes integrand families and single integrands; run them apart")
    return "family" if names and is_family(names[0]) else "integrand"


def _samplers(names):
    """The sampler names, each resolved (:func:`clsamp.samplers.sampler_class`) before any work."""
    from .samplers import sampler_class
    return [name for name in names if sampler_class(name)]


def _wrote(paths, what=""):
    print("wrote " + ", ".join(str(p) for p in paths) + (f": {what}" if what else ""), file=sys.stderr)




# -- devices -------------------------------------------------------------------
def _add_devices(sub):
    p = sub.add_parser("devices", help="list the OpenCL devices clsamp can use")
    p.add_argument("--calibrate", action="store_true",
                   help="measure each usable device's launch shape again (a second or so "
                        "each, after its builds) and keep it beside pyopencl's cache")
    p.set_defaults(run=_run_devices)


def _run_devices(args):
    from . import runtime
    current = runtime.current_device()
    for device in runtime.devices():
        mark = "*" if device.index == current.index else " "
        broken = "" if runtime.compiles(device.index) else "  (its compiler fails: not usable)"
        print(f"{mark} {device}  {device.compute_units} CUs, "
              f"{device.global_memory / 2**30:.1f} GiB{broken}")
        print(f"    implementation: {device.implementation or 'unknown'}")
        runs = runtime.capabilities(device.index)
        print("    runs: " + ", ".join(
            name if why is None else f"{name} (no: {why})" for name, why in runs.items()))
        if args.calibrate and not broken and not device.simulator:
            shape = runtime.calibrate(device.index)
        else:
            shape = runtime.known_shape(device)
        print("    launch shape: " + ("not measured yet (measured on first use; "
                                      "--calibrate measures now)" if shape is None
                                      else runtime.describe(shape)))
    return 0


# -- sample --------------------------------------------------------------------
def _add_sample(sub):
    p = sub.add_parser("sample", help="generate a point set and write it as text or .npy")
    p.add_argument("name", help="sampler name (see `clsamp sample --list`), e.g. jittered, sobol:owen",
                   nargs="?")
    p.add_argument("-n", type=int, help="points per set")
    p.add_argument("-d", "--d", dest="d", type=int, default=2, help="dimension (default 2)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--realizations", type=int, default=None, help="independent sets (default one)")
    p.add_argument("--start", type=int, default=0, help="index of the first point (sequences)")
    p.add_argument("--param", action="append", metavar="KEY=VALUE",
                   help="sampler parameter, e.g. --param randomize=owen (repeatable)")
    p.add_argument("--backend", default="opencl", choices=("opencl", "numpy"))
    p.add_argument("--list", action="store_true", help="list the sampler names and exit")
    p.add_argument("-o", "--output", help="output file: .npy, or text (one point a line) as "
                   f"{', '.join(TEXT_POINTS)}; default: text to standard output ({FOLDERS})")
    p.add_argument("--plot", metavar="FIGURE", help=f"also draw the set (the first {PLOTTED_SETS} "
                   f"realizations; for d > 2 x1 and x2) as a figure: {', '.join(FIGURES)}")
    p.add_argument("--tiled", action="store_true", help="--plot the torus tiled 2x2 (clumps across "
                   "the border show whole)")
    p.add_argument("--projections", action="store_true", help="--plot the 1-D projections beside")
    p.set_defaults(run=_run_sample)


def _run_sample(args):
    from . import files
    from .samplers import make_sampler, sampler_class, sampler_names
    if args.list or not args.name:
        for name in sampler_names(aliases=True):     # and the randomizations of each
            print(" ".join([name] + [f"{name}:{r}" for r in sampler_class(name).randomizations if r]))
        return 0
    outputs = [("-o", _output(args.output, (".npy",) + TEXT_POINTS, "sample"))] if args.output else []
    if args.plot:
        outputs.append(("--plot", _output(args.plot, FIGURES, "sample", "--plot")))
        if args.d < 2:
            raise InvalidArgumentError(f"'--plot' draws points in 2-D; got '-d' {args.d}")
    elif args.tiled or args.projections:
        raise InvalidArgumentError("'--tiled' and '--projections' shape the '--plot' figure; give '--plot'")
    sampler = make_sampler(args.name, d=args.d, seed=args.seed, backend=args.backend,
                           **parse_params(args.param))
    points = sampler.sample(args.n, realizations=args.realizations, start=args.start)
    shape = "x".join(str(s) for s in points.shape)
    if args.output:
        files.save_points(outputs[0][1], points)
    else:
        sys.stdout.write(files.format_points(points))
    if args.plot:
        from . import plots
        plots.points_figure(outputs[-1][1], (points[:PLOTTED_SETS] if points.ndim == 3 else points)[..., :2],
                            title=f"{sampler.label}, {shape} points" + (", x1 and x2" if args.d > 2 else ""),
                            tiled=args.tiled, projections=args.projections)
    if outputs:
        _wrote([path for _, path in outputs], f"{shape} points of {args.name}")
    return 0


# -- tour ----------------------------------------------------------------------
def _add_tour(sub):
    p = sub.add_parser("tour", help="the whole story in one report: DIR/index.html", description=(
        "Every sampler's points, spectra, PCF; discrepancy and MSE against N with the published "
        "rates; AO renders; accuracy against time; the device: DIR/index.html and tour.json. "
        "About 2 min 55 s on 2 cores (plus about 25 s once, to cache the reference renders)."))
    p.add_argument("--out", default="tour", help=f"output folder (default: tour; {FOLDERS})")
    p.add_argument("--quick", action="store_true", help="smaller sizes (CI-sized; about 40 s)")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    _add_scheduler(p)
    p.set_defaults(run=_run_tour)


def _add_scheduler(p):
    p.add_argument("--scheduler", default=None,
                   help="run the sweeps on a Dask cluster: a scheduler address (tcp://host:8786) "
                   "or local:N for N local worker processes (needs clsamp[dask]); same numbers")


def _client(args):
    """The Dask client of ``--scheduler``, or None."""
    if getattr(args, "scheduler", None) is None:
        return None
    from .parallel import connect
    return connect(args.scheduler)


def _close(client):
    """Close ``client`` and its local cluster now, not at exit: Ctrl-C then stops at once."""
    if client is not None:
        cluster = client.cluster              # the LocalCluster of local:N; None for a remote one
        client.close()
        if cluster is not None:
            cluster.close()


def _run_tour(args):
    from .tour import check_out, run_tour
    check_out(args.out, "'--out'")
    client = _client(args)
    try:
        index = run_tour(args.out, quick=args.quick, progress=not args.no_progress, client=client)
    finally:
        _close(client)
    print(f"wrote {index}")
    return 0




# -- spectrum ------------------------------------------------------------------
def _add_spectrum(sub):
    p = sub.add_parser("spectrum", help="power spectrum of a sampler's points or of a point file",
                       description="Expected power spectrum (mean periodogram) of a sampler's "
                       "realizations or of points read from a file (text or .npy).")
    add_source(p, "dimension, 1 to 3 (sampler only; default 2; 3: -o .npy only)")
    p.add_argument("--resolution", type=int, default=256, help="R: frequencies [-R/2, R/2) (even)")
    p.add_argument("--method", default="auto", choices=("auto", "direct", "fast"))
    p.add_argument("--tol", type=float, default=None, help="error bound of the fast method (x N)")
    p.add_argument("--backend", default="opencl", choices=("opencl", "numpy"))
    p.add_argument("--scale", default="linear", choices=("linear", "log"), help="PNG tone mapping")
    p.add_argument("-o", "--output", required=True,
                   help="output: .png (picture), .exr (raw float values) or .npy (raw float64)")
    p.add_argument("--plots", help="also write a figure (.png, .pdf, .svg) with the spectrum, its "
                   "radial mean and anisotropy")
    p.set_defaults(run=_run_spectrum)


def _run_spectrum(args):
    import numpy as np

    from . import files, plots, spectrum
    output = _output(args.output, (".png", ".exr", ".npy"), "spectrum")
    outputs = [("-o", output)]
    if args.plots:
        outputs.append(("--plots", _output(args.plots, FIGURES, "spectrum", "--plots")))
    _distinct(outputs)

    def check(d, n):    # before the sampler's work
        if d > 3:
            raise InvalidArgumentError(f"a spectrum is made in 1-D to 3-D; the points have d={d}")
        ok = {1: (".npy", ".exr"), 2: (".npy", ".exr", ".png")}.get(d, (".npy",))
        if output.suffix.lower() not in ok or (args.plots and d > 2):
            raise InvalidArgumentError(f"a {d}-D spectrum goes to -o {' or '.join(ok)} (--plots: 1-D, 2-D)")
        if args.resolution < 2 or args.resolution % 2:
            raise InvalidArgumentError(f"'--resolution' must be even and at least 2, got {args.resolution}")

    points, label = points_from_source(args, check)
    P = spectrum.power_spectrum(points, resolution=args.resolution, method=args.method, tol=args.tol,
                                backend=args.backend)
    n, r = points.shape[-2], (points.shape[0] if points.ndim == 3 else 1)
    if args.plots:      # first: what it refuses (a spectrum too small for its annuli) leaves no -o
        plots.spectrum_figure(outputs[1][1], P, n=n, realizations=r, label=label, scale=args.scale)
    if output.suffix.lower() == ".exr":
        plots.save_spectrum_exr(output, P, header={"source": label})
    elif output.suffix.lower() == ".npy":
        import io as _io
        buffer = _io.BytesIO()
        np.save(buffer, P)
        files.write_bytes(output, buffer.getvalue())
    else:
        plots.save_spectrum_png(output, P, scale=args.scale)
    _wrote([path for _, path in outputs],
           f"the {'x'.join(map(str, P.shape))} spectrum of {r} x {n} points of {label}")
    return 0


# -- metrics -------------------------------------------------------------------
METRICS = {"cd": "CD", "wd": "WD", "md": "MD", "l2-star": "L2-star", "symmetric": "symmetric",
           "l2": "L2", "star": "star", "pcf": "pcf", "nn": "nn"}


def _add_metrics(sub):
    p = sub.add_parser("metrics", help="discrepancies, star discrepancy, pair correlation and "
                       "nearest neighbours of a sampler's points or of a point file",
                       description="Point-set metrics per set (mean and spread over the sets) "
                       "as JSON (-o); with pcf also the expected PCF as a figure "
                       "(<stem>_pcf.png).")
    add_source(p)
    p.add_argument("--metric", default="cd,l2-star,star,pcf",
                   help=f"comma-separated, of {', '.join(METRICS)} (default cd,l2-star,star,pcf)")
    p.add_argument("--bounds", action="store_true",
                   help="star: certified bounds instead of the exact value (any d)")
    p.add_argument("--backend", default="opencl", choices=("opencl", "numpy"))
    p.add_argument("-o", "--output", required=True, help="the numbers, .json")
    p.set_defaults(run=_run_metrics)


def _summary(values):
    import numpy as np
    values = np.atleast_1d(np.asarray(values, dtype=np.float64))
    return {"values": values.tolist(), "mean": float(values.mean()),
            "std": float(values.std(ddof=1)) if len(values) > 1 else 0.0}


def _run_metrics(args):
    import numpy as np

    from . import files, metrics, plots
    output = _output(args.output, (".json",), "metrics")
    wanted = [m.strip().lower() for m in args.metric.split(",") if m.strip()]
    unknown = [m for m in wanted if m not in METRICS]
    if unknown or not wanted:
        raise InvalidArgumentError(f"'--metric' must name some of {', '.join(METRICS)}; got "
                                   f"{', '.join(map(repr, unknown)) or 'none'}"
                                   + _nearest(unknown[:1], METRICS))
    if len(set(wanted)) < len(wanted):
        raise InvalidArgumentError(f"'--metric' names one twice: {args.metric}")
    if args.bounds and "star" not in wanted:
        raise InvalidArgumentError("'--bounds' is the star discrepancy's; '--metric' has no star")
    if args.n is not None and args.n < 2 and {"pcf", "nn"} & set(wanted):
        raise InvalidArgumentError(f"'-n' must be at least 2 for pcf and nn (pairs), got {args.n}")

    def check(d, n):    # before the sampler's work
        if "star" in wanted and not args.bounds and d > 3:
            raise InvalidArgumentError(f"'--metric' star is exact for d = 1 to 3, got d = {d}; "
                                       "'--bounds' gives certified bounds in any d")
        most = metrics.star.exact_limit(d, args.backend)
        if "star" in wanted and not args.bounds and n > most:
            raise InvalidArgumentError(f"'--metric' star: the exact value takes n <= {most} in {d}-D "
                                       f"here, got {n}; '--bounds' gives certified bounds")
    outputs = [("-o", output)]
    if "pcf" in wanted:
        outputs.append(("-o (pcf figure)", output.with_name(output.stem + "_pcf.png")))
    _distinct(outputs)
    points, label = points_from_source(args, check)
    batch = points if points.ndim == 3 else points[None]
    r, n, d = batch.shape
    document = {"source": label, "n": n, "d": d, "realizations": r, "backend": args.backend, "metrics": {}}
    for name in wanted:
        key = METRICS[name]
        if key in metrics.METHODS:
            value = metrics.discrepancy(batch, key, backend=args.backend)
            document["metrics"][key] = {**_summary(value), "squared": key in ("CD", "WD", "MD")}
        elif key == "star":
            value = metrics.star_discrepancy(batch, bounds=args.bounds, backend=args.backend)
            if args.bounds:
                document["metrics"]["star"] = {"bounds": True, "lower": _summary(value[:, 0]),
                                               "upper": _summary(value[:, 1])}
            else:
                document["metrics"]["star"] = {"bounds": False, **_summary(value)}
        elif key == "pcf":
            radii, pcf = metrics.pair_correlation(batch, backend=args.backend)
            document["metrics"]["pcf"] = {"radii": radii.tolist(), "pcf": pcf.tolist(),
                                          "sigma": 0.05 * metrics.mean_spacing(n, d),
                                          "peak": float(pcf.max()),
                                          "peak_radius": float(radii[np.argmax(pcf)])}
        else:
            nn = metrics.nearest_neighbor_distances(batch, backend=args.backend)
            document["metrics"]["nn"] = {"mean": float(nn.mean()), "min": float(nn.min()),
                                         "quantiles": dict(zip(("5%", "50%", "95%"),
                                                               np.quantile(nn, [0.05, 0.5, 0.95]).tolist(),
                                                               strict=True))}
    files.write_json(output, document)
    if "pcf" in wanted:
        entry = document["metrics"]["pcf"]
        plots.pcf_figure(outputs[1][1], entry["radii"], entry["pcf"], n=n, d=d,
                         label=f"{label}: expected PCF, {r} x {n} points")
    for key, entry in document["metrics"].items():
        if key == "pcf":
            text = f"peak {entry['peak']:.3f} at r = {entry['peak_radius']:.4g}"
        elif key == "nn":
            text = f"mean {entry['mean']:.4g}, min {entry['min']:.4g}"
        elif key == "star" and entry["bounds"]:
            text = f"in [{entry['lower']['mean']:.4g}, {entry['upper']['mean']:.4g}] (mean bounds)"
        else:
            text = f"{entry['mean']:.6g} +- {entry['std']:.2g}"
            text += " (squared, as scipy)" if entry.get("squared") else ""
        print(f"{key:>10}: {text}")
    _wrote([path for _, path in outputs], f"metrics of {r} x {n} points of {label}")
    return 0


# -- convergence ---------------------------------------------------------------
def _add_convergence(sub):
    p = sub.add_parser(
        "convergence", help="MSE against N of samplers on an integrand, rates against theory",
        description="MSE, bias and variance of integral estimates against the number of samples, "
        "for each sampler and integrand; writes the MSE-against-N plot (-o), the accuracy-"
        "against-time plot beside it (<stem>_time.<suffix>; not for families) and every number "
        "as JSON (<stem>.json).")
    p.add_argument("--samplers", default="random,jittered,sobol:owen",
                   help="comma-separated sampler names (default random,jittered,sobol:owen)")
    p.add_argument("--integrand", default=None,
                   help="comma-separated integrands: gaussian, disk, heaviside, pmj_disk, "
                   "pmj_gaussian, pmj_bilinear, pmj_step, pmj_triangle, genz_oscillatory, "
                   "genz_product_peak, genz_corner_peak, genz_gaussian, genz_continuous, "
                   "genz_discontinuous, keister (default gaussian)")
    p.add_argument("--family", default=None,
                   help="comma-separated integrand families instead of --integrand: "
                   "random_gaussians, random_heavisides, random_disks, random_boxes, "
                   "random_clipped_gaussians (or gaussians, heavisides, disks, boxes); the plot "
                   "shows the spread of the MSE across members")
    p.add_argument("--members", type=int, default=None, help="members per family (default 256)")
    p.add_argument("--ns", default="16..16384",
                   help="sample counts: 'a..b' is a, 4a, 16a, ... <= b (powers of 4 from a, squares "
                   "for jittered); 'a..b:2' uses ratio 2; or a list '16,64,256' (default 16..16384)")
    p.add_argument("--realizations", type=int, default=None,
                   help="estimates per n (default 1000; 64 for families)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--no-homogenize", action="store_true", help="no random toroidal shift per realization")
    p.add_argument("--backend", default="opencl", choices=("opencl", "numpy"))
    p.add_argument("--no-progress", action="store_true", help="hide the progress bars")
    p.add_argument("--checkpoint", default=None,
                   help="a folder keeping every finished block of the sweeps, to resume them")
    _add_scheduler(p)
    p.add_argument("-o", "--output", default="conv.png",
                   help=f"the MSE plot ({', '.join(FIGURES)}; default conv.png)")
    p.set_defaults(run=_run_convergence)


def _run_convergence(args):
    from .files import check_output
    from .sweep import parse_ns, prepare
    output = _output(args.output, FIGURES, "convergence")
    samplers = _samplers([s.strip() for s in args.samplers.split(",") if s.strip()])
    option = "--integrand" if args.family is None else "--family"
    if args.family is not None and args.integrand is not None:
        raise InvalidArgumentError("give '--family' or '--integrand', not both")
    given = args.family if args.family is not None else args.integrand
    names = [s.strip() for s in ("gaussian" if given is None else given).split(",") if s.strip()]
    if not samplers or not names:
        raise InvalidArgumentError(f"'--samplers' and '{option}' must each name at least one")
    for listed, given in (("--samplers", samplers), (option, names)):
        if len(set(given)) < len(given):
            raise InvalidArgumentError(f"'{listed}' names one twice: {', '.join(given)}")
    family = _integrands(names, option) == "family"          # families work in --integrand too
    if args.members is not None and not family:
        raise InvalidArgumentError("'--members' is the families' ('--family'); these are integrands")
    if family and args.members is None:
        args.members = 256
    paths = [("-o", output), ("-o (JSON)", output.with_suffix(".json"))]
    paths += [] if family else [("-o (time plot)", output.with_name(f"{output.stem}_time{output.suffix}"))]
    _distinct(paths)
    if args.checkpoint is not None:
        if not args.checkpoint.strip():
            raise InvalidArgumentError("'--checkpoint' must name a folder, got ''")
        check_output(Path(args.checkpoint) / "checkpoint", "'--checkpoint'")
    ns = parse_ns(args.ns)
    for integrand in names:       # every sweep's samplers, n and d, before the first runs
        for name in samplers:
            prepare(name, integrand, ns, members=args.members,
                    realizations=(64 if family else 1000) if args.realizations is None
                    else args.realizations, seed=args.seed, backend=args.backend)
    client = _client(args)
    try:
        if family:
            return _run_family_convergence(args, samplers, names, paths, client)
        return _convergence_runs(args, samplers, names, paths, client)
    finally:
        _close(client)


def _checkpoint(args, *labels):
    """A checkpoint folder per sweep under ``--checkpoint``."""
    if args.checkpoint is None:
        return None
    return Path(args.checkpoint) / "-".join(label.replace(":", "_").replace("/", "_") for label in labels)


def _convergence_runs(args, samplers, integrands, paths, client):
    from . import files, plots, theory
    from .results import pareto_front
    from .sweep import convergence, parse_ns
    (_, output), (_, json_path), (_, time_path) = paths
    ns = parse_ns(args.ns)
    realizations = 1000 if args.realizations is None else args.realizations
    results, records = [], []
    for integrand in integrands:
        for name in samplers:
            res = convergence(name, integrand, ns, realizations=realizations,
                              homogenize=not args.no_homogenize, seed=args.seed,
                              progress=not args.no_progress, backend=args.backend, client=client,
                              checkpoint=_checkpoint(args, name, integrand))
            verdict = theory.compare(res)
            results.append(res)
            records.append({**res.to_dict(), "comparison": verdict})
            print(f"{name:>26} {integrand:<14} slope {verdict['slope']:+.2f} +- {verdict['stderr']:.2f}"
                  f"  theory {verdict['expected_text'] or '-':<8} {verdict['verdict'].split()[0]}"
                  f"  MSE(N={res.ns[-1]}) {res.mse[-1]:.3g}  {res.seconds.sum():.2f} s")
    plots.convergence(results, output)
    plots.accuracy_time(results, time_path)
    fronts = {f: pareto_front([r for r in results if r.integrand == f]) for f in integrands}
    document = {"ns": sorted(ns), "realizations": realizations, "seed": args.seed,
                "homogenize": not args.no_homogenize, "backend": args.backend,
                "results": records, "pareto_front": fronts}
    files.write_json(json_path, document)
    _wrote([output, time_path, json_path])


def _run_family_convergence(args, samplers, names, paths, client):
    from . import families, files, plots, theory
    from .sweep import convergence, parse_ns
    (_, output), (_, json_path) = paths
    names = [families.make_family(name, members=1).name for name in names]
    ns = parse_ns(args.ns)
    realizations = 64 if args.realizations is None else args.realizations
    results, records = [], []
    for family in names:
        for name in samplers:
            res = convergence(name, family, ns, realizations=realizations, members=args.members,
                              homogenize=not args.no_homogenize, seed=args.seed,
                              progress=not args.no_progress, backend=args.backend, client=client,
                              checkpoint=_checkpoint(args, name, family))
            verdict = theory.compare(res)
            results.append(res)
            records.append({**res.to_dict(), "comparison": verdict})
            lo, hi = verdict["ci"]
            expected = "-" if verdict["expected"] is None else f"N^{verdict['expected']:g}"
            print(f"{name:>26} {res.family:<26} mean slope {verdict['slope']:+.2f} [{lo:+.2f}, {hi:+.2f}]"
                  f"  theory {expected:<8} {verdict['verdict']}  mean MSE(N={res.ns[-1]}) "
                  f"{res.mean[-1]:.3g}, worst {res.max[-1]:.3g}  {res.seconds.sum():.2f} s")
    plots.family_convergence(results, output)
    document = {"ns": sorted(ns), "realizations": realizations, "members": args.members,
                "seed": args.seed,
                "homogenize": not args.no_homogenize, "backend": args.backend, "results": records}
    files.write_json(json_path, document)
    _wrote([output, json_path])


# -- integrate -----------------------------------------------------------------
def _add_integrate(sub):
    p = sub.add_parser(
        "integrate", help="an integral to a tolerance, with its confidence interval",
        description="Replicated randomized QMC: doubles the points per replication (to the "
        "sampler's nearest valid count) until the "
        "Student-t interval over the replications is as narrow as asked.")
    p.add_argument("function", help="a clsamp integrand name (gaussian, disk, heaviside, pmj_...) "
                   "or module:function, a vectorised Python function of an (m, d) array")
    p.add_argument("--d", type=int, default=2, help="dimension (default 2)")
    p.add_argument("--sampler", default="sobol:owen", help="a randomized sampler (default sobol:owen)")
    p.add_argument("--abs-tol", type=float, default=None)
    p.add_argument("--rel-tol", type=float, default=None)
    p.add_argument("--max-n", type=int, default=2**24, help="points per replication at most")
    p.add_argument("--replications", type=int, default=16)
    p.add_argument("--confidence", type=float, default=0.95)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("-o", "--output", default=None, help="also write the result as JSON (.json)")
    p.set_defaults(run=_run_integrate)


def _load_function(text):
    if ":" not in text:
        return text                                       # an integrand name
    import importlib
    import os
    module, _, name = text.partition(":")
    sys.path.insert(0, os.getcwd())
    try:
        found = getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError, ValueError) as error:     # ValueError: ':f', no module
        raise InvalidArgumentError(f"'function' {text!r} cannot be loaded: {error}") from None
    finally:
        sys.path.pop(0)
    if not callable(found):
        raise InvalidArgumentError(f"'function' {text!r} is not callable")
    from .integrands import Integrand
    if isinstance(found, Integrand):            # its kernel and its own checks
        return found

    def function(x):        # its own failure in one line, as a bad name's
        try:
            return found(x)
        except Exception as error:
            raise InvalidArgumentError(
                f"'function' {text!r} raised {type(error).__name__}: {error}") from None
    return function


def _run_integrate(args):
    import dataclasses
    import warnings

    from . import files
    from .integration import integrate
    output = _output(args.output, (".json",), "integrate") if args.output else None
    _samplers([args.sampler])
    f = _load_function(args.function)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = integrate(f, args.d, sampler=args.sampler, abs_tol=args.abs_tol, rel_tol=args.rel_tol,
                        max_n=args.max_n, replications=args.replications,
                        confidence=args.confidence, seed=args.seed)
    for w in caught:
        print(f"clsamp integrate: warning: {w.message}", file=sys.stderr)
    print(f"{res.estimate:.12g} +- {res.half_width:.3g} ({100 * res.confidence:g} % interval; "
          f"{res.replications} x {res.n} points of {res.sampler}, {res.evaluations} evaluations, "
          f"{res.seconds:.3f} s; {'converged' if res.converged else 'NOT converged'})")
    if output is not None:
        files.write_json(output, dataclasses.asdict(res))
        _wrote([output])
    return 0 if res.converged else 1
# -- render --------------------------------------------------------------------
def _image_size(text):
    """``N`` or ``WxH`` as (width, height)."""
    parts = text.lower().split("x")
    try:
        values = [int(p) for p in parts]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected N or WxH (e.g. 256 or 320x180), got {text!r}") from None
    if len(values) not in (1, 2) or min(values) < 1:
        raise argparse.ArgumentTypeError(f"expected N or WxH with sides >= 1, got {text!r}")
    return (values[0], values[-1])


def _add_render(sub):
    p = sub.add_parser("render", help="render a scene with a sampler; OpenEXR plus a PNG preview",
                       description="Ray-cast a scene (a JSON file, or a shipped scene's name: ao, "
                       "dof, motion_blur, soft_shadows, combined) with SPP samples per pixel from a "
                       "sampler; write OpenEXR (sampler, spp and seed in the header) and a "
                       "tone-mapped PNG beside it.")
    p.add_argument("scene", help="scene file (e.g. scenes/ao.json) or shipped scene name (e.g. ao)")
    p.add_argument("--sampler", default="random", help="sampler name, e.g. jittered, sobol:owen")
    p.add_argument("--spp", type=int, default=None, help="samples per pixel (default: the scene's)")
    p.add_argument("--resolution", type=_image_size, default=(256, 256), metavar="N or WxH",
                   help="image side in pixels, or width x height as 320x180 (default 256)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--param", action="append", metavar="KEY=VALUE",
                   help="sampler parameter, e.g. --param strata=12x8 (repeatable)")
    p.add_argument("--no-pad", action="store_true",
                   help="one d-dimensional set per pixel instead of padded 2-D sets")
    p.add_argument("--reference", action="store_true",
                   help="also print MSE, PSNR and SSIM against the cached reference render")
    p.add_argument("--reference-spp", type=int, default=None,
                   help="samples per pixel of the reference: 16 passes x 2^k (default 16 x the "
                   "power of two at or above 4 x the scene's spp)")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    p.add_argument("-o", "--output", required=True,
                   help="the image, .exr or .png: writes <stem>.exr and a <stem>.png preview")
    p.set_defaults(run=_run_render)


def _run_render(args):
    import time

    from . import render as rendering
    from .scene import as_scene
    output = _output(args.output, (".exr", ".png"), "render")
    _distinct([("-o", output.with_suffix(".exr")), ("-o (preview)", output.with_suffix(".png"))])
    _samplers([args.sampler])
    if args.reference_spp is not None:          # checked here, not after the render
        if not args.reference:
            raise InvalidArgumentError("'--reference-spp' is the reference's; give '--reference'")
        try:
            rendering.reference_spp(args.reference_spp)
        except InvalidArgumentError as error:
            raise InvalidArgumentError(f"'--reference-spp': {error}") from None
    scene = as_scene(args.scene)
    spp = scene.default_spp if args.spp is None else args.spp
    params = parse_params(args.param, (("d", "the scene's dimensions"), ("seed", "--seed")))
    t0 = time.perf_counter()
    image = rendering.render(scene, args.sampler, spp, args.resolution, seed=args.seed,
                             sampler_params=params or None, pad=not args.no_pad,
                             progress=not args.no_progress)
    seconds = time.perf_counter() - t0
    written = rendering.save(args.output, image, args.sampler, spp, args.seed, scene=scene)
    print(f"wrote {' and '.join(map(str, written))}: {scene.name}, {args.sampler}, {spp} spp, "
          f"{args.resolution[0]}x{args.resolution[1]}, seed {args.seed}, {seconds:.2f} s")
    if args.reference:
        ref, stderr = rendering.reference(scene, args.resolution, spp=args.reference_spp,
                                          progress=not args.no_progress, return_noise=True)
        m = rendering.compare(image, ref, stderr)
        print(f"against the reference: MSE {m['mse']:.4g} (the reference's own noise adds "
              f"{m['floor']:.2g}: MSE - floor {m['mse_excess']:.4g})  PSNR {m['psnr']:.2f} dB  "
              f"SSIM {m['ssim']:.4f}")
    return 0


_COMMANDS = (_add_devices, _add_sample, _add_spectrum, _add_metrics, _add_convergence, _add_integrate,
             _add_render, _add_tour)


class _Parser(argparse.ArgumentParser):
    """argparse's parser with its errors in one line, as clsamp's own (``-h`` shows usage)."""
    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} -h)\n")


def build_parser():
    """The ``clsamp`` command line: one subcommand per task, each with ``--device``.

    Returns
    -------
    argparse.ArgumentParser
        Its subcommands are devices, sample, spectrum, metrics, convergence, integrate,
        render and tour; a parsed command's ``run`` attribute is the function that runs it.
    """
    parser = _Parser(prog="clsamp", description="Sampling patterns for Monte Carlo rendering, "
                     "generated and measured in OpenCL.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for add in _COMMANDS:
        add(sub)
    for command in sub.choices.values():
        command.add_argument("--device", help="OpenCL device: index or name substring "
                             "(default: $CLSAMP_DEVICE, else the first CPU device)")
    return parser


class Terminated(BaseException):
    """SIGTERM, raised where the program is so that files being written are cleaned up."""


_signalled = []    # the signals this command received, in order


def _on_sigterm(signum, frame):
    _signalled.append(signum)
    raise Terminated()


def _on_sigint(signum, frame):
    _signalled.append(signum)
    raise KeyboardInterrupt()


def main(argv=None):
    """Run the ``clsamp`` command line (the ``clsamp`` console script).

    Parameters
    ----------
    argv : list of str, optional
        The arguments after the program's name; ``sys.argv[1:]`` by default.

    Returns
    -------
    int
        The exit status: 0 on success, 1 when ``integrate`` did not converge, 2 for a usage
        or clsamp error (printed, not raised), 130 when interrupted (Ctrl-C) and 143 when
        terminated (SIGTERM). Every file
        written before an interruption is whole: outputs are written to a temporary name
        and renamed.
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "run", None):
        parser.print_help()
        return 2
    import signal
    import threading

    from .report import one_line_warnings
    main_thread = threading.current_thread() is threading.main_thread()
    before = signal.getsignal(signal.SIGINT)
    _signalled.clear()
    if main_thread:
        # SIGTERM unwinds like Ctrl-C: outputs are written whole (a temporary file renamed,
        # one cut short removed) or not at all. Both are recorded, so one whose exception a C
        # extension turned into another (matplotlib's renderer does) still ends as interrupted.
        signal.signal(signal.SIGTERM, _on_sigterm)
        if before is signal.default_int_handler:
            signal.signal(signal.SIGINT, _on_sigint)
    try:
        if args.device is not None:
            from . import runtime
            runtime.use_device(args.device)
        with one_line_warnings():
            return args.run(args) or 0
    except ClsampError as error:
        if not _signalled:
            print(f"clsamp {args.command}: error: {error}", file=sys.stderr)
            return 2
        return _stopped(args.command, _signalled[0])
    except (KeyboardInterrupt, Terminated) as stop:
        return _stopped(args.command, signal.SIGTERM if isinstance(stop, Terminated) else signal.SIGINT)
    except Exception:
        if _signalled:
            return _stopped(args.command, _signalled[0])
        raise
    finally:
        if main_thread:
            signal.signal(signal.SIGTERM, signal.SIG_DFL)   # after the work, SIGTERM just ends it
            signal.signal(signal.SIGINT, before)


def _stopped(command, signum):
    """Say that the command was stopped by ``signum``; its exit status (130 or 143)."""
    import signal
    terminated = signum == signal.SIGTERM
    why = "terminated" if terminated else "interrupted"
    print(f"clsamp {command}: {why}; every file written so far is whole", file=sys.stderr)
    return 143 if terminated else 130


if __name__ == "__main__":
    sys.exit(main())
