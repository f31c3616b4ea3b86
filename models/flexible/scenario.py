"""Paper V's scenario on the flexible satellite as data: the V-slew and its disturbance.

Paper V's initial state, disturbance values and torque bound were lost in extraction; the toolkit's
choices (all **assumed** unless tagged):

- slew: rest to rest, to ``q = [1, 0, 0, 0]`` from a rotation of 160 deg (**likely**; printed
  "134" in a garbled digit font, 169, 260, 269 also possible: a parameter) about
  ``(1, 1, 1)/sqrt(3)`` (**assumed**; variant: body z), modes at rest;
- hub disturbance ``d(t) = 0.05 [sin(0.1 t), cos(0.1 t), sin(0.1 t + pi/4)] N m``, ``d_f = 0``;
- ``u_max = 2 N m`` per axis (paper V: a bound exists, **certain**; value lost), no PZT limit;
- ``Ts = 0.01 s`` ZOH, 150 s (paper V implies at least 60 s), the published 4-mode plant with
  ``Gamma_a = I_4``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from models.actuators import TorqueLimiter
from models.attitude.quaternion import quat_from_axis_angle
from models.flexible.satellite import FlexibleSatellite
from toolkit_common.errors import ArgumentTypeError
from toolkit_common.validation import as_vector, check_positive, check_real

__all__ = [
    "F2_EPSILONS",
    "F3_INTEGRAL_GAINS",
    "ConstantHubTorque",
    "PaperVDisturbance",
    "VSlewScenario",
    "paper_v_scenario",
    "steady_error_scenario",
]

#: F2: the boundary-layer widths ``eps`` (rad/s) of the chattering sweep (**assumed**).
F2_EPSILONS: tuple[float, ...] = (0.002, 0.005, 0.01, 0.02, 0.05)
#: F3: the integral gains ``k_I`` (1/s^2) of the steady-error study (**assumed**).
F3_INTEGRAL_GAINS: tuple[float, ...] = (0.0, 0.01)


@dataclass(frozen=True)
class PaperVDisturbance:
    """``d(t) = a [sin(r t), cos(r t), sin(r t + pi/4)]`` (N m), paper V's hub disturbance.

    Parameters
    ----------
    amplitude : float
        ``a`` (N m), default 0.05 (**assumed**).
    rate : float
        ``r`` (rad/s), default 0.1 (**assumed**).

    Examples
    --------
    >>> from models.flexible.scenario import PaperVDisturbance
    >>> PaperVDisturbance()(0.0).round(4).tolist()
    [0.0, 0.05, 0.0354]
    """

    amplitude: float = 0.05
    rate: float = 0.1

    def __post_init__(self) -> None:
        object.__setattr__(self, "amplitude", check_real(self.amplitude, "amplitude"))
        object.__setattr__(self, "rate", check_positive(self.rate, "rate"))

    def __call__(self, t: float) -> np.ndarray:
        """The disturbance torque at ``t`` (s)."""
        phase = self.rate * t
        return self.amplitude * np.array([np.sin(phase), np.cos(phase), np.sin(phase + np.pi / 4)])


@dataclass(frozen=True)
class ConstantHubTorque:
    """A constant hub disturbance torque ``d`` (N m), one value per body axis.

    Examples
    --------
    >>> from models.flexible.scenario import ConstantHubTorque
    >>> ConstantHubTorque()(12.0).tolist()
    [0.05, 0.05, 0.05]
    """

    value: Any = (0.05, 0.05, 0.05)

    def __post_init__(self) -> None:
        object.__setattr__(self, "value", as_vector(self.value, "value", 3))

    def __call__(self, t: float) -> np.ndarray:
        """The torque (the same at every ``t``)."""
        return self.value.copy()


@dataclass(frozen=True)
class VSlewScenario:
    """Paper V's rest-to-rest slew as data.

    Attributes
    ----------
    satellite : FlexibleSatellite
        The plant (default the published 4-mode set).
    angle_deg : float
        Slew angle (deg).
    axis : (3,) ndarray
        Slew axis (body frame, normalised by the quaternion constructor).
    duration : float
        Run length (s).
    dt : float
        Sample time (s).
    u_max : float
        Per-axis hub torque bound (N m).
    disturbance : object or None
        ``d(t)`` on the hub (``None``: undisturbed).
    """

    satellite: FlexibleSatellite = field(default_factory=FlexibleSatellite.di_gennaro)
    angle_deg: float = 160.0
    axis: Any = (1.0, 1.0, 1.0)
    duration: float = 150.0
    dt: float = 0.01
    u_max: float = 2.0
    disturbance: Any = field(default_factory=PaperVDisturbance)

    def __post_init__(self) -> None:
        if not isinstance(self.satellite, FlexibleSatellite):
            expected = "a models.FlexibleSatellite"
            raise ArgumentTypeError("satellite", expected, type(self.satellite).__name__)
        object.__setattr__(self, "angle_deg", check_real(self.angle_deg, "angle_deg"))
        object.__setattr__(self, "axis", as_vector(self.axis, "axis", 3))
        object.__setattr__(self, "duration", check_positive(self.duration, "duration"))
        object.__setattr__(self, "dt", check_positive(self.dt, "dt"))
        object.__setattr__(self, "u_max", check_positive(self.u_max, "u_max"))
        if self.disturbance is not None and not callable(self.disturbance):
            expected = "None or a callable d(t)"
            raise ArgumentTypeError("disturbance", expected, type(self.disturbance).__name__)

    def initial_state(self) -> np.ndarray:
        """At rest, rotated by ``angle_deg`` about ``axis`` from the target, modes at rest."""
        q0 = quat_from_axis_angle(self.axis, np.deg2rad(self.angle_deg))
        return self.satellite.state(q0)

    def limiter(self) -> TorqueLimiter:
        """The per-axis hub-torque clip (PZT commands unlimited)."""
        return self.satellite.input_limiter(self.u_max)


def paper_v_scenario(**overrides: Any) -> VSlewScenario:
    """The V-slew with the toolkit defaults; keyword arguments override fields.

    Examples
    --------
    >>> from models.flexible.scenario import paper_v_scenario
    >>> sc = paper_v_scenario(duration=20.0)
    >>> sc.angle_deg, sc.duration, sc.initial_state().shape
    (160.0, 20.0, (15,))
    """
    return VSlewScenario(**overrides)


def steady_error_scenario(**overrides: Any) -> VSlewScenario:
    """F3: at the target at rest under a constant 0.05 N m per axis, 250 s.

    Without integral action the error settles at ``2 ||d|| / (alpha_f (W_0/eps + K_s))``
    (0.83 deg with the MTSMC defaults); with ``k_I = 0.01`` it falls below 0.1 deg by 250 s.

    Examples
    --------
    >>> from models.flexible.scenario import steady_error_scenario
    >>> sc = steady_error_scenario()
    >>> sc.angle_deg, sc.duration, sc.disturbance(0.0).tolist()
    (0.0, 250.0, [0.05, 0.05, 0.05])
    """
    fields: dict[str, Any] = {"angle_deg": 0.0, "duration": 250.0, "disturbance": ConstantHubTorque()}
    fields.update(overrides)
    return VSlewScenario(**fields)
