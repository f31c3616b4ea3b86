"""Paper M's scenarios M1-M3 as data.

Paper M's initial state, target, duration and step were lost; the toolkit's scenarios are
**assumed**:

- initial attitude of B relative to O: 3-2-1 ``(roll, pitch, yaw) = (40, -30, 20)`` deg, at rest
  in O (``w_BO(0) = 0``, so ``w(0) = -n c2(sigma0)``);
- target ``(10, 5, -10)`` deg, fixed in O; initial error angle 57.83 deg;
- 100 s, steady window [50, 100] s, RK4 with ``dt = 0.01`` s;
- M1 nominal; M2 with the spinning disk; M3 = M2 with the true inertia ``1.3 J0`` (also
  ``0.7 J0``) and a 1 N m per-axis torque limit (paper P's limit; paper M gives none).

Examples
--------
>>> from models import paper_m_scenario
>>> m2 = paper_m_scenario("M2")
>>> round(m2.initial_error_deg, 4), m2.disk, m2.u_max
(57.8316, True, None)
>>> paper_m_scenario("M3", inertia_scale=0.7).true_satellite().inertia.diagonal().round(6).tolist()
[2.1, 2.1, 1.4]
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np

from models.attitude.mrp import mrp_error, mrp_from_euler321
from models.mrp.satellite import MRPSatellite
from models.mrp.spinning_disk import SpinningDisk
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import as_vector, check_positive

__all__ = ["PAPER_M_NOTES", "PAPER_M_SCENARIOS", "PaperMScenario", "paper_m_scenario"]

#: What a report on paper M must say: paper M's inconsistencies and how the toolkit
#: resolved them.
PAPER_M_NOTES: tuple[str, ...] = (
    "(a) paper M's disk inertia in body axes carries a parallel-axis term -m S(R)^2 multiplying the "
    "spin rate, contradicting its premise of a disk spinning about its centre of mass; the toolkit "
    "uses the central inertia for the spin momentum (same result for the default zero offset)",
    "(b) the printed disk torque lost its grouping; the toolkit uses Td = -(w x Jb wb + Jb wb'), "
    "from dH/dt",
    "(c) 'MAB beats TF-AB' depends on tuning (TF-AB with Gamma = 100 beats MAB with w_o = 10 on M2); "
    "reports print Gamma and w_o",
    "(d) paper M never mentions shadow sets; at a switch se, alpha1 and the filter input jump while "
    "the filter output stays continuous, and chi1 is not remapped",
    "(e) paper M promises state and input limits but gives no values; M3's 1 N m limit is paper P's",
    "(f) the inertias J2 and J3 of paper M may be swapped (decoded diag(3, 3, 2))",
)


@dataclass(frozen=True)
class PaperMScenario:
    """One of paper M's scenarios (every value **assumed**).

    Attributes
    ----------
    name : str
        ``"M1"``, ``"M2"`` or ``"M3"``.
    description : str
        One line for reports.
    initial_euler_deg : tuple of float
        3-2-1 ``(roll, pitch, yaw)`` of the body relative to the orbital frame at ``t = 0`` (deg).
    target_euler_deg : tuple of float
        The target, fixed in the orbital frame (deg).
    duration : float
        Simulated time (s).
    dt : float
        Sample time of the controllers and RK4 step of the plant (s).
    steady_window : tuple of float
        Where steady-state metrics are taken (s).
    disk : bool
        Whether the spinning disk (:meth:`disturbance`) acts.
    inertia_scale : float
        True inertia as a multiple of the model's ``J0`` (M3: 1.3; also run at 0.7).
    u_max : float or None
        Per-axis torque limit of every controller (N m); ``None`` for none.
    """

    name: str
    description: str
    initial_euler_deg: tuple[float, float, float] = (40.0, -30.0, 20.0)
    target_euler_deg: tuple[float, float, float] = (10.0, 5.0, -10.0)
    duration: float = 100.0
    dt: float = 0.01
    steady_window: tuple[float, float] = (50.0, 100.0)
    disk: bool = False
    inertia_scale: float = 1.0
    u_max: float | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str):
            raise ArgumentTypeError("name", "a str", type(self.name).__name__)
        for field in ("initial_euler_deg", "target_euler_deg"):
            value = tuple(float(v) for v in as_vector(getattr(self, field), field, 3))
            object.__setattr__(self, field, value)
        object.__setattr__(self, "duration", check_positive(self.duration, "duration"))
        object.__setattr__(self, "dt", check_positive(self.dt, "dt"))
        lo, hi = (float(v) for v in as_vector(self.steady_window, "steady_window", 2))
        if not 0.0 <= lo < hi <= self.duration:
            raise InvalidArgumentError(
                "steady_window", f"0 <= start < end <= duration = {self.duration:g} s", repr((lo, hi))
            )
        object.__setattr__(self, "steady_window", (lo, hi))
        object.__setattr__(self, "disk", bool(self.disk))
        object.__setattr__(self, "inertia_scale", check_positive(self.inertia_scale, "inertia_scale"))
        if self.u_max is not None:
            object.__setattr__(self, "u_max", check_positive(self.u_max, "u_max"))

    @property
    def sigma0(self) -> np.ndarray:
        """Initial MRP of the body relative to the orbital frame."""
        return mrp_from_euler321(np.radians(self.initial_euler_deg))

    @property
    def sigma_ref(self) -> np.ndarray:
        """The target's MRP relative to the orbital frame."""
        return mrp_from_euler321(np.radians(self.target_euler_deg))

    @property
    def initial_error_deg(self) -> float:
        """The initial error angle ``4 atan|se(0)|`` (deg)."""
        return float(np.degrees(4.0 * np.arctan(np.linalg.norm(mrp_error(self.sigma0, self.sigma_ref)))))

    def model(self) -> MRPSatellite:
        """The controllers' model: paper M's satellite with ``J0 = diag(3, 3, 2)``."""
        return MRPSatellite.paper_m()

    def true_satellite(self) -> MRPSatellite:
        """The simulated satellite: the model with ``J = inertia_scale * J0``."""
        model = self.model()
        return model.with_inertia(self.inertia_scale * model.inertia)

    def disturbance(self) -> SpinningDisk | None:
        """The spinning disk (:meth:`models.SpinningDisk.paper_m`) when ``disk``, else ``None``."""
        return SpinningDisk.paper_m() if self.disk else None

    def initial_state(self) -> np.ndarray:
        """``[sigma0, w(0)]`` with ``w(0) = -n c2(sigma0)`` (at rest in the orbital frame)."""
        return self.true_satellite().state_at_rest(self.sigma0)

    def settings(self) -> dict[str, Any]:
        """Every value of the scenario, for reports (plain Python types)."""
        out = dataclasses.asdict(self)
        out["sigma0"] = self.sigma0.tolist()
        out["sigma_ref"] = self.sigma_ref.tolist()
        out["initial_error_deg"] = self.initial_error_deg
        out["notes"] = list(PAPER_M_NOTES)
        return out


#: The three scenarios at their defaults (read-only mapping).
PAPER_M_SCENARIOS: MappingProxyType[str, PaperMScenario] = MappingProxyType(
    {
        "M1": PaperMScenario("M1", "nominal: constant target, no disturbance"),
        "M2": PaperMScenario("M2", "spinning disk inside the bus", disk=True),
        "M3": PaperMScenario(
            "M3", "spinning disk, true inertia 1.3 J0, 1 N m per-axis torque limit",
            disk=True, inertia_scale=1.3, u_max=1.0,
        ),
    }
)


def paper_m_scenario(name: str, **overrides: Any) -> PaperMScenario:
    """Paper M's scenario ``"M1"``, ``"M2"`` or ``"M3"``, with fields overridden by keyword.

    A shorter ``duration`` without a ``steady_window`` moves the window to its second half, as
    the default [50, 100] s is for 100 s.

    Examples
    --------
    >>> from models import paper_m_scenario
    >>> paper_m_scenario("M3").inertia_scale, paper_m_scenario("M1", duration=20.0).steady_window
    (1.3, (10.0, 20.0))
    """
    if name not in PAPER_M_SCENARIOS:
        raise InvalidArgumentError("name", f"one of {', '.join(PAPER_M_SCENARIOS)}", repr(name))
    base = PAPER_M_SCENARIOS[name]
    fields = {f.name for f in dataclasses.fields(PaperMScenario)}
    unknown = sorted(set(overrides) - fields)
    if unknown:
        raise InvalidArgumentError("overrides", f"fields of PaperMScenario ({', '.join(sorted(fields))})",
                                   ", ".join(unknown))
    if "duration" in overrides and "steady_window" not in overrides:
        duration = check_positive(overrides["duration"], "duration")
        overrides["steady_window"] = (0.5 * duration, duration)
    return dataclasses.replace(base, **overrides)
