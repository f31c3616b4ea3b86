"""Run one scenario: build plant, controller, limiter and disturbance, simulate, measure.

:func:`run_case` is the function worker processes (or Dask workers) execute; it never raises
for a failing case but returns the error, so a sweep can record it and go on.
"""

from __future__ import annotations

import time
import traceback
from typing import Any

import numpy as np

from benchmarks.families.rigid.controllers import build_controller
from benchmarks.families.rigid.defaults import SETTLING_BAND
from benchmarks.core.metrics import AXES, compute_metrics
from benchmarks.core.scenario import Scenario, initial_attitude

__all__ = ["run_case", "simulate_scenario"]


def _json_safe(value: Any) -> Any:
    """Replace NaN/inf by ``None`` and numpy scalars by Python numbers, recursively."""
    if isinstance(value, dict):
        return {str(k): _json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_json_safe(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value


def simulate_scenario(
    scenario: Scenario, experiment: str | None = None, keep_trace: bool = False
) -> tuple[dict[str, Any], dict[str, np.ndarray] | None]:
    """Simulate ``scenario``; return its record and (with ``keep_trace``) the time series.

    Parameters
    ----------
    scenario : Scenario
        The validated case.
    experiment : str, optional
        The record's ``experiment`` (default: the case id).
    keep_trace : bool
        Also return ``t, x, u_cmd, u_applied, d, gamma`` as arrays (for figures).

    Returns
    -------
    record : dict
        ``experiment, case_id, label, controller, plant, saturation, status, settings, metrics,
        wall_time_s, cpu_time_s`` (the process's CPU time, which shows how much a loaded machine
        slowed the case down).
    trace : dict of ndarray or None
    """
    from models import ReactionWheelActuator, RigidSatellite, TorqueLimiter
    from rmpc import StepDisturbance, simulate

    start, cpu_start = time.perf_counter(), time.process_time()
    sat = RigidSatellite.paper_p()
    x0 = np.concatenate((initial_attitude(scenario.initial_attitude, scenario.ic_scale), np.zeros(3)))
    if scenario.kinematics == "cover":
        middle = np.concatenate((0.5 * x0[:3], np.zeros(3)))
        half = 0.5 * np.abs(x0[:3]) + np.radians(scenario.cover_margin)
        poly = sat.polytope(middle, scenario.dt, scenario.spread, scenario.mode, attitude_range=half)
    else:
        poly = sat.polytope(x0, scenario.dt, scenario.spread, scenario.mode)
    built = build_controller(poly, scenario)
    true_sat = sat if scenario.true_inertia is None else RigidSatellite(list(scenario.true_inertia))
    limiter = TorqueLimiter(scenario.u_max) if built.needs_limiter else None
    disturbance = None
    if scenario.disturbance != 0.0:
        magnitude = np.array(
            [scenario.disturbance if ax in scenario.disturbance_axes else 0.0 for ax in AXES]
        )
        disturbance = StepDisturbance(magnitude, t_start=scenario.disturbance_start)
    actuator = ReactionWheelActuator() if scenario.actuator == "reaction_wheel" else None
    if scenario.plant == "nonlinear":
        plant, true_plant, dt = true_sat, None, scenario.dt
    else:
        plant, dt = poly, None
        true_plant = None if scenario.true_inertia is None else true_sat.discretize(x0, scenario.dt)
    traj = simulate(
        built.controller,
        plant,
        x0,
        duration=scenario.duration,
        dt=dt,
        true_plant=true_plant,
        limiter=limiter,
        disturbance=disturbance,
        actuator=actuator,
    )
    settings = scenario.to_dict()
    settings.update(
        {
            "x0": x0.tolist(),
            "true_inertia_used": np.diag(true_sat.inertia).tolist(),
            "linearization_point": x0.tolist(),
            "limiter_in_loop": limiter is not None,
            "settling_band": SETTLING_BAND,
            "n_vertices": poly.n_vertices,
        }
    )
    record = {
        "experiment": experiment if experiment is not None else scenario.case_id,
        "case_id": scenario.case_id,
        "label": scenario.label(),
        "controller": scenario.controller,
        "plant": scenario.plant,
        "saturation": scenario.saturation,
        "status": "done",
        "settings": settings,
        "metrics": compute_metrics(traj, scenario.u_max, SETTLING_BAND),
        "wall_time_s": time.perf_counter() - start,
        "cpu_time_s": time.process_time() - cpu_start,
    }
    trace = None
    if keep_trace:
        trace = {
            "t": traj.t,
            "x": traj.x,
            "u_cmd": traj.u_cmd,
            "u_applied": traj.u_applied,
            "d": traj.d,
            "gamma": traj.gamma,
        }
    return _json_safe(record), trace


def run_case(payload: dict[str, Any]) -> dict[str, Any]:
    """Worker entry point: ``payload = {"scenario": dict, "experiment": str|None, "trace": bool}``.

    Returns ``{"ok": True, "record": ..., "trace": ...}`` or, when the case raised,
    ``{"ok": False, "error": "<type>: <message>", "traceback": ...}``.
    """
    try:
        scenario = Scenario.from_dict(payload["scenario"])
        record, trace = simulate_scenario(
            scenario, experiment=payload.get("experiment"), keep_trace=bool(payload.get("trace"))
        )
        return {"ok": True, "record": record, "trace": trace}
    except Exception as err:  # a failing case is data, not a crash of the sweep
        return {
            "ok": False,
            "error": f"{type(err).__name__}: {err}".replace("\n", " "),
            "traceback": traceback.format_exc(),
        }
