"""Online robust MPC with LMIs (Kothare, Balakrishnan & Morari 1996), as used in paper P.

At every sample the controller solves :class:`lmi.KothareProblem` at the measured state and
applies ``u = F x`` with ``F = Y Q^-1`` (sign convention ``u = +F x``).
"""

from __future__ import annotations

from typing import Any, ClassVar, Literal

import numpy as np

from lmi import KothareProblem, LMISolution
from lmi.status import INACCURATE, OPTIMAL
from models import PolytopicModel
from rmpc.controller import StepInfo
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError, SolverError
from toolkit_common.validation import as_vector, check_choice, check_positive

__all__ = ["RMPC"]

#: Statuses whose gain may be applied: converged (or nearly) *and* certified.
_USABLE = (OPTIMAL, INACCURATE)


class RMPC:
    """Robust MPC over a polytopic model (Kothare et al. 1996), the ``step(x)`` protocol.

    Parameters
    ----------
    plant : PolytopicModel
        The polytope ``Co{[A_j B_j]}`` of discrete-time models.
    Q : (n, n) array_like
        State weight ``Q1`` (positive semidefinite).
    R : (m, m) array_like
        Input weight (positive definite).
    u_max : float or array_like, optional
        Input bound; ``None`` means no input constraint.
    input_constraint : {"ellipsoid", "peak", None}, optional
        ``||u||_2 <= u_max`` or ``|u_j| <= u_max_j``. Defaults to ``"ellipsoid"`` when
        ``u_max`` is given and to ``None`` otherwise.
    output_matrix, y_max : array_like, optional
        Output (state) constraints ``|(C x(k+i))_r| <= y_max_r``.
    x_ref : (n,) array_like, optional
        Reference state; it must be an equilibrium of every vertex with zero input
        (``A_j x_ref = x_ref``). The controller regulates ``x - x_ref`` to zero.
    backend, solver, solver_options, formulation, certificate_tol
        Passed to :class:`lmi.KothareProblem`.
    on_failure : {"fallback", "raise"}
        What to do when a solve gives no usable (certified) answer: keep the last certified
        gain and record the fallback, or raise :class:`~toolkit_common.errors.SolverError`.
    hold_radius : float
        Below this norm of ``x - x_ref`` the problem degenerates (``gamma -> 0``); the last
        certified gain is kept without re-solving (its invariant ellipsoid contains the state).
    resolve_threshold : float
        ``rho`` in ``(0, 1]``. With ``rho = 1`` (default, Kothare's algorithm) the problem is
        solved at every step. With ``rho < 1`` the last certified gain is kept while the state
        stays inside its invariant ellipsoid with ``x' Q^-1 x > rho`` and re-solved once the
        level has dropped to ``rho`` (or the state has left the ellipsoid, e.g. under a
        disturbance). Every constraint and stability guarantee of the kept gain holds inside
        its ellipsoid; the cost is some performance, the gain is far fewer solves.

    Attributes
    ----------
    name : str
        ``"RMPC"``, the short name in reports.
    last : StepInfo or None
        The last step: ``status``, ``solve_time``, ``gamma``, ``iterations``, ``fallback``, and
        ``extra["solution"]`` (the :class:`lmi.LMISolution`, ``None`` if no solve was made).

    Examples
    --------
    >>> import numpy as np
    >>> from models import RigidSatellite
    >>> from rmpc import RMPC
    >>> sat = RigidSatellite.paper_p()
    >>> x0 = sat.initial_state()
    >>> plant = sat.polytope(x0, dt=0.01, spread=0.3, mode="scalar")
    >>> ctrl = RMPC(plant, Q=np.diag([1, 1, 1, 0.1, 0.1, 0.1]), R=np.eye(3), u_max=1.0)
    >>> sol = ctrl.solve(x0)
    >>> sol.status, bool(np.linalg.norm(sol.F @ x0) <= 1.0 + 1e-6)
    ('optimal', True)
    """

    name = "RMPC"
    accepts: ClassVar[frozenset[str]] = frozenset()

    def __init__(
        self,
        plant: PolytopicModel,
        Q: Any,
        R: Any,
        u_max: Any = None,
        input_constraint: Literal["ellipsoid", "peak"] | str | None = "auto",
        *,
        output_matrix: Any = None,
        y_max: Any = None,
        x_ref: Any = None,
        backend: str = "ipm",
        solver: str | None = None,
        solver_options: dict[str, Any] | None = None,
        formulation: Literal["delta", "delta_shared", "standard"] = "delta_shared",
        certificate_tol: float = 1e-7,
        on_failure: Literal["fallback", "raise"] = "fallback",
        hold_radius: float = 1e-9,
        resolve_threshold: float = 1.0,
    ) -> None:
        if not isinstance(plant, PolytopicModel):
            raise ArgumentTypeError("plant", "a models.PolytopicModel", type(plant).__name__)
        if input_constraint == "auto":
            input_constraint = None if u_max is None else "ellipsoid"
        self.plant = plant
        self.problem = KothareProblem(
            plant.A, plant.B, Q, R, dt=plant.dt, input_constraint=input_constraint, u_max=u_max,
            output_matrix=output_matrix, y_max=y_max, backend=backend, solver=solver,
            solver_options=solver_options, formulation=formulation, certificate_tol=certificate_tol,
        )
        self.on_failure = check_choice(on_failure, "on_failure", ("fallback", "raise"))
        self.hold_radius = check_positive(hold_radius, "hold_radius", allow_zero=True)
        self.resolve_threshold = check_positive(resolve_threshold, "resolve_threshold")
        if self.resolve_threshold > 1.0:
            raise InvalidArgumentError("resolve_threshold", "a level in (0, 1]", repr(resolve_threshold))
        n = plant.n_states
        self.x_ref = np.zeros(n) if x_ref is None else as_vector(x_ref, "x_ref", n)
        drift = max(float(np.max(np.abs(a @ self.x_ref - self.x_ref))) for a in plant.A)
        if drift > 1e-9 * max(1.0, float(np.max(np.abs(self.x_ref)))):
            raise InvalidArgumentError(
                "x_ref", "an equilibrium of every vertex with zero input (A_j x_ref = x_ref)",
                f"max |A_j x_ref - x_ref| = {drift:.3g}",
            )
        self.dt = plant.dt
        self.last: StepInfo | None = None
        self._gain: np.ndarray | None = None
        self._q_inv: np.ndarray | None = None
        self._gain_bound: np.ndarray | None = None

    @property
    def input_constraint(self) -> str | None:
        return self.problem.data.input_constraint

    @property
    def gain(self) -> np.ndarray | None:
        """The gain currently applied (the last certified ``F``), or ``None``."""
        return None if self._gain is None else self._gain.copy()

    def _current_gain(self) -> np.ndarray:
        if self._gain is None:
            return np.zeros((self.plant.n_inputs, self.plant.n_states))
        return self._gain

    def reset(self) -> None:
        """Forget the last gain and step."""
        self.last = None
        self._gain = None
        self._q_inv = None
        self._gain_bound = None

    def solve(self, x: Any, u_max: Any = None) -> LMISolution:
        """Solve the LMI problem at ``x`` (the deviation ``x - x_ref`` is used); no side effects.

        ``u_max`` replaces the input bound for this solve (see :meth:`lmi.KothareProblem.solve`).
        """
        x = as_vector(x, "x", self.plant.n_states)
        return self.problem.solve(x - self.x_ref, u_max=u_max)

    def _bound_vector(self, u_max: Any) -> np.ndarray | None:
        """The input bound of a step as a vector (``None``: the constructed bound)."""
        if u_max is None:
            return None
        return self.problem._with_bound(u_max).u_max

    def in_ellipsoid(self, x: Any) -> bool:
        """Whether ``x - x_ref`` lies in the invariant ellipsoid of the current gain."""
        if self._q_inv is None:
            return False
        z = as_vector(x, "x", self.plant.n_states) - self.x_ref
        return bool(z @ self._q_inv @ z <= 1.0 + 1e-9)

    def step(self, x: Any, u_max: Any = None) -> np.ndarray:
        """Solve at ``x`` and return ``u = F (x - x_ref)``; see the class notes on failures.

        Parameters
        ----------
        x : (n,) array_like
            The measured state.
        u_max : float or array_like, optional
            The input bound for this step instead of the constructed one (same kind). With
            ``resolve_threshold < 1`` a kept gain is re-solved when the requested bound is
            tighter than the one it was certified for. :class:`rmpc.CRMPC` passes what its
            disturbance correction leaves of the torque limit.
        """
        x = as_vector(x, "x", self.plant.n_states)
        bound = self._bound_vector(u_max)
        z = x - self.x_ref
        if float(np.linalg.norm(z)) <= self.hold_radius:
            gain = self._current_gain()
            self.last = StepInfo(status="reused", extra={"solution": None, "reason": "near origin"})
            return gain @ z
        tighter = (
            bound is not None and self._gain_bound is not None
            and bool(np.any(bound < self._gain_bound * (1.0 - 1e-12)))
        )
        if self.resolve_threshold < 1.0 and self._q_inv is not None and not tighter:
            level = float(z @ self._q_inv @ z)
            if self.resolve_threshold < level <= 1.0:
                self.last = StepInfo(
                    status="reused", extra={"solution": None, "reason": "inside ellipsoid", "level": level}
                )
                return self._current_gain() @ z
        sol = self.problem.solve(z, u_max=bound)
        usable = sol.status in _USABLE and sol.certificate is not None and sol.certificate.ok
        if usable:
            assert sol.F is not None and sol.Q is not None
            self._gain = sol.F
            self._q_inv = np.linalg.inv(sol.Q)
            self._gain_bound = self.problem.data.u_max if bound is None else bound
            self.last = StepInfo(
                status=sol.status, solve_time=sol.solve_time, gamma=sol.gamma,
                iterations=sol.iterations, extra={"solution": sol},
            )
            return self._gain @ z
        if self.on_failure == "raise":
            raise SolverError(
                f"RMPC.step: the LMI solve at x = {x.tolist()} returned status {sol.status!r} "
                f"(solver: {sol.solver_status!r}) and on_failure='raise'"
            )
        inside = self.in_ellipsoid(x)
        gain = self._current_gain()
        self.last = StepInfo(
            status=sol.status, solve_time=sol.solve_time, gamma=None, iterations=sol.iterations,
            fallback=True,
            extra={"solution": sol, "inside_ellipsoid": inside, "had_gain": self._gain is not None},
        )
        return gain @ z
