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
  here: exit code 139). The first solve after ``init`` is therefore always cold: ``setup``
  only builds the solver, and the first ``solve`` (and the one after a rebuild) solves
  cold once and then, as every later call, from the warm start of that result; after a
  failed solve the next one is cold again. (Until the time limit below, ``setup`` made that
  cold solve itself; it moved into ``solve`` so that its time counts against the limit.)
* False infeasibility: ProxQP reported ``PROXQP_PRIMAL_INFEASIBLE`` on feasible QPs with a
  degenerate solution (an input-bound row and ``du`` box bounds active at the same point,
  or two parallel rows), while OSQP and Clarabel solved them. Infeasibility detection is
  therefore set nearly off (``eps_primal_inf = eps_dual_inf = 1e-12``); it did not detect a
  genuinely infeasible QP anyway (ProxQP ran to ``max_iter``, cf. proxsuite issue #291), so
  an infeasible problem comes back as ``"max_iterations"``. Re-solving in the same solver
  object from a cold start was no cure (it also ran to ``max_iter``), so a warm-started
  solve that ends non-optimal is repeated once in a freshly built solver (``init`` + cold
  solve; ``retry_cold``, ``QPResult.info["retried_cold"]``). ``QPResult.info`` also holds the
  outer iterations of the answer's solve (``"outer_iterations"``) and, after a setup, of the
  cold solve that came before it (``"first_solve_outer_iterations"``, 0 without one).
* Time: proxsuite 0.8 has no time limit, and an outer iteration may run up to ``max_iter_in``
  inner ones. At a state of 1e8, one ``GIPC.step`` ran 54-76 s: 10000 outer iterations of
  about 1450 inner ones each, to ``max_iter``. With a finite ``time_limit`` a solve runs in
  chunks of outer iterations (proxsuite's ``max_iter`` set to the chunk), each chunk after the
  first warm-started from the previous chunk's result (proxsuite keeps its proximal
  parameters across such a solve), and the clock is read between chunks: past the deadline
  the solve stops with ``"time_limit"``; ``max_iter`` still bounds the outer iterations of all
  chunks together. The deadline is one for the whole ``solve`` call: the cold solve after
  ``init`` and a ``retry_cold`` count against it (no retry starts past it).

  The first chunk (``first_chunk``, 1000 outer iterations) is the unchunked solve, the same
  computation, for every solve that converges within it: proxsuite uses ``max_iter`` only as
  its loop bound (its arithmetic itself varies in the last digits from run to run, by up to
  3e-12 of ``x`` on GIPC's QPs, with or without chunks). Measured with proxsuite's own counts
  on about 300000 GIPC solves (paper P's and paper W's suites, short and at full length, and
  the GIPC cases of the shipped sweeps), the most outer iterations a solve needed was 654
  (``gipc_tuning``; 203 in the suites). Those solves hold no clock reading, so ProxQP's normal
  answers do not depend on the machine's load. The first chunk is also what the clock cannot
  interrupt: at most ``first_chunk * max_iter_in`` inner iterations; at the state of 1e8
  (about 1450 inner per outer) it took 7-8 s on a shared 2-core machine (17.5 s under a load
  of 5), so such a step ends ``"time_limit"`` after about that long. Later chunks are sized to
  take at most half the time left even if each of their outer iterations ran ``max_iter_in``
  inner ones (at the cost per inner iteration measured in the call), so past the first chunk
  the bound is overrun by at most :data:`MIN_CHUNK` outer iterations; an attempt that starts
  in the second half of the budget (a retry, the solve after the cold one) is sized so from
  its first chunk on. Cut after 10, 50 or 100 outer iterations, the long solves of a GIPC
  closed loop came out the same to that run-to-run noise (proxsuite resumes from its saved
  state); cut after 5, they moved by up to 3.5e-8, within the tolerances.
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Any, ClassVar

import numpy as np
from proxsuite import proxqp

from rmpc.qp.base import DEFAULT_TIME_LIMIT, BackendSettings, QPBackend
from rmpc.qp.problem import QPResult, SolverResiduals
from toolkit_common.status import Status

__all__ = ["MIN_CHUNK", "ProxQPBackend", "ProxQPSettings"]

#: The fewest outer iterations of a chunk after the first (see the module docstring).
MIN_CHUNK = 10


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
        Outer iteration limit (of all chunks together; a solve it stops reports
        ``"max_iterations"``) and inner iterations per outer one.
    time_limit : float
        Bound in seconds on one ``solve`` call, retries included
        (:data:`~rmpc.qp.base.DEFAULT_TIME_LIMIT` by default, ``inf`` for none: then each
        attempt is one proxsuite solve); a solve it stops reports ``"time_limit"``. Checked
        between chunks of outer iterations (see the module docstring).
    first_chunk : int
        Outer iterations of the first chunk of each attempt, and the most of any later one
        (1000, about 1.5 times the most a GIPC solve of the suites and sweeps needed): a solve
        that converges within it is the unchunked one, and the clock cannot stop it earlier.
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
    time_limit: float = DEFAULT_TIME_LIMIT
    first_chunk: int = 1000
    warm_start: bool = True
    retry_cold: bool = True
    dense_backend: str = "automatic"
    box: str = "rows"
    verbose: bool = False

    _POSITIVE: ClassVar[tuple[str, ...]] = (
        "eps_abs", "eps_duality_gap_abs", "eps_primal_inf", "eps_dual_inf",
    )
    _NONNEGATIVE: ClassVar[tuple[str, ...]] = ("eps_rel", "eps_duality_gap_rel")
    _COUNTS: ClassVar[tuple[str, ...]] = ("max_iter", "max_iter_in", "first_chunk")
    _SECONDS: ClassVar[tuple[str, ...]] = ("time_limit",)
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
        self._solver = solver
        self._m = m
        self._native = native
        # No solve since init: the next one is cold (see the module docstring: the dense back-end
        # of proxsuite 0.8.0 segfaults on init -> update -> warm-started solve otherwise).
        self._fresh = True

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

    def _chunk(self, deadline: float, spent: list[float], left: int, first: bool) -> int:
        """Outer iterations of the next chunk (see the module docstring)."""
        now = time.perf_counter()
        most = self.settings.first_chunk
        if spent[1] == 0 or (first and deadline - now >= 0.5 * self.settings.time_limit):
            return min(most, left)
        worst = self.settings.max_iter_in * spent[0] / spent[1]  # seconds per outer iteration, at most
        room = 0.5 * (deadline - now) / worst if worst > 0 else most
        return int(min(most, left, max(MIN_CHUNK, room)))

    def _run(self, deadline: float, spent: list[float]) -> tuple[int, int, bool]:
        """One attempt from the current initial guess: ``(inner, outer iterations, timed out)``.

        With no deadline (``time_limit = inf``) it is one proxsuite solve; otherwise it runs in
        chunks of outer iterations until proxsuite stops for another reason than its
        ``max_iter``, ``max_iter`` outer iterations are done, or the deadline has passed.
        ``spent`` (seconds, inner iterations) accumulates the solver's work in this call.
        """
        solver, st = self._solver, self.settings
        self._fresh = False
        if math.isinf(deadline):
            solver.settings.max_iter = st.max_iter
            solver.solve()
            info = solver.results.info
            return int(info.iter), int(info.iter_ext), False
        inner = outer = 0
        first = True
        while True:
            chunk = self._chunk(deadline, spent, st.max_iter - outer, first)
            solver.settings.max_iter = chunk
            begin = time.perf_counter()
            solver.solve()
            now = time.perf_counter()
            info = solver.results.info
            inner += int(info.iter)
            spent[0] += now - begin
            spent[1] += int(info.iter)
            if info.status != _O.PROXQP_MAX_ITER_REACHED:
                return inner, outer + int(info.iter_ext), False
            outer += chunk
            if outer >= st.max_iter:
                return inner, outer, False
            if now >= deadline:
                return inner, outer, True
            solver.settings.initial_guess = _WARM  # go on from this chunk's result (a solve happened)
            first = False

    def _solve(self) -> QPResult:
        start = time.perf_counter()
        deadline = start + self.settings.time_limit
        spent = [0.0, 0]
        first_outer = 0
        if self._fresh:  # the cold solve after init, then the call goes on as after any solve
            try:  # as when setup made this solve: a solver that refuses the data is a status
                inner, outer, timed_out = self._run(deadline, spent)
            except Exception as err:  # the binding's own exception types
                return self._failed(f"first solve failed: {type(err).__name__}: {err}", start)
            if timed_out:
                return self._report(Status.TIME_LIMIT, inner, outer, start, False, outer)
            first_outer = outer
            self._set_guess(self._solver.results.info.status == _O.PROXQP_SOLVED)
        warm = self._solver.settings.initial_guess == _WARM
        inner, outer, timed_out = self._run(deadline, spent)
        status = Status.TIME_LIMIT if timed_out else self.map_status(self._solver.results.info.status)
        retried = False
        retry = warm and self.settings.retry_cold and status not in (Status.OPTIMAL, Status.TIME_LIMIT)
        if retry and time.perf_counter() < deadline:
            self._build()  # a fresh solver (init), then a cold solve with the current data
            if self._setup_error is not None:
                return self._failed(f"rebuild failed: {self._setup_error}", start)
            try:
                inner, outer, timed_out = self._run(deadline, spent)
            except Exception as err:
                return self._failed(f"rebuild failed: {type(err).__name__}: {err}", start)
            status = Status.TIME_LIMIT if timed_out else self.map_status(self._solver.results.info.status)
            retried = True
        return self._report(status, inner, outer, start, retried, first_outer)

    def _failed(self, raw: str, start: float) -> QPResult:
        self._set_guess(False)
        return self._result(
            Status.NUMERICAL_ERROR, raw, None, None, None, -1, time.perf_counter() - start, SolverResiduals()
        )

    def _report(
        self, status: Status, inner: int, outer: int, start: float, retried: bool, first_outer: int = 0
    ) -> QPResult:
        elapsed = time.perf_counter() - start
        res = self._solver.results
        info = res.info
        self._set_guess(status == Status.OPTIMAL)
        z = np.asarray(res.z)
        m = self._m
        return self._result(
            status, str(info.status).rsplit(".", 1)[-1], res.x, z[:m], z[m:], inner, elapsed,
            SolverResiduals(
                primal=float(info.pri_res), dual=float(info.dua_res), gap=float(info.duality_gap)
            ),
            {"retried_cold": retried, "outer_iterations": outer, "first_solve_outer_iterations": first_outer},
        )
