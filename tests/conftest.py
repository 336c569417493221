"""Shared fixtures. Tests run on the default device (PoCL on the CPU unless
CLSAMP_DEVICE says otherwise); built programs are cached per process, so the
suite compiles each kernel variant once."""

import os
import sys

import pytest

# Import the checkout's clsamp even when another copy is installed.
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from hypothesis import HealthCheck, settings  # noqa: E402

import clsamp  # noqa: E402

# hypothesis: "ci" (the default here) keeps the fuzzing inside CI's time; pass
# --hypothesis-profile=long for the run before a release (50 times the examples)
_quiet = [HealthCheck.too_slow, HealthCheck.filter_too_much, HealthCheck.function_scoped_fixture]
settings.register_profile("ci", max_examples=25, deadline=None, suppress_health_check=_quiet)
settings.register_profile("long", max_examples=1250, deadline=None, suppress_health_check=_quiet)
settings.load_profile("ci")


@pytest.fixture(scope="session")
def device():
    return clsamp.current_device()


def is_net(points, m):
    """Every elementary interval of area 2^-m (all 2^a x 2^(m-a) boxes) holds one point."""
    import numpy as np
    ints = np.floor(points * 2**m).astype(np.int64)
    for a in range(m + 1):
        boxes = (ints[:, 0] >> (m - a)) * (1 << (m - a)) + (ints[:, 1] >> a)
        if len(np.unique(boxes)) != len(points):
            return False
    return True


def net_cells(x, base, k):
    """floor(x b^k) of coordinates in [0, 1): exact in base 2; in base b != 2 a point on a
    cell's edge, j / b^k, is a double just below or above it, so a value within 1e-12 below
    an integer is taken as it."""
    import numpy as np
    c = x * float(base) ** k
    cell = np.floor(c)
    if base != 2:
        cell += c - cell > 1 - 1e-12
    return cell.astype(np.int64)


def is_tms_net(points, t, m, base=2):
    """Whether (n = b^m, s) points form a (t, m, s)-net in base b: every elementary interval
    Π_j [a_j b^-k_j, (a_j + 1) b^-k_j) with Σ_j k_j = m - t (volume b^(t-m)) holds exactly
    b^t points (Niederreiter 1992, Def. 4.1)."""
    import itertools

    import numpy as np
    n, s = points.shape
    assert n == base**m, (n, base, m)
    q = m - t
    if q <= 0:
        return True
    digits = [[net_cells(points[:, j], base, k) for k in range(q + 1)] for j in range(s)]
    for bars in itertools.combinations(range(q + s - 1), s - 1):     # stars and bars
        ks = np.diff((-1,) + bars + (q + s - 1,)) - 1
        cell = np.zeros(n, dtype=np.int64)
        for j, k in enumerate(ks):
            cell = cell * base**int(k) + digits[j][int(k)]
        if not np.all(np.bincount(cell, minlength=base**q) == base**t):
            return False
    return True
