"""A benchmark scenario: plant, uncertainty, saturation, initial condition, disturbance, controller.

A :class:`Scenario` is a frozen, validated description of one closed-loop run; its
:attr:`Scenario.case_id` is a stable hash of :meth:`Scenario.to_dict`, so the same case gets
the same id in every sweep and every run. :func:`run_scenario` simulates it and returns the
record that ``results.json`` holds.

Examples
--------
>>> from benchmarks.core.scenario import Scenario
>>> sc = Scenario.from_dict({"controller": "LQR", "saturation": "limiter", "duration": 1.0})
>>> sc.plant, sc.spread, sc.settings["R_diag"]
('nonlinear', 0.3, (0.01, 0.01, 0.01))
>>> len(sc.case_id)
16
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, fields
from typing import Any

from benchmarks.families.rigid import defaults
from benchmarks.families.rigid.controllers import CONSTRAINED, CONTROLLERS, effective_settings
from benchmarks.core.metrics import AXES
from models import PAPER_P_INITIAL_STATE
from toolkit_common.errors import ConfigError

__all__ = ["Scenario", "initial_attitude", "run_scenario", "unsupported"]

PLANTS = ("linear", "nonlinear")
SATURATIONS = ("none", "limiter", "constraint")
MODES = ("scalar", "box")
ACTUATORS = ("none", "reaction_wheel")
KINEMATICS = ("single", "cover", "scheduled")


@dataclass(frozen=True)
class Scenario:
    """One closed-loop run of the benchmark (every field has a default).

    Attributes
    ----------
    plant : {"nonlinear", "linear"}
        The simulated satellite: the nonlinear model, or the discretised linearisation at the
        initial state (the controller's model) with the true inertia.
    controller : {"RMPC", "GIPC", "CRMPC", "OfflineRMPC", "LQR"}
        A name of :data:`benchmarks.families.rigid.controllers.CONTROLLERS`.
    settings : mapping
        The controller's settings: its defaults (:data:`benchmarks.families.rigid.defaults.CONTROLLER_DEFAULTS`)
        updated by what the scenario gives; after validation it holds every setting.
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
        Widening of the covering box on each side (deg, >= 0; default 5).
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

    plant: str = "nonlinear"
    controller: str = "RMPC"
    settings: Mapping[str, Any] = field(default_factory=dict)
    spread: float = defaults.SPREAD
    mode: str = defaults.MODE
    true_inertia: tuple[float, float, float] | None = None
    saturation: str = "constraint"
    u_max: float = defaults.U_MAX
    ic_scale: float = 1.0
    initial_attitude: tuple[float, float, float] | None = None
    kinematics: str = "single"
    cover_margin: float = 5.0
    disturbance: float = 0.0
    disturbance_start: float = defaults.DISTURBANCE_START
    disturbance_axes: tuple[str, ...] = defaults.DISTURBANCE_AXES
    actuator: str = "none"
    duration: float = defaults.DURATION
    dt: float = defaults.DT

    @classmethod
    def field_names(cls) -> tuple[str, ...]:
        """Names of the scenario fields, in declaration order."""
        return tuple(f.name for f in fields(cls))

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], where: str = "", lenient_settings: bool = False) -> Scenario:
        """Validate ``data`` (field name -> value; missing fields take their defaults).

        Parameters
        ----------
        data : mapping
            Scenario fields, as read from TOML or JSON.
        where : str
            Dotted prefix naming ``data`` in error messages (e.g. ``"base"``).
        lenient_settings : bool
            Drop settings that belong to another controller (sweeps over several controllers
            share one settings table); see :func:`benchmarks.families.rigid.controllers.effective_settings`.

        Raises
        ------
        ConfigError
            On an unknown field or an impossible value; its argument is the dotted field.
        """

        def name(key: str) -> str:
            return f"{where}.{key}" if where else key

        if not isinstance(data, Mapping):
            raise ConfigError(where or "scenario", "a table of scenario fields", type(data).__name__)
        known = cls.field_names()
        for key in data:
            if key not in known:
                raise ConfigError(
                    name(str(key)), "a scenario field (" + ", ".join(known) + ")", "an unknown field"
                )
        d = {**{f.name: f.default for f in fields(cls) if f.name != "settings"}, **data}
        out: dict[str, Any] = {key: cls.check_field(key, d[key], name(key)) for key in d if key != "settings"}
        overrides = data.get("settings", {})
        if not isinstance(overrides, Mapping):
            raise ConfigError(name("settings"), "a table of controller settings", repr(overrides))
        out["settings"] = effective_settings(out["controller"], overrides, name("settings"), lenient_settings)
        problem = unsupported(out["controller"], out["saturation"])
        if problem is not None:
            raise ConfigError(name("saturation"), problem, "'constraint'")
        if out["kinematics"] == "scheduled" and out["controller"] != "RMPC":
            expected = "'single' or 'cover' for " + out["controller"]
            raise ConfigError(name("kinematics"), expected, "'scheduled'")
        attitude = initial_attitude(out["initial_attitude"], out["ic_scale"])
        if abs(attitude[1]) >= 0.5 * math.pi - 1e-3:
            raise ConfigError(
                name("ic_scale") if out["initial_attitude"] is None else name("initial_attitude"),
                "an initial pitch below 90 deg (3-2-1 Euler angles are singular there)",
                f"pitch {math.degrees(attitude[1]):.1f} deg",
            )
        if out["duration"] < out["dt"]:
            raise ConfigError(
                name("duration"), f"at least one sample (dt = {out['dt']:g} s)", repr(out["duration"])
            )
        return cls(**out)

    @classmethod
    def check_field(cls, key: str, value: Any, where: str) -> Any:
        """Check one field's value on its own (no other field involved); return it normalised.

        Examples
        --------
        >>> Scenario.check_field("u_max", 2, "grid.u_max")
        2.0
        """
        if key not in _FIELD_CHECKS:
            known = ", ".join(cls.field_names())
            raise ConfigError(where, f"a scenario field ({known})", "an unknown field")
        return _FIELD_CHECKS[key](value, where)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready values of every field (the inverse of :meth:`from_dict`)."""
        out: dict[str, Any] = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name == "settings":
                value = {k: list(v) if isinstance(v, tuple) else v for k, v in sorted(value.items())}
            elif isinstance(value, tuple):
                value = list(value)
            out[f.name] = value
        return out

    def __hash__(self) -> int:
        return hash(self.case_id)

    @property
    def case_id(self) -> str:
        """A stable 16-hex-digit id: a SHA-256 of the canonical JSON of :meth:`to_dict`."""
        text = json.dumps(self.to_dict(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]

    def label(self) -> str:
        """A short human-readable description for tables and progress."""
        parts = [self.controller, self.plant, self.saturation]
        if self.disturbance:
            parts.append(f"d={self.disturbance:g}")
        if self.ic_scale != 1.0:
            parts.append(f"ic x{self.ic_scale:g}")
        if self.initial_attitude is not None:
            parts.append("ic " + "/".join(f"{v:g}" for v in self.initial_attitude) + " deg")
        if self.kinematics != "single":
            parts.append(self.kinematics)
        return " ".join(parts)


def initial_attitude(attitude_deg: Any, ic_scale: float) -> tuple[float, float, float]:
    """The initial roll, pitch, yaw (rad): ``attitude_deg`` (or paper P's) times ``ic_scale``."""
    if attitude_deg is None:
        base = PAPER_P_INITIAL_STATE[:3]
    else:
        base = tuple(math.radians(v) for v in attitude_deg)
    return (base[0] * ic_scale, base[1] * ic_scale, base[2] * ic_scale)


def _choice(value: Any, where: str, choices: tuple[str, ...]) -> str:
    if not isinstance(value, str) or value not in choices:
        raise ConfigError(where, "one of " + ", ".join(repr(c) for c in choices), repr(value))
    return value


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ConfigError(where, "a finite number", repr(value))
    return float(value)


def _real(
    value: Any,
    where: str,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
) -> float:
    x = _number(value, where)
    bad_low = low is not None and (x < low or (low_open and x == low))
    bad_high = high is not None and (x > high or (high_open and x == high))
    if bad_low or bad_high:
        lo = "" if low is None else f"{'>' if low_open else '>='} {low:g}"
        hi = "" if high is None else f"{'<' if high_open else '<='} {high:g}"
        raise ConfigError(where, "a number " + " and ".join(p for p in (lo, hi) if p), repr(value))
    return x


def _inertia(value: Any, where: str) -> tuple[float, float, float] | None:
    if value is None:
        return None
    ok = isinstance(value, list | tuple) and len(value) == 3
    if ok:
        nums = [_number(v, where) for v in value]
        ok = all(v > 0 for v in nums)
    if not ok:
        raise ConfigError(where, "three principal inertias > 0 (kg m^2)", repr(value))
    return (nums[0], nums[1], nums[2])


def _axes(value: Any, where: str) -> tuple[str, ...]:
    ok = isinstance(value, list | tuple) and len(value) > 0 and len(set(value)) == len(value)
    if not ok or not all(isinstance(v, str) and v in AXES for v in value):
        raise ConfigError(
            where, "a non-empty list of distinct axes among 'roll', 'pitch', 'yaw'", repr(value)
        )
    return tuple(value)


def _ic_scale(value: Any, where: str) -> float:
    return _real(value, where, low=0.0, low_open=True)


def _attitude_deg(value: Any, where: str) -> tuple[float, float, float] | None:
    if value is None:
        return None
    ok = isinstance(value, list | tuple) and len(value) == 3
    if ok:
        nums = [_number(v, where) for v in value]
    if not ok:
        raise ConfigError(where, "three angles in degrees (roll, pitch, yaw)", repr(value))
    return (nums[0], nums[1], nums[2])


def _positive(value: Any, where: str) -> float:
    return _real(value, where, low=0.0, low_open=True)


#: The check of each field on its own (cross-field checks are in :meth:`Scenario.from_dict`).
_FIELD_CHECKS: dict[str, Callable[[Any, str], Any]] = {
    "plant": lambda v, w: _choice(v, w, PLANTS),
    "controller": lambda v, w: _choice(v, w, tuple(CONTROLLERS)),
    "spread": lambda v, w: _real(v, w, low=0.0, high=1.0, high_open=True),
    "mode": lambda v, w: _choice(v, w, MODES),
    "true_inertia": _inertia,
    "saturation": lambda v, w: _choice(v, w, SATURATIONS),
    "u_max": _positive,
    "ic_scale": _ic_scale,
    "initial_attitude": _attitude_deg,
    "kinematics": lambda v, w: _choice(v, w, KINEMATICS),
    "cover_margin": lambda v, w: _real(v, w, low=0.0, high=45.0),
    "disturbance": _real,
    "disturbance_start": lambda v, w: _real(v, w, low=0.0),
    "disturbance_axes": _axes,
    "actuator": lambda v, w: _choice(v, w, ACTUATORS),
    "duration": _positive,
    "dt": _positive,
}


def unsupported(controller: str, saturation: str) -> str | None:
    """Why ``controller`` cannot run with ``saturation`` (``None`` if it can)."""
    if saturation == "constraint" and controller not in CONSTRAINED:
        return f"'none' or 'limiter' for {controller} (it has no constraint)"
    return None


def run_scenario(scenario: Scenario, experiment: str | None = None) -> dict[str, Any]:
    """Simulate ``scenario`` and return its record (see :func:`benchmarks.core.runner.simulate_scenario`)."""
    from benchmarks.core.runner import simulate_scenario

    record, _ = simulate_scenario(scenario, experiment=experiment)
    return record
