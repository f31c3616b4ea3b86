"""Polytopic sets of tube MPC: polytopes (on cddlib), the mRPI outer approximation, tightenings.

Examples
--------
>>> import numpy as np
>>> from rmpc.sets import Polytope, mrpi_outer
>>> A_K = np.array([[0.5, 0.1], [0.0, 0.4]])
>>> approx = mrpi_outer(A_K, Polytope.box([0.1, 0.1]), epsilon=1e-4)
>>> bool(approx.bound <= 1e-4), approx.Z.contains([0.1, 0.1])
(True, True)
"""

from rmpc.sets.invariant import (
    LyapunovEllipsoid,
    MRPIApproximation,
    admissible_set,
    mrpi_outer,
    mrpi_parameters,
    mrpi_support_bound,
    reachable_tightening,
    schur_radius,
)
from rmpc.sets.polytope import Polytope, PolytopeError

__all__ = [
    "LyapunovEllipsoid",
    "MRPIApproximation",
    "Polytope",
    "PolytopeError",
    "admissible_set",
    "mrpi_outer",
    "mrpi_parameters",
    "mrpi_support_bound",
    "reachable_tightening",
    "schur_radius",
]
