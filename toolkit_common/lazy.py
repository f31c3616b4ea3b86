"""A package's public names imported from their modules on first use (PEP 562).

``import rmpc`` used to import every controller, and with them python-control, matplotlib and
scipy's signal and statistics packages (4-5 s here); a package's ``__init__`` now lists its
public names and the module that defines each, and a name's module is imported the first time
the name is looked up (``rmpc.RMPC``, ``from rmpc import RMPC``). The value is then stored in
the package's namespace, so later look-ups are ordinary attribute reads. ``dir(package)`` and
``from package import *`` see every listed name before it is loaded.

A package's ``__init__`` uses it so (the imports under ``TYPE_CHECKING`` show the names to type
checkers and to the import-graph test, and cost nothing at run time)::

    from typing import TYPE_CHECKING

    from toolkit_common.lazy import lazy_exports

    if TYPE_CHECKING:
        from rmpc.mpc.robust_mpc import RMPC

    __all__ = ["RMPC"]
    __getattr__, __dir__ = lazy_exports(__name__, {"rmpc.mpc.robust_mpc": ("RMPC",)})
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Iterable, Mapping
from typing import Any

from toolkit_common.errors import InvalidArgumentError

__all__ = ["lazy_exports"]


def lazy_exports(
    package: str, exports: Mapping[str, Iterable[str]]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """The module ``__getattr__`` and ``__dir__`` of a package whose names load on first use.

    Parameters
    ----------
    package : str
        The package's ``__name__``; it must be in ``sys.modules`` when a name is looked up (it
        is while its ``__init__`` runs and after).
    exports : mapping of str to iterable of str
        For each defining module (its full dotted name), the public names taken from it.

    Returns
    -------
    getattr : callable
        ``__getattr__(name)``: imports the module defining ``name``, stores the value in the
        package's namespace and returns it; ``AttributeError`` for a name not listed.
    dir : callable
        ``__dir__()``: the package's namespace and every listed name, sorted.

    Raises
    ------
    InvalidArgumentError
        If a name is listed under two modules.
    """
    where: dict[str, str] = {}
    for module, names in exports.items():
        for name in names:
            if name in where:
                raise InvalidArgumentError(
                    "exports", "each name under one module", f"{name!r} under {where[name]!r} and {module!r}"
                )
            where[name] = module

    def __getattr__(name: str) -> Any:
        module = where.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module), name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(where))

    return __getattr__, __dir__
