"""The scaffolding of the tour's HTML report: sections, the output folder, tables.

:class:`Report` owns the output folder (``img/`` for pictures, ``data/`` for raw data, every
file written whole through :mod:`clsamp.io`); :func:`write_html` turns its sections into
``index.html``; :func:`json_safe` makes numbers JSON can hold (non-finite ones as strings).
"""

import dataclasses
import html
import platform
from pathlib import Path

import numpy as np

from . import io


@dataclasses.dataclass
class Section:
    """One part of the report: its HTML body, its numbers and how long it took."""

    key: str
    title: str
    body: str = ""
    data: dict = dataclasses.field(default_factory=dict)
    seconds: float = 0.0
    error: str | None = None


class Report:
    """Collects sections, figures and data files under one output folder."""

    def __init__(self, out):
        self.out = Path(out)
        (self.out / "img").mkdir(parents=True, exist_ok=True)
        (self.out / "data").mkdir(parents=True, exist_ok=True)
        self.sections = []
        self.results = {}   # objects a later section reuses (convergence results, renders)
        self.client = None  # a dask.distributed.Client for the sweeps, or None (in-process)

    def figure(self, name, fig):
        """Save a matplotlib figure as img/<name>.png; return its relative path."""
        path = io.save_figure(self.out / "img" / f"{name}.png", fig)
        return path.relative_to(self.out).as_posix()

    def points(self, name, points):
        """data/<name>.npy, or for sets of different sizes data/<name>.txt (realizations
        separated by a line ``#``)."""
        suffix = ".txt" if isinstance(points, list) else ".npy"
        if isinstance(points, list):
            path = self.out / "data" / f"{name}{suffix}"
            io.write_text(path, "#\n".join(io.format_points(p) for p in points))
        else:
            path = io.save_points(self.out / "data" / f"{name}{suffix}", points)
        return path.relative_to(self.out).as_posix()

    def array(self, name, array):
        from io import BytesIO
        buffer = BytesIO()
        np.save(buffer, np.asarray(array))
        path = self.out / "data" / f"{name}.npy"
        io.write_bytes(path, buffer.getvalue())
        return path.relative_to(self.out).as_posix()

    def exr(self, name, image, header=None):
        path = io.write_exr(self.out / "data" / f"{name}.exr", image, header)
        return path.relative_to(self.out).as_posix()

    def png(self, name, image, **tone):
        path = io.write_png(self.out / "img" / f"{name}.png", image, **tone)
        return path.relative_to(self.out).as_posix()


def table(headers, rows):
    head = "".join(f"<th>{html.escape(str(h))}</th>" for h in headers)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(fmt(c))}</td>" for c in row) + "</tr>"
                   for row in rows)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def fmt(value):
    if isinstance(value, float):
        if value == 0 or 1e-3 <= abs(value) < 1e4:
            return f"{value:.4g}"
        return f"{value:.3e}"
    return str(value)


def img(src, alt, width=None):
    w = f' width="{width}"' if width else ""
    return f'<img src="{html.escape(src)}" alt="{html.escape(alt)}"{w}>'


def json_safe(value):
    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if isinstance(value, np.ndarray):
        return json_safe(value.tolist())
    if isinstance(value, (np.floating, float)):
        value = float(value)
        return value if np.isfinite(value) else str(value)
    if isinstance(value, np.integer):
        return int(value)
    return value


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
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>clsamp tour</title>"
             f"<style>{CSS}</style></head><body>",
             "<h1>clsamp tour</h1>",
             f"<p class='note'>Measured in this run on {html.escape(meta['device'])}, "
             f"{html.escape(meta['date'])}; mode {'quick' if meta['quick'] else 'full'}. "
             "Raw numbers: <a href='tour.json'>tour.json</a>; point sets and images in "
             "<a href='data/'>data/</a>.</p><ol>"]
    parts += [f"<li><a href='#{s.key}'>{html.escape(s.title)}</a></li>" for s in report.sections]
    parts.append("</ol>")
    for s in report.sections:
        parts.append(f"<section id='{s.key}'><h2>{html.escape(s.title)}</h2>")
        if s.error:
            parts.append(f"<div class='error'>This section failed:\n{html.escape(s.error)}</div>")
        parts.append(s.body)
        parts.append(f"<p class='note'>{s.seconds:.1f} s</p></section>")
    parts.append("</body></html>")
    io.write_text(report.out / "index.html", "\n".join(parts))


def versions():
    import matplotlib
    import pyopencl
    versions = {"python": platform.python_version(), "numpy": np.__version__,
                "pyopencl": pyopencl.VERSION_TEXT, "matplotlib": matplotlib.__version__}
    from . import __version__
    versions["clsamp"] = __version__
    return versions
