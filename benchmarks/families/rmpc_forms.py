"""The robust MPC's forms as settings of a scenario: their defaults, their checks, the keyword arguments.

:class:`rmpc.RMPC` selects the field's robust MPC forms (:mod:`lmi.forms`) by nine keyword arguments,
``lyapunov``, ``cost``, ``free_moves``, ``saturation``, ``soft``, ``disturbance``, ``horizon``,
``step_gains`` and ``unsaturated_weight`` (Huang et al.'s ``beta``, a number; left out for none),
and takes
``certificate_tol`` and ``on_failure``; a sweep file sets them as ``settings.<name>`` of a
family's controller ``"RMPC"`` (every shipped family: :class:`RMPCForms` holds what a family
needs, its state count and whether its RMPC has output bounds). Each value is checked by the
Python constructor's own check (:func:`lmi.forms.options.form_options`), and the error names the
sweep file's key path (``base.settings.soft.u``, ``grid.settings.lyapunov``) instead of the
Python argument. The values TOML cannot write as Python does:

- ``soft``: a table ``{u = w_u, y = w_y}`` (Python's dict), per component ``{u = [w_1, 0, w_3],
  u_limit = [l_1, 0, l_3]}`` (:mod:`lmi.forms.soft`; the lengths are checked when the case's
  controller is built);
- ``disturbance``: a table ``{E = [[...], ...], w_max = w, lam = l}`` (``lam`` optional) or the
  list ``[E, w_max]`` / ``[E, w_max, lam]`` (Python's tuple); ``E`` is ``n x q`` (``n`` the
  controller's states) or a list of ``n`` numbers (one column);
- ``saturation``: ``"auxiliary"``; Python's ``None`` (the default) is left out of the file;
- ``solver_options``: a table of the back-end's settings (``{core = "numba", max_iter = 60}``),
  checked by :class:`rmpc.RMPC` itself with the case's ``backend``
  (:func:`check_solver_options`), its error naming ``settings.solver_options.<name>``;
- ``output_matrix`` and ``y_max`` (rigid, wheel and MRP families, :data:`OUTPUT_DEFAULTS`): the
  output bounds ``|(C x)_r| <= y_max_r``, ``C`` a list of rows of the RMPC's states (``[[1.0, 0,
  0, 0, 0, 0]]`` bounds the roll angle), ``y_max`` a number > 0 or one per row, given together;
  the flexible family's RMPC takes its output bounds from the field ``modal_bound`` instead;
- ``solver``: the cvxpy solver with ``backend = "cvxpy"`` (``"SCS"``, ``"CLARABEL"``), checked the
  same way (an error names ``settings.solver``); ``None`` (the default) is left out of the file.

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
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np

from toolkit_common.errors import ArgumentTypeError, ConfigError, InvalidArgumentError

__all__ = [
    "FORM_DEFAULTS", "FORM_SETTINGS", "OUTPUT_DEFAULTS", "RMPCForms", "changed_forms", "check_solver_options",
    "rmpc_kwargs",
]

#: The forms' settings with :class:`rmpc.RMPC`'s defaults (Kothare's problem).
FORM_SETTINGS: Mapping[str, Any] = MappingProxyType(
    {"lyapunov": "common", "cost": "worst_case", "free_moves": 0, "saturation": None, "soft": None,
     "disturbance": None, "horizon": 1, "step_gains": "common", "unsaturated_weight": None}
)
#: Every setting of this module with its default: the forms and the solve's three options.
FORM_DEFAULTS: Mapping[str, Any] = MappingProxyType(
    {**FORM_SETTINGS, "certificate_tol": 1e-7, "on_failure": "fallback", "solver_options": None,
     "solver": None}
)
_DISTURBANCE_KEYS = ("E", "w_max", "lam")
_RMPC_BACKEND = "ipm"
"""The default ``backend`` of :class:`rmpc.RMPC` (``tests/test_sweep_reach.py`` checks it is)."""


def _python_check(where: str, n_states: int, has_output: bool, **options: Any) -> Any:
    """:func:`lmi.forms.options.form_options` on ``options`` alone, its errors named by ``where``."""
    from lmi.forms.options import form_options

    try:
        return form_options(n_states=n_states, input_constraint="peak", has_output=has_output, **options)
    except (InvalidArgumentError, ArgumentTypeError) as err:
        raise ConfigError(key_path(err.argument, where), err.expected, err.found) from None


def key_path(argument: str, where: str) -> str:
    """The key path of a Python argument: ``soft['u']`` -> ``<where>.u``, ``soft['u'][1]`` ->
    ``<where>.u[1]``, ``disturbance E`` -> ``<where>.E``, ``solver_options['max_iter']`` ->
    ``<where>.max_iter``; a bare name -> ``<where>``.
    """
    inner = re.match(r"^\w+(?:\[['\"]?(\w+)['\"]?\](\[\d+\])?| (\w+))?$", argument)
    if inner is None:
        return where
    part = inner.group(1) or inner.group(3)
    return f"{where}.{part}{inner.group(2) or ''}" if part else where


def setting_key_path(part: str, where: str) -> str:
    """The key path of one argument named in a constructor's error, under the table ``where``
    (``soft['u']`` -> ``<where>.soft.u``, ``horizon`` -> ``<where>.horizon``)."""
    return key_path(part, f"{where}.{part.split(' ')[0].split('[')[0]}")


def raise_at_key_path(err: InvalidArgumentError | ArgumentTypeError, where: str, backend: Any,
                      direct: tuple[str, ...]) -> None:
    """Re-raise a stand-in constructor's error at the sweep file's key path.

    An argument in ``direct`` is ``<where>.<argument>``; a solver option is
    ``<where>.solver_options.<name>`` (the message names ``backend``); any other error returns
    (the case's own build reports it).
    """
    if err.argument in direct:
        raise ConfigError(f"{where}.{err.argument}", err.expected, err.found) from None
    if not err.argument.startswith("solver_options"):
        return
    raise ConfigError(
        key_path(err.argument, f"{where}.solver_options"), f"{err.expected} (backend {backend!r})", err.found,
    ) from None


def _lyapunov(value: Any, where: str, n: int, out: bool) -> str:
    # alone as if with its saturation (the combinations: check_case)
    sat = "auxiliary" if value == "saturation_dependent" else None
    return _python_check(where, n, out, lyapunov=value, saturation=sat).lyapunov


def _cost(value: Any, where: str, n: int, out: bool) -> str:
    return _python_check(where, n, out, cost=value).cost


def _free_moves(value: Any, where: str, n: int, out: bool) -> int:
    return _python_check(where, n, out, free_moves=value).free_moves


def _saturation(value: Any, where: str, n: int, out: bool) -> str:
    if value is None:
        raise ConfigError(where, "'auxiliary' (leave the setting out for none)", "None")
    return _python_check(where, n, out, saturation=value).saturation


def _soft(value: Any, where: str, n: int, out: bool) -> Mapping[str, float]:
    if not isinstance(value, Mapping):
        raise ConfigError(where, "a table of weights {u = w_u, y = w_y}", repr(value))
    weights = _python_check(where, n, out, soft=dict(value)).soft
    return MappingProxyType(dict(weights))


def _disturbance(value: Any, where: str, n: int, out: bool) -> Mapping[str, Any]:
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
    dist = _python_check(where, n, out, disturbance=given).disturbance
    table: dict[str, Any] = {"E": tuple(tuple(float(v) for v in row) for row in dist.E), "w_max": dist.w_max}
    if dist.lam is not None:
        table["lam"] = dist.lam
    return MappingProxyType(table)


def _solver_options(value: Any, where: str, n: int, out: bool) -> Mapping[str, Any]:
    """A table of the back-end's settings; its names and values are checked with the case's backend."""
    if not isinstance(value, Mapping):
        expected = "a table of the backend's settings (e.g. {core = \"numba\"} for the ipm)"
        raise ConfigError(where, expected, repr(value))
    for key, item in value.items():
        if isinstance(item, Mapping | list):
            raise ConfigError(f"{where}.{key}", "a number, a string, true or false", repr(item))
    return MappingProxyType(dict(value))


def check_solver_options(settings: Mapping[str, Any], n_states: int, where: str) -> None:
    """``settings.backend``, ``settings.solver_options``, ``settings.solver`` and the output bounds
    (``output_matrix`` with ``y_max``) checked by :class:`rmpc.RMPC` itself, when the sweep file is
    read (a family's ``backend`` choices may include its QP controller's, ``"proxqp"``).

    An RMPC is built on a one-vertex stand-in of the case's ``n_states`` states (the check of the
    options does not depend on the model), with the forms' problem when a form is set, as the
    case's RMPC is; its error names the key path ``<where>.solver_options.<name>``.

    Raises
    ------
    ConfigError
        Naming the option the backend refuses.
    """
    options, solver = settings.get("solver_options"), settings.get("solver")
    outputs = _output_kwargs(settings) if "output_matrix" in settings else {}
    given = options is not None or solver is not None or any(v is not None for v in outputs.values())
    from models import PolytopicModel
    from rmpc.mpc.robust_mpc import RMPC

    if not given and settings["backend"] == _RMPC_BACKEND:
        return  # the constructor's own defaults
    # the states matter for the output matrix only (a 6-state ipm stand-in takes 45 ms to build)
    n = n_states if outputs and outputs["output_matrix"] is not None else 1
    stand_in = PolytopicModel([(0.5 * np.eye(n), np.ones((n, 1)))], dt=1.0)
    form = {"lyapunov": "vertex"} if changed_forms(settings) else {}
    try:
        RMPC(stand_in, np.eye(n), np.eye(1), u_max=[1.0], input_constraint="peak",
             backend=settings["backend"], solver=solver,
             solver_options=None if options is None else dict(options), **outputs, **form)
    except (InvalidArgumentError, ArgumentTypeError) as err:
        # backend: a family's choices are shared with its QP controller's ("proxqp")
        raise_at_key_path(err, where, settings["backend"], ("solver", "output_matrix", "y_max", "backend"))


def _output_matrix(value: Any, where: str, n: int, out: bool) -> tuple[tuple[float, ...], ...]:
    """``C`` of the output bounds ``|(C x)_r| <= y_max_r``: a list of rows of ``n`` numbers."""
    from toolkit_common.validation import as_matrix

    rows = isinstance(value, list | tuple) and value and all(isinstance(row, list | tuple) for row in value)
    if not rows:
        raise ConfigError(where, f"a list of rows of {n} numbers (the output matrix C)", repr(value)[:80])
    try:
        mat = as_matrix(value, "output_matrix", (None, n))
    except (InvalidArgumentError, ArgumentTypeError) as err:
        raise ConfigError(where, err.expected, err.found) from None
    return tuple(tuple(float(v) for v in row) for row in mat)


def _y_max(value: Any, where: str, n: int, out: bool) -> tuple[float, ...]:
    """The output bounds: one number > 0 per row of ``output_matrix`` (or one for all)."""
    from toolkit_common.validation import is_real

    values = value if isinstance(value, list | tuple) else [value]
    if not values or not all(is_real(v) and np.isfinite(v) and v > 0 for v in values):
        raise ConfigError(where, "a number > 0 or a list of them (one per row of output_matrix)", repr(value))
    return tuple(float(v) for v in values)


def _solver(value: Any, where: str, n: int, out: bool) -> str:
    """A cvxpy solver's name; which ones the case's ``backend`` takes is checked by the constructor."""
    if not isinstance(value, str):
        raise ConfigError(where, "a cvxpy solver's name (with backend = 'cvxpy'), e.g. 'SCS'", repr(value))
    return value


def _on_failure(value: Any, where: str, n: int, out: bool) -> str:
    from rmpc.mpc.fallback import ON_FAILURE

    if not isinstance(value, str) or value not in ON_FAILURE:
        raise ConfigError(where, "one of " + ", ".join(repr(c) for c in ON_FAILURE), repr(value))
    return value


def _horizon(value: Any, where: str, n: int, out: bool) -> int:
    return _python_check(where, n, out, horizon=value).horizon


def _step_gains(value: Any, where: str, n: int, out: bool) -> str:
    # on its own with the horizon it needs, so that only the value is judged here (the case
    # check judges the combination with the case's own horizon)
    horizon = 2 if value == "vertex" else 1
    return _python_check(where, n, out, step_gains=value, horizon=horizon).step_gains
def _unsaturated_weight(value: Any, where: str, n: int, out: bool) -> float:
    """Huang et al.'s ``beta``, alone as if with ``saturation = "auxiliary"`` (the combination:
    :meth:`RMPCForms.check_case`)."""
    if value is None:
        raise ConfigError(where, "a weight >= 0 (leave the setting out for none)", "None")
    return _python_check(where, n, out, saturation="auxiliary", unsaturated_weight=value).unsaturated_weight


_CHECKS: Mapping[str, Callable[[Any, str, int, bool], Any]] = MappingProxyType(
    {"lyapunov": _lyapunov, "cost": _cost, "free_moves": _free_moves, "saturation": _saturation,
     "soft": _soft, "disturbance": _disturbance, "on_failure": _on_failure, "solver_options": _solver_options,
     "horizon": _horizon, "step_gains": _step_gains, "unsaturated_weight": _unsaturated_weight,
     "output_matrix": _output_matrix, "y_max": _y_max, "solver": _solver}
)
#: The output bounds of an RMPC as settings (families whose RMPC has no output of its own).
OUTPUT_DEFAULTS: Mapping[str, Any] = MappingProxyType({"output_matrix": None, "y_max": None})


def rmpc_kwargs(settings: Mapping[str, Any]) -> dict[str, Any]:
    """The keyword arguments of :class:`rmpc.RMPC` that the form settings stand for."""
    out = {key: settings[key] for key in ("lyapunov", "cost", "free_moves", "saturation")}
    out.update({key: settings.get(key, FORM_SETTINGS[key]) for key in ("horizon", "step_gains")})
    out["soft"] = None if settings["soft"] is None else dict(settings["soft"])
    dist = settings["disturbance"]
    out["disturbance"] = None if dist is None else (
        (np.array(dist["E"]), dist["w_max"]) + ((dist["lam"],) if "lam" in dist else ())
    )
    options = settings.get("solver_options")
    out["solver_options"] = None if options is None else dict(options)
    out["unsaturated_weight"] = settings.get("unsaturated_weight")
    out["solver"] = settings.get("solver")
    if "output_matrix" in settings:  # a family whose RMPC takes its output bounds as settings
        out.update(_output_kwargs(settings))
    return out


def _output_kwargs(settings: Mapping[str, Any]) -> dict[str, Any]:
    matrix, bound = settings.get("output_matrix"), settings.get("y_max")
    return {"output_matrix": None if matrix is None else np.array(matrix, dtype=float),
            "y_max": None if bound is None else np.array(bound, dtype=float)}


def _no_output(values: Mapping[str, Any]) -> bool:
    return False


@dataclass(frozen=True)
class RMPCForms:
    """What a family's RMPC needs to take the forms as settings.

    Attributes
    ----------
    n_states : int
        The states of the family's RMPC (the rows of a disturbance's ``E``).
    has_output : callable
        ``has_output(values) -> bool``: whether the RMPC of a case (its scenario fields
        ``values``) has output bounds (then ``soft`` may weigh ``y``).
    output_settings : bool
        The RMPC takes its output bounds from the settings ``output_matrix`` and ``y_max``
        (:data:`OUTPUT_DEFAULTS`; the families whose scenario fields bound no output).

    Examples
    --------
    >>> forms = RMPCForms(6)
    >>> dict(forms.setting_checks()["soft"]({"u": 10}, "settings.soft"))
    {'u': 10.0}
    """

    n_states: int
    has_output: Callable[[Mapping[str, Any]], bool] = _no_output
    output_settings: bool = False

    def setting_checks(self) -> Mapping[str, Callable[[Any, str], Any]]:
        """The check of each form setting on its own (``check(value, where) -> normalised value``).

        A setting alone is checked as if the RMPC had an input bound (``input_constraint="peak"``)
        and, for ``soft``, output bounds if the family's RMPC can have them at all; the case check
        (:meth:`check_case`) then checks it with the case's own bounds.
        """
        out = self.has_output is not _no_output or self.output_settings

        def bind(check: Callable[[Any, str, int, bool], Any]) -> Callable[[Any, str], Any]:
            return lambda value, where: check(value, where, self.n_states, out)

        keys = [key for key in _CHECKS if self.output_settings or key not in OUTPUT_DEFAULTS]
        return MappingProxyType({key: bind(_CHECKS[key]) for key in keys})

    def check_case(
        self, values: dict[str, Any], controller: str, settings: Mapping[str, Any], name: Callable[[str], str]
    ) -> None:
        """The forms' combinations, with the case's input bound (``saturation = "constraint"``).

        Raises
        ------
        ConfigError
            Naming the settings (and the field ``saturation``) that do not go together.
        """
        if controller != "RMPC":
            return
        check_solver_options(settings, self.n_states, name("settings"))
        if not changed_forms(settings):
            return
        from lmi.forms.options import form_options

        where = name("settings")
        constrained = values["saturation"] == "constraint"
        bound = settings["input_constraint"] if constrained else None
        try:
            has_output = self.has_output(values) or settings.get("output_matrix") is not None
            form_options(
                n_states=self.n_states, input_constraint=bound, has_output=has_output,
                **{k: v for k, v in rmpc_kwargs(settings).items()
                   if k not in ("solver_options", "solver", "output_matrix", "y_max")},
            )
        except (InvalidArgumentError, ArgumentTypeError) as err:
            parts = []
            for part in err.argument.split(", "):
                if part == "input_constraint":
                    parts.append(f"{where}.input_constraint" if constrained else name("saturation"))
                else:
                    parts.append(setting_key_path(part, where))
            expected = err.expected
            if not constrained and ("u_max" in expected or "input_constraint" in err.argument):
                expected += " (the controller has an input bound with saturation = 'constraint')"
                if name("saturation") not in parts:
                    parts.append(name("saturation"))
            raise ConfigError(", ".join(parts), expected, err.found) from None


def changed_forms(settings: Mapping[str, Any]) -> list[str]:
    """The form settings of ``settings`` that are not at their defaults (Kothare's problem)."""
    return [key for key, default in FORM_SETTINGS.items() if settings.get(key, default) != default]
