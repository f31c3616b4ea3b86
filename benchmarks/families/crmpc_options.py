"""CRMPC's ``rmpc_options`` as a setting of a sweep, and the keywords no sweep can set.

:class:`rmpc.CRMPC` passes ``rmpc_options`` (a dict of further keyword arguments) to its inner
:class:`rmpc.RMPC`. In a sweep file it is the table ``settings.rmpc_options`` of a family's
``"CRMPC"`` (rigid, wheel, MRP; also ``"CRMPC-MIT"``, rigid): its entries are RMPC's keywords,
each written as the RMPC's own setting of the same name is (``soft = {u = 100.0}``,
``disturbance = {E = [[...]], w_max = w}``, ``solver_options = {max_iter = 60}``,
``output_matrix = [[...]]``) and checked by the same check (:mod:`benchmarks.families.rmpc_forms`),
then the whole table by :class:`rmpc.CRMPC` itself with the case's other settings
(:func:`check_crmpc_options`); an error names the key path ``settings.rmpc_options.<name>``.
Left out of a case's record at its default (``None``), so no case id changes.

Keys a sweep cannot give (:data:`NOT_IN_RMPC_OPTIONS`): the ones the family sets from a setting
of CRMPC's own (``resolve_threshold`` in the rigid family, ``backend`` in the wheel and MRP
families: set that setting instead), ``x_ref`` and ``offset_free`` (:data:`NOT_SETTINGS`).

Examples
--------
>>> from benchmarks.core.scenario import Scenario
>>> sc = Scenario.from_dict({"controller": "CRMPC", "settings": {"rmpc_options": {"hold_radius": 1e-6}}})
>>> dict(sc.settings["rmpc_options"])
{'hold_radius': 1e-06}
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import Any

import numpy as np

from toolkit_common.errors import ArgumentTypeError, ConfigError, InvalidArgumentError

__all__ = [
    "CRMPC_DEFAULTS", "NOT_IN_RMPC_OPTIONS", "NOT_SETTINGS", "check_crmpc_options", "crmpc_rmpc_kwargs",
    "rmpc_options_check",
]

#: CRMPC's ``rmpc_options`` with the constructor's default (left out of a record at it).
CRMPC_DEFAULTS: Mapping[str, Any] = MappingProxyType({"rmpc_options": None})

#: Keywords of the controllers a sweep file cannot set, with why (a family's ``not_settings``).
NOT_SETTINGS: Mapping[str, str] = MappingProxyType({
    "x_ref": "a case regulates to its family's target, and the metrics measure the error to it",
    "offset_free": "it needs a disturbance estimate, which no scenario gives the controller",
    "plant": "the family builds the controller's model from the scenario's fields",
    "Q": "the state weight is the setting Q_diag (the flexible family's q_weight, w_weight, eta_weight)",
    "R": "the input weight is the setting R_diag (the flexible family's r_weight)",
    "u_max": "the input bound is the scenario's field u_max, with saturation = 'constraint'",
    "x_design": "the off-line table is designed from the family's initial state",
    "adaptation": "CRMPC's rule is built from adaptation_gain (CRMPC-MIT's from mit_gain, normalized, alpha, "
                  "reset_period)",
    "theta_bound": "it is the setting theta_fraction times u_max",
})

#: Keys of ``rmpc_options`` a sweep cannot give, with why.
NOT_IN_RMPC_OPTIONS: Mapping[str, str] = MappingProxyType({
    key: NOT_SETTINGS[key] for key in ("x_ref", "offset_free")
})


def rmpc_options_check(
    checks: Mapping[str, Callable[[Any, str], Any]], own: tuple[str, ...]
) -> Callable[[Any, str], Mapping[str, Any]]:
    """The check of ``settings.rmpc_options`` on its own: a table of RMPC keywords.

    Parameters
    ----------
    checks : mapping
        The family's RMPC setting checks (``RMPCForms.setting_checks()``): an entry of the table
        with one of these names is checked by it, as the RMPC's setting of that name is.
    own : tuple of str
        The RMPC keywords the family sets from CRMPC's own settings (refused in the table).
    """

    def check(value: Any, where: str) -> Mapping[str, Any]:
        if not isinstance(value, Mapping):
            raise ConfigError(where, "a table of RMPC keyword arguments (e.g. {hold_radius = 1e-6})",
                              repr(value)[:80])
        out: dict[str, Any] = {}
        for key, item in value.items():
            path = f"{where}.{key}"
            if key in own:
                raise ConfigError(path, f"no {key} here (the setting {key} of the controller sets it)",
                                  f"{key} given")
            if key in NOT_IN_RMPC_OPTIONS:
                why = NOT_IN_RMPC_OPTIONS[key]
                raise ConfigError(path, f"no {key} in a sweep file ({why})", f"{key} given")
            if key in checks:
                out[key] = checks[key](item, path)
            elif isinstance(item, Mapping | list):
                raise ConfigError(path, "a number, a string, true or false", repr(item)[:80])
            else:
                out[key] = item
        return MappingProxyType(out)

    return check


def crmpc_rmpc_kwargs(settings: Mapping[str, Any], own: Mapping[str, Any]) -> dict[str, Any]:
    """CRMPC's ``rmpc_options``: the family's ``own`` entries and the table's, as Python values."""
    options = dict(own)
    table = settings.get("rmpc_options")
    for key, value in (table or {}).items():
        if key == "soft":
            options[key] = dict(value)
        elif key == "disturbance":
            lam = (value["lam"],) if "lam" in value else ()
            options[key] = (np.array(value["E"]), value["w_max"], *lam)
        elif key in ("output_matrix", "y_max"):
            options[key] = np.array(value, dtype=float)
        elif key == "solver_options":
            options[key] = dict(value)
        else:
            options[key] = value
    return options


def check_crmpc_options(
    settings: Mapping[str, Any], own: Mapping[str, Any], n_states: int, constrained: bool, where: str
) -> None:
    """``settings.rmpc_options`` checked by :class:`rmpc.CRMPC` itself with the case's settings.

    A CRMPC is built (nothing is solved) on a one-vertex stand-in of the controller's
    ``n_states`` states and one input, with the case's input bound kind (``constrained``: the
    family's ``input_constraint``), torque budget and the family's ``own`` entries; its error
    names the key path ``<where>.rmpc_options.<name>`` (``<where>.<name>`` for an ``own`` entry:
    the wheel's and MRP's ``backend = "proxqp"``, which CRMPC's RMPC does not take, is refused
    here, not when the case runs).

    Raises
    ------
    ConfigError
        Naming the entry CRMPC or its RMPC refuses.
    """
    table = settings.get("rmpc_options")
    if table is None and own.get("backend", "ipm") == "ipm":
        return  # nothing the setting checks left unchecked (the wheel's and MRP's backend may be)
    from benchmarks.families.rmpc_forms import setting_key_path
    from models import PolytopicModel
    from rmpc.mpc.crmpc import CRMPC

    # the states matter for a disturbance's E and an output matrix only (a 6-state ipm stand-in
    # takes 45 ms to build, a 1-state one 5 ms)
    n = n_states if table is not None and ("disturbance" in table or "output_matrix" in table) else 1
    stand_in = PolytopicModel([(0.5 * np.eye(n), np.ones((n, 1)))], dt=1.0)
    options = crmpc_rmpc_kwargs(settings, own)
    base = f"{where}.rmpc_options"
    try:
        CRMPC(stand_in, np.eye(n), np.eye(1), u_max=1.0 if constrained else None,
              input_constraint=settings["input_constraint"] if constrained else None,
              torque_budget="current" if constrained else "none", rmpc_options=options)
    except (InvalidArgumentError, ArgumentTypeError) as err:
        if err.argument == "rmpc_options":
            raise ConfigError(base, err.expected, err.found) from None
        if err.argument in own:  # CRMPC's own setting, passed on to its RMPC (backend = "proxqp")
            expected = f"{err.expected} (the RMPC inside CRMPC)"
            raise ConfigError(f"{where}.{err.argument}", expected, err.found) from None
        parts = [setting_key_path(part, base) for part in err.argument.split(", ")]
        raise ConfigError(", ".join(parts), err.expected, err.found) from None
