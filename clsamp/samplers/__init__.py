"""Samplers: one module per family, all reachable through :func:`make_sampler`."""

from . import random, stratified  # noqa: F401  (importing a module registers its samplers)
from .base import Sampler, make_sampler, register, sampler_names

__all__ = ["Sampler", "make_sampler", "register", "sampler_names"]
