"""benchmarks.core.registry: families by name, checked on the way in, the shipped ones by default."""

from __future__ import annotations

import dataclasses

import pytest

from benchmarks.core.registry import FamilyRegistry, default_registry, family_names, get_family
from benchmarks.families import FLEXIBLE, MRP, RIGID, SHIPPED_FAMILIES, WHEEL
from toolkit_common.errors import ConfigError


def test_the_default_registry_holds_the_shipped_families_in_their_order():
    assert SHIPPED_FAMILIES == (RIGID, WHEEL, MRP, FLEXIBLE)
    assert family_names()[:4] == ("rigid", "wheel", "mrp", "flexible")
    assert get_family("wheel") is WHEEL
    assert default_registry() is default_registry()


def test_importing_the_families_registers_nothing():
    registry = FamilyRegistry()
    assert registry.names() == () and "rigid" not in registry
    with pytest.raises(ConfigError, match=r"grid\.family"):
        registry.get("rigid", where="grid.family")


def test_a_registry_checks_what_it_is_given():
    registry = FamilyRegistry([RIGID])
    assert registry.add(RIGID) is RIGID  # the same object again is no clash
    other = dataclasses.replace(RIGID, description="another rigid satellite")
    with pytest.raises(ConfigError, match="a name not registered yet"):
        registry.add(other)
    assert registry.add(other, replace=True) is other and registry.get("rigid") is other
    with pytest.raises(ConfigError, match="PlantFamily"):
        registry.add("rigid")  # type: ignore[arg-type]
    fields = {k: v for k, v in RIGID.fields.items() if k != "dt"}
    with pytest.raises(ConfigError, match="no dt"):
        registry.add(dataclasses.replace(RIGID, name="no_dt", fields=fields))
    clash = {**RIGID.fields, "controller": RIGID.fields["plant"]}
    with pytest.raises(ConfigError, match="no core field"):
        registry.add(dataclasses.replace(RIGID, name="clash", fields=clash))
    with pytest.raises(ConfigError, match="one of 'rigid'"):
        registry.get(["rigid"])  # type: ignore[arg-type]
    assert registry.names() == ("rigid",)
