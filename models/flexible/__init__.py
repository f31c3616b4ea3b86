"""The flexible satellite of papers S and V: a rigid hub with flexible modes and PZT actuators.

:mod:`models.flexible.satellite` (the nonlinear hybrid model), :mod:`models.flexible.linear`
(its ``6 + 2N`` linear model), :mod:`models.flexible.polytope` (the uncertainty polytope),
:mod:`models.flexible.single_axis` (the single-axis transfer function and paper S's regime
label) and :mod:`models.flexible.scenario` (paper V's slew).
"""

from models.flexible.satellite import FlexibleSatellite

__all__ = ["FlexibleSatellite"]
