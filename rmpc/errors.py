"""The toolkit's exceptions, importable from one place.

>>> from rmpc.errors import ToolkitError, InvalidArgumentError
>>> issubclass(InvalidArgumentError, ValueError) and issubclass(InvalidArgumentError, ToolkitError)
True
"""

from toolkit_common.errors import (
    ArgumentTypeError,
    ConfigError,
    ControllerFileError,
    InvalidArgumentError,
    NoCertifiedGainWarning,
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
    "NoCertifiedGainWarning",
    "SingularityError",
    "SolverError",
    "StoreError",
    "ToolkitError",
]
