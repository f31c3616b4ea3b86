"""The plant families the harness ships, one sub-package each, registered on import.

- :mod:`benchmarks.families.rigid`: paper P's rigid satellite (``family = "rigid"``, the default);
- :mod:`benchmarks.families.wheel`: paper W's four-wheel satellite with wheel faults (``"wheel"``);
- :mod:`benchmarks.families.mrp`: paper M's MRP satellite with the spinning disk (``"mrp"``);
- :mod:`benchmarks.families.flexible`: paper V's flexible satellite with PZT patches (``"flexible"``).

A new family is a sub-package with a :class:`~benchmarks.core.family.PlantFamily` object,
registered below with :func:`~benchmarks.core.family.register_family`; a user's own family can
be registered the same way from their code, before the scenarios that name it are built.
"""

from benchmarks.core.family import register_family
from benchmarks.families.flexible.family import FLEXIBLE
from benchmarks.families.mrp.family import MRP
from benchmarks.families.rigid.family import RIGID
from benchmarks.families.wheel.family import WHEEL

register_family(RIGID)
register_family(WHEEL)
register_family(MRP)
register_family(FLEXIBLE)

__all__ = ["FLEXIBLE", "MRP", "RIGID", "WHEEL"]
