"""The C99 export of the on-line robust MPC: :class:`rmpc.RMPC` of Kothare's form, solver included.

The step solves Kothare's LMIs at every call with the toolkit's interior-point method written in
C for the problem's fixed block structure (:mod:`lmi.ccore`: the iterations of
:class:`lmi.BlockLMISolver` on the dense path, warm-started from the previous call, the
infeasibility proof by the dual iterate's Farkas ray, and the certificate: every LMI recomputed
at the answer in C). ``rmpc_step`` follows :meth:`rmpc.RMPC.step`:

- ``z = x - x_ref``; within the controller's ``hold_radius`` of ``x_ref`` no solve, ``u = F_last
  z`` with the last certified gain and ``RMPC_STATUS_HELD`` (Python: ``"reused"``);
- otherwise a solve; a certified answer gives ``RMPC_OK`` and ``u = F z`` with its gain, any other
  outcome its status code and the fallback ``u = F_last z`` (zero before any certified gain), as
  the Python controller's ``on_failure="fallback"`` does.

What the C core leaves out (the Python controller has them): phase one after a failed run, the
retry in rebalanced coordinates and the Clarabel fallback; a stalled run that reached only
reduced accuracy is reported (``RMPC_STATUS_INACCURATE``) with the fallback command, where
Python applies such an answer when its certificate holds. Other forms (vertex Lyapunov
matrices, nominal cost, free moves, ...), another back-end, a set-point's input, offset-free
action and kept gains (``resolve_threshold < 1``) are refused by name.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rmpc.export.c_writer import CArray, CProgram, c_double
from toolkit_common.errors import InvalidArgumentError

__all__ = ["online_program"]

_COMPUTE = """\
    double z[RMPC_NX];
    int code;
    int j;
    for (j = 0; j < RMPC_NX; ++j) {
        z[j] = x[j] - rmpc_x_ref[j];
    }
    if (sqrt(rmpc_dot(z, z, RMPC_NX)) <= RMPC_HOLD_RADIUS) {
        kothare_apply_gain(z, v);
        return RMPC_STATUS_HELD;
    }
    code = kothare_solve(z, v, NULL, &rmpc_ws.gamma, &rmpc_ws.iterations);
    switch (code) {
    case KOTHARE_STATUS_OPTIMAL:
        return RMPC_OK;
    case KOTHARE_STATUS_INFEASIBLE:
        return RMPC_STATUS_INFEASIBLE;
    case KOTHARE_STATUS_MAX_ITERATIONS:
        return RMPC_STATUS_MAX_ITERATIONS;
    case KOTHARE_STATUS_CERTIFICATE_FAILED:
        return RMPC_STATUS_UNCERTIFIED;
    case KOTHARE_STATUS_INACCURATE:
        return RMPC_STATUS_INACCURATE;
    case KOTHARE_STATUS_NONFINITE_X: /* a finite z whose norm overflows */
        return RMPC_STATUS_OVERFLOW;
    case KOTHARE_STATUS_ZERO_STATE: /* z = 0 with a hold radius of 0: nothing to solve */
        return RMPC_STATUS_HELD;
    default:
        return RMPC_STATUS_NUMERICAL_ERROR;
    }
"""

_RETURNS = (
    "RMPC_OK", "RMPC_STATUS_BAD_STATE", "RMPC_STATUS_OVERFLOW", "RMPC_STATUS_NULL_ARGUMENT",
    "RMPC_STATUS_INFEASIBLE", "RMPC_STATUS_MAX_ITERATIONS", "RMPC_STATUS_NUMERICAL_ERROR",
    "RMPC_STATUS_UNCERTIFIED", "RMPC_STATUS_INACCURATE", "RMPC_STATUS_HELD",
)


def online_program(ctrl: Any) -> CProgram:
    """The :class:`~rmpc.export.c_writer.CProgram` of an :class:`rmpc.RMPC` of Kothare's form."""
    from lmi.ccore import check_controller, solver_source
    from lmi.kothare import KothareProblem

    form = getattr(ctrl, "form", None)
    if form is not None and not form.is_kothare:
        raise InvalidArgumentError(
            "controller", "an RMPC of Kothare's form (common Lyapunov matrix, worst-case cost, no "
            "free move, saturation, soft bound or disturbance): the C solver carries that structure",
            f"the form {form}",
        )
    if not isinstance(ctrl.problem, KothareProblem) or ctrl.problem.backend != "ipm":
        raise InvalidArgumentError(
            "controller", "an RMPC on the toolkit's interior-point method (backend='ipm')",
            f"backend {getattr(ctrl.problem, 'backend', type(ctrl.problem).__name__)!r}",
        )
    check_controller(ctrl)
    solver, solver_tables = solver_source(ctrl, omit_macros=("RMPC_NX", "RMPC_NU"))
    x_ref = np.asarray(ctrl.x_ref, dtype=float)
    n, m = x_ref.size, int(ctrl.plant.n_inputs)
    return CProgram(
        controller="RMPC",
        summary=(
            "On-line robust MPC (Kothare, Balakrishnan & Morari 1996): at each step the LMIs of",
            "Kothare's form are solved at z = x - x_ref by the toolkit's interior-point method in C",
            "(warm-started from the previous step) and the answer is certified (every LMI",
            "recomputed at it); u = F z with its gain. Within the hold radius of x_ref no solve.",
            "On any failure u = F_last z, the last certified gain (0 before any).",
        ),
        nx=n, nu=m,
        returns=_RETURNS,
        gamma_doc="the certified cost bound gamma of the last step's solve; NaN after a step "
                  "that did not certify a new gain.",
        iterations_doc="the interior-point iterations of the last step's solve (a failed warm "
                       "start's included); 0 after a held step.",
        arrays=(CArray("rmpc_x_ref", x_ref, "double", f"x_ref, {n} entries"),),
        defines=(("RMPC_HOLD_RADIUS", f"({c_double(float(ctrl.hold_radius))})",
                  "no solve within this distance of x_ref (the controller's hold_radius)"),),
        helpers=solver,
        compute=_COMPUTE,
        init="kothare_reset();",
        accessors=(
            ("unsigned long rmpc_solver_workspace_bytes(void)",
             "bytes of the solver's static workspace (its iterates, factors and warm start)",
             "    return (unsigned long)kothare_workspace_bytes();"),
        ),
        helper_table_bytes=solver_tables,
    )
