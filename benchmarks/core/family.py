"""Plant families: what the harness core needs to know about a kind of plant (the protocol).

A :class:`PlantFamily` brings everything that is particular to one kind of plant (paper P's
rigid satellite, the four-wheel satellite with faults, ...): its scenario fields with their
defaults and checks, its controllers with their settings, the checks that involve several
fields, how one case is built, simulated and measured, and (optionally) what a Monte-Carlo draw
changes. The core (scenarios, sweeps, runner, store, executors) only talks to this interface,
so a new family is a new sub-package of :mod:`benchmarks.families` listed in its
``SHIPPED_FAMILIES``, or a user's own object registered with
:func:`benchmarks.core.registry.register_family`: nothing in the core is edited.

This module is the bottom of the harness: it imports nothing of :mod:`benchmarks`, not even for
type hints (a scenario is typed ``Any``), and the families import it (with
:mod:`benchmarks.core.metrics`) and nothing else of the core. Looking a family up by name is
:mod:`benchmarks.core.registry`'s job, and :mod:`benchmarks.core.scenario` uses both.

Every family has at least the fields ``plant``, ``saturation``, ``duration`` and ``dt`` (the
record of a case names its plant and saturation; a ``duration`` of ``None`` lets the family pick
the run length, e.g. from a paper's scenario). The
scenario fields ``family``, ``controller`` and ``settings`` are the core's.

Examples
--------
>>> from benchmarks.core.family import check_real
>>> check_real(0.5, "spread", low=0.0, high=1.0, high_open=True)
0.5
"""

from __future__ import annotations

import math
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from toolkit_common.errors import ConfigError
from toolkit_common.validation import is_integer, is_real

__all__ = [
    "REQUIRED_FIELDS",
    "BuiltController",
    "CaseResult",
    "ControllerSpec",
    "Field",
    "MonteCarlo",
    "PlantFamily",
    "check_bool",
    "check_choice",
    "check_ellipsoid_count",
    "check_horizon",
    "check_number",
    "check_real",
    "check_run_length",
    "controller_specs",
]

#: Fields every family must declare.
REQUIRED_FIELDS = ("plant", "saturation", "duration", "dt")


@dataclass(frozen=True)
class Field:
    """One scenario field of a family: its default and the check of a value on its own.

    ``check(value, where) -> normalised value`` raises :class:`ConfigError` naming ``where``.
    ``written_at_default=False`` leaves the field out of :meth:`Scenario.to_dict` (records, case
    ids) while it holds its default: a field added to a family later keeps the records and case
    ids of the cases that do not set it.
    """

    default: Any
    check: Callable[[Any, str], Any]
    doc: str = ""
    written_at_default: bool = True


@dataclass(frozen=True)
class BuiltController:
    """A controller ready for :func:`rmpc.sim.simulate` and whether it needs a limiter in the loop."""

    controller: Any
    needs_limiter: bool


@dataclass(frozen=True)
class ControllerSpec:
    """A controller of a family.

    Attributes
    ----------
    build : callable
        ``build(model, scenario, settings) -> BuiltController``; ``model`` is what the family's
        :attr:`PlantFamily.simulate` hands over (e.g. the controller's polytope).
    defaults : mapping
        Every setting with its default; the type of the default is the type a value must have
        (bool, positive int, float >= 0, tuple of floats, or a string among
        :attr:`PlantFamily.setting_choices`).
    constrained : bool
        Whether it can enforce the input limit itself (``saturation = "constraint"``).
    """

    build: Callable[[Any, Any, Mapping[str, Any]], BuiltController]
    defaults: Mapping[str, Any]
    constrained: bool = True


def controller_specs(
    builders: Mapping[str, Callable[[Any, Any, Mapping[str, Any]], BuiltController]],
    defaults: Mapping[str, Mapping[str, Any]],
    constrained: Collection[str],
) -> dict[str, ControllerSpec]:
    """One :class:`ControllerSpec` per controller of ``builders``, in their order.

    ``defaults[name]`` are its settings' defaults; it can enforce the input limit itself when its
    name is in ``constrained``.
    """
    return {
        name: ControllerSpec(build, defaults[name], name in constrained) for name, build in builders.items()
    }


@dataclass(frozen=True)
class CaseResult:
    """What a family's simulation of one case returns to the runner.

    Attributes
    ----------
    settings : dict
        What the record's ``settings`` adds to the scenario's fields (initial state, the model
        the controller used, ...). The shipped families write ``duration_used``, the time that
        ran (``n_steps dt`` of the trajectory; the scenario's ``duration`` is what was asked for,
        which :func:`rmpc.sim.simulate` rounds to whole samples).
    metrics : dict
        The record's ``metrics``.
    trace : dict of ndarray
        The time series of the run (for figures); kept only when asked for.
    """

    settings: dict[str, Any]
    metrics: dict[str, Any]
    trace: dict[str, np.ndarray]


@dataclass(frozen=True)
class MonteCarlo:
    """What one seeded Monte-Carlo draw changes in a scenario.

    Attributes
    ----------
    dims : int
        Size of a draw ``u``, uniform in ``[-1, 1]^dims``.
    sets : tuple of str
        The fields a draw sets (a sweep may not set them in ``[base]`` or ``[grid]``).
    apply : callable
        ``apply(scenario, u) -> {field: value}``.
    """

    dims: int
    sets: tuple[str, ...]
    apply: Callable[[Any, np.ndarray], Mapping[str, Any]]


def _no_cross_check(values: dict[str, Any], controller: str, name: Callable[[str], str]) -> None:
    return None


@dataclass(frozen=True)
class PlantFamily:
    """A kind of plant the harness can run (see the module notes).

    Attributes
    ----------
    name : str
        The value of the scenario field ``family``.
    description : str
        One line for ``--help`` and reports.
    fields : mapping of str to Field
        The family's scenario fields, in the order records list them; must include
        :data:`REQUIRED_FIELDS`.
    controllers : mapping of str to ControllerSpec
        The controllers this family runs.
    simulate : callable
        ``simulate(scenario, settings, keep_trace) -> CaseResult``: build the plant and the
        controller (through :meth:`build_controller`), run, measure. ``settings`` are the
        effective controller settings.
    check : callable, optional
        ``check(values, controller, name)``: checks that involve several fields (``values``
        field name -> normalised value; ``name(field)`` gives the dotted name for errors).
    label : callable, optional
        ``label(scenario) -> str``, a short description for tables and progress.
    setting_choices : mapping, optional
        Allowed values of string-valued settings.
    zero_allowed : frozenset of str
        Float settings that may be 0.
    settings_check : callable, optional
        ``settings_check(controller, settings, where)``: checks between settings.
    montecarlo : MonteCarlo, optional
        What a sweep's ``[montecarlo]`` draw changes; ``None``: the family has no draws.
    setting_checks : mapping of str to callable, optional
        ``check(value, where) -> normalised value`` of the settings whose values are not of the
        kinds a default's type describes (a table of weights, a matrix, ``None`` by default): the
        check raises :class:`ConfigError` naming ``where`` and returns a read-only value.
    quiet_settings : frozenset of str
        Settings left out of a case's record (and of its case id) while they hold their default,
        so that a setting added later keeps the records and case ids of the cases that do not
        set it (as :attr:`Field.written_at_default` does for fields). ``"<controller>.<setting>"``
        quiets the setting of that controller only (``"OfflineRMPC.backend"``: the RMPC's
        ``backend`` stays written).
    case_check : callable, optional
        ``case_check(values, controller, settings, name)``: checks between fields and settings
        (a form that needs an input bound the scenario does not give); ``name(key)`` gives the
        dotted name for errors (``name("settings")`` the settings table's).
    controller_defaults : callable, optional
        ``controller_defaults(controller) -> {field: default}``: defaults that depend on the
        controller (e.g. ``saturation = "limiter"`` for a controller without a constraint),
        used where the scenario does not set the field.
    not_settings : mapping of str to str
        Constructor keywords of the family's controllers that a sweep cannot set, each with why
        (the family's target, a field that sets it): a sweep file that names one is refused
        with that reason instead of "an unknown name".
    """

    name: str
    description: str
    fields: Mapping[str, Field]
    controllers: Mapping[str, ControllerSpec]
    simulate: Callable[[Any, Mapping[str, Any], bool], CaseResult]
    check: Callable[[dict[str, Any], str, Callable[[str], str]], None] = _no_cross_check
    label: Callable[[Any], str] | None = None
    setting_choices: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    zero_allowed: frozenset[str] = frozenset()
    settings_check: Callable[[str, dict[str, Any], str], None] | None = None
    montecarlo: MonteCarlo | None = None
    controller_defaults: Callable[[str], Mapping[str, Any]] | None = None
    setting_checks: Mapping[str, Callable[[Any, str], Any]] = field(default_factory=dict)
    quiet_settings: frozenset[str] = frozenset()
    case_check: Callable[[dict[str, Any], str, Mapping[str, Any], Callable[[str], str]], None] | None = None
    not_settings: Mapping[str, str] = field(default_factory=dict)

    def default(self, key: str, controller: str) -> Any:
        """The default of field ``key`` for ``controller``."""
        if self.controller_defaults is not None:
            own = self.controller_defaults(controller)
            if key in own:
                return own[key]
        return self.fields[key].default

    # -- settings ---------------------------------------------------------------------
    def _check_value(self, default: Any, value: Any, where: str, key: str | None = None) -> Any:
        if key is not None and key in self.setting_checks:
            # a setting that is None by default (none asked for) is left out of a file, or null in a record
            return None if value is None and default is None else self.setting_checks[key](value, where)
        if isinstance(default, bool):
            return check_bool(value, where)
        if isinstance(default, int):
            if not is_integer(value) or value < 1:
                raise ConfigError(where, "a positive integer", repr(value))
            return int(value)
        if isinstance(default, float):
            zero_ok = where.rsplit(".", 1)[-1] in self.zero_allowed
            number = is_real(value) and np.isfinite(value)
            if not number or value < 0 or (value == 0 and not zero_ok):
                raise ConfigError(where, "a number >= 0" if zero_ok else "a number > 0", repr(value))
            return float(value)
        if isinstance(default, tuple):
            ok = (
                isinstance(value, list | tuple)
                and len(value) == len(default)
                and all(
                    is_real(v) and np.isfinite(v) and v >= 0
                    for v in value
                )
            )
            if not ok:
                raise ConfigError(where, f"a list of {len(default)} numbers >= 0", repr(value))
            return tuple(float(v) for v in value)
        choices = self.setting_choices.get(where.rsplit(".", 1)[-1])
        if not isinstance(value, str) or (choices is not None and value not in choices):
            expected = "a string" if choices is None else "one of " + ", ".join(repr(c) for c in choices)
            raise ConfigError(where, expected, repr(value))
        return value

    def setting_names(self) -> list[str]:
        """Every setting name of every controller of the family, sorted."""
        return sorted({k for spec in self.controllers.values() for k in spec.defaults})

    def check_setting(self, key: str, value: Any, where: str) -> Any:
        """Check one setting's value against the controller(s) that have it; return it normalised."""
        owners = [spec.defaults for spec in self.controllers.values() if key in spec.defaults]
        if not owners:
            self._refuse_not_setting(key, where)
            expected = f"a controller setting ({', '.join(self.setting_names())})"
            raise ConfigError(where, expected, "an unknown name")
        return self._check_value(owners[0][key], value, where, key)

    def effective_settings(
        self, controller: str, overrides: Mapping[str, Any], where: str = "settings", lenient: bool = False
    ) -> dict[str, Any]:
        """The controller's defaults updated by ``overrides``, each checked.

        With ``lenient`` a setting of another controller of the family is dropped instead of
        refused (one settings table can then serve a sweep over several controllers); a name no
        controller has is an error either way.
        """
        defaults = self.controllers[controller].defaults
        out = dict(defaults)
        for key, value in overrides.items():
            if key not in defaults:
                if lenient and any(key in spec.defaults for spec in self.controllers.values()):
                    continue
                self._refuse_not_setting(key, f"{where}.{key}")
                raise ConfigError(
                    f"{where}.{key}", f"a setting of {controller} ({', '.join(defaults)})", "an unknown name"
                )
            out[key] = self._check_value(defaults[key], value, f"{where}.{key}", key)
        if self.settings_check is not None:
            self.settings_check(controller, out, where)
        return out

    def _refuse_not_setting(self, key: str, where: str) -> None:
        """A keyword the family's controllers take but a sweep cannot set: refused, saying why."""
        why = self.not_settings.get(key)
        if why is not None:
            raise ConfigError(where, f"no {key} in a sweep file ({why})", f"{key} given")

    def unsupported(self, controller: str, saturation: str) -> str | None:
        """Why ``controller`` cannot run with ``saturation`` (``None`` if it can)."""
        spec = self.controllers.get(controller)
        if saturation == "constraint" and spec is not None and not spec.constrained:
            return f"'none' or 'limiter' for {controller} (it has no constraint)"
        return None

    def build_controller(self, model: Any, scenario: Any) -> BuiltController:
        """Build the scenario's controller on ``model`` with its effective settings.

        ``scenario`` is a :class:`benchmarks.core.scenario.Scenario` (typed ``Any`` here, like the
        scenario every callable above receives: the scenario module imports this one).
        """
        settings = self.effective_settings(scenario.controller, scenario.settings)
        return self.controllers[scenario.controller].build(model, scenario, settings)


# -- field checks families share ---------------------------------------------------------
def check_bool(value: Any, where: str) -> bool:
    """``value`` if it is ``true`` or ``false``; a :class:`ConfigError` naming ``where`` otherwise.

    The configuration-file counterpart of :func:`toolkit_common.validation.check_bool` (a TOML
    boolean, reported as a :class:`ConfigError` with the field's dotted path).
    """
    if not isinstance(value, bool):
        raise ConfigError(where, "true or false", repr(value))
    return value


def check_choice(value: Any, where: str, choices: tuple[str, ...]) -> str:
    """``value`` if it is one of ``choices``; a :class:`ConfigError` naming ``where`` otherwise."""
    if not isinstance(value, str) or value not in choices:
        raise ConfigError(where, "one of " + ", ".join(repr(c) for c in choices), repr(value))
    return value


def check_number(value: Any, where: str) -> float:
    """``value`` as a float if it is a finite number (not a bool)."""
    if not is_real(value) or not math.isfinite(value):
        raise ConfigError(where, "a finite number", repr(value))
    return float(value)


def check_real(
    value: Any,
    where: str,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
) -> float:
    """A finite number inside the given bounds (open or closed)."""
    x = check_number(value, where)
    bad_low = low is not None and (x < low or (low_open and x == low))
    bad_high = high is not None and (x > high or (high_open and x == high))
    if bad_low or bad_high:
        lo = "" if low is None else f"{'>' if low_open else '>='} {low:g}"
        hi = "" if high is None else f"{'<' if high_open else '<='} {high:g}"
        raise ConfigError(where, "a number " + " and ".join(p for p in (lo, hi) if p), repr(value))
    return x


# -- sizes, bounded where the file is read (not after a case has been started) ---------------------


def check_run_length(duration: float, dt: float, where: str) -> int:
    """The samples of a run, ``round(duration / dt)``, if :func:`rmpc.sim.simulate` takes that many.

    A run of more than :data:`rmpc.sim.simulate.MAX_STEPS` samples (10 million), or of less than
    one, is refused here, naming ``where``, instead of failing in each case after the sweep has
    started. A sweep cannot lift the bound (the families call ``simulate`` with its default); a
    longer run is a script calling ``simulate(..., max_steps=N)``.

    Examples
    --------
    >>> check_run_length(30.0, 0.01, "duration")
    3000
    >>> try:
    ...     check_run_length(1e12, 0.01, "base.duration")
    ... except ValueError as err:
    ...     print(err.argument, "|", err.found)
    base.duration | 1e+12 s / dt 0.01 s = 1e+14 samples
    """
    from rmpc.sim.simulate import MAX_STEPS

    samples = duration / dt
    found = f"{duration:g} s / dt {dt:g} s = {samples:.3g} samples"
    if not math.isfinite(samples) or round(samples) > MAX_STEPS:
        expected = (
            f"a run of at most rmpc.sim.simulate.MAX_STEPS = {MAX_STEPS} samples (a sweep cannot lift it: "
            "shorten the run or lengthen dt; simulate(..., max_steps=N) in a script lifts it)"
        )
        raise ConfigError(where, expected, found)
    if round(samples) < 1:
        raise ConfigError(where, f"a run of at least one sample (dt = {dt:g} s)", found)
    return round(samples)


def check_horizon(value: int, where: str) -> int:
    """A GIPC prediction horizon ``Np`` up to :data:`rmpc.mpc.gipc.MAX_HORIZON` (20000), named ``where``.

    Examples
    --------
    >>> check_horizon(400, "settings.Np")
    400
    """
    from rmpc.mpc.gipc import MAX_HORIZON

    if value > MAX_HORIZON:
        expected = (
            f"at most rmpc.mpc.gipc.MAX_HORIZON = {MAX_HORIZON} samples (a sweep cannot lift it; "
            "GIPC(..., max_horizon=N) in a script lifts it)"
        )
        raise ConfigError(where, expected, repr(value))
    return value


def check_ellipsoid_count(n_ellipsoids: int, shrink: float, where: str) -> int:
    """An OfflineRMPC table size that ``shrink`` allows (:func:`lmi.offline.check_ellipsoid_count`).

    Examples
    --------
    >>> check_ellipsoid_count(15, 0.5, "settings.n_ellipsoids")
    15
    """
    from lmi.offline import check_ellipsoid_count as lmi_check

    try:
        return lmi_check(n_ellipsoids, shrink)
    except ValueError as err:
        raise ConfigError(where, getattr(err, "expected", str(err)), repr(n_ellipsoids)) from None
