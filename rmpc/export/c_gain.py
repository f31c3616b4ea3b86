"""The C99 export of a fixed-gain controller: :class:`rmpc.LQR`, ``u = F (x - x_ref)``.

The Python step computes ``F @ (x - x_ref)`` with ``F = -K`` (python-control's ``dlqr``) and
applies no saturation; the C step does the same: ``d = x - x_ref`` entry by entry, then each
``u_r`` is the dot product of row ``r`` of ``F`` with ``d``, summed in index order. numpy hands
the product to BLAS, whose kernel may sum the terms in another order (see ``docs/export_c.rst``),
so the two agree to the rounding of a dot product, not always bit for bit.
"""

from __future__ import annotations

import numpy as np

from rmpc.export.c_writer import CArray, CProgram
from rmpc.mpc.lqr import LQR
from toolkit_common.errors import InvalidArgumentError

__all__ = ["lqr_program"]

_COMPUTE = """\
    double d[RMPC_NX];
    int j;
    int r;
    for (j = 0; j < RMPC_NX; ++j) {
        d[j] = x[j] - rmpc_x_ref[j];
    }
    for (r = 0; r < RMPC_NU; ++r) {
        v[r] = rmpc_dot(rmpc_gain + r * RMPC_NX, d, RMPC_NX);
    }
    rmpc_ws.iterations = 0;
    return RMPC_OK;
"""


def lqr_program(ctrl: LQR) -> CProgram:
    """The :class:`~rmpc.export.c_writer.CProgram` of an :class:`rmpc.LQR`."""
    gain = np.asarray(ctrl.F, dtype=float)
    x_ref = np.asarray(ctrl.x_ref, dtype=float)
    if gain.ndim != 2 or x_ref.shape != (gain.shape[1],):
        raise InvalidArgumentError(
            "controller", "an LQR with a gain F of shape (m, n) and x_ref of length n",
            f"F of shape {gain.shape}, x_ref of shape {x_ref.shape}",
        )
    for name, arr in (("F", gain), ("x_ref", x_ref)):
        if not np.isfinite(arr).all():
            raise InvalidArgumentError(f"controller.{name}", "finite values", "NaN or infinity")
    m, n = gain.shape
    return CProgram(
        controller="LQR",
        summary=(
            "LQR: u = F (x - x_ref), F = -K the discrete LQR gain, no saturation (as LQR.step).",
            "Each u_r = F[r][0] d[0] + ... + F[r][n-1] d[n-1], d = x - x_ref, summed in order.",
        ),
        nx=n, nu=m,
        returns=("RMPC_OK", "RMPC_STATUS_BAD_STATE", "RMPC_STATUS_OVERFLOW", "RMPC_STATUS_NULL_ARGUMENT"),
        gamma_doc="NaN always (an LQR has no cost bound; Python's last.gamma is None).",
        iterations_doc="0 always (nothing is solved or searched).",
        arrays=(
            CArray("rmpc_gain", gain, "double", f"F, {m} x {n}, row-major"),
            CArray("rmpc_x_ref", x_ref, "double", f"x_ref, {n} entries"),
        ),
        compute=_COMPUTE,
    )
