"""The controllers of the wheel-fault benchmarks and how each meets the wheel torque limit.

Every wheel's torque and momentum limits act in the plant (the input stage of
:func:`benchmarks.families.wheel.plant.wheel_plant`), whatever the controller. ``saturation`` says whether the
controller designs for the torque limit itself:

- ``"constraint"``: RMPC (per-wheel peak bound ``|u_j| <= u_max`` in its LMIs), CRMPC (the same,
  with the torque budget for its correction), GIPC (``|u_j| <= u_max``, ``|du_j| <= du_max``);
- ``"limiter"``: the controller ignores the limit and the plant clips (paper W's compensator,
  ``ABFTC``, has no other mode).

RMPC, CRMPC and GIPC see the attitude and the rates (the first six states) through
:class:`rmpc.MappedController`; ABFTC sees the whole state. None of them sees the fault.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from benchmarks.core.family import BuiltController, check_horizon
from toolkit_common.errors import ConfigError

__all__ = ["CONSTRAINED", "CONTROLLERS", "WheelModel", "settings_check"]


class WheelModel:
    """What the controllers are built on: the nominal satellite and the controller's polytope."""

    def __init__(self, satellite: Any, polytope: Any) -> None:
        self.satellite = satellite
        self.polytope = polytope


def _weights(s: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    return np.diag(s["Q_diag"]), np.diag(s["R_diag"])


def _mapped(ctrl: Any, name: str) -> Any:
    from rmpc import MappedController

    return MappedController(ctrl, measure=range(6), name=name)


def _abftc(model: WheelModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from rmpc import AdaptiveBacksteppingFTC

    ctrl = AdaptiveBacksteppingFTC(
        model.satellite,
        c1=s["c1"],
        c2=s["c2"],
        gamma_g=s["gamma_g"],
        gamma_theta=s["gamma_theta"],
        dt=scenario.dt,
        freeze=s["freeze"],
        leakage=s["leakage"],
    )
    return BuiltController(ctrl, False)


def _rmpc(model: WheelModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from benchmarks.families.rmpc_forms import rmpc_kwargs
    from rmpc import RMPC

    q, r = _weights(s)
    constrained = scenario.saturation == "constraint"
    ctrl = RMPC(
        model.polytope,
        q,
        r,
        u_max=scenario.u_max if constrained else None,
        input_constraint=s["input_constraint"] if constrained else None,
        resolve_threshold=s["resolve_threshold"],
        backend=s["backend"],
        certificate_tol=s["certificate_tol"],
        on_failure=s["on_failure"],
        **rmpc_kwargs(s),
    )
    return BuiltController(_mapped(ctrl, "RMPC"), False)


def _crmpc(model: WheelModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from benchmarks.families.crmpc_options import crmpc_rmpc_kwargs
    from rmpc import CRMPC
    from rmpc.mpc.adaptation import LyapunovRule

    q, r = _weights(s)
    constrained = scenario.saturation == "constraint"
    u_max = scenario.u_max if constrained else None
    ctrl = CRMPC(
        model.polytope,
        q,
        r,
        u_max=u_max,
        input_constraint=s["input_constraint"] if constrained else None,
        adaptation=LyapunovRule(gain=s["adaptation_gain"]),
        theta_bound=s["theta_fraction"] * scenario.u_max if constrained else None,
        torque_budget=s["torque_budget"] if constrained else "none",
        rmpc_options=crmpc_rmpc_kwargs(s, {"backend": s["backend"]}),
    )
    return BuiltController(_mapped(ctrl, "CRMPC"), False)


def _gipc(model: WheelModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from rmpc import GIPC

    constrained = scenario.saturation == "constraint"
    ctrl = GIPC(
        model.polytope,
        Np=s["Np"],
        Nc=s["Nc"],
        Qy=s["Qy"],
        R_du=s["R_du"],
        u_max=scenario.u_max if constrained else None,
        du_max=s["du_max"] if constrained else None,
        backend=s["backend"],
        solver_options=None if s["solver_options"] is None else dict(s["solver_options"]),
    )
    return BuiltController(_mapped(ctrl, "GIPC"), False)


#: Controller name -> factory ``(WheelModel, scenario, settings) -> BuiltController``.
CONTROLLERS: Mapping[str, Callable[[Any, Any, Mapping[str, Any]], BuiltController]] = {
    "ABFTC": _abftc,
    "RMPC": _rmpc,
    "CRMPC": _crmpc,
    "GIPC": _gipc,
}

#: Controllers that design for the torque limit themselves (``saturation = "constraint"``).
CONSTRAINED = ("RMPC", "CRMPC", "GIPC")


def settings_check(controller: str, out: dict[str, Any], where: str) -> None:
    """Checks between the settings of one controller."""
    if controller == "RMPC" and out["resolve_threshold"] > 1.0:
        raise ConfigError(f"{where}.resolve_threshold", "a level in (0, 1]", repr(out["resolve_threshold"]))
    if controller == "CRMPC" and out["theta_fraction"] >= 1.0:
        raise ConfigError(
            f"{where}.theta_fraction", "a fraction of u_max in (0, 1)", repr(out["theta_fraction"])
        )
    if controller == "GIPC":
        check_horizon(out["Np"], f"{where}.Np")
    if controller == "GIPC" and out["Nc"] > out["Np"]:
        raise ConfigError(f"{where}.Nc", f"an integer <= Np = {out['Np']}", repr(out["Nc"]))
