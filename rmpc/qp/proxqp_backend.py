"""ProxQP back-end (proxsuite 0.8; Bambade et al. 2022, "PROX-QP: Yet another Quadratic
Programming Solver for Robotics and beyond", RSS).

Uses the dense API ``proxsuite.proxqp.dense.QP``. With ``box="rows"`` (the default) the box
is stacked under ``C`` as identity rows (``n_in = m + n``); with ``box="native"`` it is passed
as proxsuite's ``l_box``/``u_box`` (``box_constraints=True``). Infinite bounds are passed as
they are. ``update`` changes the vectors in place (the preconditioner computed at setup is
kept) and the next solve starts from the previous result
(``WARM_START_WITH_PREVIOUS_RESULT``).

Measured pitfalls shape the defaults (GIPC QPs of paper P's satellite, ``|du| <= 0.01``):

* Accuracy: without ``check_duality_gap`` ProxQP reported ``PROXQP_SOLVED`` while off by up to
  100 % of the ``du`` bound (``eps_abs = 1e-4``; 13-200 % in an earlier exploration). Here
  ``check_duality_gap=True``, ``eps_abs = eps_duality_gap_abs = 1e-8``, ``eps_rel = 0``:
  answers within 1.1e-5 of the ``du`` bound of a high-accuracy reference. At 1e-9 ProxQP
  stalled just above the tolerance (primal residual ~5e-9) on nearly degenerate QPs and
  ran to ``max_iter`` several times more often in closed-loop stress runs.
* A crash: proxsuite 0.8.0's dense back-end segfaults on ``init -> update -> solve`` with a
  warm start from the previous result when no solve happened after ``init`` (reproduced
  here: exit code 139). ``setup`` therefore always solves once, cold, right after ``init``,
  and only then switches the initial guess to the warm start; after a failed solve the
  next one is cold again.
* False infeasibility: ProxQP reported ``PROXQP_PRIMAL_INFEASIBLE`` on feasible QPs with a
  degenerate solution (an input-bound row and ``du`` box bounds active at the same point,
  or two parallel rows), while OSQP and Clarabel solved them. Infeasibility detection is
  therefore set nearly off (``eps_primal_inf = eps_dual_inf = 1e-12``); it did not detect a
  genuinely infeasible QP anyway (ProxQP ran to ``max_iter``, cf. proxsuite issue #291), so
  an infeasible problem comes back as ``"max_iterations"``. Re-solving in the same solver
  object from a cold start was no cure (it also ran to ``max_iter``), so a warm-started
  solve that ends non-optimal is repeated once in a freshly built solver (``init`` + cold
  solve; ``retry_cold``, ``QPResult.info["retried_cold"]``).
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any, ClassVar

import numpy as np
from proxsuite import proxqp

from rmpc.qp.base import BackendSettings, QPBackend
from rmpc.qp.problem import QPResult, SolverResiduals
from toolkit_common.status import Status

__all__ = ["ProxQPBackend", "ProxQPSettings"]


@dataclasses.dataclass(frozen=True)
class ProxQPSettings(BackendSettings):
    """Settings of :class:`ProxQPBackend` (names as in ``proxsuite.proxqp.Settings``).

    Attributes
    ----------
    eps_abs, eps_rel : float
        Termination tolerances on the primal and dual residuals (here 1e-8 and 0; proxsuite's
        defaults are 1e-5 and 0).
    check_duality_gap : bool
        Also require the duality gap below ``eps_duality_gap_abs/rel`` (here on: without it
        ProxQP can stop far from the optimum).
    eps_duality_gap_abs, eps_duality_gap_rel : float
        Duality-gap tolerances.
    eps_primal_inf, eps_dual_inf : float
        Infeasibility detection tolerances (here 1e-12, nearly off: see the module docstring;
        proxsuite's defaults are 1e-4).
    max_iter, max_iter_in : int
        Outer and inner iteration limits.
    warm_start : bool
        Start each solve after the first from the previous result.
    retry_cold : bool
        When a warm-started solve ends with any status but optimal, rebuild the solver, solve
        again from a cold start and report that (see the module docstring); the time of
        both counts.
    dense_backend : {"automatic", "primal_dual_ldlt", "primal_ldlt"}
        Factorisation of the dense back-end.
    box : {"rows", "native"}
        The box as identity rows of ``C`` or as proxsuite's own box constraints.
    verbose : bool
        Let ProxQP print.
    """

    eps_abs: float = 1e-8
    eps_rel: float = 0.0
    check_duality_gap: bool = True
    eps_duality_gap_abs: float = 1e-8
    eps_duality_gap_rel: float = 0.0
    eps_primal_inf: float = 1e-12
    eps_dual_inf: float = 1e-12
    max_iter: int = 10000
    max_iter_in: int = 1500
    warm_start: bool = True
    retry_cold: bool = True
    dense_backend: str = "automatic"
    box: str = "rows"
    verbose: bool = False

    _POSITIVE: ClassVar[tuple[str, ...]] = (
        "eps_abs", "eps_duality_gap_abs", "eps_primal_inf", "eps_dual_inf",
    )
    _NONNEGATIVE: ClassVar[tuple[str, ...]] = ("eps_rel", "eps_duality_gap_rel")
    _COUNTS: ClassVar[tuple[str, ...]] = ("max_iter", "max_iter_in")
    _FLAGS: ClassVar[tuple[str, ...]] = ("check_duality_gap", "warm_start", "retry_cold", "verbose")
    _CHOICES: ClassVar[dict[str, tuple[str, ...]]] = {
        "dense_backend": ("automatic", "primal_dual_ldlt", "primal_ldlt"),
        "box": ("rows", "native"),
    }


_DENSE_BACKENDS = {
    "automatic": proxqp.dense.DenseBackend.Automatic,
    "primal_dual_ldlt": proxqp.dense.DenseBackend.PrimalDualLDLT,
    "primal_ldlt": proxqp.dense.DenseBackend.PrimalLDLT,
}
_O = proxqp.QPSolverOutput
_WARM = proxqp.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT
_COLD = proxqp.InitialGuess.EQUALITY_CONSTRAINED_INITIAL_GUESS


class ProxQPBackend(QPBackend):
    """QP back-end on ProxQP's dense solver (warm-started, duality gap checked).

    Examples
    --------
    >>> import numpy as np
    >>> from rmpc.qp import QP, ProxQPBackend
    >>> be = ProxQPBackend()
    >>> be.setup(QP(H=np.eye(2), g=[-1.0, -1.0], ub=[0.5, 2.0]))
    >>> res = be.solve()
    >>> res.status, np.round(res.x, 7).tolist()
    ('optimal', [0.5, 1.0])
    """

    name = "proxqp"
    settings_class = ProxQPSettings
    STATUS_MAP: ClassVar[dict[Any, Status]] = {
        _O.PROXQP_SOLVED: Status.OPTIMAL,
        _O.PROXQP_MAX_ITER_REACHED: Status.MAX_ITERATIONS,
        _O.PROXQP_PRIMAL_INFEASIBLE: Status.INFEASIBLE,
        _O.PROXQP_SOLVED_CLOSEST_PRIMAL_FEASIBLE: Status.INFEASIBLE,
        _O.PROXQP_DUAL_INFEASIBLE: Status.UNBOUNDED,
        _O.PROXQP_NOT_RUN: Status.NOT_SOLVED,
    }

    def _setup(self) -> None:
        assert self._qp is not None
        qp, st = self._qp, self.settings
        n, m = qp.n_vars, qp.n_cons
        native = st.box == "native"
        n_in = m if native else m + n
        solver = proxqp.dense.QP(n, 0, n_in, native, dense_backend=_DENSE_BACKENDS[st.dense_backend])
        s = solver.settings
        s.eps_abs, s.eps_rel = st.eps_abs, st.eps_rel
        s.check_duality_gap = st.check_duality_gap
        s.eps_duality_gap_abs, s.eps_duality_gap_rel = st.eps_duality_gap_abs, st.eps_duality_gap_rel
        s.eps_primal_inf, s.eps_dual_inf = st.eps_primal_inf, st.eps_dual_inf
        s.max_iter, s.max_iter_in = st.max_iter, st.max_iter_in
        s.verbose = st.verbose
        s.initial_guess = _COLD
        v = self._vec
        if native:
            c, lo, up = (qp.C, v["l"], v["u"]) if m > 0 else (None, None, None)
            solver.init(qp.H, v["g"], None, None, c, lo, up, v["lb"], v["ub"])
        else:
            solver.init(qp.H, v["g"], None, None, np.vstack((qp.C, np.eye(n))), self._lower(), self._upper())
        # Always solve once after init (see the module docstring: the dense back-end of
        # proxsuite 0.8.0 segfaults on init -> update -> warm-started solve otherwise).
        solver.solve()
        self._solver = solver
        self._m = m
        self._native = native
        self._set_guess(solver.results.info.status == _O.PROXQP_SOLVED)

    def _lower(self) -> np.ndarray:
        return np.concatenate((self._vec["l"], self._vec["lb"]))

    def _upper(self) -> np.ndarray:
        return np.concatenate((self._vec["u"], self._vec["ub"]))

    def _set_guess(self, last_ok: bool) -> None:
        self._solver.settings.initial_guess = _WARM if (self.settings.warm_start and last_ok) else _COLD

    def _update(self, changed: dict[str, np.ndarray]) -> None:
        kwargs: dict[str, np.ndarray] = {}
        if "g" in changed:
            kwargs["g"] = changed["g"]
        if not self._native:
            if {"l", "lb"} & changed.keys():
                kwargs["l"] = self._lower()
            if {"u", "ub"} & changed.keys():
                kwargs["u"] = self._upper()
        else:
            if self._m > 0:
                for key in ("l", "u"):
                    if key in changed:
                        kwargs[key] = changed[key]
            if "lb" in changed:
                kwargs["l_box"] = changed["lb"]
            if "ub" in changed:
                kwargs["u_box"] = changed["ub"]
        if kwargs:
            self._solver.update(update_preconditioner=False, **kwargs)

    def _solve(self) -> QPResult:
        start = time.perf_counter()
        warm = self._solver.settings.initial_guess == _WARM
        self._solver.solve()
        status = self.map_status(self._solver.results.info.status)
        retried = False
        if warm and status != Status.OPTIMAL and self.settings.retry_cold:
            self._build()  # a fresh solver: init + cold solve with the current data
            if self._setup_error is not None:
                return self._result(
                    Status.NUMERICAL_ERROR, f"rebuild failed: {self._setup_error}", None, None, None, -1,
                    time.perf_counter() - start, SolverResiduals(),
                )
            status, retried = self.map_status(self._solver.results.info.status), True
        elapsed = time.perf_counter() - start
        res = self._solver.results
        info = res.info
        self._set_guess(status == Status.OPTIMAL)
        z = np.asarray(res.z)
        m = self._m
        return self._result(
            status, str(info.status).rsplit(".", 1)[-1], res.x, z[:m], z[m:], int(info.iter), elapsed,
            SolverResiduals(
                primal=float(info.pri_res), dual=float(info.dua_res), gap=float(info.duality_gap)
            ),
            {"retried_cold": retried},
        )
