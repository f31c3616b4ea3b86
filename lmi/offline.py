"""Off-line robust MPC (Wan & Kothare 2003): a sequence of nested invariant ellipsoids and gains.

Reference: Z. Wan, M. V. Kothare, "An efficient off-line formulation of robust model predictive
control using linear matrix inequalities", Automatica 39(5), 837-846, 2003.

At each design state ``x_i`` (``i = 1, ..., N``) the Kothare (1996) problem is solved with one
more LMI, the nesting ``Q_{i-1} - Q_i >= 0``, so that the invariant ellipsoids
``E_i = {x : x' Q_i^-1 x <= 1}`` satisfy ``E_N ⊆ ... ⊆ E_2 ⊆ E_1``. The nesting is an LMI in the
unknowns of step ``i``, and the previous solution, scaled to the new state, satisfies it, so
every design state strictly inside the previous ellipsoid gives a feasible problem.

By default (``backend="ipm"``) the LMIs are those of the on-line problem on the toolkit's
interior-point method (:class:`lmi.backends.ipm.IPMKothare`: the conic data of
:class:`~lmi.backends.conic.KothareConic`, state scaling, factored coefficients, warm starts,
the rebalanced retry, phase one and the Clarabel fallback) with one more block, the nesting
``Q_{i-1} - Q_i >= 0`` (``nesting=True``); the first design state is solved without it, i.e.
exactly as the on-line problem. ``backend="clarabel"`` hands the same conic data to Clarabel,
and ``backend="cvxpy"`` writes the LMIs with cvxpy (the formulation of
:mod:`lmi.backends.cvxpy`, any installed conic solver). Every stored ellipsoid is certified by
:func:`lmi.certify` (the LMIs recomputed in numpy) and by the recomputed nesting margin, whatever
the back-end.

Wan & Kothare's condition (18) for interpolating between neighbours,
``Q_i^-1 - (A_j + B_j F_{i+1})' Q_i^-1 (A_j + B_j F_{i+1}) > 0`` for every vertex ``j``, is
checked after the fact (:func:`interpolation_margin`); where it fails, the table records that
interpolation between those neighbours is off.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from itertools import pairwise
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from lmi.backends.base import KothareBackend, RawResult
from lmi.backends.clarabel import ClarabelKothare
from lmi.backends.conic import KothareConic
from lmi.backends.ipm import IPMKothare
from lmi.certificate import Certificate, certify
from lmi.data import Formulation, InputConstraint, KothareData, build_kothare_data
from lmi.forms import FormProblem
from lmi.status import CVXPY_STATUS_MAP, INACCURATE, OPTIMAL, SOLVER_ERROR, UNCERTIFIED
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import as_matrix, as_vector, check_positive

__all__ = [
    "NestedEllipsoid",
    "NestedKothareProblem",
    "OfflineTable",
    "interpolation_margin",
    "nesting_margin",
]


def _rel_min_eig(mat: np.ndarray) -> float:
    sym = 0.5 * (mat + mat.T)
    lam = np.linalg.eigvalsh(sym)
    scale = max(float(np.max(np.abs(lam))), np.finfo(float).tiny)
    return float(lam[0] / scale)


def nesting_margin(q_outer: np.ndarray, q_inner: np.ndarray) -> float:
    """Smallest eigenvalue of ``Q_outer - Q_inner`` divided by ``||Q_outer||_2``.

    ``>= 0`` means ``E_inner ⊆ E_outer``.
    """
    lam = np.linalg.eigvalsh(0.5 * ((q_outer - q_inner) + (q_outer - q_inner).T))
    return float(lam[0] / max(float(np.linalg.norm(q_outer, 2)), np.finfo(float).tiny))


def interpolation_margin(data: KothareData, q_outer: np.ndarray, f_inner: np.ndarray) -> float:
    """Wan & Kothare's condition (18) for the neighbours ``(Q_i, F_{i+1})``, as a relative margin.

    ``Q_i^-1 - M_j' Q_i^-1 M_j > 0`` with ``M_j = A_j + B_j F_{i+1}`` is, after the congruence
    with ``Q_i`` and division by ``dt``, ``[[-(H_j + H_j'), sqrt(dt) H_j'], [sqrt(dt) H_j, Q_i]] > 0``
    with ``H_j = (M_j - I) Q_i / dt`` (the delta form of :mod:`lmi.backends.conic`, exact for
    any ``dt`` and well conditioned when ``M_j`` is close to ``I``). Returns the smallest
    relative eigenvalue over the vertices; the condition holds when it is ``> 0``.
    """
    n, dt = data.n, data.dt
    worst = np.inf
    for a, b in zip(data.A, data.B, strict=True):
        h = ((a + b @ f_inner - np.eye(n)) / dt) @ q_outer
        mat = np.block([[-(h + h.T), np.sqrt(dt) * h.T], [np.sqrt(dt) * h, q_outer]])
        worst = min(worst, _rel_min_eig(mat))
    return float(worst)


@dataclass(frozen=True)
class NestedEllipsoid:
    """One entry of the off-line table: the solution at one design state.

    Attributes
    ----------
    status : str
        ``"optimal"`` (converged, certified and nested) or a failure word (:mod:`lmi.status`).
    x : ndarray
        The design state.
    gamma : float
        The cost bound at ``x``; ``P = gamma Q^-1``.
    Q, Y, F : ndarray or None
        The LMI variables and the gain ``F = Y Q^-1`` (``u = F x``).
    certificate : Certificate or None
        The recomputed Kothare LMIs (:func:`lmi.certify`).
    nesting_margin : float
        :func:`nesting_margin` of ``(Q_{i-1}, Q_i)``; NaN for the first ellipsoid.
    solve_time : float
    solver_status : str
    iterations : int or None
        The solver's iterations, summed over its stages (``None`` where the back-end does not
        count them, as through cvxpy).
    """

    status: str
    x: np.ndarray = field(repr=False)
    gamma: float
    Q: np.ndarray | None = field(repr=False)
    Y: np.ndarray | None = field(repr=False)
    F: np.ndarray | None = field(repr=False)
    certificate: Certificate | None = field(repr=False)
    nesting_margin: float
    solve_time: float
    solver_status: str
    iterations: int | None = None

    @property
    def ok(self) -> bool:
        return self.status == OPTIMAL

    @property
    def P(self) -> np.ndarray | None:
        """``gamma Q^-1``."""
        return None if self.Q is None else self.gamma * np.linalg.inv(self.Q)


@dataclass(frozen=True)
class OfflineTable:
    """The nested sequence ``E_1 ⊇ E_2 ⊇ ... ⊇ E_N`` and what is known about it.

    Attributes
    ----------
    ellipsoids : tuple of NestedEllipsoid
        Certified entries only, outermost first.
    interpolation_margins : ndarray, shape (N - 1,)
        :func:`interpolation_margin` of ``(Q_i, F_{i+1})``.
    interpolable : ndarray of bool, shape (N - 1,)
        Whether condition (18) holds between ``i`` and ``i + 1`` (margin ``> interpolation_tol``).
    design_time : float
        Wall time of the whole design (s).
    stop_reason : str
        Why the sequence ends where it does (``"complete"`` when all design states were used).
    failed_status : str or None
        The status of the solve that ended the sequence early, if one did.
    skipped : tuple of (int, float)
        Design states not used: (position in the given sequence, level ``x' Q_{i-1}^-1 x``).
    """

    ellipsoids: tuple[NestedEllipsoid, ...]
    interpolation_margins: np.ndarray
    interpolable: np.ndarray
    design_time: float
    stop_reason: str
    failed_status: str | None = None
    skipped: tuple[tuple[int, float], ...] = ()

    @property
    def n_ellipsoids(self) -> int:
        return len(self.ellipsoids)

    @property
    def gammas(self) -> np.ndarray:
        return np.array([e.gamma for e in self.ellipsoids])

    @property
    def states(self) -> np.ndarray:
        """The design states, shape ``(N, n)``."""
        return np.array([e.x for e in self.ellipsoids])


class NestedKothareProblem:
    """The Kothare LMIs plus the nesting LMIs of Wan & Kothare (2003), built once.

    Parameters
    ----------
    A, B, Q, R, dt, input_constraint, u_max, output_matrix, y_max, formulation
        As :class:`lmi.KothareProblem`.
    backend : {"ipm", "clarabel", "cvxpy"}
        ``"ipm"`` (default): the on-line problem's interior-point back-end
        (:class:`lmi.backends.ipm.IPMKothare`) with the nesting block; ``"clarabel"``: the same
        conic data handed to Clarabel; ``"cvxpy"``: the LMIs written with cvxpy, solved by
        ``solver``.
    solver : str, optional
        With ``backend="cvxpy"``: any installed cvxpy conic solver (default ``"CLARABEL"``);
        ``None`` otherwise.
    solver_options : dict, optional
        Solver settings, validated by the back-end (:data:`lmi.backends.ipm.DEFAULT_IPM_OPTIONS`,
        :func:`lmi.backends.clarabel.clarabel_settings`, :mod:`lmi.backends.cvxpy`).
    certificate_tol : float
        Every recomputed relative margin (Kothare LMIs, nesting) must be ``>= -tol``.
    interpolation_tol : float
        Condition (18) is taken to hold when its relative margin is ``> interpolation_tol``.
    cost : {"worst_case", "nominal"}
        ``"nominal"``: each ellipsoid minimises the cost bound on the nominal model with robust
        invariance on every vertex (Wan & Kothare, "Efficient robust constrained model
        predictive control with a time varying terminal constraint set", Systems & Control
        Letters 48, 2003; the LMIs of :mod:`lmi.forms`, solved by :class:`lmi.forms.FormProblem`
        with the nesting block, certified block by block). Needs ``nominal``.
    lyapunov : {"common"}
        The nesting argument (each ellipsoid invariant under its own gain, nested inside the
        previous one) needs one Lyapunov matrix per ellipsoid: the vertex forms, whose
        invariant set depends on the unknown plant, are refused with an error.
    nominal : (A0, B0), optional
        The nominal model for ``cost="nominal"``.

    Examples
    --------
    Kothare (1996), example 1, four nested ellipsoids along the ray of ``x0 = [0.05, 0]``:

    >>> import numpy as np
    >>> from lmi.offline import NestedKothareProblem
    >>> A = [[[1, 0.1], [0, 1 - 0.1 * a]] for a in (0.1, 10.0)]
    >>> B = [[[0.0], [0.1 * 0.787]]] * 2
    >>> prob = NestedKothareProblem(A, B, Q=np.diag([1.0, 0.0]), R=[[2e-5]], dt=0.1,
    ...                             input_constraint="peak", u_max=2.0)
    >>> table = prob.design_ray([0.05, 0.0], n_ellipsoids=4, shrink=0.5)
    >>> table.n_ellipsoids, round(float(table.gammas[0]), 5)
    (4, 0.00972)
    >>> all(e.nesting_margin >= -1e-7 for e in table.ellipsoids[1:])
    True
    """

    def __init__(
        self,
        A: ArrayLike,
        B: ArrayLike,
        Q: ArrayLike,
        R: ArrayLike,
        *,
        dt: float = 1.0,
        input_constraint: InputConstraint = "ellipsoid",
        u_max: ArrayLike | None = None,
        output_matrix: ArrayLike | None = None,
        y_max: ArrayLike | None = None,
        backend: str = "ipm",
        solver: str | None = None,
        solver_options: dict[str, Any] | None = None,
        formulation: Formulation = "delta_shared",
        certificate_tol: float = 1e-7,
        interpolation_tol: float = 1e-9,
        cost: str = "worst_case",
        lyapunov: str = "common",
        nominal: tuple[ArrayLike, ArrayLike] | None = None,
    ) -> None:
        self.data: KothareData = build_kothare_data(
            A, B, Q, R, dt=dt, input_constraint=input_constraint, u_max=u_max,
            output_matrix=output_matrix, y_max=y_max, formulation=formulation,
        )
        if lyapunov != "common":
            raise InvalidArgumentError(
                "lyapunov", "'common' (the off-line design nests one invariant ellipsoid per gain; a "
                "vertex form's invariant set depends on the unknown plant)", repr(lyapunov),
            )
        if cost not in ("worst_case", "nominal"):
            raise InvalidArgumentError("cost", "'worst_case' or 'nominal'", repr(cost))
        self.cost = cost
        self._forms: FormProblem | None = None
        if cost == "nominal":
            if formulation != "delta_shared":
                raise InvalidArgumentError("formulation, cost", "the default formulation with cost='nominal' "
                                           "(the forms' own delta congruence)", repr(formulation))
            if backend == "cvxpy" and solver not in (None, "CLARABEL", "clarabel"):
                raise InvalidArgumentError("solver", "None or 'CLARABEL' with cost='nominal'", repr(solver))
            self._forms = FormProblem(
                A, B, Q, R, dt=dt, input_constraint=input_constraint, u_max=u_max,
                output_matrix=output_matrix, y_max=y_max, nominal=nominal, cost="nominal",
                backend=backend, solver_options=solver_options, certificate_tol=certificate_tol,
            )
        if solver_options is not None and not isinstance(solver_options, dict):
            raise InvalidArgumentError(
                "solver_options", "a dict of solver settings", type(solver_options).__name__
            )
        self.certificate_tol = check_positive(certificate_tol, "certificate_tol")
        self.interpolation_tol = check_positive(interpolation_tol, "interpolation_tol", allow_zero=True)
        # The first design state is the on-line problem (no nesting block); the others go to a
        # back-end whose data have the nesting block.
        self._plain: KothareBackend
        self._nest: KothareBackend
        if self._forms is not None:
            self._kind = "forms"
            return
        if backend == "ipm":
            if solver is not None:
                raise InvalidArgumentError("solver", "None with backend='ipm'", repr(solver))
            self._plain = IPMKothare(self.data, solver_options)
            self._nest = IPMKothare(self.data, solver_options, nesting=True)
        elif backend == "clarabel":
            if solver not in (None, "clarabel", "CLARABEL"):
                raise InvalidArgumentError("solver", "None with backend='clarabel'", repr(solver))
            self._plain = ClarabelKothare(self.data, solver_options)
            self._nest = ClarabelKothare(self.data, solver_options,
                                         conic=KothareConic(self.data, nesting=True))
        elif backend == "cvxpy":
            self._setup_cvxpy(solver or "CLARABEL", solver_options)
        else:
            raise InvalidArgumentError("backend", "'ipm', 'clarabel' or 'cvxpy'", repr(backend))
        self._kind = backend

    def _setup_cvxpy(self, solver: str, solver_options: dict[str, Any] | None) -> None:
        import cvxpy as cp  # ~0.5 s to import: only for this back-end

        from lmi.backends.cvxpy import CvxpyKothare

        self._base = CvxpyKothare(self.data, solver, solver_options)
        n = self.data.n
        base = self._base
        # gamma_s = dt gamma in the delta formulations (see lmi.backends.conic).
        self._gamma_scale = 1.0 if self.data.formulation == "standard" else self.data.dt
        self._outer = cp.Parameter((n, n), symmetric=True)
        extra = [self._outer - base.Qv >> 0]
        self._nested = cp.Problem(cp.Minimize(base.gs), [*base.problem.constraints, *extra])

    @property
    def backend(self) -> str:
        """``"ipm"``, ``"clarabel"`` or ``"cvxpy:SOLVER"``."""
        return self._base.name if self._kind == "cvxpy" else self._plain.name

    def reset(self) -> None:
        """Forget what earlier solves left behind (the IPM's warm starts and rebalanced
        coordinates); every design starts with this, so a table does not depend on earlier ones."""
        if self._forms is not None:
            self._forms.reset()
        elif self._kind != "cvxpy":
            self._plain.reset()
            self._nest.reset()

    # -- one design state ----------------------------------------------------------------
    def solve(self, x: ArrayLike, outer: NestedEllipsoid | None = None) -> NestedEllipsoid:
        """Solve at ``x`` (non-zero), nested inside ``outer`` when given.

        The problem is solved at ``x / ||x||`` with the bounds (and ``Q_outer``) rescaled, as
        in :class:`lmi.KothareProblem`. Failures come back as a status, never raised.
        """
        d = self.data
        x = as_vector(x, "x", d.n)
        s = float(np.linalg.norm(x))
        if s == 0.0:
            raise InvalidArgumentError("x", "a non-zero design state", "x = 0")
        if outer is not None and (outer.Q is None or not outer.ok):
            raise InvalidArgumentError("outer", "a certified NestedEllipsoid", f"status {outer.status!r}")
        if self._forms is not None:
            return self._solve_forms(x, outer)
        if self._kind != "cvxpy":
            return self._solve_conic(x, s, outer)
        return self._solve_cvxpy(x, s, outer)

    def _solve_forms(self, x: np.ndarray, outer: NestedEllipsoid | None) -> NestedEllipsoid:
        """The nominal cost: :class:`lmi.forms.FormProblem` with the nesting block, its own
        certificate (every block, the nesting one included), and the nesting margin again."""
        assert self._forms is not None
        sol = self._forms.solve(x, q_outer=None if outer is None else outer.Q)
        if sol.Q is None:
            return NestedEllipsoid(sol.status, x, np.nan, None, None, None, None, np.nan, sol.solve_time,
                                   sol.solver_status, sol.iterations)
        nest = np.nan if outer is None or outer.Q is None else nesting_margin(outer.Q, sol.Q)
        status = sol.status
        if status == OPTIMAL and nest < -self.certificate_tol:
            status = UNCERTIFIED
        return NestedEllipsoid(status, x, sol.gamma, sol.Q, sol.Y, sol.F, sol.certificate, nest,
                               sol.solve_time, sol.solver_status, sol.iterations)

    def _solve_conic(self, x: np.ndarray, s: float, outer: NestedEllipsoid | None) -> NestedEllipsoid:
        """The ``"ipm"`` and ``"clarabel"`` back-ends: the normalised problem, ``Q_outer / s^2``."""
        d = self.data
        if outer is None:
            raw: RawResult = self._plain.solve(x / s, d.u_max / s, d.y_max / s)
        else:
            assert outer.Q is not None
            q_out = 0.5 * (outer.Q + outer.Q.T) / s**2
            raw = self._nest.solve(x / s, d.u_max / s, d.y_max / s, q_out)  # type: ignore[call-arg]
        if raw.Q is None or raw.Y is None:
            return NestedEllipsoid(raw.status, x, np.nan, None, None, None, None, np.nan, raw.solve_time,
                                   raw.solver_status, raw.iterations)
        q_mat = 0.5 * (raw.Q + raw.Q.T) * s**2
        return self._finish(raw.status, raw.solver_status, x, raw.gamma * s**2, q_mat, raw.Y * s**2, outer,
                            raw.solve_time, raw.iterations)

    def _solve_cvxpy(self, x: np.ndarray, s: float, outer: NestedEllipsoid | None) -> NestedEllipsoid:
        import cvxpy as cp

        d = self.data
        base = self._base
        base.x.value = x / s
        if base.inv_u is not None:
            base.inv_u.value = s / float(d.u_max[0]) if d.input_constraint == "ellipsoid" else s / d.u_max
        if base.inv_y is not None:
            base.inv_y.value = s / d.y_max
        problem = base.problem
        if outer is not None:
            assert outer.Q is not None
            problem = self._nested
            self._outer.value = 0.5 * (outer.Q + outer.Q.T) / s**2
        start = time.perf_counter()
        try:
            with warnings.catch_warnings():
                # cvxpy warns on "optimal_inaccurate"; the status and the certificate record it.
                warnings.filterwarnings("ignore", message="Solution may be inaccurate")
                problem.solve(solver=base.solver_arg, **base.options)  # SCS: Ctrl-C handed back
        except cp.error.SolverError as err:
            return NestedEllipsoid(
                SOLVER_ERROR, x, np.nan, None, None, None, None, np.nan,
                time.perf_counter() - start, str(err),
            )
        elapsed = time.perf_counter() - start
        raw = str(problem.status)
        status = CVXPY_STATUS_MAP.get(raw, SOLVER_ERROR)
        if base.Qv.value is None or base.gs.value is None:
            return NestedEllipsoid(status, x, np.nan, None, None, None, None, np.nan, elapsed, raw)
        q_mat = 0.5 * (base.Qv.value + base.Qv.value.T) * s**2
        y_mat = np.asarray(base.Yv.value) * s**2
        gamma = float(base.gs.value) / self._gamma_scale * s**2
        return self._finish(status, raw, x, gamma, q_mat, y_mat, outer, elapsed)

    def _finish(
        self, status: str, raw: str, x: np.ndarray, gamma: float, q_mat: np.ndarray,
        y_mat: np.ndarray, outer: NestedEllipsoid | None, elapsed: float, iterations: int | None = None,
    ) -> NestedEllipsoid:
        tol = self.certificate_tol
        cert = certify(self.data, x, gamma, q_mat, y_mat, tol=tol)
        try:
            f_mat = np.linalg.solve(q_mat.T, y_mat.T).T
        except np.linalg.LinAlgError:
            f_mat = None
        nest = np.nan
        if outer is not None:
            assert outer.Q is not None
            nest = nesting_margin(outer.Q, q_mat)
        checks_ok = (
            cert.ok and f_mat is not None and bool(np.all(np.isfinite(f_mat)))
            and not nest < -tol
        )
        if status in (OPTIMAL, INACCURATE):
            status = OPTIMAL if checks_ok else UNCERTIFIED
        return NestedEllipsoid(status, x, gamma, q_mat, y_mat, f_mat, cert, nest, elapsed, raw, iterations)

    # -- sequences -------------------------------------------------------------------------
    def _table(
        self, entries: list[NestedEllipsoid], start: float, failed: NestedEllipsoid | None = None,
        reason: str = "complete", skipped: Sequence[tuple[int, float]] = (),
    ) -> OfflineTable:
        pairs = list(pairwise(entries))
        margins = np.array([interpolation_margin(self.data, o.Q, i.F) for o, i in pairs])  # type: ignore[arg-type]
        if failed is not None:
            reason = f"design state {len(entries) + len(skipped)}: status {failed.status!r}"
        return OfflineTable(
            ellipsoids=tuple(entries), interpolation_margins=margins,
            interpolable=margins > self.interpolation_tol,
            design_time=time.perf_counter() - start, stop_reason=reason,
            failed_status=None if failed is None else failed.status, skipped=tuple(skipped),
        )

    def design(self, states: ArrayLike) -> OfflineTable:
        """The nested sequence at the given design states (outermost first).

        A state that is not strictly inside the previous ellipsoid (level
        ``x' Q_{i-1}^-1 x >= 1``, so no nested ellipsoid can contain it) is skipped and listed
        in ``skipped``; the sequence stops at the first solve that is not certified.
        """
        pts = as_matrix(states, "states", (None, self.data.n))
        if pts.shape[0] == 0:
            raise InvalidArgumentError("states", "at least one design state", "an empty sequence")
        norms = np.linalg.norm(pts, axis=1)
        if np.any(norms == 0.0):
            raise InvalidArgumentError(
                "states", "non-zero design states", f"x = 0 at row {int(np.argmin(norms))}"
            )
        start = time.perf_counter()
        self.reset()
        entries: list[NestedEllipsoid] = []
        skipped: list[tuple[int, float]] = []
        for k, x in enumerate(pts):
            outer = entries[-1] if entries else None
            if outer is not None:
                level = float(x @ np.linalg.solve(outer.Q, x))  # type: ignore[arg-type]
                if not level < 1.0:
                    skipped.append((k, level))
                    continue
            sol = self.solve(x, outer)
            if not sol.ok:
                return self._table(entries, start, sol, skipped=skipped)
            entries.append(sol)
        return self._table(entries, start, skipped=skipped)

    def design_ray(self, x0: ArrayLike, n_ellipsoids: int, shrink: float = 0.5) -> OfflineTable:
        """Design states geometrically spaced along the ray of ``x0``: ``x_i = shrink^(i-1) x0``."""
        x0 = as_vector(x0, "x0", self.data.n)
        count = check_ellipsoid_count(n_ellipsoids, shrink)
        shrink = _check_shrink(shrink)
        return self.design(np.array([x0 * shrink**i for i in range(count)]))

    def design_trajectory(
        self,
        x0: ArrayLike,
        n_ellipsoids: int,
        shrink: float = 0.5,
        *,
        A: ArrayLike | None = None,
        B: ArrayLike | None = None,
        max_steps: int = 100_000,
    ) -> OfflineTable:
        """Design states along a closed loop: ``x_{i+1}`` is the first state of the loop under
        ``F_i`` with ``x' Q_i^-1 x <= shrink^2``.

        The loop runs on the model ``(A, B)`` (default: the mean of the vertices). Since
        ``E_i`` is invariant under ``F_i``, every such state is strictly inside ``E_i``.
        """
        d = self.data
        x = as_vector(x0, "x0", d.n)
        count = check_ellipsoid_count(n_ellipsoids, shrink)
        level_next = _check_shrink(shrink) ** 2
        a_sim = d.A.mean(axis=0) if A is None else as_matrix(A, "A", (d.n, d.n))
        b_sim = d.B.mean(axis=0) if B is None else as_matrix(B, "B", (d.n, d.m))
        if not isinstance(max_steps, int | np.integer) or max_steps < 1:
            raise InvalidArgumentError("max_steps", "a positive integer", repr(max_steps))
        start = time.perf_counter()
        if float(np.linalg.norm(x)) == 0.0:
            raise InvalidArgumentError("x0", "a non-zero design state", "x0 = 0")
        self.reset()
        entries: list[NestedEllipsoid] = []
        steps = 0
        while True:
            sol = self.solve(x, entries[-1] if entries else None)
            if not sol.ok:
                return self._table(entries, start, sol)
            entries.append(sol)
            if len(entries) == count:
                return self._table(entries, start)
            assert sol.Q is not None and sol.F is not None
            q_inv = np.linalg.inv(sol.Q)
            closed = a_sim + b_sim @ sol.F
            while float(x @ q_inv @ x) > level_next:
                if steps == max_steps:
                    return self._table(entries, start, reason=f"max_steps={max_steps} reached")
                x = closed @ x
                steps += 1


SMALLEST_SCALE = 1e-12
"""The smallest design state, relative to the first, the nested design goes down to."""


def check_ellipsoid_count(n_ellipsoids: Any, shrink: Any) -> int:
    """``n_ellipsoids`` as an int, at most what ``shrink`` allows.

    Ellipsoid ``k`` is designed at a state ``shrink^k`` times the first (on the ray, or at least
    that much smaller along a trajectory), so beyond ``1 + log(1e-12) / log(shrink)`` ellipsoids
    (40 at the default 0.5) the design states fall below 1e-12 of the first and the SDPs
    degenerate; a count above that is refused, naming the ``shrink`` that would allow it. (A count
    of 10 million was accepted and designed ellipsoid by ellipsoid.)

    Examples
    --------
    >>> check_ellipsoid_count(15, 0.5)
    15
    >>> try:
    ...     check_ellipsoid_count(41, 0.5)
    ... except ValueError as err:
    ...     print(err.found, "|", err.expected)
    41 | at most 40 for shrink = 0.5 (a shrink nearer 1 allows more)
    """
    if isinstance(n_ellipsoids, bool) or not isinstance(n_ellipsoids, int | np.integer) or n_ellipsoids < 1:
        raise InvalidArgumentError("n_ellipsoids", "a positive integer", repr(n_ellipsoids))
    factor = _check_shrink(shrink)
    most = 1 + int(np.floor(np.log(SMALLEST_SCALE) / np.log(factor)))
    if n_ellipsoids > most:
        raise InvalidArgumentError(
            "n_ellipsoids", f"at most {most} for shrink = {factor:g} (a shrink nearer 1 allows more)",
            repr(int(n_ellipsoids)),
        )
    return int(n_ellipsoids)


def _check_shrink(shrink: Any) -> float:
    value = check_positive(shrink, "shrink")
    if not value < 1.0:
        raise InvalidArgumentError("shrink", "a number in (0, 1)", repr(shrink))
    return value
