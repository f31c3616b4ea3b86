"""The robust MPC's forms as settings of a scenario: their defaults, their checks, the keyword arguments.

:class:`rmpc.RMPC` selects the field's robust MPC forms (:mod:`lmi.forms`) by six keyword arguments,
``lyapunov``, ``cost``, ``free_moves``, ``saturation``, ``soft`` and ``disturbance``, and takes
``certificate_tol`` and ``on_failure``; a sweep file sets them as ``settings.<name>`` of the
controller ``"RMPC"``. Each value is checked by the Python constructor's own check
(:func:`lmi.forms.options.form_options`), and the error names the sweep file's key path
(``base.settings.soft.u``, ``grid.settings.lyapunov``) instead of the Python argument. The values
TOML cannot write as Python does:

- ``soft``: a table ``{u = w_u, y = w_y}`` (Python's dict);
- ``disturbance``: a table ``{E = [[...], ...], w_max = w, lam = l}`` (``lam`` optional) or the
  list ``[E, w_max]`` / ``[E, w_max, lam]`` (Python's tuple); ``E`` is ``6 x q`` (rows: roll,
  pitch, yaw, then their rates) or a list of 6 numbers (one column);
- ``saturation``: ``"auxiliary"``; Python's ``None`` (the default) is left out of the file.

Each of them is left out of a case's record while it holds its default, so the records and case
ids of the cases that do not set them are those they had before the forms were settings.

Examples
--------
>>> from benchmarks.core.scenario import Scenario
>>> sc = Scenario.from_dict({"controller": "RMPC", "settings": {"soft": {"u": 100}}})
>>> dict(sc.settings["soft"]), "lyapunov" in sc.to_dict()["settings"]
({'u': 100.0}, False)
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import Any

import numpy as np

from toolkit_common.errors import ArgumentTypeError, ConfigError, InvalidArgumentError

__all__ = ["FORM_DEFAULTS", "FORM_SETTINGS", "SETTING_CHECKS", "check_case", "rmpc_kwargs"]

#: The controller's states (paper P's satellite: roll, pitch, yaw and their rates).
N_STATES = 6

#: The forms' settings with :class:`rmpc.RMPC`'s defaults (Kothare's problem).
FORM_SETTINGS: Mapping[str, Any] = MappingProxyType(
    {"lyapunov": "common", "cost": "worst_case", "free_moves": 0, "saturation": None, "soft": None,
     "disturbance": None}
)
#: Every setting of this module with its default: the forms and the solve's two options.
FORM_DEFAULTS: Mapping[str, Any] = MappingProxyType(
    {**FORM_SETTINGS, "certificate_tol": 1e-7, "on_failure": "fallback"}
)
_DISTURBANCE_KEYS = ("E", "w_max", "lam")


def _python_check(where: str, **options: Any) -> Any:
    """:func:`lmi.forms.options.form_options` on ``options`` alone, its errors named by ``where``."""
    from lmi.forms.options import form_options

    try:
        return form_options(n_states=N_STATES, input_constraint="peak", has_output=False, **options)
    except (InvalidArgumentError, ArgumentTypeError) as err:
        raise ConfigError(_path(err.argument, where), err.expected, err.found) from None


def _path(argument: str, where: str) -> str:
    """The key path of a Python argument: ``soft['u']`` -> ``<where>.u``, ``disturbance E`` -> ``<where>.E``.
    """
    inner = re.match(r"^\w+(?:\[['\"]?(\w+)['\"]?\]| (\w+))?$", argument)
    if inner is None:
        return where
    part = inner.group(1) or inner.group(2)
    return f"{where}.{part}" if part else where


def _lyapunov(value: Any, where: str) -> str:
    return _python_check(where, lyapunov=value).lyapunov


def _cost(value: Any, where: str) -> str:
    return _python_check(where, cost=value).cost


def _free_moves(value: Any, where: str) -> int:
    return _python_check(where, free_moves=value).free_moves


def _saturation(value: Any, where: str) -> str:
    if value is None:
        raise ConfigError(where, "'auxiliary' (leave the setting out for none)", "None")
    return _python_check(where, saturation=value).saturation


def _soft(value: Any, where: str) -> Mapping[str, float]:
    if not isinstance(value, Mapping):
        raise ConfigError(where, "a table of weights {u = w_u, y = w_y}", repr(value))
    weights = _python_check(where, soft=dict(value)).soft
    return MappingProxyType(dict(weights))


def _disturbance(value: Any, where: str) -> Mapping[str, Any]:
    if isinstance(value, Mapping):
        for key in value:
            if key not in _DISTURBANCE_KEYS:
                raise ConfigError(f"{where}.{key}", "E, w_max or lam", "an unknown key")
        for key in ("E", "w_max"):
            if key not in value:
                expected = f"{key} in the table {{E = [[...]], w_max = w}}"
                raise ConfigError(f"{where}.{key}", expected, "nothing")
        given: Any = (value["E"], value["w_max"]) + ((value["lam"],) if "lam" in value else ())
    elif isinstance(value, list):
        given = tuple(value)
    else:
        expected = "a table {E = [[...]], w_max = w, lam = l} or a list [E, w_max(, lam)]"
        raise ConfigError(where, expected, repr(value))
    dist = _python_check(where, disturbance=given).disturbance
    out: dict[str, Any] = {"E": tuple(tuple(float(v) for v in row) for row in dist.E), "w_max": dist.w_max}
    if dist.lam is not None:
        out["lam"] = dist.lam
    return MappingProxyType(out)


#: The checks of the settings whose values a default's type does not describe.
SETTING_CHECKS: Mapping[str, Callable[[Any, str], Any]] = MappingProxyType(
    {"lyapunov": _lyapunov, "cost": _cost, "free_moves": _free_moves, "saturation": _saturation,
     "soft": _soft, "disturbance": _disturbance}
)


def rmpc_kwargs(settings: Mapping[str, Any]) -> dict[str, Any]:
    """The keyword arguments of :class:`rmpc.RMPC` that the form settings stand for."""
    out = {key: settings[key] for key in ("lyapunov", "cost", "free_moves", "saturation")}
    out["soft"] = None if settings["soft"] is None else dict(settings["soft"])
    dist = settings["disturbance"]
    out["disturbance"] = None if dist is None else (
        (np.array(dist["E"]), dist["w_max"]) + ((dist["lam"],) if "lam" in dist else ())
    )
    return out


def check_case(
    values: dict[str, Any], controller: str, settings: Mapping[str, Any], name: Callable[[str], str]
) -> None:
    """The forms' combinations, with the scenario's input bound (``saturation = "constraint"``).

    Raises
    ------
    ConfigError
        Naming the settings (and the field ``saturation`` or ``kinematics``) that do not go together.
    """
    if controller != "RMPC":
        return
    changed = [key for key, default in FORM_SETTINGS.items() if settings[key] != default]
    if not changed:
        return
    where = name("settings")
    if values["kinematics"] == "scheduled":
        expected = (
            f"'single' or 'cover' with {where}.{changed[0]} (the scheduled RMPC solves Kothare's LMIs only)"
        )
        raise ConfigError(name("kinematics"), expected, "'scheduled'")
    from lmi.forms.options import form_options

    constrained = values["saturation"] == "constraint"
    bound = settings["input_constraint"] if constrained else None
    try:
        form_options(n_states=N_STATES, input_constraint=bound, has_output=False, **rmpc_kwargs(settings))
    except (InvalidArgumentError, ArgumentTypeError) as err:
        parts = []
        for part in err.argument.split(", "):
            if part == "input_constraint":
                parts.append(f"{where}.input_constraint" if constrained else name("saturation"))
            else:
                parts.append(_path(part, f"{where}.{part.split(' ')[0].split('[')[0]}"))
        expected = err.expected
        if not constrained and ("u_max" in expected or "input_constraint" in err.argument):
            expected += " (the controller has an input bound with saturation = 'constraint')"
            if name("saturation") not in parts:
                parts.append(name("saturation"))
        raise ConfigError(", ".join(parts), expected, err.found) from None
