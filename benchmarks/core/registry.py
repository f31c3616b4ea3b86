"""The plant families by name: the shipped ones and those a user registers.

The dependency runs one way. :mod:`benchmarks.core.family` defines what a family is; each
family sub-package imports that protocol (and :mod:`benchmarks.core.metrics`) and nothing else
of the core; :mod:`benchmarks.families` lists the shipped families in one tuple,
``SHIPPED_FAMILIES``, and registers nothing. This module builds the registry from that tuple on
the first look-up (so importing a scenario does not load every plant model) and adds what
:func:`register_family` is given. No family module imports this one, so the registry never
imports back into a module that is still loading.

Examples
--------
>>> from benchmarks.core.registry import family_names, get_family
>>> family_names()[:2]
('rigid', 'wheel')
>>> get_family("rigid").fields["plant"].default
'nonlinear'
>>> get_family("tumbling", where="base.family")
Traceback (most recent call last):
...
toolkit_common.errors.ConfigError: base.family: expected one of 'rigid', ..., but found 'tumbling'
"""

from __future__ import annotations

import functools
from collections.abc import Iterable

from benchmarks.core.family import REQUIRED_FIELDS, PlantFamily
from toolkit_common.errors import ConfigError

__all__ = ["FamilyRegistry", "default_registry", "family_names", "get_family", "register_family"]

#: The scenario fields the core owns; a family may not declare them.
_CORE_FIELDS = frozenset({"family", "controller", "settings"})


class FamilyRegistry:
    """Plant families by name, each checked against the protocol when it is added.

    Parameters
    ----------
    families : iterable of PlantFamily
        The families to start with, in order.

    Examples
    --------
    >>> from benchmarks.families import RIGID
    >>> registry = FamilyRegistry([RIGID])
    >>> registry.names(), "rigid" in registry, registry.get("rigid") is RIGID
    (('rigid',), True, True)
    """

    def __init__(self, families: Iterable[PlantFamily] = ()) -> None:
        self._families: dict[str, PlantFamily] = {}
        for family in families:
            self.add(family)

    def add(self, family: PlantFamily, replace: bool = False) -> PlantFamily:
        """Add ``family``; another family under a name already taken raises unless ``replace``."""
        if not isinstance(family, PlantFamily):
            raise ConfigError("family", "a benchmarks.core.family.PlantFamily", type(family).__name__)
        missing = [f for f in REQUIRED_FIELDS if f not in family.fields]
        if missing:
            raise ConfigError(
                f"family {family.name!r}",
                "the fields " + ", ".join(REQUIRED_FIELDS),
                "no " + ", ".join(missing),
            )
        clash = _CORE_FIELDS & set(family.fields)
        if clash:
            raise ConfigError(f"family {family.name!r}", "no core field among its fields", ", ".join(clash))
        if family.name in self._families and not replace and self._families[family.name] is not family:
            raise ConfigError("family", "a name not registered yet", repr(family.name))
        self._families[family.name] = family
        return family

    def get(self, name: str, where: str = "family") -> PlantFamily:
        """The family ``name``; a :class:`ConfigError` naming ``where`` otherwise."""
        try:
            return self._families[name]
        except (KeyError, TypeError):
            names = ", ".join(repr(n) for n in self._families)
            raise ConfigError(where, f"one of {names}", repr(name)) from None

    def names(self) -> tuple[str, ...]:
        """The names, in the order the families were added."""
        return tuple(self._families)

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and name in self._families


@functools.cache
def default_registry() -> FamilyRegistry:
    """The registry scenarios and sweeps look families up in (one per process, built on first use).

    It holds :data:`benchmarks.families.SHIPPED_FAMILIES`, then whatever :func:`register_family`
    adds.
    """
    from benchmarks.families import SHIPPED_FAMILIES

    return FamilyRegistry(SHIPPED_FAMILIES)


def register_family(family: PlantFamily, replace: bool = False) -> PlantFamily:
    """Make ``family`` available to scenarios (``family = "<name>"``), sweeps and suites.

    Registering another family under a name already taken raises unless ``replace``. Worker
    processes started by ``--workers`` or Dask know only the shipped families and what they
    import themselves.
    """
    return default_registry().add(family, replace)


def get_family(name: str, where: str = "family") -> PlantFamily:
    """The registered family ``name``; a :class:`ConfigError` naming ``where`` otherwise."""
    return default_registry().get(name, where)


def family_names() -> tuple[str, ...]:
    """The names of the registered families (the shipped ones first)."""
    return default_registry().names()
