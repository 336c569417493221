"""Geometry of the unit torus, below the samplers and the analyses that both use it.

* :mod:`clsamp.geometry.torus` -- float points on [0, 1)^d: the Cranley-Patterson shift,
  wrapped differences and distances, the densest packings (d_max).
* :mod:`clsamp.geometry.integer_torus` -- points on the exact 2^22 integer torus of the
  Voronoi optimizers: differences, distances, rounded means and exact sums in int64.
* :mod:`clsamp.geometry.cells` -- a grid of cells for neighbour searches: points sorted
  by (set, cell) and the 3^d stencil of neighbouring cells (``kernels/cells.h``).
* :mod:`clsamp.geometry.voronoi` -- nearest-site assignment of a regular density grid
  (OpenCL and NumPy), the CVT energy it gives, and the grid helpers around it.
"""
