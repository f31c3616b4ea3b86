"""Paper M's MRP satellite as a plant family: scenario fields, one case simulated, metrics.

The fields (all with defaults; :mod:`benchmarks.families.mrp.defaults` holds what paper M
leaves out):

plant : {"mrp"}
    The plant family's name: the rigid satellite in MRPs relative to the orbital
    frame, RK4 at the control step, the shadow-set switch after every step.
scenario : {"M1", "M2", "M3"}
    Paper M's scenario (:func:`models.paper_m_scenario`): M1 nominal, M2 the spinning disk, M3
    the disk with an inertia error and a torque limit.
saturation : {"none", "limiter", "constraint"}
    How the torque limit ``u_max`` is met (:mod:`benchmarks.families.mrp.controllers`).
u_max : float
    Per-axis torque limit (N m, default 1; used unless ``saturation = "none"``).
inertia_scale : float or None
    The plant's inertia ``inertia_scale * J0``; ``None``: the scenario's (M3: 1.3).
spread : float
    Relative inertia uncertainty of the robust MPC's polytope, in ``[0, 1)`` (default 0.3).
kinematics : {"cover", "single"}
    The robust MPC's polytope: ``"cover"`` (default) also covers the kinematics over the box of
    attitude errors from the initial one to zero (5 deg margin); ``"single"``: linearised at the
    target only.
duration : float or None
    Run length (s); ``None``: the scenario's 100 s. The steady window is its second half.
time_scale : float
    Factor on the scenario's run length (``rmpc bench mrp --short``; no measurement).
dt : float
    Control step (s, default 0.01).
plant_step : float
    RK4 step of the plant (s, default 0.01; at most ``dt``).

Metrics beyond the core's (:func:`simulate_case`): the error angle ``4 atan|se|`` on the steady
window (the run's second half): ``err_angle_ss_max_deg``, ``err_angle_rms_deg``; and on the
*late window* ``t >= min(20 s, steady window's start)`` (:func:`late_window_start`; from 20 s on
the 100 s runs): ``td_est_err_max``, the largest ``|Tdhat_i - Td_i|`` of MAB's and TF-AB's
disk-torque estimate (N m), and the chattering pair of :func:`chattering`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from benchmarks.core.family import (
    CaseResult,
    Field,
    PlantFamily,
    check_choice,
    check_real,
    check_run_length,
    controller_specs,
)
from benchmarks.core.metrics import step_timing, total_variation_rate
from benchmarks.families.crmpc_options import (
    CRMPC_DEFAULTS,
    NOT_SETTINGS,
    check_crmpc_options,
    rmpc_options_check,
)
from benchmarks.families.mrp import defaults
from benchmarks.families.mrp.controllers import CONSTRAINED, CONTROLLERS, MRPModel, settings_check
from benchmarks.families.rmpc_forms import FORM_DEFAULTS, OUTPUT_DEFAULTS, RMPCForms
from toolkit_common.errors import ConfigError

__all__ = ["LATE_WINDOW_START", "MRP", "chattering", "late_window_start", "simulate_case"]

COVER_MARGIN_DEG = 5.0

LATE_WINDOW_START = 20.0
"""Start (s) of the late window of the observer error and the chattering metric.

Paper M's scenarios start 57.8 deg from the target: the torque peaks at ``t = 0``, the command
filter and the estimators settle within about 15 s, and from 20 s on the torque only answers the
disk (a period of its speed is 20.9 s). Measured over the slew, the torque's variation would be
the slew's, not chattering."""


def late_window_start(steady_start: float) -> float:
    """Start of the late window: :data:`LATE_WINDOW_START`, or the steady window's start if earlier.

    A run shorter than 40 s (``--short``) cannot hold 20 s of transient and a window; its late
    window is its steady window (the second half).

    Examples
    --------
    >>> late_window_start(50.0), late_window_start(2.5)
    (20.0, 2.5)
    """
    return min(LATE_WINDOW_START, steady_start)


def chattering(t: ArrayLike, u: ArrayLike, d: ArrayLike, start: float) -> dict[str, float | None]:
    """The chattering metric of a run: the torque's total variation per second on ``t >= start``.

    ``chatter_tv_rate`` is :func:`benchmarks.core.metrics.total_variation_rate` of the applied
    torque samples ``u_k`` with ``t_k >= start``, over the window's length ``t_end - start``
    (N m/s). ``chatter_ratio`` divides it by the same quantity of the disturbance torque ``d``
    (the disk's), the yardstick of a torque that follows the disk smoothly: near 1 without
    chattering, far above 1 when the law switches (paper M claims "no chattering"). ``None``
    without a disturbance or with a constant one.

    Parameters
    ----------
    t : (N + 1,) array_like
        Sample times of the run (``t_N`` its end).
    u, d : (N, 3) array_like
        Applied torque and disturbance torque per sample (``d`` may have no rows).
    start : float
        Start of the window (s), :func:`late_window_start` in the suite.

    Returns
    -------
    dict
        ``chatter_tv_rate`` (None if the window holds fewer than two samples) and ``chatter_ratio``.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(5.0)
    >>> chattering(t, [[0, 0, 0], [1, 0, 0], [0, 0, 0], [1, 0, 0]], [[0, 0, 0], [0.5, 0, 0]] * 2, 0.0)
    {'chatter_tv_rate': 0.75, 'chatter_ratio': 2.0}
    """
    t = np.asarray(t, dtype=float)
    late = t[:-1] >= start
    if late.sum() < 2:
        return {"chatter_tv_rate": None, "chatter_ratio": None}
    length = float(t[-1] - start)
    tv_u = total_variation_rate(np.asarray(u, dtype=float)[late], length)
    d = np.asarray(d, dtype=float)
    tv_d = total_variation_rate(d[late], length) if d.size else 0.0
    return {"chatter_tv_rate": tv_u, "chatter_ratio": tv_u / tv_d if tv_d > 0 else None}


def _positive(value: Any, where: str) -> float:
    return check_real(value, where, low=0.0, low_open=True)


def _optional_positive(value: Any, where: str) -> float | None:
    return None if value is None else _positive(value, where)


FIELDS: Mapping[str, Field] = {
    "plant": Field("mrp", lambda v, w: check_choice(v, w, ("mrp",))),
    "scenario": Field("M2", lambda v, w: check_choice(v, w, ("M1", "M2", "M3"))),
    "saturation": Field("none", lambda v, w: check_choice(v, w, ("none", "limiter", "constraint"))),
    "u_max": Field(defaults.U_MAX, _positive),
    "inertia_scale": Field(None, _optional_positive),
    "spread": Field(0.3, lambda v, w: check_real(v, w, low=0.0, high=1.0, high_open=True)),
    "kinematics": Field("cover", lambda v, w: check_choice(v, w, ("cover", "single"))),
    "duration": Field(None, _optional_positive),
    "time_scale": Field(1.0, lambda v, w: check_real(v, w, low=0.0, high=1.0, low_open=True)),
    "dt": Field(0.01, _positive),
    "plant_step": Field(0.01, _positive),
}


def _check(values: dict[str, Any], controller: str, name: Callable[[str], str]) -> None:
    if values["saturation"] == "constraint" and controller not in CONSTRAINED:
        return  # the core's unsupported() names it
    if values["plant_step"] > values["dt"]:
        raise ConfigError(name("plant_step"), f"at most dt = {values['dt']:g} s", repr(values["plant_step"]))
    if values["duration"] is not None and values["duration"] < values["dt"]:
        expected = f"at least one sample (dt = {values['dt']:g} s)"
        raise ConfigError(name("duration"), expected, repr(values["duration"]))
    if values["duration"] is None:  # the scenario's own length, in samples of dt
        from models import paper_m_scenario

        length = paper_m_scenario(values["scenario"]).duration * values["time_scale"]
        check_run_length(length, values["dt"], name("dt"))


def _label(scenario: Any) -> str:
    parts = [scenario.controller, scenario.scenario, scenario.saturation]
    if scenario.inertia_scale is not None:
        parts.append(f"J x{scenario.inertia_scale:g}")
    return " ".join(parts)


def paper_scenario(scenario: Any) -> Any:
    """The :class:`models.mrp.scenarios.PaperMScenario` of a case (its length, step, inertia)."""
    from models import paper_m_scenario

    base = paper_m_scenario(scenario.scenario)
    duration = scenario.duration if scenario.duration is not None else base.duration * scenario.time_scale
    overrides: dict[str, Any] = {"duration": duration, "dt": scenario.dt}
    if scenario.inertia_scale is not None:
        overrides["inertia_scale"] = scenario.inertia_scale
    return paper_m_scenario(scenario.scenario, **overrides)


def simulate_case(scenario: Any, settings: Mapping[str, Any], keep_trace: bool) -> CaseResult:
    """Build paper M's satellite, the disk, the controller (and the RMPC polytope); run; measure."""
    from models import RigidSatellite, TorqueLimiter
    from models.attitude.mrp import mrp_error_angle
    from models.mrp.tracking import RMPCStateMap
    from rmpc import simulate
    from rmpc.sim.plants import SampledPlant

    case = paper_scenario(scenario)
    model = case.model()
    state_map = RMPCStateMap(case.sigma_ref, model.mean_motion)
    x0 = case.initial_state()
    poly = None
    if scenario.controller in ("RMPC", "CRMPC"):
        rigid = RigidSatellite(np.diag(model.inertia).tolist())
        if scenario.kinematics == "cover":
            half = np.abs(state_map(x0)[:3]) + math.radians(COVER_MARGIN_DEG)
            half[2] = 0.0  # yaw does not enter the kinematics matrix
            poly = rigid.polytope(np.zeros(6), scenario.dt, scenario.spread, attitude_range=half)
        else:
            poly = rigid.polytope(np.zeros(6), scenario.dt, scenario.spread)
    built = CONTROLLERS[scenario.controller](
        MRPModel(model, case.sigma_ref, poly, state_map), scenario, settings
    )
    limiter = TorqueLimiter(scenario.u_max) if built.needs_limiter else None
    plant = SampledPlant(case.true_satellite(), scenario.dt, integrator="RK4", substep=scenario.plant_step)
    traj = simulate(
        built.controller, plant, x0, duration=case.duration, disturbance=case.disturbance(), limiter=limiter
    )
    phi = np.degrees([mrp_error_angle(x[:3], case.sigma_ref) for x in traj.x])
    lo, hi = case.steady_window
    window = (traj.t >= lo) & (traj.t <= hi)
    late_start = late_window_start(lo)
    err = np.array([state_map(x)[:3] for x in traj.x])
    metrics: dict[str, Any] = {
        "final_abs_err": {ax: float(abs(err[-1, i])) for i, ax in enumerate(("roll", "pitch", "yaw"))},
        "sum_abs_err": {ax: float(np.abs(err[:, i]).sum()) for i, ax in enumerate(("roll", "pitch", "yaw"))},
        "err_angle_initial_deg": float(phi[0]),
        "err_angle_ss_max_deg": float(phi[window].max()) if window.any() else None,
        "err_angle_rms_deg": float(np.sqrt(np.mean(phi[window] ** 2))) if window.any() else None,
        "err_angle_final_deg": float(phi[-1]),
        "max_abs_u": float(np.abs(traj.u_applied).max()),
        "max_abs_u_time": float(traj.t[int(np.abs(traj.u_applied).max(axis=1).argmax())]),
        "max_abs_u_cmd": float(np.abs(traj.u_cmd).max()),
    }
    metrics.update(step_timing(traj))
    metrics.update(chattering(traj.t, traj.u_applied, traj.d, late_start))
    estimate = [info.extra.get("torque_estimate") if info is not None else None for info in traj.info]
    if traj.d.size and all(e is not None for e in estimate):
        est = np.asarray(estimate, dtype=float)
        late = traj.t[:-1] >= late_start
        metrics["td_est_err_max"] = float(np.abs(est[late] - traj.d[late]).max()) if late.any() else None
    extra = {
        "duration_used": traj.n_steps * traj.dt,  # what ran (whole samples of dt)
        "steady_window": [lo, hi],
        "late_window": [late_start, hi],
        "inertia_scale_used": case.inertia_scale,
        "disk": case.disk,
        "initial_error_deg": case.initial_error_deg,
        "n_vertices": None if poly is None else poly.n_vertices,
        "limiter_in_loop": limiter is not None,
        "notes": list(case.settings()["notes"]),
    }
    trace: dict[str, np.ndarray] = {}
    if keep_trace:
        trace = {
            "t": traj.t,
            "x": traj.x,
            "u_cmd": traj.u_cmd,
            "u_applied": traj.u_applied,
            "d": traj.d,
            "error_angle_deg": phi,
        }
        if "td_est_err_max" in metrics:
            trace["torque_estimate"] = np.asarray(estimate, dtype=float)
    return CaseResult(extra, metrics, trace)


#: The robust MPC's forms as settings of the controller "RMPC" (benchmarks.families.rmpc_forms).
FORMS = RMPCForms(6, output_settings=True)
#: The inner RMPC's keyword CRMPC's own setting sets (not in settings.rmpc_options).
_OWN = ("backend",)
_SETTING_CHECKS = MappingProxyType(
    {**FORMS.setting_checks(), "rmpc_options": rmpc_options_check(FORMS.setting_checks(), _OWN)}
)


def _case_check(
    values: dict[str, Any], controller: str, settings: Mapping[str, Any], name: Callable[[str], str]
) -> None:
    """The RMPC's forms with the case's bounds; CRMPC's rmpc_options by its constructor."""
    if controller == "CRMPC":
        own = {key: settings[key] for key in _OWN}
        constrained = values["saturation"] == "constraint"
        check_crmpc_options(settings, own, FORMS.n_states, constrained, name("settings"))
    FORMS.check_case(values, controller, settings, name)


MRP = PlantFamily(
    name="mrp",
    description="paper M's rigid satellite in MRPs on its orbit, with the spinning disk (M1-M3)",
    fields=FIELDS,
    controllers=controller_specs(
        CONTROLLERS,
        {
            **defaults.CONTROLLER_DEFAULTS,
            "RMPC": {**defaults.CONTROLLER_DEFAULTS["RMPC"], **FORM_DEFAULTS, **OUTPUT_DEFAULTS},
            # the inner RMPC's further keywords (left out of a record at their default, None)
            "CRMPC": {**defaults.CONTROLLER_DEFAULTS["CRMPC"], **CRMPC_DEFAULTS},
        },
        CONSTRAINED,
    ),
    simulate=simulate_case,
    check=_check,
    label=_label,
    setting_choices=defaults.SETTING_CHOICES,
    zero_allowed=frozenset({"adaptation_gain"}),
    settings_check=settings_check,
    setting_checks=_SETTING_CHECKS,
    quiet_settings=frozenset(FORM_DEFAULTS) | frozenset(OUTPUT_DEFAULTS) | frozenset(CRMPC_DEFAULTS),
    case_check=_case_check,
    not_settings=NOT_SETTINGS,
)
