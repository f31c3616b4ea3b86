"""Paper W's four-wheel satellite as a plant family: scenario fields, one case simulated, metrics.

The fields (all with defaults; ``benchmarks.families.wheel.defaults`` holds what paper W leaves
out):

plant : {"wheel"}
    The plant family's name: the nonlinear wheel satellite (RK4 at 5 ms inside the 40 ms hold, the
    wheel input stage with faults, torque and momentum limits inside the integration).
saturation : {"constraint", "limiter"}
    Whether the controller designs for the wheel torque limit (see
    :mod:`benchmarks.families.wheel.controllers`); the plant clips either way. Default:
    ``"constraint"`` for RMPC, CRMPC and GIPC, ``"limiter"`` for ABFTC (it has no constraint).
scenario : {"S1", "S2", "S3", "S4"}
    Paper W's scenario: initial attitude, faults, run length, S4's wheel disturbance
    (:func:`models.paper_w_scenario`).
fault_kind : {"scenario", "none", "stuck", "sinusoidal", "outage", "effectiveness", "bias"}
    ``"scenario"`` (default): the scenario's faults; otherwise one fault of this kind replaces
    them (``"none"``: no fault), on ``fault_wheel`` from ``fault_onset`` for ``fault_duration``
    seconds, with ``fault_value`` (N m for stuck, sinusoidal amplitude and bias; the remaining
    effectiveness in ``[0, 1]`` for effectiveness). The sinusoid's frequency is 0.2 rad/s.
fault_wheel : int
    Wheel of the fault, 1..4 (wheel 4 is the skew wheel).
fault_onset, fault_duration : float
    Start (s, before the run's end) and length (s, > 0; ``inf``: to the end).
fault_value : float
    See ``fault_kind``.
inertia_scale : float or None
    The plant's inertia is ``inertia_scale * J`` (the controllers keep ``J``); ``None``: the
    scenario's (1.2 for S4, else 1).
inertia_spread : float or None
    Relative inertia error the robust MPC's polytope covers (product with the effectiveness
    polytope); ``None``: 0.2 when the plant's inertia differs from the nominal one, else none.
gravity : {"pendulous", "inverted"}
    The imbalance torque's sign (paper W's signs conflict; the controllers' model follows it).
seed : int
    Seed of S4's wheel disturbance.
u_max : float
    Per-wheel torque bound the controllers design for (N m, default 0.123).
duration : float or None
    Run length (s); ``None``: the scenario's (60 s for S1, 150 s otherwise).
time_scale : float
    Factor on the scenario's run length and fault windows (default 1; ``rmpc bench faults
    --short`` uses a small one to check the whole path in seconds: the dynamics are not scaled,
    so such runs are no measurement).
dt : float
    Control period (s, default 0.04).
wheel_limits : bool
    Apply every wheel's torque and momentum limits in the plant (default ``true``; ``false``
    removes both, for the adaptation-gain study W5; the controllers keep their own bounds).
viscous_friction, coulomb_friction : float
    Bearing friction of every wheel in the plant, ``b`` (N m s/rad) and ``c`` (N m), see
    :class:`models.WheelSatellite` (default 0: off; the controllers do not model it).
angle_noise : float
    Standard deviation of the noise on the three measured angles, deg (default 0: off; paper W's
    sensors are accurate to 0.2 deg), drawn by :class:`models.AttitudeNoiseSensor` with ``seed``.
d_misalignment : float
    Error in the distribution matrix, deg (default 0): the plant's wheel axes are the nominal
    ones, each tilted by this angle in a direction drawn with ``seed``; the controllers keep the
    nominal ``D``. A tilt of ``a`` deg moves a unit column by ``2 sin(a/2)`` (5 deg: 8.7 %).

The last five fields are written into records and case ids only when they differ from their
defaults, so the cases that leave them alone keep their records and case ids.
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
    PlantFamily,
    check_bool,
    check_choice,
    check_real,
    check_run_length,
    controller_specs,
)
from benchmarks.core.metrics import compute_metrics
from benchmarks.families.controller_options import check_gipc_solver_options
from benchmarks.families.crmpc_options import (
    CRMPC_DEFAULTS,
    NOT_SETTINGS,
    check_crmpc_options,
    rmpc_options_check,
)
from benchmarks.families.rmpc_forms import FORM_DEFAULTS, OUTPUT_DEFAULTS, RMPCForms
from benchmarks.families.wheel import defaults
from benchmarks.families.wheel.controllers import CONSTRAINED, CONTROLLERS, WheelModel, settings_check
from toolkit_common.errors import ConfigError
from toolkit_common.validation import is_integer, is_real

__all__ = ["WHEEL", "case_faults", "misaligned_axes", "simulate_case"]

SCENARIOS = ("S1", "S2", "S3", "S4")
FAULT_KINDS = ("scenario", "none", "stuck", "sinusoidal", "outage", "effectiveness", "bias")
SINE_FREQUENCY = 0.2


def _positive(value: Any, where: str) -> float:
    return check_real(value, where, low=0.0, low_open=True)


def _optional_positive(value: Any, where: str) -> float | None:
    return None if value is None else _positive(value, where)


def _duration(value: Any, where: str) -> float:
    if is_real(value) and value == math.inf:
        return math.inf
    return _positive(value, where)


def _wheel(value: Any, where: str) -> int:
    if not is_integer(value) or not 1 <= value <= 4:
        raise ConfigError(where, "a wheel number 1..4 (wheel 4 is the skew wheel)", repr(value))
    return int(value)


def _seed(value: Any, where: str) -> int:
    if not is_integer(value) or value < 0:
        raise ConfigError(where, "an integer >= 0", repr(value))
    return int(value)


def _spread(value: Any, where: str) -> float | None:
    return None if value is None else check_real(value, where, low=0.0, high=1.0, high_open=True)


FIELDS: Mapping[str, Field] = {
    "plant": Field("wheel", lambda v, w: check_choice(v, w, ("wheel",))),
    "scenario": Field("S1", lambda v, w: check_choice(v, w, SCENARIOS)),
    "saturation": Field("constraint", lambda v, w: check_choice(v, w, ("constraint", "limiter"))),
    "fault_kind": Field("scenario", lambda v, w: check_choice(v, w, FAULT_KINDS)),
    "fault_wheel": Field(2, _wheel),
    "fault_onset": Field(8.0, lambda v, w: check_real(v, w, low=0.0)),
    "fault_duration": Field(math.inf, _duration),
    "fault_value": Field(0.05, check_real),
    "inertia_scale": Field(None, _optional_positive),
    "inertia_spread": Field(None, _spread),
    "gravity": Field("pendulous", lambda v, w: check_choice(v, w, ("pendulous", "inverted"))),
    "seed": Field(0, _seed),
    "u_max": Field(defaults.U_MAX, _positive),
    "duration": Field(None, _optional_positive),
    "time_scale": Field(1.0, lambda v, w: check_real(v, w, low=0.0, high=1.0, low_open=True)),
    "dt": Field(defaults.DT, _positive),
    "wheel_limits": Field(True, check_bool, written_at_default=False),
    "viscous_friction": Field(0.0, lambda v, w: check_real(v, w, low=0.0), written_at_default=False),
    "coulomb_friction": Field(0.0, lambda v, w: check_real(v, w, low=0.0), written_at_default=False),
    "angle_noise": Field(0.0, lambda v, w: check_real(v, w, low=0.0, high=5.0), written_at_default=False),
    "d_misalignment": Field(
        0.0, lambda v, w: check_real(v, w, low=0.0, high=30.0), written_at_default=False
    ),
}


def _paper_scenario(values: Mapping[str, Any]) -> Any:
    from models import paper_w_scenario

    return paper_w_scenario(values["scenario"])


def _run_length(values: Mapping[str, Any]) -> float:
    if values["duration"] is not None:
        return values["duration"]
    return values["time_scale"] * _paper_scenario(values).duration


def _scaled(fault: Any, scale: float) -> Any:
    from models import WheelFault

    if scale == 1.0:
        return fault
    options: dict[str, Any] = {}
    if fault.kind == "sinusoidal":
        options = {"frequency": fault.frequency, "phase": fault.phase}
    if fault.kind == "effectiveness":
        options = {"effectiveness": fault.effectiveness}
    value = fault.value if fault.kind in ("stuck", "sinusoidal", "bias") else None
    return WheelFault(fault.wheel, fault.kind, fault.t_on * scale, fault.t_off * scale, value, **options)


def _check(values: dict[str, Any], controller: str, name: Callable[[str], str]) -> None:
    length = _run_length(values)
    if values["duration"] is not None and values["duration"] < values["dt"]:
        raise ConfigError(
            name("duration"), f"at least one sample (dt = {values['dt']:g} s)", repr(values["duration"])
        )
    if values["duration"] is None:  # the scenario's own length, in samples of dt
        check_run_length(length, values["dt"], name("dt"))
    kind = values["fault_kind"]
    if kind == "scenario":
        last = max((f.t_on for f in _paper_scenario(values).faults), default=0.0) * values["time_scale"]
        if last >= length:
            raise ConfigError(
                name("duration"), f"a run past the scenario's last fault onset ({last:g} s)", repr(length)
            )
        return
    if kind == "none":
        return
    if values["fault_onset"] >= length:
        raise ConfigError(
            name("fault_onset"), f"an onset before the run's end ({length:g} s)", repr(values["fault_onset"])
        )
    if kind == "effectiveness" and not 0.0 <= values["fault_value"] <= 1.0:
        raise ConfigError(name("fault_value"), "an effectiveness in [0, 1]", repr(values["fault_value"]))


def case_faults(scenario: Any) -> list[Any]:
    """The faults of a case: the paper scenario's, or the one ``fault_*`` describes, or none."""
    from models import WheelFault

    kind = scenario.fault_kind
    if kind == "scenario":
        return [
            _scaled(f, scenario.time_scale) for f in _paper_scenario({"scenario": scenario.scenario}).faults
        ]
    if kind == "none":
        return []
    t_on = scenario.fault_onset
    t_off = t_on + scenario.fault_duration
    value = scenario.fault_value
    if kind == "outage":
        return [WheelFault(scenario.fault_wheel, "outage", t_on, t_off)]
    if kind == "effectiveness":
        return [WheelFault(scenario.fault_wheel, "effectiveness", t_on, t_off, effectiveness=value)]
    if kind == "sinusoidal":
        return [
            WheelFault(scenario.fault_wheel, "sinusoidal", t_on, t_off, value=value, frequency=SINE_FREQUENCY)
        ]
    return [WheelFault(scenario.fault_wheel, kind, t_on, t_off, value=value)]


def misaligned_axes(D: Any, angle_deg: float, seed: int) -> np.ndarray:
    """``D`` with every column tilted by ``angle_deg`` toward a direction drawn with ``seed``.

    Each column ``d_j`` turns by exactly ``angle_deg`` about an axis perpendicular to it (the
    direction of the tilt drawn uniformly from ``numpy.random.default_rng(seed)``); the columns
    stay unit vectors.

    Examples
    --------
    >>> import numpy as np
    >>> from models import WheelArray
    >>> d = WheelArray.paper_w().D
    >>> tilted = misaligned_axes(d, 5.0, 0)
    >>> np.degrees(np.arccos(np.sum(d * tilted, axis=0))).round(6).tolist()
    [5.0, 5.0, 5.0, 5.0]
    """
    d = np.array(D, dtype=float)
    rng = np.random.default_rng(seed)
    angle = math.radians(angle_deg)
    out = np.empty_like(d)
    for j in range(d.shape[1]):
        axis = d[:, j] / np.linalg.norm(d[:, j])
        v = rng.normal(size=3)
        v -= axis * float(axis @ v)
        v /= np.linalg.norm(v)
        out[:, j] = math.cos(angle) * axis + math.sin(angle) * v
    return out


def _label(scenario: Any) -> str:
    parts = [scenario.controller, scenario.scenario]
    if scenario.fault_kind != "scenario":
        parts.append(
            "no fault"
            if scenario.fault_kind == "none"
            else f"{scenario.fault_kind} w{scenario.fault_wheel} @{scenario.fault_onset:g}s"
        )
    if scenario.inertia_scale is not None:
        parts.append(f"J x{scenario.inertia_scale:g}")
    if scenario.gravity != "pendulous":
        parts.append(scenario.gravity)
    s, base = scenario.settings, defaults.CONTROLLER_DEFAULTS[scenario.controller]
    if scenario.controller == "ABFTC":
        if (s["gamma_g"], s["gamma_theta"]) != (base["gamma_g"], base["gamma_theta"]):
            g0, gj = s["gamma_g"], s["gamma_theta"]
            parts.append(f"Gamma {g0:g} I" if g0 == gj else f"Gamma_0 {g0:g} I, Gamma_j {gj:g} I")
        if s["freeze"]:
            parts.append("freeze")
    if not scenario.wheel_limits:
        parts.append("no wheel limits")
    if scenario.viscous_friction or scenario.coulomb_friction:
        parts.append("friction")
    if scenario.angle_noise:
        parts.append(f"noise {scenario.angle_noise:g} deg")
    if scenario.d_misalignment:
        parts.append(f"D tilted {scenario.d_misalignment:g} deg")
    return " ".join(parts)


def simulate_case(scenario: Any, settings: Mapping[str, Any], keep_trace: bool) -> CaseResult:
    """Build paper W's satellite, the faults, the controller's polytope and the controller; run; measure."""
    from benchmarks.families.wheel.metrics import fault_metrics
    from benchmarks.families.wheel.plant import wheel_plant
    from models import AttitudeNoiseSensor, FaultSchedule, WheelArray, WheelSatellite
    from rmpc import simulate

    paper = _paper_scenario({"scenario": scenario.scenario})
    duration = _run_length(
        {"duration": scenario.duration, "time_scale": scenario.time_scale, "scenario": scenario.scenario}
    )
    nominal = WheelSatellite.paper_w(gravity=scenario.gravity)
    scale = scenario.inertia_scale if scenario.inertia_scale is not None else paper.inertia_scales[0]
    plant_sat = nominal if scale == 1.0 else nominal.replace(inertia=scale * nominal.inertia)
    plant_changes: dict[str, Any] = {}
    if scenario.viscous_friction or scenario.coulomb_friction:
        plant_changes["viscous_friction"] = scenario.viscous_friction
        plant_changes["coulomb_friction"] = scenario.coulomb_friction
    if scenario.d_misalignment:
        w = nominal.wheels
        tilted = misaligned_axes(w.D, scenario.d_misalignment, scenario.seed)
        plant_changes["wheels"] = WheelArray(tilted, w.torque_max, w.momentum_max, w.wheel_inertia)
    if plant_changes:
        plant_sat = plant_sat.replace(**plant_changes)
    spread = scenario.inertia_spread
    if spread is None and scale != 1.0:
        spread = 0.2
    poly = nominal.polytope(dt=scenario.dt, spread=spread)
    built = CONTROLLERS[scenario.controller](WheelModel(nominal, poly), scenario, settings)
    n = nominal.n_wheels
    schedule = FaultSchedule(case_faults(scenario), n, duration)
    disturbance = paper.disturbance(scenario.seed, n)
    limits = scenario.wheel_limits
    plant = wheel_plant(
        plant_sat,
        schedule,
        dt=scenario.dt,
        substep=defaults.SUBSTEP,
        wheel_disturbance=disturbance,
        torque_limit=limits,
        momentum_limit=limits,
    )
    x0 = paper.initial_state(n)
    sensor = None
    if scenario.angle_noise:
        sensor = AttitudeNoiseSensor(math.radians(scenario.angle_noise), seed=scenario.seed)
    traj = simulate(built.controller, plant, x0, duration=duration, sensor=sensor)
    metrics = compute_metrics(traj, scenario.u_max, 0.02)
    faults = fault_metrics(traj, schedule, nominal.wheels, threshold=math.radians(defaults.RECOVERY_DEG))
    metrics["faults"] = faults
    extra = {
        "x0": x0.tolist(),
        "duration_used": traj.n_steps * traj.dt,  # what ran (whole samples of dt)
        "inertia_scale_used": scale,
        "polytope_inertia_spread": spread,
        "n_vertices": poly.n_vertices,
        "faults_used": [repr(f) for f in schedule.faults],
        "wheel_disturbance": disturbance is not None,
        "limits_in_plant": limits,
        # the plant's wheel limits (what its figure draws; none when the plant applies none)
        "wheel_torque_max": plant_sat.wheels.torque_max.tolist() if limits else None,
        "wheel_momentum_max": plant_sat.wheels.momentum_max.tolist() if limits else None,
    }
    if scenario.d_misalignment:
        extra["plant_D"] = plant_sat.wheels.D.tolist()
    trace: dict[str, np.ndarray] = {}
    if keep_trace:
        trace = {"t": traj.t, "x": traj.x, "u_cmd": traj.u_cmd, "u_applied": traj.u_applied}
        for key, values in traj.stage_log.items():
            arr = np.asarray(values)
            if arr.dtype != object:
                trace[f"stage_{key}"] = arr
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
    """The RMPC's forms with the case's bounds; GIPC's solver options with the case's backend."""
    if controller == "GIPC":
        check_gipc_solver_options(settings, name("settings"))
    if controller == "CRMPC":
        own = {key: settings[key] for key in _OWN}
        constrained = values["saturation"] == "constraint"
        check_crmpc_options(settings, own, FORMS.n_states, constrained, name("settings"))
    FORMS.check_case(values, controller, settings, name)


WHEEL = PlantFamily(
    name="wheel",
    description="paper W's satellite with four reaction wheels and wheel faults (S1-S4)",
    fields=FIELDS,
    controllers=controller_specs(
        CONTROLLERS,
        {
            **defaults.CONTROLLER_DEFAULTS,
            "RMPC": {**defaults.CONTROLLER_DEFAULTS["RMPC"], **FORM_DEFAULTS, **OUTPUT_DEFAULTS},
            # the QP back-end's settings (left out of a record at their default, None)
            "GIPC": {**defaults.CONTROLLER_DEFAULTS["GIPC"], "solver_options": None},
            # the inner RMPC's further keywords (left out of a record at their default, None)
            "CRMPC": {**defaults.CONTROLLER_DEFAULTS["CRMPC"], **CRMPC_DEFAULTS},
        },
        CONSTRAINED,
    ),
    simulate=simulate_case,
    check=_check,
    label=_label,
    setting_choices=defaults.SETTING_CHOICES,
    zero_allowed=frozenset({"adaptation_gain", "leakage", "gamma_g", "gamma_theta"}),
    settings_check=settings_check,
    controller_defaults=lambda controller: {} if controller in CONSTRAINED else {"saturation": "limiter"},
    setting_checks=_SETTING_CHECKS,
    quiet_settings=frozenset(FORM_DEFAULTS) | frozenset(OUTPUT_DEFAULTS) | frozenset(CRMPC_DEFAULTS),
    case_check=_case_check,
    not_settings=NOT_SETTINGS,
)
