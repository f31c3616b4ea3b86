"""The plant families the harness ships, one sub-package each, listed in :data:`SHIPPED_FAMILIES`.

- :mod:`benchmarks.families.rigid`: paper P's rigid satellite (``family = "rigid"``, the default);
- :mod:`benchmarks.families.wheel`: paper W's four-wheel satellite with wheel faults (``"wheel"``);
- :mod:`benchmarks.families.mrp`: paper M's MRP satellite with the spinning disk (``"mrp"``);
- :mod:`benchmarks.families.flexible`: paper V's flexible satellite with PZT patches (``"flexible"``).

A new family is a sub-package with a :class:`~benchmarks.core.family.PlantFamily` object, added
to :data:`SHIPPED_FAMILIES` below; :mod:`benchmarks.core.registry` builds the registry from that
tuple. A user's own family is registered from their code with
:func:`~benchmarks.core.registry.register_family`, before the scenarios that name it are built.
Nothing here imports the registry: the families depend on the core's protocol, never the
other way round.
"""

from benchmarks.core.family import PlantFamily
from benchmarks.families.flexible.family import FLEXIBLE
from benchmarks.families.mrp.family import MRP
from benchmarks.families.rigid.family import RIGID
from benchmarks.families.wheel.family import WHEEL

#: The families every process knows, in the order ``family_names()`` lists them.
SHIPPED_FAMILIES: tuple[PlantFamily, ...] = (RIGID, WHEEL, MRP, FLEXIBLE)

__all__ = ["FLEXIBLE", "MRP", "RIGID", "SHIPPED_FAMILIES", "WHEEL"]
