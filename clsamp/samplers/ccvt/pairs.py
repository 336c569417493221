"""The neighbour pairs of CCVT and the site records its kernels keep: the constants the
host and ``kernels/ccvt*.cl`` share, with this module as their one source (the kernels
get them as build options, :func:`ccvt_defines`)."""

import math

from ... import runtime
from ...geometry import integer_torus as it

CCVT_TOP = 16          # candidates per site and round of an exchange
CCVT_SECTORS = 16      # angular sectors of a site's buckets
CCVT_BANDS = 4         # radial bands of a site's buckets
CCVT_BUCKETS = CCVT_SECTORS * CCVT_BANDS
CCVT_META = 7 + CCVT_BUCKETS + CCVT_SECTORS   # int64 record per site (see kernels/ccvt.h)
MAX_POINTS_PER_SITE = it.MAX_CELL_POINTS
NO_OWNER = 0xFFFFFFFF      # a density point with no candidate site (the power pass's owner then)
NO_SECOND = (1 << 63) - 1  # the power pass's margin where a point has one candidate
# The swap phases of one iteration: (ox, oy, parity); (0, 0) pairs the sites inside a cell.
PHASES = ((0, 0, 0),) + tuple((ox, oy, parity) for ox, oy in ((1, 0), (0, 1), (1, 1), (1, -1))
                              for parity in (0, 1))

NEAR = 2   # neighbours: sites closer than NEAR / sqrt(n) (about twice the hexagonal spacing)


def ccvt_near2(n):
    """Squared distance (integer torus units) below which two sites are neighbours and
    exchange points: (NEAR / sqrt(n))^2. A site's Voronoi neighbours in a CCVT lie within
    about 1.4 / sqrt(n); this is the pair graph, found through the grid, never all pairs.

    Parameters
    ----------
    n : int
        Sites.

    Returns
    -------
    int
    """
    return (NEAR * NEAR * it.SIZE * it.SIZE) // n


def ccvt_grid_size(n):
    """Cells per axis of the site grid: even, at least 2, and with cells at least NEAR /
    sqrt(n) wide, so every neighbour pair is in the same or adjacent cells.

    Parameters
    ----------
    n : int
        Sites.

    Returns
    -------
    int

    Examples
    --------
    >>> ccvt_grid_size(16), ccvt_grid_size(1024)
    (2, 16)
    """
    return max(2, (math.isqrt(n) // NEAR) // 2 * 2)


def ccvt_defines():
    """Build options of ``kernels/ccvt*.cl`` on the current device.

    Returns
    -------
    dict
        The constants the kernels share with Python, and CCVT_PREFETCH: software prefetch
        of the records and points a pair reads, where the device's launch shape says
        (``runtime.shape().prefetch``: under PoCL, whose scans of pairs wait on memory;
        other implementations may lower ``prefetch`` differently, or not at all). It never
        changes a result.
    """
    return {**it.DEFINES, "CCVT_TOP": CCVT_TOP, "CCVT_SECTORS": CCVT_SECTORS,
            "CCVT_BANDS": CCVT_BANDS, "CCVT_META": CCVT_META, "CCVT_NO_OWNER": f"{NO_OWNER}u",
            "CCVT_NO_SECOND": f"{NO_SECOND}L",
            "CCVT_PREFETCH": runtime.shape().prefetch}
