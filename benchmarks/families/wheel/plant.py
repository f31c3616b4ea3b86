"""The simulation plant of paper W's runs: the wheel satellite behind its input stage, RK4 at 5 ms.

Paper W's control period is 40 ms; the rest is the toolkit's (**assumed**): the controller runs with a 40 ms
zero-order hold and the plant is integrated with classical RK4 at 5 ms, the input stage
(wheel disturbance, faults, torque and momentum limits; :class:`models.WheelInputStage`)
acting inside the integration. :func:`wheel_plant` builds exactly that
:class:`~rmpc.sim.plants.SampledPlant` (integrator ``"RK4"``); :func:`scenario_plant` does it for
one of paper W's scenarios.
"""

from __future__ import annotations

from typing import Any

from models import WheelDisturbance, WheelInputStage, WheelSatellite, WheelScenario
from rmpc.sim.plants import SampledPlant
from toolkit_common.errors import ArgumentTypeError
from toolkit_common.validation import check_positive

__all__ = ["scenario_plant", "wheel_plant"]


def wheel_plant(
    satellite: WheelSatellite,
    faults: Any = None,
    *,
    dt: float = 0.04,
    substep: float = 0.005,
    integrator: str = "RK4",
    wheel_disturbance: WheelDisturbance | None = None,
    torque_limit: bool = True,
    momentum_limit: bool = True,
) -> SampledPlant:
    """The wheel satellite as a sampled plant for :func:`rmpc.sim.simulate`.

    Parameters
    ----------
    satellite : WheelSatellite
        The plant (its inertia may differ from the controller's model).
    faults : FaultSchedule, WheelFault or sequence of WheelFault, optional
        The faults of the run (wheels numbered from 1).
    dt : float
        Control period (default 0.04 s).
    substep : float
        RK4 step (default 0.005 s).
    integrator : {"RK4", "DOP853"}
        The integrator (default RK4, the toolkit's choice; the input stage switches inside a
        sample when a momentum limit is reached). See :mod:`rmpc.sim.integrators`.
    wheel_disturbance : WheelDisturbance, optional
        S4's wheel-level disturbance.
    torque_limit, momentum_limit : bool
        Apply the per-wheel limits (default ``True``).

    Returns
    -------
    SampledPlant
        Its ``input_stage`` is the :class:`~models.WheelInputStage`.

    Examples
    --------
    >>> from models import WheelFault, WheelSatellite
    >>> from benchmarks.families.wheel.plant import wheel_plant
    >>> plant = wheel_plant(WheelSatellite.paper_w(), [WheelFault(2, "stuck", 8.0, 37.0, value=0.05)])
    >>> plant.dt, plant.integrator, plant.n_substeps, plant.n_states, plant.n_inputs, plant.n_disturbances
    (0.04, RK4(substep=0.005), 8, 10, 4, 3)
    """
    if not isinstance(satellite, WheelSatellite):
        raise ArgumentTypeError("satellite", "a models.WheelSatellite", type(satellite).__name__)
    stage = WheelInputStage(
        satellite.wheels, faults, wheel_disturbance, torque_limit=torque_limit, momentum_limit=momentum_limit
    )
    return SampledPlant(
        satellite, check_positive(dt, "dt"), integrator=integrator, substep=substep, input_stage=stage
    )


def scenario_plant(
    scenario: WheelScenario,
    *,
    satellite: WheelSatellite | None = None,
    inertia_scale: float | None = None,
    seed: int | None = 0,
    **options: Any,
) -> SampledPlant:
    """The plant of one of paper W's scenarios (:func:`models.paper_w_scenario`).

    Parameters
    ----------
    scenario : WheelScenario
        The scenario: its faults (checked against its duration) and, for S4, its wheel
        disturbance with ``seed``.
    satellite : WheelSatellite, optional
        The nominal satellite (default :meth:`WheelSatellite.paper_w`).
    inertia_scale : float, optional
        The plant's inertia is ``inertia_scale * J`` (default: the scenario's first scale,
        1.0 for S1-S3 and 1.2 for S4).
    seed : int or None
        Seed of the wheel disturbance (S4).
    **options
        Further arguments of :func:`wheel_plant` (``dt``, ``substep``, limits).
    """
    if not isinstance(scenario, WheelScenario):
        raise ArgumentTypeError("scenario", "a models.WheelScenario", type(scenario).__name__)
    nominal = WheelSatellite.paper_w() if satellite is None else satellite
    scale = (
        scenario.inertia_scales[0]
        if inertia_scale is None
        else check_positive(inertia_scale, "inertia_scale")
    )
    plant_sat = nominal if scale == 1.0 else nominal.replace(inertia=scale * nominal.inertia)
    n = nominal.n_wheels
    return wheel_plant(
        plant_sat, scenario.schedule(n), wheel_disturbance=scenario.disturbance(seed, n), **options
    )
