"""Samplers: one module (or package) per family, all reachable through :func:`make_sampler`."""

import functools
import inspect

# Importing a module registers its samplers.
from . import (  # noqa: F401
    bnot,  # bnot (blue noise through optimal transport)
    ccvt,  # ccvt
    digital_net,  # digital_net (user matrices), faure, niederreiter
    gbn,  # gbn (Gaussian blue noise)
    lattice,  # lattice (rank-1: Kuo's extensible sequence, Fibonacci), kronecker (R_d)
    lloyd,  # lloyd
    lowdiscrepancy,  # van_der_corput, halton, hammersley, sobol
    pmj,  # pmj02, pmj02bn (progressive multi-jittered (0, 2) sequences)
    poisson_disk,  # poisson_disk (dart throwing)
    random,  # random
    sample_elimination,  # sample_elimination (weighted sample elimination)
    sot,  # sot (sliced optimal transport, projective variant)
    stratified,  # regular, jittered, uncorrelated_jitter, latin_hypercube, (correlated_)multijittered
    zsobol,  # zsobol (Morton-ordered Owen-scrambled Sobol' for renderers)
)
from .base import (
    Rate,
    SampleInfo,
    Sampler,
    make_sampler,
    register,
    sampler_class,
    sampler_names,
)
from .dither import dither_mask
from .engine import as_qmc_engine

__all__ = ["Rate", "SampleInfo", "Sampler", "as_qmc_engine", "dither_mask", "make_quiet_sampler",
           "make_sampler", "register", "sampler_class", "sampler_names"]


def make_quiet_sampler(name, d=2, seed=0, **params):
    """:func:`~clsamp.make_sampler` with the sampler's own progress bar off where it has one
    (``bnot``'s), for callers that show their own: a sweep, the renderer, the tour.

    Parameters
    ----------
    name : str
    d : int
    seed : int
    **params
        As :func:`~clsamp.make_sampler` takes them.

    Returns
    -------
    Sampler

    Examples
    --------
    >>> make_quiet_sampler("bnot", seed=1).progress, make_quiet_sampler("random").d
    (False, 2)
    """
    takes = _takes_progress(sampler_class(name)) and "progress" not in params
    return make_sampler(name, d=d, seed=seed, **params, **({"progress": False} if takes else {}))


@functools.cache
def _takes_progress(cls):
    # once per class: the renderer makes a sampler a seed block
    return "progress" in inspect.signature(cls).parameters

