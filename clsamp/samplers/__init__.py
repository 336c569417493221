"""Samplers: one module per family, all reachable through :func:`make_sampler`."""

from . import (
    lowdiscrepancy,  # noqa: F401  (registers van_der_corput, halton, hammersley, sobol)
    random,  # noqa: F401  (registers "random")
)
from .base import Sampler, make_sampler, register, sampler_names

__all__ = ["Sampler", "make_sampler", "register", "sampler_names"]
