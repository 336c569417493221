"""Pictures of point sets: one set on the unit square (optionally the torus tiled 2x2, where
clumps across the border show), a figure of sets, each with its 1-D projections if asked.

:mod:`clsamp.plots` makes these public as ``plots.points`` and ``plots.points_figure``;
matplotlib is imported when a picture is made.
"""

import functools
import inspect
import os
from pathlib import Path

import numpy as np

from . import files
from .errors import InvalidArgumentError
from .validation import check_points, check_positive_int, check_real, point_sets

__all__ = ["points", "points_figure", "pyplot", "writes"]

FIGURES = (".png", ".pdf", ".svg")       # the formats a figure is saved in


def writes(suffixes=FIGURES):
    """Decorate a function that writes its argument ``path``: the path is checked before any
    work (:func:`clsamp.files.check_output`, and its suffix one of ``suffixes``), and the
    figures the function opened are closed if it raises.

    Parameters
    ----------
    suffixes : tuple of str
        The suffixes taken, lower case, with the dot.

    Returns
    -------
    callable
        The decorator.
    """
    def decorate(fn):
        signature = inspect.signature(fn)

        @functools.wraps(fn)
        def checked(*args, **kwargs):
            path = signature.bind(*args, **kwargs).arguments["path"]
            if not isinstance(path, (str, os.PathLike)):
                raise InvalidArgumentError(f"'path' must be a file path, got {path!r}")
            if Path(path).suffix.lower() not in suffixes:
                raise InvalidArgumentError(
                    f"'path' {str(path)!r} must end in {', '.join(suffixes)}")
            files.check_output(path)
            opened = set(pyplot().get_fignums())
            try:
                return fn(*args, **kwargs)
            except BaseException:
                for number in set(pyplot().get_fignums()) - opened:
                    pyplot().close(number)
                raise
        return checked
    return decorate


def pyplot():
    """matplotlib.pyplot on the Agg backend (files, no screen).

    Returns
    -------
    module
        ``matplotlib.pyplot``.
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def point_sets_2d(points, name="points"):
    """The (n, 2) sets of one set, a batch (r, n, 2) or a list of sets of different sizes.

    Parameters
    ----------
    points : ndarray (n, 2) or (r, n, 2), or list of (n_k, 2) arrays
    name : str
        The argument's name in an error.

    Returns
    -------
    list of ndarray (n_k, 2)
    """
    sets = point_sets(points, name, d=2)
    return sets if sets is not None else list(check_points(points, name, d=2)[0])


def scatter(ax, one, title, size=None, color="black", tiled=False):
    """One checked (n, 2) set on the unit square, or its 2x2 tiling of the torus (the body of
    :func:`points`).

    Parameters
    ----------
    ax : matplotlib Axes
    one : ndarray (n, 2)
        Checked points.
    title, size, color, tiled
        As :func:`points` takes them (``size`` checked).

    Returns
    -------
    matplotlib PathCollection
    """
    copies = 2 if tiled else 1
    size = max(0.5, 1600.0 / (len(one) * copies**2)) if size is None else size
    shifts = [(i, j) for i in range(copies) for j in range(copies)]
    shown = np.concatenate([one + np.array(shift, dtype=one.dtype) for shift in shifts])
    dots = ax.scatter(shown[:, 0], shown[:, 1], s=size, color=color, linewidths=0)
    ax.set(xlim=(0, copies), ylim=(0, copies), xticks=[], yticks=[], aspect="equal")
    if tiled:
        ax.axhline(1.0, color="0.7", linewidth=0.6)
        ax.axvline(1.0, color="0.7", linewidth=0.6)
    if title:
        ax.set_title(title, fontsize=10)
    return dots


def _projections(ax, one, color):
    """The x and y coordinates of ``one`` as ticks in thin strips below and left of ``ax``."""
    below = ax.inset_axes([0.0, -0.1, 1.0, 0.07])
    left = ax.inset_axes([-0.1, 0.0, 0.07, 1.0])
    below.eventplot(one[:, 0], colors=color, linewidths=0.3, lineoffsets=0.5, linelengths=1.0)
    left.eventplot(one[:, 1], orientation="vertical", colors=color, linewidths=0.3,
                   lineoffsets=0.5, linelengths=1.0)
    below.set(xlim=(0, 1), ylim=(0, 1), xticks=[], yticks=[])
    left.set(xlim=(0, 1), ylim=(0, 1), xticks=[], yticks=[])
    return below, left


def points(ax, points, title=None, size=None, color="black", tiled=False, projections=False):
    """Draw a 2-D point set on a matplotlib Axes: the unit square, square aspect, no ticks.

    Parameters
    ----------
    ax : matplotlib Axes
    points : ndarray (n, 2) or (r, n, 2), or list of (n_k, 2) arrays
        One set, or sets (``sample``, ``sample_sets``) of which the first is drawn.
    title : str, optional
    size : float, optional
        Marker area in points^2; by default 1600 / (points drawn), at least 0.5.
    color : matplotlib colour
    tiled : bool
        Draw the set four times, the torus tiled 2x2 with the seams marked: a clump or a
        gap that wraps around the border of the square shows whole.
    projections : bool
        Also draw the x and y coordinates as ticks in strips below and left of the square
        (a set whose 1-D projections are stratified shows evenly spaced ticks).

    Returns
    -------
    matplotlib PathCollection

    Examples
    --------
    >>> import clsamp
    >>> ax = clsamp.plots.pyplot().gca()
    >>> dots = clsamp.plots.points(ax, clsamp.make_sampler("jittered", seed=1).sample(256), "jittered")
    >>> len(clsamp.plots.points(ax, clsamp.make_sampler("jittered").sample(64), tiled=True).get_offsets())
    256
    """
    if size is not None:
        size = check_real(size, "size", minimum=0.0, open_minimum=True)
    one = point_sets_2d(points)[0]
    dots = scatter(ax, one, title, size, color, tiled)
    if projections:
        _projections(ax, one, color)
    return dots


@writes()
def points_figure(path, points, title=None, columns=4, tiled=False, projections=False):
    """Point sets saved as a figure, one panel a set, titled with its n.

    Parameters
    ----------
    path : str or Path
    points : ndarray (n, 2) or (r, n, 2), or list of (n_k, 2) arrays
    title : str, optional
    columns : int
        Panels per row.
    tiled, projections : bool
        As :func:`points` takes them, for every panel.

    Returns
    -------
    Path

    Examples
    --------
    >>> import clsamp, tempfile, pathlib
    >>> from clsamp import plots
    >>> sets = clsamp.make_sampler("poisson_disk", rho=0.75, seed=2).sample(256, realizations=2)
    >>> plots.points_figure(pathlib.Path(tempfile.mkdtemp()) / "pd.png", sets, tiled=True,
    ...                     projections=True).suffix
    '.png'
    """
    sets = point_sets_2d(points)
    columns = min(check_positive_int(columns, "columns"), len(sets))
    rows = -(-len(sets) // columns)
    fig, axes = pyplot().subplots(rows, columns, figsize=(3.0 * columns, 3.2 * rows), squeeze=False)
    for ax in axes.ravel()[len(sets):]:
        ax.axis("off")
    for k, (ax, one) in enumerate(zip(axes.ravel(), sets, strict=False)):
        scatter(ax, one, f"set {k}, n = {len(one)}" if len(sets) > 1 else f"n = {len(one)}",
                tiled=tiled)
        if projections:
            _projections(ax, one, "black")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return files.save_figure(path, fig)
