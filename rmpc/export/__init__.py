"""C99 export of designed controllers: ``rmpc.export_c(ctrl, "build/")``.

:func:`export_c` writes ``rmpc_controller.h`` and ``rmpc_controller.c`` (C99, no dynamic
allocation, libm only, one static workspace; the interface and the status codes are those of
:mod:`rmpc.export.c_writer`) for the controllers of :func:`writers`: :class:`rmpc.LQR`
(:mod:`rmpc.export.c_gain`), :class:`rmpc.OfflineRMPC` (:mod:`rmpc.export.c_offline`) and the
on-line :class:`rmpc.RMPC` of Kothare's form with its solver (:mod:`rmpc.export.c_online`).
``docs/export_c.rst`` describes the interface, the fallbacks and the limits.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

from rmpc.export.c_writer import CProgram, ExportResult, write_program
from toolkit_common.errors import ArgumentTypeError

__all__ = ["ExportResult", "export_c", "writers"]

#: A writer: the controller in, the program to write out (it raises on a controller it cannot
#: export, naming what is missing).
Writer = Callable[[Any], CProgram]


def writers() -> dict[type, Writer]:
    """The writer of each exportable class (a new dict at each call: the registry).

    A class is matched exactly, not through a base class: a subclass may change ``step``.
    """
    from rmpc.export.c_gain import lqr_program
    from rmpc.export.c_offline import offline_program
    from rmpc.export.c_online import online_program
    from rmpc.mpc.lqr import LQR
    from rmpc.mpc.offline import OfflineRMPC
    from rmpc.mpc.robust_mpc import RMPC

    return {LQR: lqr_program, OfflineRMPC: offline_program, RMPC: online_program}


def export_c(controller: Any, out_dir: str | os.PathLike[str]) -> ExportResult:
    """Write ``controller`` as ``out_dir/rmpc_controller.h`` and ``out_dir/rmpc_controller.c``.

    Parameters
    ----------
    controller : LQR, OfflineRMPC or RMPC
        A designed controller (an :class:`~rmpc.OfflineRMPC` with its table; an
        :class:`~rmpc.RMPC` of Kothare's form on the ``"ipm"`` back-end).
    out_dir : str or os.PathLike
        The folder to write into, created when missing; existing files of the same names are
        replaced.

    Returns
    -------
    ExportResult
        The paths written, their sizes and the static memory (constant tables and workspace).

    Raises
    ------
    ArgumentTypeError
        For a controller of a class without a C export (the message lists those with one), or
        an ``out_dir`` that is not a path.
    InvalidArgumentError
        For a controller with no design yet, sizes beyond the limits (``RMPC_NX``, ``RMPC_NU``
        at most 64, at most 1000 ellipsoids; the C core's limits for an RMPC), an
        :class:`~rmpc.RMPC` of a form or back-end the C solver does not carry (the message
        names it), or an ``out_dir`` that is a file or cannot be written.

    Examples
    --------
    >>> import numpy as np, tempfile
    >>> from models import PolytopicModel
    >>> from rmpc import LQR, export_c
    >>> plant = PolytopicModel([(np.array([[1.0, 0.1], [0.0, 1.0]]), np.array([[0.0], [0.1]]))], dt=0.1)
    >>> result = export_c(LQR(plant, Q=np.eye(2), R=np.eye(1)), tempfile.mkdtemp())
    >>> result.header.name, result.source.name, result.nx, result.nu, result.static_bytes > 0
    ('rmpc_controller.h', 'rmpc_controller.c', 2, 1, True)
    """
    table = writers()
    writer = table.get(type(controller))
    if writer is None:
        supported = ", ".join(sorted(cls.__name__ for cls in table))
        raise ArgumentTypeError(
            "controller", f"a controller with a C export ({supported})", type(controller).__name__
        )
    return write_program(writer(controller), out_dir)
