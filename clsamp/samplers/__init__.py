"""Samplers: one module per family, all reachable through :func:`make_sampler`."""

from . import random  # noqa: F401  (registers "random")
from .base import Sampler, make_sampler, register, sampler_names

__all__ = ["Sampler", "make_sampler", "register", "sampler_names"]
