"""The Kothare, Balakrishnan & Morari (1996) min-max robust MPC problem, built once, solved per state.

Reference: M. V. Kothare, V. Balakrishnan, M. Morari, "Robust constrained model predictive
control using linear matrix inequalities", Automatica 32(10), 1361-1379, 1996.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from lmi.backends.base import KothareBackend, RawResult
from lmi.backends.clarabel import ClarabelKothare
from lmi.backends.ipm import IPMKothare
from lmi.certificate import Certificate, certify
from lmi.data import Formulation, InputConstraint, KothareData, build_kothare_data
from lmi.infeasibility import InfeasibilityCertificate
from lmi.status import INACCURATE, OPTIMAL, UNCERTIFIED
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import as_vector, check_positive

__all__ = ["MIX_WEIGHTS", "KothareProblem", "LMISolution"]

#: The weights of a strictly feasible point (phase one's) mixed into an answer that is not
#: certified (see :meth:`KothareProblem.solve`), smallest first: the first whose mix passes is
#: taken; the last, 1, is the point itself.
MIX_WEIGHTS: tuple[float, ...] = (1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0)


@dataclass(frozen=True)
class LMISolution:
    """The answer of one solve.

    Attributes
    ----------
    status : str
        ``"optimal"`` (converged and certified) or a failure word (:mod:`lmi.status`).
    gamma : float
        The worst-case cost bound ``x' P x`` (NaN when the solver returned nothing).
    Q, Y : ndarray or None
        The LMI variables; ``P = gamma Q^-1``.
    F : ndarray or None
        The state-feedback gain ``F = Y Q^-1``, applied as ``u = F x``.
    solve_time : float
        Time inside the solver (s).
    iterations : int or None
    solver_status : str
        The back-end's own status word.
    certificate : Certificate or None
        Recomputed LMI margins.
    backend : str
    x : ndarray
        The state the problem was solved at.
    infeasibility : InfeasibilityCertificate or None
        With status ``"infeasible"`` from the ``"ipm"`` back-end: the Farkas certificate its
        phase one found, checked on the conic data of the problem as solved (normalised state,
        balanced coordinates; see :mod:`lmi.infeasibility`). ``ok`` is always true here: an
        unchecked proof never makes a status ``"infeasible"``.
    G, Q_vertices, u0, H, slack, lam
        What the robust MPC forms of :mod:`lmi.forms` add (``None`` where the form has none):
        the slack matrix ``G`` and the per-vertex ``Q_j`` of the vertex Lyapunov forms (then
        ``F = Y G^-1`` and ``Q`` is an ellipsoid inside every ``{x' Q_j^-1 x <= 1}``), the free
        first move ``u0``, the auxiliary gain ``H`` of the saturation-aware form, the soft
        constraints' slacks ``{"u": s_u, "y": s_y}`` (squared units) and the disturbance
        form's contraction factor ``lam``.
    gamma_dual : float or None
        The back-end's own dual bound on the optimal ``gamma`` (Clarabel's dual objective; with
        ``gamma`` it brackets the optimum to the accuracy the solver actually reached, whatever
        its status says); ``None`` where the back-end reports none.
    steps : dict of str to ndarray or None
        The forms with steps (:mod:`lmi.forms.steps`): the later steps' variables by name
        (``"Y@2"``, ``"G@2"``, ``"Q0@2"``, Li et al.'s second-step gains ``"Y@v0"``, ...), at the
        scale of ``Y`` and ``Q``; the first step's are ``Q``, ``Y``, ``G``, ``Q_vertices``, ``H``.
    gamma_s : float or None
        Huang et al.'s bound on the unsaturated sign pattern's cost (``unsaturated_weight`` of
        :mod:`lmi.forms`, ``gamma_s <= gamma``); ``None`` in every other form.
    """

    status: str
    gamma: float
    Q: np.ndarray | None
    Y: np.ndarray | None
    F: np.ndarray | None
    solve_time: float
    iterations: int | None
    solver_status: str
    certificate: Certificate | None
    backend: str
    x: np.ndarray = field(repr=False)
    infeasibility: InfeasibilityCertificate | None = field(default=None, repr=False)
    G: np.ndarray | None = field(default=None, repr=False)
    Q_vertices: tuple[np.ndarray, ...] | None = field(default=None, repr=False)
    u0: np.ndarray | None = field(default=None, repr=False)
    H: np.ndarray | None = field(default=None, repr=False)
    slack: dict[str, float] | None = field(default=None, repr=False)
    lam: float | None = field(default=None, repr=False)
    gamma_dual: float | None = field(default=None, repr=False)
    steps: dict[str, np.ndarray] | None = field(default=None, repr=False)
    gamma_s: float | None = field(default=None, repr=False)

    @property
    def ok(self) -> bool:
        """``status == "optimal"``."""
        return self.status == OPTIMAL

    @property
    def margins(self) -> dict[str, float]:
        """The certificate's relative margins (empty without a certificate)."""
        return {} if self.certificate is None else dict(self.certificate.margins)

    @property
    def P(self) -> np.ndarray | None:
        """``gamma Q^-1``, the cost matrix of the bound ``x' P x``."""
        if self.Q is None:
            return None
        return self.gamma * np.linalg.inv(self.Q)


class KothareProblem:
    """Min-max robust MPC over a polytope ``Co{[A_j B_j]}``, Kothare et al. (1996).

    At a state ``x`` it minimises ``gamma`` over ``Q > 0``, ``Y`` subject to
    ``[[1, x'], [x, Q]] >= 0``, one cost LMI per vertex and the input (and output) constraint
    LMIs; the control law is ``u = F x`` with ``F = Y Q^-1``.

    The problem is solved at ``x / ||x||`` with the bounds divided by ``||x||`` and the answer
    rescaled (``gamma``, ``Q``, ``Y`` times ``||x||^2``; ``F`` unchanged). This is exact (the
    LMIs are homogeneous) and keeps states near the origin well conditioned.

    Parameters
    ----------
    A : (N, n, n) array_like
        Vertex state matrices (discrete time).
    B : (N, n, m) array_like
        Vertex input matrices.
    Q : (n, n) array_like
        State weight ``Q1``, symmetric positive semidefinite.
    R : (m, m) array_like
        Input weight, symmetric positive definite.
    dt : float
        Sample time, used by the ``"delta"`` formulation (any positive value is exact; the
        model's own sample time conditions best).
    input_constraint : {"ellipsoid", "peak", None}
        ``||u||_2 <= u_max`` (scalar ``u_max``), ``|u_j| <= u_max_j`` (scalar or vector) or none.
    u_max : float or array_like
    output_matrix, y_max : array_like, optional
        Output constraints ``|(C x(k+i))_r| <= y_max_r`` for ``i >= 1`` (Kothare 1996, sec. 3.2).
    backend : str
        ``"ipm"`` (default: the toolkit's own structure-exploiting interior-point method
        :mod:`lmi.ipm`, data built once, warm-started; an infeasible problem is proved so by
        the run's own dual iterates or, after a failed solve, by phase one (status
        ``"infeasible"`` with ``LMISolution.infeasibility``); a strictly feasible point phase
        one finds is mixed into an answer that is not certified, or is the answer, status
        ``"inaccurate"`` with ``gamma`` an upper bound (:data:`MIX_WEIGHTS`); what neither settles
        goes to Clarabel; :mod:`lmi.backends.ipm`),
        ``"clarabel"`` (Clarabel's own API, data built once) or
        ``"cvxpy"`` with ``solver`` naming any installed
        cvxpy conic solver (``"CLARABEL"``, ``"SCS"``, ...).
    solver : str, optional
        The cvxpy solver for ``backend="cvxpy"`` (default ``"CLARABEL"``).
    solver_options : dict, optional
        Solver settings; unknown names raise :class:`~toolkit_common.errors.InvalidArgumentError`.
    formulation : {"delta_shared", "delta", "standard"}
        Default ``"delta_shared"``. ``"delta"`` rewrites the vertex LMIs with ``(A_j - I)/dt``
        (a congruence; same optimum, better conditioned at small ``dt``); ``"delta_shared"``
        also lifts the common ``Q1``/``R`` part into one shared block so each vertex cone
        shrinks to ``2n``;
        ``"standard"`` is eq. (14) as printed. See :mod:`lmi.backends.conic`.
    certificate_tol : float
        A solve is ``"optimal"`` only if every recomputed relative LMI margin is ``>= -tol``.

    Examples
    --------
    Kothare (1996), example 1, with the plant at ``alpha = 0.1`` and ``alpha = 10``:

    >>> import numpy as np
    >>> from lmi import KothareProblem
    >>> A = [[[1, 0.1], [0, 1 - 0.1 * a]] for a in (0.1, 10.0)]
    >>> B = [[[0.0], [0.1 * 0.787]]] * 2
    >>> prob = KothareProblem(A, B, Q=np.diag([1.0, 0.0]), R=[[2e-5]], dt=0.1,
    ...                       input_constraint="peak", u_max=2.0)
    >>> sol = prob.solve([0.05, 0.0])
    >>> sol.status, round(sol.gamma, 5)
    ('optimal', 0.00972)
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
    ) -> None:
        self.data: KothareData = build_kothare_data(
            A, B, Q, R, dt=dt, input_constraint=input_constraint, u_max=u_max,
            output_matrix=output_matrix, y_max=y_max, formulation=formulation,
        )
        self.certificate_tol = check_positive(certificate_tol, "certificate_tol")
        if solver_options is not None and not isinstance(solver_options, dict):
            raise InvalidArgumentError(
                "solver_options", "a dict of solver settings", type(solver_options).__name__
            )
        if backend == "clarabel":
            if solver not in (None, "clarabel", "CLARABEL"):
                raise InvalidArgumentError("solver", "None with backend='clarabel'", repr(solver))
            self._backend: KothareBackend = ClarabelKothare(
                self.data, solver_options
            )
        elif backend == "ipm":
            if solver is not None:
                raise InvalidArgumentError("solver", "None with backend='ipm'", repr(solver))
            self._backend = IPMKothare(self.data, solver_options)
        elif backend == "cvxpy":
            from lmi.backends.cvxpy import CvxpyKothare  # cvxpy costs ~0.5 s to import

            self._backend = CvxpyKothare(self.data, solver or "CLARABEL", solver_options)
        else:
            raise InvalidArgumentError("backend", "'clarabel', 'ipm' or 'cvxpy'", repr(backend))

    @property
    def backend(self) -> str:
        """Name of the back-end (``"ipm"``, ``"clarabel"`` or ``"cvxpy:SOLVER"``)."""
        return self._backend.name

    @property
    def n_states(self) -> int:
        return self.data.n

    @property
    def n_inputs(self) -> int:
        return self.data.m

    def reset(self) -> None:
        """Forget what earlier solves left behind (the IPM's warm-start point and rebalanced
        coordinates): the next solve gives what a freshly built problem gives."""
        self._backend.reset()

    def solve(self, x: ArrayLike, u_max: ArrayLike | None = None) -> LMISolution:
        """Solve at the state ``x`` (non-zero); failures come back as a status, never raised.

        Parameters
        ----------
        x : (n,) array_like
            The measured state (non-zero).
        u_max : float or array_like, optional
            The input bound for this solve only, instead of the one the problem was built with
            (same kind: a scalar for the ellipsoid, a scalar or ``(m,)`` for the peak bound). The
            certificate checks the bound actually used. :class:`rmpc.CRMPC` uses it to give the
            robust MPC what its disturbance correction leaves of the torque limit.
        """
        x = as_vector(x, "x", self.data.n)
        scale = float(np.linalg.norm(x))
        if scale == 0.0:
            raise InvalidArgumentError(
                "x", "a non-zero state (the problem is degenerate at the origin)", "x = 0"
            )
        data = self.data if u_max is None else dataclasses.replace(self.data, u_max=self.input_bound(u_max))
        raw: RawResult = self._backend.solve(x / scale, data.u_max / scale, data.y_max / scale)
        return self._finish(raw, x, scale, data)

    def input_bound(self, u_max: ArrayLike) -> np.ndarray:
        """``u_max`` checked as an input bound of this problem's kind, as the problem holds it.

        The form :meth:`solve` takes for a per-solve bound: a scalar (or a one-element array) for
        the ellipsoid, a scalar or an ``(m,)`` vector for the peak bound; the result is the
        ``(1,)`` or ``(m,)`` vector ``u_max`` of :class:`~lmi.KothareData`.

        Raises
        ------
        InvalidArgumentError
            Naming ``u_max``: a bound of the wrong size, not positive, or any bound for a
            problem without an input constraint.

        Examples
        --------
        >>> import numpy as np
        >>> from lmi import KothareProblem
        >>> prob = KothareProblem([[1.0]], [[1.0, 0.5]], Q=[[1.0]], R=np.eye(2),
        ...                       input_constraint="peak", u_max=1.0)
        >>> prob.input_bound(0.5).tolist(), prob.input_bound([0.2, 0.3]).tolist()
        ([0.5, 0.5], [0.2, 0.3])
        """
        kind = self.data.input_constraint
        if kind is None:
            raise InvalidArgumentError("u_max", "None (the problem has no input constraint)", repr(u_max))
        if kind == "ellipsoid":
            if np.size(u_max) != 1 or np.ndim(u_max) > 1:
                expected = "a scalar bound for the ellipsoid constraint"
                raise InvalidArgumentError("u_max", expected, repr(u_max))
            bound = np.array([check_positive(float(np.asarray(u_max, dtype=float).reshape(-1)[0]), "u_max")])
        else:
            if np.ndim(u_max) == 0:
                bound = np.full(self.data.m, check_positive(u_max, "u_max"))
            else:
                bound = as_vector(u_max, "u_max", self.data.m)
                if np.any(bound <= 0.0):
                    raise InvalidArgumentError("u_max", "bounds > 0", repr(bound.tolist()))
        return bound

    def _finish(
        self, raw: RawResult, x: np.ndarray, scale: float, data: KothareData | None = None
    ) -> LMISolution:
        if raw.Q is None or raw.Y is None:
            return LMISolution(
                raw.status, np.nan, None, None, None, raw.solve_time, raw.iterations,
                raw.solver_status, None, self.backend, x, raw.infeasibility,
            )
        s2 = scale**2
        q_mat = 0.5 * (raw.Q + raw.Q.T) * s2
        y_mat = raw.Y * s2
        gamma = raw.gamma * s2
        cert = certify(self.data if data is None else data, x, gamma, q_mat, y_mat, tol=self.certificate_tol)
        try:
            f_mat = np.linalg.solve(q_mat.T, y_mat.T).T
        except np.linalg.LinAlgError:
            f_mat = None
        status = raw.status
        certified = cert.ok and f_mat is not None and bool(np.all(np.isfinite(f_mat)))
        if raw.interior is not None and not (certified and status in (OPTIMAL, INACCURATE)):
            mixed = self._mixed(raw, raw.interior, x, s2, data)
            if mixed is not None:
                return mixed
        if status == OPTIMAL and not certified:
            status = UNCERTIFIED
        return LMISolution(
            status, gamma, q_mat, y_mat, f_mat, raw.solve_time, raw.iterations, raw.solver_status,
            cert, self.backend, x,
            gamma_dual=None if raw.gamma_dual is None else raw.gamma_dual * s2,
        )

    def _mixed(self, raw: RawResult, interior: tuple[float, np.ndarray, np.ndarray], x: np.ndarray,
               s2: float, data: KothareData | None) -> LMISolution | None:
        """An answer that is not certified (or not an answer: a failure word with its last
        iterate) mixed with a strictly feasible point (phase one's): ``(1 - w) answer + w point``
        for the first weight ``w`` of :data:`MIX_WEIGHTS` whose certificate holds (``w = 1``: the
        point itself), status ``"inaccurate"``, its ``gamma`` an upper bound on the optimum;
        ``None`` if none holds.

        Every LMI is affine in ``(gamma, Q, Y)``, so the mix is feasible wherever both are; at the
        optimum of a thin feasible set (``Q`` spanning ten decades or more) the optimum sits on
        the boundary and the recomputed peak-bound margin ``1 - (Y Q^-1 Y')_jj / u_j^2`` falls a
        little below ``-certificate_tol`` (measured: -3e-7 on Kothare's example 2 at 7e3 times
        beyond the bound), while the point has a positive margin."""
        gamma_p, q_p, y_p = interior
        data = self.data if data is None else data
        for w in MIX_WEIGHTS:
            gamma = ((1.0 - w) * raw.gamma + w * gamma_p) * s2
            q_mat = 0.5 * ((1.0 - w) * (raw.Q + raw.Q.T) + w * (q_p + q_p.T)) * s2  # type: ignore[operator]
            y_mat = ((1.0 - w) * raw.Y + w * y_p) * s2  # type: ignore[operator]
            cert = certify(data, x, gamma, q_mat, y_mat, tol=self.certificate_tol)
            try:
                f_mat = np.linalg.solve(q_mat.T, y_mat.T).T
            except np.linalg.LinAlgError:
                continue
            if cert.ok and np.all(np.isfinite(f_mat)):
                how = "phase one's point" if w == 1.0 else f"mixed with phase one's point at w={w:g}"
                return LMISolution(
                    INACCURATE, gamma, q_mat, y_mat, f_mat, raw.solve_time, raw.iterations,
                    f"{raw.solver_status}; {how} (gamma an upper bound)", cert, self.backend, x,
                )
        return None
