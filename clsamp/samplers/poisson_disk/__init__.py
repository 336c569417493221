"""The ``poisson_disk`` sampler: parallel dart throwing into tracked voids.

Two modes:

* fixed n (the default, ``rho=0.75``): ``sample(n)`` returns exactly n points whose
  minimum toroidal distance is at least ``rho * d_max(n)``
  (:func:`clsamp.geometry.torus.max_min_distance`);
* maximal (``radius=r``, n left out): ``sample()`` returns a maximal set, one where no
  further disk centre of radius r fits anywhere on the torus.

Both run the same process (Ebeida et al. 2011, 2012), by stage:

* :mod:`.grid` -- the background grid, the windows and the threshold both backends share;
* :mod:`.device` -- the steps in OpenCL (``kernels/dart_throwing.cl``);
* :mod:`.reference` -- their NumPy twin (``backend="numpy"``), the same sets bit for bit;
* :mod:`.coarse` -- d = 5..8 (fixed n; a sparse n below): darts into the whole torus,
  neighbours through cells at least r wide, its round loop (kernels ``coarse_*`` in the
  same file);
* :mod:`.sampler` -- the round loop, the batches and :class:`PoissonDiskSampler`.
"""

from .grid import acceptance_threshold, grid_size, reach
from .sampler import PoissonDiskInfo, PoissonDiskSampler

__all__ = ["PoissonDiskInfo", "PoissonDiskSampler", "acceptance_threshold", "grid_size", "reach"]
