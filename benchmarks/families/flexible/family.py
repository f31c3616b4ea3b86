"""Paper V's flexible satellite as a plant family: scenario fields, one case simulated, metrics.

The fields (all with defaults; :mod:`benchmarks.families.flexible.defaults` holds what papers S
and V leave out):

plant : {"flexible"}
    The plant family's name: the hub with four flexible modes and the PZT channel
    (:class:`models.FlexibleSatellite`, Di Gennaro's published 4-mode set), quaternion attitude,
    integrated by DOP853 (rtol 1e-8) between samples.
experiment : {"vslew", "steady", "small"}
    The run: paper V's V-slew (:func:`models.flexible.scenario.paper_v_scenario`, 160 deg,
    150 s, the assumed hub disturbance ``d(t)``), the steady-error study
    (:func:`models.flexible.scenario.steady_error_scenario`: at the target under a constant
    0.05 N m per axis, 250 s) or the small-angle slew (10 deg, 200 s, where the linear model
    of the robust MPC holds).
angle_deg : float or None
    Slew angle (deg) about ``(1, 1, 1)/sqrt(3)``; ``None``: the experiment's (160, 0, 10).
saturation : {"none", "limiter", "constraint"}
    How the hub-torque limit ``u_max`` is met (:mod:`benchmarks.families.flexible.controllers`);
    default ``"limiter"``, ``"constraint"`` for ``RMPC`` and ``OfflineRMPC``.
u_max : float
    Per-axis hub-torque limit (N m, default 2).
avc : bool
    Paper V's robust active vibration control by the PZT voltages with the attitude law
    (:class:`rmpc.FlexibleHybrid`); the record's ``label`` and ``settings.controller_name`` then
    read ``"<controller>+AVC"`` (the record's ``controller`` stays the attitude law's name).
switch : {"tanh", "sign"}
    CSMC's switching function (MTSMC always uses ``tanh(sigma/epsilon)``).
epsilon : float
    Boundary layer (rad/s) of the tanh switching term (default 0.01).
integral_gain : float
    MTSMC's integral gain ``k_I`` (1/s^2, default 0; ``theta_I = 5 deg``).
duration : float or None
    Run length (s); ``None``: the experiment's times ``time_scale``.
time_scale : float
    Factor on the experiment's run length (``rmpc bench flexible --short``; no measurement).
dt : float
    Control period (s): default 0.01, 0.5 for ``RMPC`` and ``OfflineRMPC`` (their LMIs).
handover_deg : float or None
    ``OfflineRMPC`` only: MTSMC slews until the rotation error first falls below this angle
    (deg), then the robust MPC takes over, its table designed from the state at the hand-over
    (:class:`benchmarks.families.flexible.controllers.HandOver`; run it at ``dt = 0.01``).
    The record's ``settings.controller_name`` is then ``"MTSMC>OfflineRMPC"``.
modal_bound : float or None
    ``RMPC`` and ``OfflineRMPC`` only: a bound (kg^1/2 m, the unit of the modal coordinates
    ``eta`` of the hybrid-coordinate model) on every ``|eta_i|``, through Kothare's output
    constraint (:func:`benchmarks.families.flexible.controllers.modal_output`). Guaranteed at the
    samples for the linear polytope only; the nonlinear plant with its disturbance is measured
    (the record's ``eta_peak_over_bound``). ``None`` (default): no bound.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from benchmarks.core.family import (
    CaseResult,
    Field,
    PlantFamily,
    check_bool,
    check_choice,
    check_real,
    check_run_length,
    controller_specs,
)
from benchmarks.core.metrics import step_timing
from benchmarks.families.controller_options import OFFLINE_DEFAULTS, OFFLINE_QUIET, check_offline_options
from benchmarks.families.crmpc_options import NOT_SETTINGS
from benchmarks.families.flexible import defaults
from benchmarks.families.flexible.controllers import (
    CONSTRAINED,
    CONTROLLERS,
    PD_LIKE,
    FlexibleModel,
    settings_check,
)
from benchmarks.families.rmpc_forms import FORM_DEFAULTS, RMPCForms
from toolkit_common.errors import ConfigError

__all__ = ["FLEXIBLE", "eta1_frequency", "simulate_case"]

#: Design state of OfflineRMPC when a run starts at the target (deg about the slew axis).
DESIGN_ANGLE_DEG = 5.0


def _positive(value: Any, where: str) -> float:
    return check_real(value, where, low=0.0, low_open=True)


def _optional_positive(value: Any, where: str) -> float | None:
    return None if value is None else _positive(value, where)


def _optional_angle(value: Any, where: str) -> float | None:
    return None if value is None else check_real(value, where, low=0.0, high=180.0)


FIELDS: Mapping[str, Field] = {
    "plant": Field("flexible", lambda v, w: check_choice(v, w, ("flexible",))),
    "experiment": Field("vslew", lambda v, w: check_choice(v, w, tuple(defaults.EXPERIMENT_ANGLES))),
    "angle_deg": Field(None, _optional_angle),
    "saturation": Field("limiter", lambda v, w: check_choice(v, w, ("none", "limiter", "constraint"))),
    "u_max": Field(defaults.U_MAX, _positive),
    "avc": Field(False, check_bool),
    "switch": Field("tanh", lambda v, w: check_choice(v, w, ("tanh", "sign"))),
    "epsilon": Field(0.01, _positive),
    "integral_gain": Field(0.0, lambda v, w: check_real(v, w, low=0.0)),
    "duration": Field(None, _optional_positive),
    "time_scale": Field(1.0, lambda v, w: check_real(v, w, low=0.0, high=1.0, low_open=True)),
    "dt": Field(defaults.SMC_PERIOD, _positive),
    "handover_deg": Field(
        None, lambda v, w: None if v is None else check_real(v, w, low=0.0, high=180.0, low_open=True)
    ),
    "modal_bound": Field(None, _optional_positive),
}


def _controller_defaults(controller: str) -> Mapping[str, Any]:
    if controller in CONSTRAINED:
        return {"dt": defaults.LINEAR_PERIOD, "saturation": "constraint"}
    if controller in defaults.LINEAR_CONTROLLERS:
        return {"dt": defaults.LINEAR_PERIOD}
    return {}


def _check(values: dict[str, Any], controller: str, name: Callable[[str], str]) -> None:
    if values["saturation"] == "constraint" and controller not in CONSTRAINED:
        return  # the core's unsupported() names it
    if values["switch"] == "sign" and controller != "CSMC":
        raise ConfigError(name("switch"), f"'tanh' for {controller} (only CSMC switches by sign)", "'sign'")
    if values["integral_gain"] > 0.0 and controller != "MTSMC":
        expected = f"0 for {controller} (only MTSMC has the integral term)"
        raise ConfigError(name("integral_gain"), expected, repr(values["integral_gain"]))
    if values["handover_deg"] is not None and controller != "OfflineRMPC":
        expected = f"none for {controller} (only OfflineRMPC takes over from MTSMC)"
        raise ConfigError(name("handover_deg"), expected, repr(values["handover_deg"]))
    if values["modal_bound"] is not None and controller not in CONSTRAINED:
        expected = f"none for {controller} (only RMPC and OfflineRMPC take an output constraint)"
        raise ConfigError(name("modal_bound"), expected, repr(values["modal_bound"]))
    if values["duration"] is not None and values["duration"] < values["dt"]:
        expected = f"at least one sample (dt = {values['dt']:g} s)"
        raise ConfigError(name("duration"), expected, repr(values["duration"]))
    if values["duration"] is None:  # the experiment's own length, in samples of dt
        length = max(defaults.EXPERIMENT_DURATIONS[values["experiment"]] * values["time_scale"], values["dt"])
        check_run_length(length, values["dt"], name("dt"))


def controller_name(scenario: Any) -> str:
    """The record name of the closed loop: the controller, ``"+AVC"`` with vibration control."""
    base = scenario.controller if scenario.handover_deg is None else "MTSMC>" + scenario.controller
    if scenario.controller == "PD" and scenario.settings.get("disturbance_observer"):
        base = "PD-DOB"  # the law's own name
    return base + ("+AVC" if scenario.avc else "")


def _label(scenario: Any) -> str:
    parts = [controller_name(scenario), scenario.experiment, scenario.saturation]
    if scenario.controller == "CSMC":
        parts.append(scenario.switch)
    if scenario.controller in ("MTSMC", "CSMC"):
        parts.append(f"eps {scenario.epsilon:g}")
        gain = "alpha_f" if scenario.controller == "MTSMC" else "lam"
        value = scenario.settings[gain]
        if value != defaults.CONTROLLER_DEFAULTS[scenario.controller][gain]:
            parts.append(f"{gain} {value:g}")
    if scenario.integral_gain > 0.0:
        parts.append(f"k_I {scenario.integral_gain:g}")
    if scenario.handover_deg is not None:
        parts.append(f"hand-over {scenario.handover_deg:g} deg")
    polytope = scenario.settings.get("polytope", "groups") if scenario.controller in CONSTRAINED else "groups"
    if polytope != "groups":
        parts.append(f"polytope {polytope}")
    if scenario.modal_bound is not None:
        parts.append(f"|eta| <= {scenario.modal_bound:g}")
    return " ".join(parts)


def paper_scenario(scenario: Any) -> Any:
    """The :class:`models.flexible.scenario.VSlewScenario` of a case (its angle, length, step)."""
    from models.flexible.scenario import paper_v_scenario, steady_error_scenario

    kind = scenario.experiment
    angle = scenario.angle_deg if scenario.angle_deg is not None else defaults.EXPERIMENT_ANGLES[kind]
    duration = scenario.duration
    if duration is None:
        duration = max(defaults.EXPERIMENT_DURATIONS[kind] * scenario.time_scale, scenario.dt)
    make = steady_error_scenario if kind == "steady" else paper_v_scenario
    return make(angle_deg=angle, duration=duration, dt=scenario.dt, u_max=scenario.u_max)


def _polytope(sat: Any, dt: float, kind: str) -> Any:
    if kind == "nominal":
        return sat.linear_model(dt=dt, attitude="quaternion")
    return sat.polytope(dt=dt, attitude="quaternion", mode=kind)


def _design_state(sat: Any, case: Any) -> np.ndarray:
    from models.attitude.quaternion import quat_from_axis_angle

    x = sat.linear_state(case.initial_state())
    if np.linalg.norm(x) > 1e-9:
        return x
    q = quat_from_axis_angle(case.axis, np.deg2rad(DESIGN_ANGLE_DEG))
    return sat.linear_state(sat.state(q))


def _bandwidth(scenario: Any, settings: Mapping[str, Any], sat: Any, gain: np.ndarray | None) -> float | None:
    """The attitude loop's bandwidth (rad/s) for paper S's regime label (see the defaults)."""
    if scenario.controller == "MTSMC":
        return settings["alpha_f"] / 2.0
    if scenario.controller in ("CSMC", "ASMC"):
        return settings["lam"] / 2.0
    if scenario.controller in PD_LIKE:
        k_p, k_d = (settings[key] for key in PD_LIKE[scenario.controller])
        jinv = np.linalg.inv(sat.inertia)
        a = np.block([[np.zeros((3, 3)), 0.5 * np.eye(3)], [-k_p * jinv, -k_d * jinv]])
        return float(np.abs(np.linalg.eigvals(a)).max())
    if gain is None:
        return None
    a, b = sat.discretize(dt=scenario.dt, attitude="quaternion")
    z = np.linalg.eigvals(a[:6, :6] + b[:6] @ np.asarray(gain)[:, :6])
    return float(np.abs(np.log(z.astype(complex))).max() / scenario.dt)


def _linear_gain(ctrl: Any, traj: Any) -> np.ndarray | None:
    """The state-feedback gain near the target: LQR's, OfflineRMPC's innermost, RMPC's first solve."""
    inner = getattr(getattr(ctrl, "attitude", None), "controller", None)
    if inner is None:
        return None
    if hasattr(inner, "F"):
        return np.asarray(inner.F)
    table = getattr(inner, "table", None)
    if table is not None and table.n_ellipsoids:
        return np.asarray(table.ellipsoids[-1].F)
    for info in traj.info:
        sol = None if info is None else (info.extra or {}).get("solution")
        if sol is not None and getattr(sol, "F", None) is not None:
            return np.asarray(sol.F)
    return None


def eta1_frequency(t: np.ndarray, eta1: np.ndarray) -> float | None:
    """Frequency (rad/s) of ``eta_1`` from its mean-removed zero crossings (``None``: too few)."""
    y = np.asarray(eta1) - np.mean(eta1)
    idx = np.flatnonzero(np.sign(y[:-1]) * np.sign(y[1:]) < 0)
    if idx.size < 3:
        return None
    tc = t[idx] - y[idx] * (t[idx + 1] - t[idx]) / (y[idx + 1] - y[idx])
    return float(np.pi * (idx.size - 1) / (tc[-1] - tc[0]))


def simulate_case(scenario: Any, settings: Mapping[str, Any], keep_trace: bool) -> CaseResult:
    """Build the flexible satellite, the case's run and controller; simulate; measure."""
    import time

    from benchmarks.families.flexible.metrics import flexible_metrics
    from rmpc import simulate
    from rmpc.sim.plants import SampledPlant

    case = paper_scenario(scenario)
    sat = case.satellite
    x0 = case.initial_state()
    poly, x_design = None, None
    if scenario.controller in CONSTRAINED:
        poly = _polytope(sat, scenario.dt, settings["polytope"])
        x_design = _design_state(sat, case)
    start = time.perf_counter()
    built = CONTROLLERS[scenario.controller](
        FlexibleModel(sat, scenario.dt, poly, x_design), scenario, settings
    )
    build_time = time.perf_counter() - start
    limiter = case.limiter() if built.needs_limiter else None
    plant = SampledPlant(sat, scenario.dt, rtol=1e-8)
    traj = simulate(built.controller, plant, x0, case.duration, limiter=limiter, disturbance=case.disturbance)
    gain = _linear_gain(built.controller, traj)
    bandwidth = _bandwidth(scenario, settings, sat, gain)
    fm = flexible_metrics(traj, sat, bandwidth=bandwidth)
    euler = np.abs([sat.linear_state(x, attitude="euler")[:3] for x in traj.x])  # error 3-2-1 angles
    err = euler[-1]
    error_deg = np.degrees(np.linalg.norm(euler, axis=1))
    n = sat.n_modes
    half = traj.t >= traj.t[-1] / 2.0
    metrics: dict[str, Any] = {
        "final_abs_err": {ax: float(err[i]) for i, ax in enumerate(("roll", "pitch", "yaw"))},
        "sum_abs_err": {ax: float(euler[:, i].sum()) for i, ax in enumerate(("roll", "pitch", "yaw"))},
        "max_abs_u": fm["peak_u"],
        **{k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in fm.items()},
        "final_error_deg": float(np.degrees(fm["final_error"])),
        "rms_error_tail_deg": float(np.degrees(fm["rms_error_tail"])),
        "settled": bool(np.isfinite(fm["t_s"])),
        "bandwidth": bandwidth,
        "eta1_frequency": eta1_frequency(traj.t[half], traj.x[half, 7]) if n else None,
        "build_time_s": build_time,
    }
    if "regime" not in metrics:
        metrics["regime"] = None
    metrics.update(step_timing(traj))
    if scenario.controller in CONSTRAINED:
        fallbacks = [bool(getattr(info, "fallback", False)) for info in traj.info if info is not None]
        metrics["fallback_steps"] = sum(fallbacks)
        metrics["eta_peak_over_bound"] = (
            None if scenario.modal_bound is None else max(fm["eta_peak"]) / scenario.modal_bound
        )
    inner = getattr(getattr(built.controller, "attitude", None), "controller", None)
    table = getattr(inner, "table", None)
    extra = {
        "controller_name": controller_name(scenario),
        "duration_used": traj.n_steps * traj.dt,  # what ran (whole samples of dt)
        "angle_deg_used": case.angle_deg,
        "n_vertices": None if poly is None else poly.n_vertices,
        "n_ellipsoids": None if table is None else table.n_ellipsoids,
        "offline_stop_reason": None if table is None else table.stop_reason,
        "offline_design_time_s": None if table is None else table.design_time,
        "limiter_in_loop": limiter is not None,
        "mode1_axis": "xyz"[int(np.argmax(np.abs(sat.coupling[0])))],
        "handover_time": _handover_time(built.controller, traj),
        "first_mode_frequency": float(sat.frequencies[0]) if n else None,
    }
    trace: dict[str, np.ndarray] = {}
    if keep_trace:
        trace = {
            "t": traj.t,
            "error_deg": np.asarray(error_deg),
            "u": traj.u_applied[:, :3],
            "v": traj.u_applied[:, 3:],
            "eta": traj.x[:, 7 : 7 + n],
            "w": traj.x[:, 4:7],
        }
    return CaseResult(extra, metrics, trace)


def _handover_time(ctrl: Any, traj: Any) -> float | None:
    step = getattr(getattr(ctrl, "attitude", None), "handover_step", None)
    return None if step is None else float(traj.t[step])


#: The robust MPC's forms as settings of the controller "RMPC" (benchmarks.families.rmpc_forms).
FORMS = RMPCForms(14, has_output=lambda values: values["modal_bound"] is not None)
#: The RMPC's and OfflineRMPC's output bounds are the field modal_bound's (not settings).
_OUTPUT_NOT_SETTINGS = {
    key: "the flexible satellite's output bounds are its modal coordinates', set by the field modal_bound"
    for key in ("output_matrix", "y_max")
}



def _case_check(
    values: dict[str, Any], controller: str, settings: Mapping[str, Any], name: Callable[[str], str]
) -> None:
    """The RMPC's forms with the case's bounds; OfflineRMPC's solve options by its constructor."""
    if controller == "OfflineRMPC":
        check_offline_options(settings, name("settings"))
    FORMS.check_case(values, controller, settings, name)


FLEXIBLE = PlantFamily(
    name="flexible",
    description="paper V's flexible satellite (4 modes, PZT channel): the V-slew, steady error, small slew",
    fields=FIELDS,
    controllers=controller_specs(
        CONTROLLERS,
        {
            **defaults.CONTROLLER_DEFAULTS,
            "RMPC": {**defaults.CONTROLLER_DEFAULTS["RMPC"], **FORM_DEFAULTS},
            # Kothare's or the nominal cost of the table (left out of a record at its default)
            "OfflineRMPC": {
                **defaults.CONTROLLER_DEFAULTS["OfflineRMPC"],
                "cost": FORM_DEFAULTS["cost"],
                **OFFLINE_DEFAULTS,  # backend, solver_options, certificate_tol
            },
        },
        CONSTRAINED,
    ),
    simulate=simulate_case,
    check=_check,
    label=_label,
    setting_choices=defaults.SETTING_CHOICES,
    zero_allowed=frozenset({"w_weight", "eta_weight"}),
    settings_check=settings_check,
    controller_defaults=_controller_defaults,
    setting_checks=FORMS.setting_checks(),
    quiet_settings=frozenset(FORM_DEFAULTS) | OFFLINE_QUIET,
    case_check=_case_check,
    not_settings={**NOT_SETTINGS, **_OUTPUT_NOT_SETTINGS},
)
