"""What a designed robust MPC covers: its certified region along directions, its ellipsoids.

>>> from rmpc.analysis import feasible_region, plot_ellipsoid
"""

from rmpc.analysis.ellipsoid import ellipse_points, plot_ellipsoid
from rmpc.analysis.region import RegionResult, TimeBudgetExceeded, boundary_along, feasible_region

__all__ = [
    "RegionResult", "TimeBudgetExceeded", "boundary_along", "ellipse_points", "feasible_region",
    "plot_ellipsoid",
]
