"""Paper P's rigid satellite as a plant family: its scenario fields, one case simulated, its metrics.

The fields (all with defaults; ``benchmarks.families.rigid.defaults`` holds the values paper P
leaves out):

plant : {"nonlinear", "linear"}
    The simulated satellite: the nonlinear model, or the discretised linearisation at the
    initial state (the controller's model) with the true inertia.
spread : float
    Relative inertia uncertainty of the controller's polytope, in ``[0, 1)`` (default 0.3).
mode : {"scalar", "box"}
    Polytope of one inertia factor (2 vertices) or one factor per axis (8 vertices).
true_inertia : (3,) tuple of float or None
    Principal inertias of the simulated satellite (kg m^2); ``None``: paper P's.
saturation : {"constraint", "limiter", "none"}
    How the torque limit is handled (see :mod:`benchmarks.families.rigid.controllers`).
u_max : float
    Torque limit per axis (N m), > 0 (default 1).
ic_scale : float
    Factor on the initial attitude (E6: 1.3); the controller's model is linearised at the
    scaled initial state.
initial_attitude : (3,) tuple of float or None
    Initial roll, pitch, yaw in degrees (zero rates); ``None``: paper P's. ``ic_scale``
    multiplies it too.
kinematics : {"single", "cover", "scheduled"}
    How the robust MPC's polytope treats the nonlinear kinematics. ``"single"`` (paper P):
    the inertia polytope linearised at the initial attitude. ``"cover"``: the polytope also
    covers every attitude of the box from zero to the initial attitude, widened by
    ``cover_margin`` on each side (``RigidSatellite.polytope(..., attitude_range=...)``).
    ``"scheduled"``: RMPC only, the polytope rebuilt at the measured attitude every step
    (:class:`rmpc.ScheduledRMPC`).
cover_margin : float
    Widening of the covering box on each side (deg, in [0, 45]; default 5).
disturbance : float
    Step disturbance torque (N m) on each of ``disturbance_axes``; 0 for none.
disturbance_start : float
    Time of the step (s), >= 0.
disturbance_axes : tuple of {"roll", "pitch", "yaw"}
    Body axes the disturbance acts on (x, y, z).
actuator : {"none", "reaction_wheel"}
    Paper P's reaction-wheel dynamics between command and torque, or none.
duration : float
    Simulated time (s), > 0.
dt : float
    Sample time (s), > 0.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import Any

import numpy as np

from benchmarks.core.family import (
    CaseResult,
    Field,
    MonteCarlo,
    PlantFamily,
    check_choice,
    check_number,
    check_real,
    controller_specs,
)
from benchmarks.core.metrics import AXES, compute_metrics, recovery
from benchmarks.families.controller_options import (
    OFFLINE_DEFAULTS,
    OFFLINE_QUIET,
    check_gipc_solver_options,
    check_offline_options,
)
from benchmarks.families.crmpc_options import (
    CRMPC_DEFAULTS,
    NOT_SETTINGS,
    check_crmpc_options,
    rmpc_options_check,
)
from benchmarks.families.rigid import defaults
from benchmarks.families.rigid.controllers import CONSTRAINED, CONTROLLERS, settings_check
from benchmarks.families.rmpc_forms import FORM_DEFAULTS, OUTPUT_DEFAULTS, RMPCForms, changed_forms
from models import PAPER_P_INERTIA, PAPER_P_INITIAL_STATE
from toolkit_common.errors import ConfigError

__all__ = ["RIGID", "initial_attitude"]

PLANTS = ("nonlinear", "linear")
SATURATIONS = ("none", "limiter", "constraint")
MODES = ("scalar", "box")
ACTUATORS = ("none", "reaction_wheel")
KINEMATICS = ("single", "cover", "scheduled")


def initial_attitude(attitude_deg: Any, ic_scale: float) -> tuple[float, float, float]:
    """The initial roll, pitch, yaw (rad): ``attitude_deg`` (or paper P's) times ``ic_scale``."""
    if attitude_deg is None:
        base = PAPER_P_INITIAL_STATE[:3]
    else:
        base = tuple(math.radians(v) for v in attitude_deg)
    return (base[0] * ic_scale, base[1] * ic_scale, base[2] * ic_scale)


def _inertia(value: Any, where: str) -> tuple[float, float, float] | None:
    if value is None:
        return None
    ok = isinstance(value, list | tuple) and len(value) == 3
    if ok:
        nums = [check_number(v, where) for v in value]
        ok = all(v > 0 for v in nums)
    if not ok:
        raise ConfigError(where, "three principal inertias > 0 (kg m^2)", repr(value))
    return (nums[0], nums[1], nums[2])


def _axes(value: Any, where: str) -> tuple[str, ...]:
    ok = (isinstance(value, list | tuple) and len(value) > 0 and all(isinstance(v, str) for v in value)
          and len(set(value)) == len(value))
    if not ok or not all(v in AXES for v in value):
        raise ConfigError(
            where, "a non-empty list of distinct axes among 'roll', 'pitch', 'yaw'", repr(value)
        )
    return tuple(value)


def _attitude_deg(value: Any, where: str) -> tuple[float, float, float] | None:
    if value is None:
        return None
    if not (isinstance(value, list | tuple) and len(value) == 3):
        raise ConfigError(where, "three angles in degrees (roll, pitch, yaw)", repr(value))
    nums = [check_number(v, where) for v in value]
    return (nums[0], nums[1], nums[2])


def _positive(value: Any, where: str) -> float:
    return check_real(value, where, low=0.0, low_open=True)


FIELDS: Mapping[str, Field] = {
    "plant": Field("nonlinear", lambda v, w: check_choice(v, w, PLANTS)),
    "spread": Field(defaults.SPREAD, lambda v, w: check_real(v, w, low=0.0, high=1.0, high_open=True)),
    "mode": Field(defaults.MODE, lambda v, w: check_choice(v, w, MODES)),
    "true_inertia": Field(None, _inertia),
    "saturation": Field("constraint", lambda v, w: check_choice(v, w, SATURATIONS)),
    "u_max": Field(defaults.U_MAX, _positive),
    "ic_scale": Field(1.0, _positive),
    "initial_attitude": Field(None, _attitude_deg),
    "kinematics": Field("single", lambda v, w: check_choice(v, w, KINEMATICS)),
    "cover_margin": Field(5.0, lambda v, w: check_real(v, w, low=0.0, high=45.0)),
    "disturbance": Field(0.0, check_real),
    "disturbance_start": Field(defaults.DISTURBANCE_START, lambda v, w: check_real(v, w, low=0.0)),
    "disturbance_axes": Field(defaults.DISTURBANCE_AXES, _axes),
    "actuator": Field("none", lambda v, w: check_choice(v, w, ACTUATORS)),
    "duration": Field(defaults.DURATION, _positive),
    "dt": Field(defaults.DT, _positive),
}


def _check(values: dict[str, Any], controller: str, name: Callable[[str], str]) -> None:
    if values["kinematics"] == "scheduled" and controller != "RMPC":
        raise ConfigError(name("kinematics"), f"'single' or 'cover' for {controller}", "'scheduled'")
    attitude = initial_attitude(values["initial_attitude"], values["ic_scale"])
    if abs(attitude[1]) >= 0.5 * math.pi - 1e-3:
        raise ConfigError(
            name("ic_scale") if values["initial_attitude"] is None else name("initial_attitude"),
            "an initial pitch below 90 deg (3-2-1 Euler angles are singular there)",
            f"pitch {math.degrees(attitude[1]):.1f} deg",
        )


#: The forms of the RMPC on the 6 states of the satellite (roll, pitch, yaw and their rates).
FORMS = RMPCForms(6, output_settings=True)
#: The inner RMPC's keyword CRMPC's own setting sets (not in settings.rmpc_options).
_OWN = ("resolve_threshold",)
_SETTING_CHECKS = MappingProxyType(
    {**FORMS.setting_checks(), "rmpc_options": rmpc_options_check(FORMS.setting_checks(), _OWN)}
)


def _case_check(
    values: dict[str, Any], controller: str, settings: Mapping[str, Any], name: Callable[[str], str]
) -> None:
    """The forms with the case's bounds; none, nor solver options, with the scheduled polytope."""
    changed = changed_forms(settings)
    changed += [key for key in ("solver_options", "solver", "output_matrix") if settings.get(key) is not None]
    if controller == "RMPC" and changed and values["kinematics"] == "scheduled":
        expected = (
            f"'single' or 'cover' with {name('settings')}.{changed[0]} (the scheduled RMPC solves "
            "Kothare's LMIs with the default solver options and no output bounds only)"
        )
        raise ConfigError(name("kinematics"), expected, "'scheduled'")
    if controller == "GIPC":
        check_gipc_solver_options(settings, name("settings"))
    if controller == "OfflineRMPC":
        check_offline_options(settings, name("settings"))
    if controller in ("CRMPC", "CRMPC-MIT"):
        own = {key: settings[key] for key in _OWN}
        constrained = values["saturation"] == "constraint"
        check_crmpc_options(settings, own, FORMS.n_states, constrained, name("settings"))
    FORMS.check_case(values, controller, settings, name)


def _label(scenario: Any) -> str:
    parts = [scenario.controller, scenario.plant, scenario.saturation]
    if scenario.disturbance:
        parts.append(f"d={scenario.disturbance:g}")
    if scenario.ic_scale != 1.0:
        parts.append(f"ic x{scenario.ic_scale:g}")
    if scenario.initial_attitude is not None:
        parts.append("ic " + "/".join(f"{v:g}" for v in scenario.initial_attitude) + " deg")
    if scenario.kinematics != "single":
        parts.append(scenario.kinematics)
    return " ".join(parts)


def _draw_inertia(scenario: Any, u: np.ndarray) -> dict[str, Any]:
    """The true principal inertias ``J0_i (1 + spread u_i)`` (one common ``u`` in scalar mode)."""
    factors = np.full(3, u[0]) if scenario.mode == "scalar" else u
    inertia = [float(j * (1.0 + scenario.spread * f)) for j, f in zip(PAPER_P_INERTIA, factors, strict=True)]
    return {"true_inertia": inertia}


def simulate_case(scenario: Any, settings: Mapping[str, Any], keep_trace: bool) -> CaseResult:
    """Build paper P's satellite, the controller's polytope and the controller; simulate; measure."""
    from models import ReactionWheelActuator, RigidSatellite, TorqueLimiter
    from rmpc import StepDisturbance, simulate

    sat = RigidSatellite.paper_p()
    x0 = np.concatenate((initial_attitude(scenario.initial_attitude, scenario.ic_scale), np.zeros(3)))
    x_lin = x0
    if scenario.kinematics == "cover":
        middle = np.concatenate((0.5 * x0[:3], np.zeros(3)))
        x_lin = middle
        half = 0.5 * np.abs(x0[:3]) + np.radians(scenario.cover_margin)
        poly = sat.polytope(middle, scenario.dt, scenario.spread, scenario.mode, attitude_range=half)
    else:
        poly = sat.polytope(x0, scenario.dt, scenario.spread, scenario.mode)
    built = CONTROLLERS[scenario.controller](poly, scenario, settings)
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
        true_plant = None if scenario.true_inertia is None else true_sat.discretize(x_lin, scenario.dt)
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
    extra = {
        "x0": x0.tolist(),
        "duration_used": traj.n_steps * traj.dt,  # what ran: simulate rounds duration / dt to whole samples
        "true_inertia_used": np.diag(true_sat.inertia).tolist(),
        "linearization_point": x_lin.tolist(),  # of the nominal model (the linear plant without true_inertia)
        "limiter_in_loop": limiter is not None,
        "settling_band": defaults.SETTLING_BAND,
        "n_vertices": poly.n_vertices,
    }
    trace = (
        {
            "t": traj.t,
            "x": traj.x,
            "u_cmd": traj.u_cmd,
            "u_applied": traj.u_applied,
            "d": traj.d,
            "gamma": traj.gamma,
        }
        if keep_trace
        else {}
    )
    metrics = compute_metrics(traj, scenario.u_max, defaults.SETTLING_BAND)
    if scenario.disturbance != 0.0:
        onset, band = scenario.disturbance_start, defaults.RECOVERY_BAND
        metrics["recovery"] = recovery(traj.t, traj.x[:, :3], onset, band)
    return CaseResult(extra, metrics, trace)


RIGID = PlantFamily(
    name="rigid",
    description="paper P's rigid satellite (3-2-1 Euler angles, inertia polytope), linear or nonlinear",
    fields=FIELDS,
    controllers=controller_specs(
        CONTROLLERS,
        {
            **defaults.CONTROLLER_DEFAULTS,
            "RMPC": {**defaults.CONTROLLER_DEFAULTS["RMPC"], **FORM_DEFAULTS, **OUTPUT_DEFAULTS},
            # Kothare's or the nominal cost of the table (left out of a record at its default)
            "OfflineRMPC": {
                **defaults.CONTROLLER_DEFAULTS["OfflineRMPC"],
                "cost": FORM_DEFAULTS["cost"],
                **OFFLINE_DEFAULTS,  # backend, solver_options, certificate_tol
            },
            # the QP back-end's settings (left out of a record at their default, None)
            "GIPC": {**defaults.CONTROLLER_DEFAULTS["GIPC"], "solver_options": None},
            # the inner RMPC's further keywords (left out of a record at their default, None)
            "CRMPC": {**defaults.CONTROLLER_DEFAULTS["CRMPC"], **CRMPC_DEFAULTS},
            "CRMPC-MIT": {**defaults.CONTROLLER_DEFAULTS["CRMPC-MIT"], **CRMPC_DEFAULTS},
        },
        CONSTRAINED,
    ),
    simulate=simulate_case,
    check=_check,
    label=_label,
    setting_choices=defaults.SETTING_CHOICES,
    zero_allowed=frozenset({"adaptation_gain", "mit_gain", "hold_radius"}),
    settings_check=settings_check,
    montecarlo=MonteCarlo(dims=3, sets=("true_inertia",), apply=_draw_inertia),
    setting_checks=_SETTING_CHECKS,
    quiet_settings=frozenset(FORM_DEFAULTS) | frozenset(OUTPUT_DEFAULTS) | frozenset(CRMPC_DEFAULTS)
    | OFFLINE_QUIET,
    case_check=_case_check,
    not_settings=NOT_SETTINGS,
)
