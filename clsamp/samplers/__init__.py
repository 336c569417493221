"""Samplers: one module per family, all reachable through :func:`make_sampler`."""

# Importing a module registers its samplers.
from . import (  # noqa: F401
    ccvt,  # ccvt
    lloyd,  # lloyd
    lowdiscrepancy,  # van_der_corput, halton, hammersley, sobol
    poisson_disk,  # poisson_disk (dart throwing)
    random,  # random
    stratified,  # regular, jittered, uncorrelated_jitter, latin_hypercube, (correlated_)multijittered
)
from .base import Sampler, make_sampler, register, sampler_names

__all__ = ["Sampler", "make_sampler", "register", "sampler_names"]
