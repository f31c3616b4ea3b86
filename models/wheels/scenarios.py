"""Paper W's four test scenarios S1-S4 as data.

Faults, windows and initial angles are **certain** as printed; the durations (60/150/150/150 s),
the zero initial rates (**likely**), the S4 inertia errors (plant ``1.2 J`` and ``0.8 J``, the
controller keeps ``J``) and the S4 disturbance's placement are **assumed**. S1's stuck torque is
0.05 N m in paper W's paragraph but 0.03 N m in its fault list: 0.05 by default,
0.03 as the variant ``stuck_torque=0.03``. Wheel 4 is the skew wheel.

The benchmark suite ("W1".."W4" = S1-S4) builds its runs from these records.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from models.wheels.faults import FaultSchedule, WheelFault
from models.wheels.noise import WheelDisturbance
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import check_choice, check_positive

__all__ = ["PAPER_W_SCENARIOS", "WheelScenario", "paper_w_scenario"]

#: Names of paper W's scenarios.
PAPER_W_SCENARIOS: tuple[str, ...] = ("S1", "S2", "S3", "S4")
_N_WHEELS = 4


@dataclass(frozen=True)
class WheelScenario:
    """One regulation-to-zero test of paper W.

    Attributes
    ----------
    name : str
        ``"S1"`` .. ``"S4"``.
    attitude_deg : tuple of float
        Initial ``[phi, theta, psi]`` (deg).
    faults : tuple of WheelFault
        The faults (wheels numbered from 1).
    duration : float
        Run length (s, **assumed**).
    inertia_scales : tuple of float
        Plant inertia ``scale * J`` for each run of the scenario (S4: 1.2 and 0.8; the
        controller keeps the nominal ``J``).
    wheel_disturbance : bool
        Whether the S4 wheel-level disturbance acts.
    paper_basis : tuple of tuple of float, or None
        Paper W's per-scenario adaptation basis, per wheel: the sinusoid frequencies (rad/s)
        besides the constant, e.g. ``((0.2,), (), (), ())`` for ``varpi_1 = [1, sin 0.2t]``
        and ``[1]`` elsewhere; ``None`` where paper W does not state it (S4).
    notes : str
        What is uncertain about the scenario.
    """

    name: str
    attitude_deg: tuple[float, float, float]
    faults: tuple[WheelFault, ...]
    duration: float
    inertia_scales: tuple[float, ...] = (1.0,)
    wheel_disturbance: bool = False
    paper_basis: tuple[tuple[float, ...], ...] | None = None
    notes: str = ""
    disturbance_options: dict[str, Any] = field(default_factory=dict)

    def initial_state(self, n_wheels: int = _N_WHEELS) -> np.ndarray:
        """``[eta0 (rad), w0 = 0, h0 = 0]``."""
        return np.concatenate((np.radians(self.attitude_deg), np.zeros(3 + n_wheels)))

    def schedule(self, n_wheels: int = _N_WHEELS) -> FaultSchedule:
        """The faults as a :class:`~models.FaultSchedule` checked against the run's length."""
        return FaultSchedule(list(self.faults), n_wheels, self.duration)

    def disturbance(self, seed: int | None = 0, n_wheels: int = _N_WHEELS) -> WheelDisturbance | None:
        """The S4 wheel disturbance with this seed, or ``None`` for S1-S3."""
        if not self.wheel_disturbance:
            return None
        return WheelDisturbance(n_wheels, seed=seed, **self.disturbance_options)


def paper_w_scenario(
    name: str, *, stuck_torque: float | None = None, disturbance_variance: float = 0.0052
) -> WheelScenario:
    """Return paper W's scenario ``name`` (``"S1"`` .. ``"S4"``).

    Parameters
    ----------
    name : {"S1", "S2", "S3", "S4"}
        The scenario.
    stuck_torque : float, optional
        S1 only: the stuck torque (default 0.05 N m; 0.03 is the variant from the fault list).
    disturbance_variance : float
        S4 only: the variance of the wheel noise (default 0.0052 as printed; 2.5e-5 if it was a
        flattened ``0.005^2``).

    Examples
    --------
    >>> from models import paper_w_scenario
    >>> s1 = paper_w_scenario("S1")
    >>> s1.attitude_deg, s1.duration, s1.faults[0]
    ((40.0, -21.0, -80.0), 60.0, WheelFault(wheel=2, kind='stuck', t_on=8, t_off=37, value=0.05))
    """
    check_choice(name, "name", PAPER_W_SCENARIOS)
    if stuck_torque is not None and name != "S1":
        raise InvalidArgumentError("stuck_torque", "None except for S1", repr(stuck_torque))
    variance = check_positive(disturbance_variance, "disturbance_variance", allow_zero=True)
    sine = {"kind": "sinusoidal", "value": 0.03, "frequency": 0.2}
    if name == "S1":
        c = 0.05 if stuck_torque is None else stuck_torque
        return WheelScenario(
            "S1",
            (40.0, -21.0, -80.0),
            (WheelFault(2, "stuck", 8.0, 37.0, value=c),),
            60.0,
            paper_basis=((), (), (), ()),
            notes="stuck torque 0.05 N m in the text, 0.03 N m in the fault list (default 0.05)",
        )
    if name == "S2":
        return WheelScenario(
            "S2",
            (23.0, 24.0, 73.0),
            (WheelFault(1, t_on=30.0, t_off=80.0, **sine), WheelFault(4, "stuck", 90.0, 120.0, value=0.03)),
            150.0,
            paper_basis=((0.2,), (), (), ()),
        )
    if name == "S3":
        return WheelScenario(
            "S3",
            (23.0, 23.0, 67.0),
            (
                WheelFault(4, "outage", 0.0, math.inf),
                WheelFault(1, t_on=30.0, t_off=80.0, **sine),
                WheelFault(2, "stuck", 90.0, 120.0, value=0.03),
            ),
            150.0,
            paper_basis=((0.2,), (), (), ()),
            notes="two wheels lost in [30, 80) and [90, 120): paper W's condition (17) fails (seed 6.7)",
        )
    return WheelScenario(
        "S4",
        (-20.0, 26.0, 79.0),
        (
            WheelFault(4, "outage", 0.0, math.inf),
            WheelFault(1, "stuck", 30.0, 60.0, value=0.03),
            WheelFault(2, t_on=70.0, t_off=100.0, **sine),
        ),
        150.0,
        inertia_scales=(1.2, 0.8),
        wheel_disturbance=True,
        paper_basis=None,
        notes="two wheels lost in [30, 60) and [70, 100); 20 % inertia error outside paper W's proof; "
        "disturbance variance 0.0052 as printed (maybe 0.005^2)",
        disturbance_options={"variance": variance},
    )
