"""clsamp: sampling patterns for Monte Carlo rendering, generated and measured in OpenCL.

Quick start::

    import clsamp
    pts = clsamp.make_sampler("jittered", d=2, seed=1).sample(256)

See README.md for a tour and ``clsamp --help`` for the command line.
"""

# clsamp.render is the module (its function is clsamp.render.render); clsamp.convergence is the
# function (its module is clsamp.sweep).
import sys as _sys

from . import families, files, integrands, metrics, parallel, plots, render, results, theory, transforms
from .errors import (
                     BuildError,
                     ClsampError,
                     DeviceMemoryError,
                     InvalidArgumentError,
                     NoDeviceError,
                     SamplingError,
)
from .families import family_names, make_family
from .integrands import Integrand
from .integration import IntegrationResult, integrate
from .metrics import StarBounds, discrepancy, nearest_neighbor_distances, pair_correlation, star_discrepancy
from .runtime import current_device, devices, use_device
from .samplers import Rate, SampleInfo, Sampler, as_qmc_engine, dither_mask, make_sampler, sampler_names
from .spectrum import anisotropy, expected_spectrum, power_spectrum, radial_mean
from .sweep import convergence

__version__ = "0.1.0"

# The file module is `files`, so that inside the package no module shadows the standard
# library's io; `clsamp.io`, the name the design gives it, is the same module.
io = files
_sys.modules[__name__ + ".io"] = files

__all__ = [
    "BuildError", "ClsampError", "DeviceMemoryError", "IntegrationResult",
    "Integrand", "InvalidArgumentError", "NoDeviceError", "Rate", "SampleInfo", "Sampler", "SamplingError",
    "StarBounds", "anisotropy", "as_qmc_engine", "convergence", "current_device", "devices",
    "discrepancy", "dither_mask", "expected_spectrum", "families", "family_names", "files", "integrands",
    "integrate", "make_family",
    "make_sampler", "metrics", "nearest_neighbor_distances", "pair_correlation", "parallel", "plots",
    "power_spectrum", "radial_mean", "render", "sampler_names", "star_discrepancy", "theory",
    "use_device", "results", "transforms",
]
