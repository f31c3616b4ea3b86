"""Clarabel back-end (interior point; Goulart & Chen 2024, "Clarabel: An interior-point
solver for conic programs with quadratic objectives", arXiv:2405.12762).

Clarabel's form is ``A z + s = b``, ``s`` in a product of cones. Each finite bound becomes
one row: equalities (``l_i == u_i``) go to the zero cone, ``C_i z <= u_i`` and
``-C_i z <= -l_i`` (and the box rows) to the non-negative cone; infinite bounds have no
row. ``update`` changes ``q`` and ``b`` in place (``DefaultSolver.update``, which needs
``presolve_enable = False`` and ``input_sparse_dropzeros = False``: both are fixed here).
If an update changes which bounds are finite or equal, the row structure changes and the
solver is rebuilt. An interior-point method takes no warm start, so every solve is cold;
the saving of ``update`` is the skipped setup (symbolic factorisation, allocations).

Tolerances are tightened from Clarabel's 1e-8 to 1e-10 (gap and feasibility): on GIPC QPs
of paper P's satellite the answer was then within 1.4e-5 of the ``du`` bound of the
reference (1.5e-4 at 1e-9, 1.1e-3 at the defaults; at 1e-12 Clarabel began to stop with
``AlmostSolved`` or ``NumericalError``). ``AlmostSolved`` (only the reduced tolerances met)
maps to ``"inaccurate"``.
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any, ClassVar

import clarabel
import numpy as np
import scipy.sparse as sp

from rmpc.qp.base import DEFAULT_TIME_LIMIT, BackendSettings, QPBackend
from rmpc.qp.problem import QPResult, SolverResiduals
from toolkit_common.status import Status

__all__ = ["ClarabelBackend", "ClarabelSettings"]


@dataclasses.dataclass(frozen=True)
class ClarabelSettings(BackendSettings):
    """Settings of :class:`ClarabelBackend` (names as in ``clarabel.DefaultSettings``).

    Attributes
    ----------
    tol_gap_abs, tol_gap_rel, tol_feas : float
        Termination tolerances (Clarabel defaults 1e-8; here 1e-10).
    tol_infeas_abs, tol_infeas_rel : float
        Infeasibility detection tolerances.
    tol_ktratio : float
        KKT ratio tolerance.
    max_iter : int
        Iteration limit.
    time_limit : float
        Bound in seconds on one solve (:data:`~rmpc.qp.base.DEFAULT_TIME_LIMIT` by default;
        ``inf`` means none); a solve it stops reports ``"time_limit"`` (Clarabel's ``MaxTime``).
    equilibrate_enable : bool
        Ruiz equilibration.
    direct_solve_method : str
        Linear solver (``"qdldl"`` or ``"auto"``).
    verbose : bool
        Let Clarabel print.
    """

    tol_gap_abs: float = 1e-10
    tol_gap_rel: float = 1e-10
    tol_feas: float = 1e-10
    tol_infeas_abs: float = 1e-9
    tol_infeas_rel: float = 1e-9
    tol_ktratio: float = 1e-7
    max_iter: int = 200
    time_limit: float = DEFAULT_TIME_LIMIT
    equilibrate_enable: bool = True
    direct_solve_method: str = "qdldl"
    verbose: bool = False

    _POSITIVE: ClassVar[tuple[str, ...]] = (
        "tol_gap_abs", "tol_gap_rel", "tol_feas", "tol_infeas_abs", "tol_infeas_rel", "tol_ktratio",
    )
    _COUNTS: ClassVar[tuple[str, ...]] = ("max_iter",)
    _SECONDS: ClassVar[tuple[str, ...]] = ("time_limit",)
    _FLAGS: ClassVar[tuple[str, ...]] = ("equilibrate_enable", "verbose")
    _CHOICES: ClassVar[dict[str, tuple[str, ...]]] = {"direct_solve_method": ("qdldl", "auto")}


class ClarabelBackend(QPBackend):
    """QP back-end on Clarabel (interior point; data updated in place, no warm start).

    Examples
    --------
    >>> import numpy as np
    >>> from rmpc.qp import QP, ClarabelBackend
    >>> be = ClarabelBackend()
    >>> be.setup(QP(H=np.eye(2), g=[-1.0, -1.0], ub=[0.5, 2.0]))
    >>> res = be.solve()
    >>> res.status, np.round(res.x, 7).tolist()
    ('optimal', [0.5, 1.0])
    """

    name = "clarabel"
    settings_class = ClarabelSettings
    STATUS_MAP: ClassVar[dict[Any, Status]] = {
        "Solved": Status.OPTIMAL,
        "AlmostSolved": Status.INACCURATE,
        "PrimalInfeasible": Status.INFEASIBLE,
        "AlmostPrimalInfeasible": Status.INFEASIBLE,
        "DualInfeasible": Status.UNBOUNDED,
        "AlmostDualInfeasible": Status.UNBOUNDED,
        "MaxIterations": Status.MAX_ITERATIONS,
        "MaxTime": Status.TIME_LIMIT,
        "NumericalError": Status.NUMERICAL_ERROR,
        "InsufficientProgress": Status.NUMERICAL_ERROR,
        "CallbackTerminated": Status.INTERRUPTED,
        "Unsolved": Status.NOT_SOLVED,
    }

    # -- row structure ----------------------------------------------------------------
    def _structure(self) -> tuple[bytes, ...]:
        v = self._vec
        keys = []
        for lo, up in ((v["l"], v["u"]), (v["lb"], v["ub"])):
            eq = np.isfinite(up) & (lo == up)
            keys += [eq.tobytes(), (np.isfinite(up) & ~eq).tobytes(), (np.isfinite(lo) & ~eq).tobytes()]
        return tuple(keys)

    def _rows(self) -> None:
        """Index sets of the rows (``C`` part and box part) in Clarabel's ``A``."""
        v = self._vec
        self._sel = {}
        for part, lo, up in (("C", v["l"], v["u"]), ("box", v["lb"], v["ub"])):
            eq = np.isfinite(up) & (lo == up)
            self._sel[part] = (
                np.flatnonzero(eq),
                np.flatnonzero(np.isfinite(up) & ~eq),
                np.flatnonzero(np.isfinite(lo) & ~eq),
            )

    def _b(self) -> np.ndarray:
        v = self._vec
        ce, cu, cl = self._sel["C"]
        be, bu, bl = self._sel["box"]
        return np.concatenate((v["u"][ce], v["ub"][be], v["u"][cu], v["ub"][bu], -v["l"][cl], -v["lb"][bl]))

    def _setup(self) -> None:
        assert self._qp is not None
        qp = self._qp
        n = qp.n_vars
        self._rows()
        self._key = self._structure()
        ce, cu, cl = self._sel["C"]
        be, bu, bl = self._sel["box"]
        if qp.is_sparse:  # a large structured QP stays sparse (see rmpc.qp.problem.QP)
            cmat, eye, stack = sp.csr_matrix(qp.C), sp.identity(n, format="csr"), sp.vstack
        else:
            cmat, eye, stack = qp.C, np.eye(n), np.vstack
        blocks = [cmat[ce], eye[be], cmat[cu], eye[bu], -cmat[cl], -eye[bl]]
        a = sp.csc_matrix(stack(blocks)) if sum(b.shape[0] for b in blocks) else sp.csc_matrix((0, n))
        n_eq = ce.size + be.size
        n_in = cu.size + bu.size + cl.size + bl.size
        cones: list[Any] = []
        if n_eq:
            cones.append(clarabel.ZeroConeT(n_eq))
        if n_in:
            cones.append(clarabel.NonnegativeConeT(n_in))
        st = clarabel.DefaultSettings()
        for name, value in dataclasses.asdict(self.settings).items():
            setattr(st, name, value)
        st.presolve_enable = False
        st.input_sparse_dropzeros = False
        p = sp.triu(sp.csc_matrix(qp.H), format="csc")
        self._solver = clarabel.DefaultSolver(p, self._vec["g"], a, self._b(), cones, st)

    def _update(self, changed: dict[str, np.ndarray]) -> None:
        if {"l", "u", "lb", "ub"} & changed.keys() and self._structure() != self._key:
            self._build()
            return
        kwargs: dict[str, np.ndarray] = {}
        if "g" in changed:
            kwargs["q"] = changed["g"]
        if {"l", "u", "lb", "ub"} & changed.keys():
            kwargs["b"] = self._b()
        self._solver.update(**kwargs)

    def _solve(self) -> QPResult:
        assert self._qp is not None
        start = time.perf_counter()
        try:
            sol = self._solver.solve()
        except Exception as err:  # pragma: no cover - Clarabel reports failures as statuses
            return self._result(
                Status.NUMERICAL_ERROR, f"exception: {err}", None, None, None, -1,
                time.perf_counter() - start, SolverResiduals(),
            )
        elapsed = time.perf_counter() - start
        raw = str(sol.status)
        z = np.asarray(sol.z, dtype=float)
        n, m = self._qp.n_vars, self._qp.n_cons
        y_c, y_box = np.zeros(m), np.zeros(n)
        ce, cu, cl = self._sel["C"]
        be, bu, bl = self._sel["box"]
        offset = 0
        for idx, target, sign in ((ce, y_c, 1.0), (be, y_box, 1.0), (cu, y_c, 1.0), (bu, y_box, 1.0),
                                  (cl, y_c, -1.0), (bl, y_box, -1.0)):
            target[idx] += sign * z[offset:offset + idx.size]
            offset += idx.size
        gap = abs(float(sol.obj_val) - float(sol.obj_val_dual))
        return self._result(
            self.map_status(raw), raw, np.asarray(sol.x, dtype=float), y_c, y_box, int(sol.iterations),
            elapsed,
            SolverResiduals(primal=float(sol.r_prim), dual=float(sol.r_dual), gap=gap),
        )
