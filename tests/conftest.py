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
