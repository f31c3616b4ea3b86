"""Leaf package shared by :mod:`models`, :mod:`lmi`, :mod:`rmpc` and :mod:`benchmarks`.

It holds the one exception hierarchy of the toolkit (:mod:`toolkit_common.errors`), the
argument checks that produce its messages (:mod:`toolkit_common.validation`) and the one status
vocabulary of solvers and controllers (:mod:`toolkit_common.status`). It imports
nothing from the other packages, so ``models`` and ``lmi`` can both use it without importing
each other.
"""

from toolkit_common.errors import (
    ArgumentTypeError,
    ConfigError,
    ControllerFileError,
    InvalidArgumentError,
    SingularityError,
    SolverError,
    StoreError,
    ToolkitError,
)

__all__ = [
    "ArgumentTypeError",
    "ConfigError",
    "ControllerFileError",
    "InvalidArgumentError",
    "SingularityError",
    "SolverError",
    "StoreError",
    "ToolkitError",
]
