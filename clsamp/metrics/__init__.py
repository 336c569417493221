"""Figures of point sets beyond the spectrum: L2-type discrepancies, the exact star
discrepancy (and certified bounds), the pair correlation function and nearest-neighbour
distances."""

from .l2 import METHODS, DiscrepancySweep, discrepancy, discrepancy_reference, discrepancy_sweep
from .neighbors import mean_spacing, nearest_neighbor_distances, nearest_neighbor_reference, pair_correlation
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
           "star_discrepancy_reference"]
