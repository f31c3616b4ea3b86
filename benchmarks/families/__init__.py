"""The plant families the harness ships, one sub-package each, registered on import.

- :mod:`benchmarks.families.rigid`: paper P's rigid satellite (``family = "rigid"``, the default).

A new family is a sub-package with a :class:`~benchmarks.core.family.PlantFamily` object,
registered below with :func:`~benchmarks.core.family.register_family`; a user's own family can
be registered the same way from their code, before the scenarios that name it are built.
"""

from benchmarks.core.family import register_family
from benchmarks.families.rigid.family import RIGID

register_family(RIGID)

__all__ = ["RIGID"]
