"""The scaffolding of the tour's HTML report: sections, the output folder, tables.

:class:`Report` owns the output folder (``img/`` for pictures, ``data/`` for raw data, every
file written whole through :mod:`clsamp.files`); :func:`write_html` turns its sections into
``index.html``; :func:`slope_text`, :func:`human_bytes` and :func:`device_rows` put fits and
devices in words;
:func:`one_line_warnings` prints clsamp's warnings as one line while a report is made.
"""

import contextlib
import dataclasses
import html
import math
import platform
import sys
import textwrap
import warnings
from pathlib import Path

import numpy as np

from . import files


@dataclasses.dataclass
class Section:
    """One part of the report: its HTML body, its numbers and how long it took.

    Attributes
    ----------
    key : str
        The section's anchor in the page (``#key``) and its entry in ``tour.json``.
    title : str
    body : str
        HTML.
    data : dict
        The section's numbers, as written to ``tour.json``.
    seconds : float
        How long the section took.
    error : str or None
        The traceback, where the section failed.
    """

    key: str
    title: str
    body: str = ""
    data: dict = dataclasses.field(default_factory=dict)
    seconds: float = 0.0
    error: str | None = None


class Report:
    """Collects sections, figures and data files under one output folder.

    Parameters
    ----------
    out : str or Path
        The output folder; it and its ``img/`` and ``data/`` subfolders are created.

    Attributes
    ----------
    sections : list of Section
        The report's parts, in order.
    results : dict
        Objects a later section reuses (convergence results, renders).
    client : dask.distributed.Client or None
        Where the sweeps run; None runs them in-process.

    Examples
    --------
    >>> import tempfile, numpy as np
    >>> from clsamp.report import Report
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     report = Report(folder)
    ...     report.array("spectrum", np.zeros((4, 4)))
    'data/spectrum.npy'
    """

    def __init__(self, out):
        self.out = Path(out)
        (self.out / "img").mkdir(parents=True, exist_ok=True)
        (self.out / "data").mkdir(parents=True, exist_ok=True)
        self.sections = []
        self.results = {}   # objects a later section reuses (convergence results, renders)
        self.client = None  # a dask.distributed.Client for the sweeps, or None (in-process)

    def picture(self, name):
        """Where a picture goes, ``img/<name>.png``, and its link from ``index.html``.

        Parameters
        ----------
        name : str

        Returns
        -------
        (Path, str)
        """
        path = self.out / "img" / f"{name}.png"
        return path, path.relative_to(self.out).as_posix()

    def figure(self, name, fig):
        """Save a matplotlib figure as ``img/<name>.png`` and close it.

        Parameters
        ----------
        name : str
            The file's name without its suffix.
        fig : matplotlib.figure.Figure

        Returns
        -------
        str
            The file's path relative to the output folder (for an ``<img>`` tag).
        """
        path = files.save_figure(self.out / "img" / f"{name}.png", fig)
        return path.relative_to(self.out).as_posix()

    def points(self, name, points):
        """Save point sets as ``data/<name>.npy``, or ``data/<name>.txt`` for a list of sets.

        Parameters
        ----------
        name : str
            The file's name without its suffix.
        points : ndarray or list of ndarray
            (n, d) or (r, n, d) points, written in NumPy's format; or sets of different
            sizes, written as text (:func:`clsamp.files.format_points`), one set after
            another, separated by a line ``#``.

        Returns
        -------
        str
            The file's path relative to the output folder.
        """
        suffix = ".txt" if isinstance(points, list) else ".npy"
        if isinstance(points, list):
            path = self.out / "data" / f"{name}{suffix}"
            files.write_text(path, "#\n".join(files.format_points(p) for p in points))
        else:
            path = files.save_points(self.out / "data" / f"{name}{suffix}", points)
        return path.relative_to(self.out).as_posix()

    def array(self, name, array):
        """Save an array as ``data/<name>.npy`` (NumPy's format, written whole).

        Parameters
        ----------
        name : str
            The file's name without its suffix.
        array : array_like

        Returns
        -------
        str
            The file's path relative to the output folder.
        """
        from io import BytesIO
        buffer = BytesIO()
        np.save(buffer, np.asarray(array))
        path = self.out / "data" / f"{name}.npy"
        files.write_bytes(path, buffer.getvalue())
        return path.relative_to(self.out).as_posix()

    def exr(self, name, image, header=None):
        """Save a float image as OpenEXR, ``data/<name>.exr`` (:func:`clsamp.files.write_exr`).

        Parameters
        ----------
        name : str
            The file's name without its suffix.
        image : ndarray
            (h, w) or (h, w, c) linear float values.
        header : dict, optional
            Entries stored as string attributes of the file (sampler, spp, seed, ...).

        Returns
        -------
        str
            The file's path relative to the output folder.
        """
        path = files.write_exr(self.out / "data" / f"{name}.exr", image, header)
        return path.relative_to(self.out).as_posix()

    def png(self, name, image, **tone):
        """Save an image as PNG, ``img/<name>.png`` (:func:`clsamp.files.write_png`).

        Parameters
        ----------
        name : str
            The file's name without its suffix.
        image : ndarray
            Linear float values (tone-mapped) or, with ``tone=False``, uint8 as is.
        **tone
            ``tone``, ``exposure``, ``gamma``: how floats become 8-bit.

        Returns
        -------
        str
            The file's path relative to the output folder.
        """
        path = files.write_png(self.out / "img" / f"{name}.png", image, **tone)
        return path.relative_to(self.out).as_posix()


def table(headers, rows):
    """An HTML table; every cell is escaped and numbers formatted by :func:`fmt`.

    Parameters
    ----------
    headers : sequence
        The column headings.
    rows : iterable of sequences
        One sequence of cells a row.

    Returns
    -------
    str
        ``<table>`` ... ``</table>``.

    Examples
    --------
    >>> from clsamp.report import table
    >>> table(["MSE"], [[0.00125]])
    '<table><thead><tr><th>MSE</th></tr></thead><tbody><tr><td>0.00125</td></tr></tbody></table>'
    """
    head = "".join(f"<th>{html.escape(str(h))}</th>" for h in headers)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(fmt(c))}</td>" for c in row) + "</tr>"
                   for row in rows)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def fmt(value):
    """A table cell's text: floats to four significant digits, very small or large ones in
    scientific notation; anything else as ``str``.

    Parameters
    ----------
    value : object

    Returns
    -------
    str

    Examples
    --------
    >>> from clsamp.report import fmt
    >>> fmt(0.123456), fmt(2.5e-7), fmt(0.0), fmt("sobol")
    ('0.1235', '2.500e-07', '0', 'sobol')
    """
    if isinstance(value, float):
        if value == 0 or 1e-3 <= abs(value) < 1e4:
            return f"{value:.4g}"
        return f"{value:.3e}"
    return str(value)


def img(src, alt, width=None):
    """An HTML ``<img>`` tag, its source and text escaped.

    Parameters
    ----------
    src : str
        The picture's path, relative to the report (as :meth:`Report.figure` returns it).
    alt : str
        The text shown in its place.
    width : int, optional
        The width in pixels; by default the picture's own.

    Returns
    -------
    str

    Examples
    --------
    >>> from clsamp.report import img
    >>> img("img/pd.png", "Poisson disk", width=300)
    '<img src="img/pd.png" alt="Poisson disk" width="300">'
    """
    w = f' width="{width}"' if width else ""
    return f'<img src="{html.escape(src)}" alt="{html.escape(alt)}"{w}>'


CSS = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 1200px; color: #222; }
h1 { margin-bottom: 0; } h2 { border-bottom: 1px solid #ccc; margin-top: 2em; }
table { border-collapse: collapse; margin: 1em 0; font-size: 0.9em; }
td, th { border: 1px solid #ddd; padding: 3px 8px; text-align: right; }
th { background: #f4f4f4; } td:first-child { text-align: left; }
.grid { display: flex; flex-wrap: wrap; gap: 12px; }
.cell { text-align: center; font-size: 0.85em; }
.error { background: #fee; border: 1px solid #c00; padding: 0.5em; white-space: pre-wrap; }
.note { color: #555; font-size: 0.9em; }
.matches { color: #070; font-weight: bold; } .differs { color: #b00; font-weight: bold; }
.pre-asymptotic { color: #a60; font-weight: bold; }
"""


def write_html(report, meta):
    """Write ``index.html`` into the report's folder: a table of contents, then every
    section with its body, the error it raised if it failed, and its time.

    Parameters
    ----------
    report : Report
    meta : dict
        ``device`` (str), ``date`` (str) and ``quick`` (bool), shown at the top; ``sections``
        (int, optional): the sections the run will have, so that a page written while it
        runs (or after it was stopped) says how many are still missing.
    """
    missing = meta.get("sections", len(report.sections)) - len(report.sections)
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>clsamp tour</title>"
             f"<style>{CSS}</style></head><body>",
             "<h1>clsamp tour</h1>",
             f"<p class='note'>Measured in this run on {html.escape(meta['device'])}, "
             f"{html.escape(meta['date'])}; mode {'quick' if meta['quick'] else 'full'}. "
             + (f"<b>Incomplete: {missing} of {meta['sections']} sections not run (still running, "
                "or stopped).</b> " if missing > 0 else "")
             + "Raw numbers: <a href='tour.json'>tour.json</a>; point sets and images in "
             "<a href='data/'>data/</a>.</p><ol>"]
    parts += [f"<li><a href='#{s.key}'>{html.escape(s.title)}</a></li>" for s in report.sections]
    parts.append("</ol>")
    for s in report.sections:
        parts.append(f"<section id='{s.key}'><h2>{html.escape(s.title)}</h2>")
        if s.error:
            parts.append(f"<div class='error'>This section failed:\n{html.escape(s.error)}</div>")
        parts.append(s.body)
        parts.append(f"<p class='note'>Section computed in {s.seconds:.1f} s.</p></section>")
    parts.append("</body></html>")
    files.write_text(report.out / "index.html", "\n".join(parts))


def versions():
    """The versions of Python, NumPy, pyopencl, matplotlib and clsamp, for a report's record.

    Returns
    -------
    dict of str to str
    """
    import matplotlib
    import pyopencl
    versions = {"python": platform.python_version(), "numpy": np.__version__,
                "pyopencl": pyopencl.VERSION_TEXT, "matplotlib": matplotlib.__version__}
    from . import __version__
    versions["clsamp"] = __version__
    return versions


def slope_text(slope, stderr, points=None):
    """A fitted slope and its standard error in words, never ``nan``.

    Parameters
    ----------
    slope, stderr : float
        As a fit gives them (nan where it could not: too few points).
    points : int, optional
        How many N the fit used, named when there were too few for an error bar.

    Returns
    -------
    str

    Examples
    --------
    >>> slope_text(-0.51234, 0.02), slope_text(-0.7, float("nan"), 2)
    ('-0.51 ± 0.02', '-0.70 (2 N: too few N for an error bar)')
    >>> slope_text(float("nan"), float("nan"))
    'too few N to fit'
    """
    if not math.isfinite(slope):
        return "too few N to fit"
    if not math.isfinite(stderr):
        many = f"{points} N: " if points else ""
        return f"{slope:+.2f} ({many}too few N for an error bar)"
    return f"{slope:+.2f} ± {stderr:.2f}"


def human_bytes(count):
    """A byte count in binary units.

    Parameters
    ----------
    count : int

    Returns
    -------
    str

    Examples
    --------
    >>> human_bytes(23128711168), human_bytes(65536), human_bytes(512)
    ('21.5 GiB', '64.0 KiB', '512 bytes')
    """
    value = float(count)
    for unit in ("bytes", "KiB", "MiB", "GiB"):
        if value < 1024 or unit == "GiB":
            return f"{int(value)} bytes" if unit == "bytes" else f"{value:.1f} {unit}"
        value /= 1024


def device_rows(device, width=100):
    """(property, value) rows of a device's record (``dataclasses.asdict`` of a
    :class:`clsamp.runtime.Device`) for a table: bytes in binary units, the extensions
    as a comma-separated list wrapped at ``width`` characters.

    Parameters
    ----------
    device : dict
    width : int

    Returns
    -------
    list of (str, str)
    """
    rows = []
    for key, value in device.items():
        if key in ("global_memory", "max_allocation", "local_memory"):
            value = human_bytes(value)
        elif isinstance(value, (tuple, list)):
            value = "\n".join(textwrap.wrap(", ".join(map(str, value)), width)) or "none"
            key = f"{key} ({len(device[key])})"
        rows.append((key, value))
    return rows


@contextlib.contextmanager
def one_line_warnings(stream=None):
    """Print the warnings clsamp raises inside the block (UserWarnings from its modules) as
    one line each, ``clsamp: warning: <message>``, with no source line; other warnings go
    to the ``warnings.showwarning`` that was there, which comes back on leaving. The tour
    and the command line both use it.

    Parameters
    ----------
    stream : file, optional
        Where the lines go; ``sys.stderr`` (as it is when a warning comes) by default.

    Yields
    ------
    None

    Examples
    --------
    >>> import io, warnings
    >>> out = io.StringIO()
    >>> with one_line_warnings(out):
    ...     warnings.warn_explicit("few points", UserWarning, __file__, 1)
    >>> out.getvalue()
    'clsamp: warning: few points\\n'
    """
    previous = warnings.showwarning
    package = str(Path(__file__).resolve().parent)

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, UserWarning) and str(Path(filename).resolve()).startswith(package):
            print("clsamp: warning: " + " ".join(str(message).split()), file=stream or file or sys.stderr)
        else:
            previous(message, category, filename, lineno, file, line)

    warnings.showwarning = show
    try:
        yield
    finally:
        warnings.showwarning = previous
