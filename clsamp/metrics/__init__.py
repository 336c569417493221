"""Figures of point sets beyond the spectrum, one home for all of them: L2-type
discrepancies, the exact star discrepancy (and certified bounds), the pair correlation
function and nearest-neighbour distances, and the figures of one set (minimum distance,
relative radius ρ, normalized CVT energy N·E)."""

from .l2 import METHODS, DiscrepancySweep, discrepancy, discrepancy_reference, discrepancy_sweep
from .neighbors import mean_spacing, nearest_neighbor_distances, nearest_neighbor_reference, pair_correlation
from .point_sets import (
                         HEXAGONAL_NE,
                         WHITE_NOISE_NE,
                         max_min_distance,
                         min_distance,
                         normalized_energy,
                         relative_radius,
)
from .star import (
                   StarBounds,
                   star_bounds,
                   star_discrepancy,
                   star_discrepancy_brute,
                   star_discrepancy_reference,
)

__all__ = ["METHODS", "DiscrepancySweep", "discrepancy", "discrepancy_reference",
           "discrepancy_sweep", "mean_spacing",
           "nearest_neighbor_distances", "nearest_neighbor_reference", "pair_correlation",
           "StarBounds", "star_bounds", "star_discrepancy", "star_discrepancy_brute",
           "star_discrepancy_reference", "HEXAGONAL_NE", "WHITE_NOISE_NE", "max_min_distance",
           "min_distance", "normalized_energy", "relative_radius"]
