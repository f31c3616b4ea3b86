"""The kinds of controller a file may hold, and :func:`load`.

:data:`KINDS` maps the ``kind`` field of a controller file to the class that reads it back
(``"module:Class"``, imported when a file of that kind is loaded). A class joins by inheriting
:class:`rmpc.io.saveable.Saveable`, writing its two hooks and adding one line here
(``docs/save_load.rst``, "Adding a class").
"""

from __future__ import annotations

import importlib
import os
from types import MappingProxyType
from typing import Any

from rmpc.io.design import Design
from rmpc.io.format import read_file
from toolkit_common.errors import ArgumentTypeError, ControllerFileError, InvalidArgumentError

__all__ = ["KINDS", "kind_of", "load"]

#: ``kind`` -> ``"module:Class"`` of every class a controller file may hold.
KINDS: MappingProxyType[str, str] = MappingProxyType({
    "RMPC": "rmpc.mpc.robust_mpc:RMPC",
    "OfflineRMPC": "rmpc.mpc.offline:OfflineRMPC",
    "ScheduledRMPC": "rmpc.mpc.scheduled:ScheduledRMPC",
    "CRMPC": "rmpc.mpc.crmpc:CRMPC",
    "GIPC": "rmpc.mpc.gipc:GIPC",
    "LQR": "rmpc.mpc.lqr:LQR",
    "MultiStageMPC": "rmpc.mpc.multistage:MultiStageMPC",
    "TubeMPC": "rmpc.mpc.tube:TubeMPC",
    "Luenberger": "rmpc.estimators.linear:Luenberger",
    "KalmanFilter": "rmpc.estimators.linear:KalmanFilter",
    "RobustObserver": "rmpc.estimators.robust:RobustObserver",
})


def kind_of(obj: Any) -> str:
    """The ``kind`` a file of ``obj`` carries: its class's name, if :data:`KINDS` lists that class.

    Raises
    ------
    InvalidArgumentError
        For a class :data:`KINDS` does not list (a subclass too: it would load as its base).
    """
    cls = type(obj)
    where = f"{cls.__module__}:{cls.__qualname__}"
    if KINDS.get(cls.__name__) != where:
        raise InvalidArgumentError(
            "controller", f"a controller of a kind a file can hold ({', '.join(KINDS)})", where
        )
    return cls.__name__


def _class(kind: str) -> Any:
    module, name = KINDS[kind].split(":")
    return getattr(importlib.import_module(module), name)


def load(path: str | os.PathLike[str]) -> Any:
    """The controller (or estimator) saved in ``path`` by its ``save`` method.

    The loaded controller gives the same ``step(x)`` outputs as the saved one did after its
    ``reset()``: bit for bit where no solve happens (an off-line table's lookup, LQR, fixed
    gains, estimators), to solver accuracy where one does. Nothing is designed or solved while
    loading. The run-time state (warm starts, the last step, an adaptation's estimate) is not in
    the file: a loaded controller is as after ``reset()``.

    Parameters
    ----------
    path : str or os.PathLike
        A file written by ``ctrl.save(path)``.

    Raises
    ------
    ControllerFileError
        Naming the file and what is wrong with it: missing, a directory, not JSON or truncated,
        not a controller file, a newer format version, a checksum that does not match, a kind
        this toolkit does not know, or a design that does not fit its kind.

    Examples
    --------
    >>> import numpy as np, tempfile, pathlib
    >>> import rmpc
    >>> from models import PolytopicModel
    >>> plant = PolytopicModel([(np.array([[1.1]]), np.array([[1.0]]))], dt=0.1)
    >>> lqr = rmpc.LQR(plant, Q=np.eye(1), R=np.eye(1))
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "lqr.rmpc"
    >>> lqr2 = rmpc.load(lqr.save(path))
    >>> bool(np.array_equal(lqr2.step([0.3]), lqr.step([0.3])))
    True
    """
    if not isinstance(path, str | os.PathLike):
        raise ArgumentTypeError("path", "a file path (str or os.PathLike)", type(path).__name__)
    file = read_file(path)
    name = str(file.path)
    if file.kind not in KINDS:
        raise ControllerFileError(name, f"a kind among {', '.join(KINDS)}", f"kind {file.kind!r}")
    cls = _class(file.kind)
    try:
        design = Design(file.design)
        ctrl = cls._from_design(design)
        design.finish()
    except (InvalidArgumentError, ArgumentTypeError) as err:
        raise ControllerFileError(name, f"a design {file.kind} can be built from", str(err)) from None
    return ctrl
