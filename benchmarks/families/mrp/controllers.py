"""The controllers of paper M's benchmarks and how each meets the torque limit.

``saturation``: ``"none"`` (no limit, M1 and M2), ``"limiter"`` (paper M's controllers clip
their torque per axis at ``u_max``, which is what their own ``u_max`` option does) or
``"constraint"`` (RMPC and CRMPC: a per-axis peak bound in the LMIs, CRMPC with the torque
budget). The robust MPC sees the error attitude (3-2-1 angles of the body relative to the
target) and the rates relative to the orbital frame, through :class:`rmpc.MappedController`
and :class:`models.mrp.tracking.RMPCStateMap`; paper M's controllers see the MRP state.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from benchmarks.core.family import BuiltController
from toolkit_common.errors import ConfigError

__all__ = ["CONSTRAINED", "CONTROLLERS", "MRPModel", "settings_check"]


class MRPModel:
    """What the controllers are built on: paper M's model, the target, the RMPC polytope and map."""

    def __init__(self, model: Any, target: np.ndarray, polytope: Any, state_map: Any) -> None:
        self.model = model
        self.target = target
        self.polytope = polytope
        self.state_map = state_map


def _limit(scenario: Any) -> float | None:
    return None if scenario.saturation == "none" else scenario.u_max


def _bs(m: MRPModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from rmpc import CFBackstepping

    ctrl = CFBackstepping(m.model, m.target, c1=s["c1"], c2=s["c2"], dt=scenario.dt, u_max=_limit(scenario))
    return BuiltController(ctrl, False)


def _mab(m: MRPModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from rmpc import MAB, NESO

    observer = NESO.from_bandwidth(m.model.inertia, s["observer_bandwidth"])
    ctrl = MAB(
        m.model,
        m.target,
        c1=s["c1"],
        c2=s["c2"],
        kappa=s["kappa"],
        estimator=observer,
        dt=scenario.dt,
        u_max=_limit(scenario),
    )
    return BuiltController(ctrl, False)


def _tfab(m: MRPModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from rmpc import TuningFunctionAB

    ctrl = TuningFunctionAB(
        m.model, m.target, c1=s["c1"], c2=s["c2"], gamma=s["gamma"], dt=scenario.dt, u_max=_limit(scenario)
    )
    return BuiltController(ctrl, False)


def _mapped(ctrl: Any, m: MRPModel, name: str) -> Any:
    from rmpc import MappedController

    return MappedController(ctrl, measure=m.state_map, name=name)


def _rmpc(m: MRPModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from benchmarks.families.rmpc_forms import rmpc_kwargs
    from rmpc import RMPC

    constrained = scenario.saturation == "constraint"
    ctrl = RMPC(
        m.polytope,
        np.diag(s["Q_diag"]),
        np.diag(s["R_diag"]),
        u_max=scenario.u_max if constrained else None,
        input_constraint=s["input_constraint"] if constrained else None,
        resolve_threshold=s["resolve_threshold"],
        backend=s["backend"],
        certificate_tol=s["certificate_tol"],
        on_failure=s["on_failure"],
        **rmpc_kwargs(s),
    )
    return BuiltController(_mapped(ctrl, m, "RMPC"), scenario.saturation == "limiter")


def _crmpc(m: MRPModel, scenario: Any, s: Mapping[str, Any]) -> BuiltController:
    from benchmarks.families.crmpc_options import crmpc_rmpc_kwargs
    from rmpc import CRMPC
    from rmpc.mpc.adaptation import LyapunovRule

    constrained = scenario.saturation == "constraint"
    ctrl = CRMPC(
        m.polytope,
        np.diag(s["Q_diag"]),
        np.diag(s["R_diag"]),
        u_max=scenario.u_max if constrained else None,
        input_constraint=s["input_constraint"] if constrained else None,
        adaptation=LyapunovRule(gain=s["adaptation_gain"]),
        theta_bound=s["theta_fraction"] * scenario.u_max,
        torque_budget=s["torque_budget"] if constrained else "none",
        rmpc_options=crmpc_rmpc_kwargs(s, {"backend": s["backend"]}),
    )
    return BuiltController(_mapped(ctrl, m, "CRMPC"), scenario.saturation == "limiter")


#: Controller name -> factory ``(MRPModel, scenario, settings) -> BuiltController``.
CONTROLLERS: Mapping[str, Callable[[Any, Any, Mapping[str, Any]], BuiltController]] = {
    "BS": _bs,
    "MAB": _mab,
    "TFAB": _tfab,
    "RMPC": _rmpc,
    "CRMPC": _crmpc,
}

#: Controllers that design for the torque limit themselves (``saturation = "constraint"``).
CONSTRAINED = ("RMPC", "CRMPC")


def settings_check(controller: str, out: dict[str, Any], where: str) -> None:
    """Checks between the settings of one controller."""
    if controller == "RMPC" and out["resolve_threshold"] > 1.0:
        raise ConfigError(f"{where}.resolve_threshold", "a level in (0, 1]", repr(out["resolve_threshold"]))
    if controller == "CRMPC" and out["theta_fraction"] >= 1.0:
        expected = "a fraction of u_max in (0, 1)"
        raise ConfigError(f"{where}.theta_fraction", expected, repr(out["theta_fraction"]))
