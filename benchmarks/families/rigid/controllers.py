"""The controller registry of the benchmarks: names to factories, and their settings.

Each factory takes the controller's polytope, the scenario and the effective settings (the
defaults of :data:`benchmarks.families.rigid.defaults.CONTROLLER_DEFAULTS` updated by the scenario's
``settings``) and returns the controller. How saturation is handled:

- ``"constraint"``: the controller's own constraint (RMPC and OfflineRMPC: the input
  ellipsoid ``||u||_2 <= u_max`` or, with ``input_constraint = "peak"``, ``|u_j| <= u_max``;
  GIPC: ``|u| <= u_max`` and ``|du| <= du_max``; CRMPC and CRMPC-MIT: the torque budget, the
  inner RMPC solved with what the disturbance correction leaves of ``u_max``, so the applied
  torque stays inside the limit without a limiter; the setting ``limiter = true`` adds one
  anyway, and ``torque_budget = "none"`` (no guarantee) always does). LQR has no constraint
  and refuses this mode.
- ``"limiter"``: no constraint in the controller and a per-axis clip at ``u_max`` in the loop.
- ``"none"``: neither.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from benchmarks.core.family import BuiltController, check_ellipsoid_count, check_horizon
from toolkit_common.errors import ConfigError

if TYPE_CHECKING:
    from models import PolytopicModel

__all__ = ["CONSTRAINED", "CONTROLLERS", "settings_check"]


def _weights(settings: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    return np.diag(settings["Q_diag"]), np.diag(settings["R_diag"])


def _rmpc(poly: PolytopicModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from benchmarks.families.rmpc_forms import rmpc_kwargs
    from rmpc.mpc.robust_mpc import RMPC

    q, r = _weights(s)
    constrained = scenario.saturation == "constraint"
    if scenario.kinematics == "scheduled":
        from models import RigidSatellite
        from rmpc.mpc.scheduled import ScheduledRMPC

        sched = ScheduledRMPC.for_satellite(
            RigidSatellite.paper_p(), poly.dt, scenario.spread, q, r,
            u_max=scenario.u_max if constrained else None,
            input_constraint=s["input_constraint"] if constrained else None,
            mode=scenario.mode, hold_radius=s["hold_radius"], backend=s["backend"],
            formulation=s["formulation"], certificate_tol=s["certificate_tol"], on_failure=s["on_failure"],
        )
        return BuiltController(sched, scenario.saturation == "limiter")
    ctrl = RMPC(
        poly,
        q,
        r,
        u_max=scenario.u_max if constrained else None,
        input_constraint=s["input_constraint"] if constrained else None,
        resolve_threshold=s["resolve_threshold"],
        hold_radius=s["hold_radius"],
        backend=s["backend"],
        formulation=s["formulation"],
        certificate_tol=s["certificate_tol"],
        on_failure=s["on_failure"],
        **rmpc_kwargs(s),
    )
    return BuiltController(ctrl, scenario.saturation == "limiter")


def _crmpc_common(
    poly: PolytopicModel,
    scenario: Any,
    s: Mapping[str, Any],
    adaptation: Any,
) -> BuiltController:
    from benchmarks.families.crmpc_options import crmpc_rmpc_kwargs
    from rmpc.mpc.crmpc import CRMPC

    q, r = _weights(s)
    constrained = scenario.saturation == "constraint"
    budget = s["torque_budget"] if constrained else "none"
    ctrl = CRMPC(
        poly,
        q,
        r,
        u_max=scenario.u_max if constrained else None,
        input_constraint=s["input_constraint"] if constrained else None,
        theta_bound=s["theta_fraction"] * scenario.u_max,  # the projection is anti-windup in every mode
        torque_budget=budget,
        rmpc_options=crmpc_rmpc_kwargs(s, {"resolve_threshold": s["resolve_threshold"]}),
        adaptation=adaptation,
    )
    limiter = scenario.saturation == "limiter" or (
        constrained and (bool(s["limiter"]) or budget == "none")
    )
    return BuiltController(ctrl, limiter)


def _crmpc(poly: PolytopicModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from rmpc.mpc.adaptation import LyapunovRule

    # the setting adaptation_gain is the Lyapunov rule's gain g
    return _crmpc_common(poly, scenario, s, LyapunovRule(gain=s["adaptation_gain"]))


def _crmpc_mit(poly: PolytopicModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from rmpc.mpc.adaptation import MITRule

    # the settings mit_gain, normalized, alpha and reset_period are the MIT rule's
    rule = MITRule(
        gain=s["mit_gain"], normalized=s["normalized"], alpha=s["alpha"], reset_period=s["reset_period"]
    )
    return _crmpc_common(poly, scenario, s, rule)


def _gipc(poly: PolytopicModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from rmpc.mpc.gipc import GIPC

    constrained = scenario.saturation == "constraint"
    ctrl = GIPC(
        poly,
        Np=s["Np"],
        Nc=s["Nc"],
        Qy=s["Qy"],
        R_du=s["R_du"],
        u_max=scenario.u_max if constrained else None,
        du_max=s["du_max"] if constrained else None,
        backend=s["backend"],
        solver_options=None if s["solver_options"] is None else dict(s["solver_options"]),
    )
    return BuiltController(ctrl, scenario.saturation == "limiter")


def _offline(poly: PolytopicModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from rmpc.mpc.offline import OfflineRMPC

    q, r = _weights(s)
    constrained = scenario.saturation == "constraint"
    ctrl = OfflineRMPC(
        poly,
        q,
        r,
        u_max=scenario.u_max if constrained else None,
        input_constraint=s["input_constraint"] if constrained else None,
        n_ellipsoids=s["n_ellipsoids"],
        shrink=s["shrink"],
        interpolate=s["interpolate"],
        cost=s["cost"],
        backend=s["backend"],
        solver=s["solver"],
        solver_options=None if s["solver_options"] is None else dict(s["solver_options"]),
        certificate_tol=s["certificate_tol"],
        path=s["path"],
    )
    return BuiltController(ctrl, scenario.saturation == "limiter")


def _lqr(poly: PolytopicModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from rmpc.mpc.lqr import LQR

    q, r = _weights(s)
    return BuiltController(LQR(poly, q, r), scenario.saturation == "limiter")


#: Controller name -> factory ``(polytope, scenario, settings) -> BuiltController``.
CONTROLLERS: Mapping[str, Callable[[Any, Any, Mapping[str, Any]], BuiltController]] = {
    "RMPC": _rmpc,
    "GIPC": _gipc,
    "CRMPC": _crmpc,
    "CRMPC-MIT": _crmpc_mit,
    "OfflineRMPC": _offline,
    "LQR": _lqr,
}

#: Controllers that can enforce the torque limit themselves (``saturation = "constraint"``).
CONSTRAINED = ("RMPC", "GIPC", "CRMPC", "CRMPC-MIT", "OfflineRMPC")


def settings_check(controller: str, out: dict[str, Any], where: str) -> None:
    """Checks between the settings of one controller (each value is already checked on its own)."""
    if controller in ("RMPC", "CRMPC", "CRMPC-MIT") and out["resolve_threshold"] > 1.0:
        raise ConfigError(f"{where}.resolve_threshold", "a level in (0, 1]", repr(out["resolve_threshold"]))
    if "theta_fraction" in out and out["theta_fraction"] >= 1.0:
        raise ConfigError(
            f"{where}.theta_fraction", "a fraction of u_max in (0, 1) (the RMPC needs part of the limit)",
            repr(out["theta_fraction"]),
        )
    if controller == "OfflineRMPC" and out["shrink"] >= 1.0:
        raise ConfigError(f"{where}.shrink", "a number in (0, 1)", repr(out["shrink"]))
    if controller == "OfflineRMPC":
        check_ellipsoid_count(out["n_ellipsoids"], out["shrink"], f"{where}.n_ellipsoids")
    if controller == "GIPC":
        check_horizon(out["Np"], f"{where}.Np")
    if controller == "GIPC" and out["Nc"] > out["Np"]:
        raise ConfigError(f"{where}.Nc", f"an integer <= Np = {out['Np']}", repr(out["Nc"]))
