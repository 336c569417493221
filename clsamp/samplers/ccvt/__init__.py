"""The ``ccvt`` sampler: capacity-constrained Voronoi tessellation (Balzer et al. 2009).

By stage, each with its OpenCL kernels and NumPy twin:

* :mod:`.pairs` -- the neighbour pairs and the constants shared with the kernels;
* :mod:`.density` -- the density points (``kernels/ccvt_density.cl``);
* :mod:`.power`, :mod:`.start`, :mod:`.relay` -- the exact-capacity start
  (``kernels/ccvt_start.cl``);
* :mod:`.reference` -- the NumPy optimizer; :mod:`.device` -- the OpenCL one
  (``kernels/ccvt.cl``, ``kernels/ccvt.h``);
* :mod:`.sampler` -- :class:`CCVTSampler`, :func:`ccvt_optimize` and :class:`CCVTInfo`.
"""

from .sampler import CCVTInfo, CCVTSampler, ccvt_optimize

__all__ = ["CCVTInfo", "CCVTSampler", "ccvt_optimize"]
