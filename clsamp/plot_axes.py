"""Axes that read well, shared by :mod:`clsamp.plots`: legends beside the data rather than
over it, log-axis tick labels that do not run into each other, and a log axis that a curve
falling far below the others (a regular grid's MSE on smooth periodic integrands, which
reaches rounding) does not stretch over thirty decades.
"""

import math

import numpy as np

__all__ = ["legend_below", "readable_log_ticks", "clip_far_below"]


def legend_below(ax, fontsize=7, columns=2):
    """Put the legend of ``ax`` under its x label, outside the data.

    Parameters
    ----------
    ax : matplotlib Axes
    fontsize : float
    columns : int

    Returns
    -------
    matplotlib Legend or None
        None when nothing on ``ax`` has a label.
    """
    handles, labels = ax.get_legend_handles_labels()
    if not handles:
        return None
    return ax.legend(handles, labels, fontsize=fontsize, ncol=columns, loc="upper center",
                     bbox_to_anchor=(0.5, -0.16), frameon=False)


def readable_log_ticks(ax, axis="x"):
    """On a log axis spanning under two decades, label ticks at 1, 2 and 5 of each decade in
    plain numbers and no minor ticks; on a wider one, the decades only.

    Parameters
    ----------
    ax : matplotlib Axes
    axis : {"x", "y"}

    Examples
    --------
    >>> from clsamp import plots
    >>> fig, ax = plots.pyplot().subplots()
    >>> _ = ax.loglog([0.05, 0.4], [1, 2])
    >>> readable_log_ticks(ax)
    >>> plots.pyplot().close(fig)
    """
    from matplotlib import ticker
    which = ax.xaxis if axis == "x" else ax.yaxis
    lo, hi = sorted(ax.get_xlim() if axis == "x" else ax.get_ylim())
    if lo <= 0 or which.get_scale() != "log":
        return
    if math.log10(hi / lo) < 2:
        which.set_major_locator(ticker.LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
        which.set_major_formatter(ticker.FormatStrFormatter("%g"))
    else:
        which.set_major_locator(ticker.LogLocator(base=10, numticks=8))
    which.set_minor_formatter(ticker.NullFormatter())


def clip_far_below(ax, series, factor=1e-6):
    """Keep a log y axis to the range of most series: one whose smallest value lies more than
    ``factor`` below every other series' smallest goes out of the bottom of the axis.

    Parameters
    ----------
    ax : matplotlib Axes
    series : dict
        ``{label: values}``: the values each drawn series spans (positive ones count).
    factor : float

    Returns
    -------
    list of str
        The labels of the series cut, for the caller to say so in the legend.
    """
    floors = {k: float(np.min(v[v > 0])) for k, v in
              ((k, np.asarray(v, dtype=np.float64).ravel()) for k, v in series.items()) if np.any(v > 0)}
    cut = [k for k, f in floors.items()
           if len(floors) > 1 and all(f < factor * g for j, g in floors.items() if j != k)]
    if cut:
        kept = min(f for k, f in floors.items() if k not in cut)
        ax.set_ylim(bottom=kept / 10)
    return cut
