"""Shared fixtures. Tests run on the default device (PoCL on the CPU unless
CLSAMP_DEVICE says otherwise); built programs are cached per process, so the
suite compiles each kernel variant once."""

import os
import sys

import pytest

# Import the checkout's clsamp even when another copy is installed.
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import clsamp  # noqa: E402


@pytest.fixture(scope="session")
def device():
    return clsamp.current_device()
