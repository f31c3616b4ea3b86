"""A benchmark scenario: the plant family, its fields, the controller and its settings.

A :class:`Scenario` is an immutable, validated description of one closed-loop run. Its fields
are the core's (``family``, ``controller``, ``settings``) and those of its plant family
(:mod:`benchmarks.core.family`, looked up in :mod:`benchmarks.core.registry`; paper P's rigid
satellite by default, whose fields are listed in :mod:`benchmarks.families.rigid.family`).
:attr:`Scenario.case_id` is a stable hash of :meth:`Scenario.to_dict`, so the same case gets the
same id in every sweep and every run. :func:`benchmarks.core.runner.run_scenario` simulates it
and returns the record that ``results.json`` holds.

Examples
--------
>>> from benchmarks.core.scenario import Scenario
>>> sc = Scenario.from_dict({"controller": "LQR", "saturation": "limiter", "duration": 1.0})
>>> sc.family, sc.plant, sc.spread, sc.settings["R_diag"]
('rigid', 'nonlinear', 0.3, (0.01, 0.01, 0.01))
>>> len(sc.case_id)
16
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from types import MappingProxyType
from typing import Any

from benchmarks.core.family import PlantFamily, check_run_length
from benchmarks.core.registry import get_family
from toolkit_common.errors import ConfigError

__all__ = ["CORE_FIELDS", "DEFAULT_FAMILY", "Scenario"]

#: The family of a scenario that does not name one: paper P's rigid satellite.
DEFAULT_FAMILY = "rigid"
#: The fields every scenario has, whatever its family.
CORE_FIELDS = ("family", "controller", "settings")
#: The controller of a scenario that does not name one.
DEFAULT_CONTROLLER = "RMPC"


class Scenario:
    """One closed-loop run of the benchmark (every field has a default).

    Build it with :meth:`from_dict`, which validates every field. The family's fields are
    attributes (``scenario.spread``, ``scenario.plant``, ...).

    Attributes
    ----------
    family : str
        A registered plant family (default ``"rigid"``, paper P's satellite).
    controller : str
        A controller of the family (default ``"RMPC"``).
    settings : mapping
        The controller's settings: its defaults updated by what the scenario gives; after
        validation it holds every setting.
    """

    __slots__ = ("_controller", "_family", "_settings", "_values")

    def __init__(self, family: str, controller: str, settings: Mapping[str, Any], values: Mapping[str, Any]):
        self._family = family
        self._controller = controller
        self._settings = MappingProxyType(dict(settings))
        self._values = MappingProxyType(dict(values))

    # -- fields -----------------------------------------------------------------------
    @property
    def family(self) -> str:
        """The plant family's name."""
        return self._family

    @property
    def controller(self) -> str:
        """The controller's name."""
        return self._controller

    @property
    def settings(self) -> Mapping[str, Any]:
        """Every setting of the controller (read-only)."""
        return self._settings

    @property
    def plant_family(self) -> PlantFamily:
        """The :class:`~benchmarks.core.family.PlantFamily` object."""
        return get_family(self._family)

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):
            raise AttributeError(name)
        try:
            return self._values[name]
        except KeyError:
            raise AttributeError(f"a {self._family!r} scenario has no field {name!r}") from None

    def __setattr__(self, name: str, value: Any) -> None:
        if name in self.__slots__ and not hasattr(self, name):
            object.__setattr__(self, name, value)
            return
        raise AttributeError("a Scenario is immutable: build a new one with Scenario.from_dict")

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Scenario) and self.to_dict() == other.to_dict()

    def __hash__(self) -> int:
        return hash(self.case_id)

    def __repr__(self) -> str:
        return f"Scenario({self.label()!r}, case_id={self.case_id!r})"

    @classmethod
    def field_names(cls, family: str = DEFAULT_FAMILY) -> tuple[str, ...]:
        """Names of the scenario fields of ``family``: the core's and the family's."""
        return (*CORE_FIELDS, *get_family(family).fields)

    @classmethod
    def default(cls, key: str, family: str = DEFAULT_FAMILY) -> Any:
        """The default of field ``key`` in ``family``."""
        if key == "family":
            return DEFAULT_FAMILY
        if key == "controller":
            return DEFAULT_CONTROLLER
        if key == "settings":
            return {}
        return get_family(family).fields[key].default

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
            Drop settings that belong to another controller of the family (sweeps over several
            controllers share one settings table).

        Raises
        ------
        ConfigError
            On an unknown field or an impossible value; its argument is the dotted field.
        """

        def name(key: str) -> str:
            return f"{where}.{key}" if where else key

        if not isinstance(data, Mapping):
            raise ConfigError(where or "scenario", "a table of scenario fields", type(data).__name__)
        family_name = data.get("family", DEFAULT_FAMILY)
        if not isinstance(family_name, str):
            raise ConfigError(name("family"), "the name of a plant family", repr(family_name))
        family = get_family(family_name, name("family"))
        known = cls.field_names(family_name)
        for key in data:
            if key not in known:
                raise ConfigError(
                    name(str(key)), "a scenario field (" + ", ".join(known) + ")", "an unknown field"
                )
        controller = data.get("controller", DEFAULT_CONTROLLER)
        if not isinstance(controller, str) or controller not in family.controllers:
            choices = ", ".join(repr(c) for c in family.controllers)
            raise ConfigError(name("controller"), "one of " + choices, repr(controller))
        values = {
            key: spec.check(data[key], name(key)) if key in data else family.default(key, controller)
            for key, spec in family.fields.items()
        }
        overrides = data.get("settings", {})
        if not isinstance(overrides, Mapping):
            raise ConfigError(name("settings"), "a table of controller settings", repr(overrides))
        settings = family.effective_settings(controller, overrides, name("settings"), lenient_settings)
        problem = family.unsupported(controller, values["saturation"])
        if problem is not None:
            raise ConfigError(name("saturation"), problem, "'constraint'")
        family.check(values, controller, name)
        if family.case_check is not None:
            family.case_check(values, controller, settings, name)
        if values["duration"] is not None:
            if values["duration"] < values["dt"]:
                expected = f"at least one sample (dt = {values['dt']:g} s)"
                raise ConfigError(name("duration"), expected, repr(values["duration"]))
            check_run_length(values["duration"], values["dt"], name("duration"))
        return cls(family_name, controller, settings, values)

    @classmethod
    def check_field(cls, key: str, value: Any, where: str, family: str = DEFAULT_FAMILY) -> Any:
        """Check one field's value on its own (no other field involved); return it normalised.

        Examples
        --------
        >>> Scenario.check_field("u_max", 2, "grid.u_max")
        2.0
        """
        fam = get_family(family)
        if key == "family":
            get_family(value, where)
            return value
        if key == "controller":
            if not isinstance(value, str) or value not in fam.controllers:
                raise ConfigError(where, "one of " + ", ".join(repr(c) for c in fam.controllers), repr(value))
            return value
        if key not in fam.fields:
            known = ", ".join(cls.field_names(family))
            raise ConfigError(where, f"a scenario field ({known})", "an unknown field")
        return fam.fields[key].check(value, where)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready values of every field (the inverse of :meth:`from_dict`).

        The default family is not written, so the records of paper P's satellite keep the
        fields (and the case ids) they had before families existed; nor is a field declared
        with ``written_at_default=False`` (:class:`benchmarks.core.family.Field`) while it
        holds its default, nor a setting among the family's ``quiet_settings`` while it holds
        its default (:class:`benchmarks.core.family.PlantFamily`).
        """
        out: dict[str, Any] = {} if self._family == DEFAULT_FAMILY else {"family": self._family}
        fields = get_family(self._family).fields
        items = [
            (key, value)
            for key, value in self._values.items()
            if fields[key].written_at_default or value != fields[key].default
        ]
        first, rest = items[:1], items[1:]
        fam = get_family(self._family)
        defaults = fam.controllers[self._controller].defaults
        settings = {
            k: _plain(v)
            for k, v in sorted(self._settings.items())
            if not {k, f"{self._controller}.{k}"} & fam.quiet_settings or v != defaults.get(k)
        }
        for key, value in [*first, ("controller", self._controller), ("settings", settings), *rest]:
            out[key] = _plain(value)
        return out

    @property
    def case_id(self) -> str:
        """A stable 16-hex-digit id: a SHA-256 of the canonical JSON of :meth:`to_dict`."""
        text = json.dumps(self.to_dict(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]

    def label(self) -> str:
        """A short human-readable description for tables and progress."""
        fam = get_family(self._family)
        if fam.label is not None:
            return fam.label(self)
        return " ".join([self._controller, self.plant, self.saturation])


def _plain(value: Any) -> Any:
    """``value`` with its tuples as lists and its read-only tables as dicts (JSON-ready)."""
    if isinstance(value, tuple | list):
        return [_plain(v) for v in value]
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    return value
