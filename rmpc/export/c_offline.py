"""The C99 export of off-line robust MPC (:class:`rmpc.OfflineRMPC`, Wan & Kothare 2003).

The C step is :meth:`rmpc.OfflineRMPC.step` on a designed table, operation for operation:

1. the level of ``x`` in ellipsoid ``i`` is ``||C_i' x||^2`` with ``C_i' `` the transposed
   Cholesky factor of ``Q_i^-1`` the Python controller stores (exported as its doubles): the
   ``n`` dot products, squared, then summed as numpy's pairwise summation sums them (in order
   below 8 terms; eight partial sums combined as ``((s0 + s1) + (s2 + s3)) + ((s4 + s5) +
   (s6 + s7))``, then the rest in order, from 8 to 128);
2. ``k``, the number of ellipsoids holding ``x``, is numpy's ``searchsorted(levels, 1 + 1e-6,
   side="right")``: the same binary search (its comparison puts NaN last), so the same answer
   even where rounding breaks the levels' order; each probe computes one level only;
3. ``k = 0``: status ``RMPC_STATUS_OUTSIDE`` and ``u = F_1 x``; otherwise ``u = F_i x``
   (``i = k - 1``), interpolated with ``F_{i+1} x`` where the table allows it:
   ``alpha = min((b - 1) / (b - a), 1)`` with ``a``, ``b`` the levels in ``E_i``, ``E_{i+1}``,
   and ``u = alpha u_i + (1 - alpha) u_{i+1}``.

The C never redesigns the table (a Python controller built with ``x_design=None`` designs anew
when a run starts outside it); it exports the table the controller holds.
"""

from __future__ import annotations

import numpy as np

from rmpc.export.c_writer import CArray, CProgram, WorkspaceField, c_double
from rmpc.mpc.offline import LEVEL_TOL, OfflineRMPC
from toolkit_common.errors import InvalidArgumentError

__all__ = ["MAX_ELLIPSOIDS", "offline_program"]

#: The largest table an export accepts.
MAX_ELLIPSOIDS = 1000

_HELPERS = """\
/* numpy's pairwise sum of a[0..n-1] (n <= 128): in order below 8 terms, else 8 partial sums */
static double rmpc_sum(const double *a, int n)
{
    double r[8];
    double res;
    int i;
    int j;
    if (n < 8) {
        res = 0.0;
        for (i = 0; i < n; ++i) {
            res += a[i];
        }
        return res;
    }
    for (j = 0; j < 8; ++j) {
        r[j] = a[j];
    }
    for (i = 8; i < n - (n % 8); i += 8) {
        for (j = 0; j < 8; ++j) {
            r[j] += a[i + j];
        }
    }
    res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
    for (; i < n; ++i) {
        res += a[i];
    }
    return res;
}

/* x' Q_i^-1 x = ||C_i' x||^2 */
static double rmpc_level(int i, const double *x)
{
    double sq[RMPC_NX];
    const double *c = rmpc_chol + (long)i * RMPC_NX * RMPC_NX;
    int r;
    for (r = 0; r < RMPC_NX; ++r) {
        const double y = rmpc_dot(c + r * RMPC_NX, x, RMPC_NX);
        sq[r] = y * y;
    }
    return rmpc_sum(sq, RMPC_NX);
}

/* numpy's order for searchsorted: a < b, NaN after every number */
static int rmpc_less(double a, double b)
{
    return a < b || (isnan(b) && !isnan(a));
}

/* v = F_i x */
static void rmpc_apply(int i, const double *x, double *v)
{
    const double *f = rmpc_gain + (long)i * RMPC_NU * RMPC_NX;
    int r;
    for (r = 0; r < RMPC_NU; ++r) {
        v[r] = rmpc_dot(f + r * RMPC_NX, x, RMPC_NX);
    }
}
"""

_COMPUTE = """\
    double w[RMPC_NU];
    int lo = 0;
    int hi = RMPC_N_ELLIPSOIDS;
    int probes = 0;
    int i;
    int r;
    while (lo < hi) { /* numpy's searchsorted(levels, RMPC_LEVEL_ONE, side="right") */
        const int mid = lo + ((hi - lo) >> 1);
        ++probes;
        if (!rmpc_less(RMPC_LEVEL_ONE, rmpc_level(mid, x))) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    rmpc_ws.iterations = probes;
    rmpc_ws.alpha = 1.0;
    if (lo == 0) {
        rmpc_ws.index = 0;
        rmpc_apply(0, x, v);
        return RMPC_STATUS_OUTSIDE;
    }
    i = lo - 1;
    rmpc_ws.index = i;
    rmpc_ws.gamma = rmpc_gamma[i];
    rmpc_apply(i, x, v);
    if (lo < RMPC_N_ELLIPSOIDS && rmpc_interpolable[i]) {
        const double a = rmpc_level(i, x);
        const double b = rmpc_level(lo, x);
        const double t = (b - 1.0) / (b - a);
        const double alpha = (1.0 < t) ? 1.0 : t; /* Python's min(t, 1.0) */
        const double beta = 1.0 - alpha;
        rmpc_ws.alpha = alpha;
        rmpc_apply(lo, x, w);
        for (r = 0; r < RMPC_NU; ++r) {
            const double p = alpha * v[r];
            const double q = beta * w[r];
            v[r] = p + q;
        }
    }
    return RMPC_OK;
"""


def _lookup(ctrl: OfflineRMPC) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The arrays :meth:`OfflineRMPC.step` reads: Cholesky factors, gains, gammas, interpolation flags.

    They are taken from the controller itself (the matrix ``_lookup`` its step multiplies by),
    so the C holds the very doubles the Python step uses.
    """
    table = ctrl.table
    if table is None:
        raise InvalidArgumentError(
            "controller", "an OfflineRMPC with a designed table (x_design=... or design())",
            "no table: the controller has not been designed yet",
        )
    count = table.n_ellipsoids
    if count == 0:
        raise InvalidArgumentError(
            "controller", "an OfflineRMPC whose table holds at least one certified ellipsoid",
            f"an empty table (stop reason: {table.stop_reason}, status {table.failed_status!r})",
        )
    if count > MAX_ELLIPSOIDS:
        raise InvalidArgumentError(
            "controller", f"a table of at most {MAX_ELLIPSOIDS} ellipsoids (the export's limit)",
            f"{count} ellipsoids",
        )
    n, m = ctrl.plant.n_states, ctrl.plant.n_inputs
    lookup = np.asarray(ctrl._lookup, dtype=float)  # the step's own matrix (see the docstring)
    if lookup.shape != (count * (n + m), n):
        raise InvalidArgumentError(
            "controller", f"a lookup matrix of shape {(count * (n + m), n)}", f"shape {lookup.shape}"
        )
    if not np.isfinite(lookup).all():
        raise InvalidArgumentError("controller", "a table of finite Cholesky factors and gains",
                                   "NaN or infinity")
    gammas = np.asarray(ctrl._gammas, dtype=float)
    flags = np.asarray(ctrl._interp, dtype=bool) if count > 1 else np.zeros(1, dtype=bool)
    return lookup[: count * n], lookup[count * n :], gammas, flags


def offline_program(ctrl: OfflineRMPC) -> CProgram:
    """The :class:`~rmpc.export.c_writer.CProgram` of a designed :class:`rmpc.OfflineRMPC`."""
    chol, gains, gammas, flags = _lookup(ctrl)
    count = gammas.size
    n, m = ctrl.plant.n_states, ctrl.plant.n_inputs
    if not np.isfinite(gammas).all():
        raise InvalidArgumentError("controller", "finite gamma_i in the table", "NaN or infinity")
    one = 1.0 + LEVEL_TOL  # the Python step's threshold, the same double
    return CProgram(
        controller="OfflineRMPC",
        summary=(
            f"Off-line robust MPC (Wan & Kothare 2003): {count} nested ellipsoids "
            "E_i = {x : x' Q_i^-1 x <= 1}, outermost first,",
            "with gains F_i, looked up as OfflineRMPC.step does: the number k of ellipsoids whose",
            "level ||C_i' x||^2 is <= RMPC_LEVEL_ONE (a binary search, numpy's searchsorted);",
            "k = 0: RMPC_STATUS_OUTSIDE, u = F_1 x; else u = F_i x (i = k - 1), interpolated with",
            "F_{i+1} x where the table allows it (alpha = min((b - 1) / (b - a), 1), a and b the",
            f"levels in E_i and E_(i+1)). Interpolation: {'on' if ctrl.interpolate else 'off'}.",
        ),
        nx=n, nu=m,
        returns=("RMPC_OK", "RMPC_STATUS_OUTSIDE", "RMPC_STATUS_BAD_STATE", "RMPC_STATUS_OVERFLOW",
                 "RMPC_STATUS_NULL_ARGUMENT"),
        gamma_doc="gamma_i, the cost bound stored with the ellipsoid in use (Python's "
                  "last.gamma), after RMPC_OK; NaN after any other code (Python's None).",
        iterations_doc="the number of ellipsoid membership tests the binary search made "
                       "(at most ceil(log2(RMPC_N_ELLIPSOIDS + 1))); 0 after codes 2-4.",
        defines=(
            ("RMPC_N_ELLIPSOIDS", str(count), "ellipsoids in the table"),
            ("RMPC_LEVEL_ONE", f"({c_double(one)})",
             f"x is in E_i when its level is <= 1 + {LEVEL_TOL:g} (rmpc.mpc.offline.LEVEL_TOL)"),
        ),
        fields=(
            WorkspaceField("double", "alpha", "1.0", "rmpc_last_alpha()"),
            WorkspaceField("int", "index", "-1", "rmpc_last_index()"),
        ),
        arrays=(
            CArray("rmpc_chol", chol, "double",
                   f"C_i' (C_i C_i' = Q_i^-1), {count} blocks of {n} x {n}, row-major"),
            CArray("rmpc_gain", gains, "double", f"F_i, {count} blocks of {m} x {n}, row-major"),
            CArray("rmpc_gamma", gammas, "double", f"gamma_i, {count} entries"),
            CArray("rmpc_interpolable", flags, "unsigned char",
                   "1: interpolate between E_i and E_(i+1) (Wan & Kothare's condition (18) holds"
                   " and interpolation is on)"),
        ),
        helpers=_HELPERS,
        compute=_COMPUTE,
        accessors=(
            ("int rmpc_last_index(void)",
             "the ellipsoid in use, counted from 0 (Python's last.extra['index']); 0 after "
             "RMPC_STATUS_OUTSIDE; -1 after the codes 2-4 and before the first step",
             "    return rmpc_ws.index;"),
            ("double rmpc_last_alpha(void)",
             "the interpolation weight of F_i (Python's last.extra['alpha']; 1 when F_i is "
             "applied alone, and after any code but RMPC_OK)",
             "    return rmpc_ws.alpha;"),
        ),
    )
