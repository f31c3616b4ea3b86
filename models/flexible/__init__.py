"""The flexible satellite of papers S and V: a rigid hub with flexible modes and PZT actuators.

:mod:`models.flexible.satellite` (the plant, :class:`~models.FlexibleSatellite`), and one module
per concern it delegates to: :mod:`models.flexible.parameters` (the parameters, their checks,
the published 4-mode set), :mod:`models.flexible.dynamics` (the nonlinear hybrid model),
:mod:`models.flexible.energy` (energy and angular momentum), :mod:`models.flexible.linear` (the
``6 + 2N`` linear model), :mod:`models.flexible.polytope` (the uncertainty polytope),
:mod:`models.flexible.single_axis` (the single-axis transfer function and paper S's regime
label); :mod:`models.flexible.scenario` holds paper V's slew.
"""

from models.flexible.satellite import FlexibleSatellite

__all__ = ["FlexibleSatellite"]
