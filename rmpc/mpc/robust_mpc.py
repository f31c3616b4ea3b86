"""Online robust MPC with LMIs (Kothare, Balakrishnan & Morari 1996), as used in paper P.

At every sample the controller solves :class:`lmi.KothareProblem` at the measured state and
applies ``u = F x`` with ``F = Y Q^-1`` (sign convention ``u = +F x``).
"""

from __future__ import annotations

from typing import Any, ClassVar, Literal

import numpy as np
from numpy.typing import ArrayLike

from lmi import KothareProblem, LMISolution
from lmi.forms import FormProblem, form_options
from models import PolytopicModel
from rmpc.controller import StepInfo, StepInputs, check_step_inputs
from rmpc.io.design import Design, encode, plant_design, snapshot
from rmpc.io.saveable import Saveable
from rmpc.mpc.diagnosis import FailureDiagnosis, diagnose
from rmpc.mpc.fallback import CertifiedGain
from rmpc.mpc.methods import method_options
from rmpc.mpc.setpoint import SteadyTarget, steady_target
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import as_vector, check_positive

__all__ = ["RMPC", "input_constraint_kind", "read_target", "rmpc_arguments", "target_design"]


def input_constraint_kind(input_constraint: str | None, u_max: ArrayLike) -> str | None:
    """The input constraint ``"auto"`` stands for: ``"ellipsoid"`` with a bound ``u_max``, else none.

    Any other value is returned as it is (the LMI problem checks it).
    """
    if input_constraint == "auto":
        return None if u_max is None else "ellipsoid"
    return input_constraint


def _output_rows(output_matrix: ArrayLike | None) -> int | None:
    """The bounded outputs (rows of ``output_matrix``) where its shape says so, else ``None`` (its
    own check then names it)."""
    if output_matrix is None:
        return None
    shape = np.shape(output_matrix)
    return int(shape[0]) if len(shape) == 2 else None


def rmpc_arguments(design: Design, partial: bool = False) -> dict[str, Any]:
    """The keyword arguments of :class:`RMPC` (all but the plant) read from a saved design.

    ``partial``: only those present (CRMPC's ``rmpc_options``); otherwise every one, each required.
    """
    readers: dict[str, Any] = {
        "Q": lambda d, k: d.array(k, 2), "R": lambda d, k: d.array(k, 2), "u_max": Design.bound,
        "input_constraint": lambda d, k: d.optional_text(k),
        "output_matrix": lambda d, k: d.optional_array(k, 2), "y_max": Design.bound,
        "x_ref": lambda d, k: d.optional_array(k, 1), "backend": Design.text,
        "solver": lambda d, k: d.optional_text(k),
        "solver_options": lambda d, k: d.optional_mapping(k), "formulation": Design.text,
        "certificate_tol": Design.number, "on_failure": Design.text, "hold_radius": Design.number,
        "resolve_threshold": Design.number, "lyapunov": Design.text, "cost": Design.text,
        "free_moves": Design.integer, "saturation": lambda d, k: d.optional_text(k),
        "soft": lambda d, k: d.optional_mapping(k), "disturbance": _disturbance,
        "offset_free": Design.flag,
        # absent from designs saved before Huang et al.'s form: None, the form they had
        "unsaturated_weight": lambda d, k: d.optional_number(k) if d.has(k) else None,
    }
    out = {name: read(design, name) for name, read in readers.items() if not partial or design.has(name)}
    # the forms with steps: written only when set (a design saved before them has neither)
    steps: dict[str, Any] = {"horizon": Design.integer, "step_gains": Design.text}
    out.update({name: read(design, name) for name, read in steps.items() if design.has(name)})
    return out


def target_design(target: SteadyTarget | None) -> dict[str, Any] | None:
    """The set-point of :meth:`RMPC.set_reference` as JSON values (``None``: none set)."""
    if target is None:
        return None
    return encode({"x": target.x, "u": target.u, "outputs": target.outputs, "reference": target.reference})


def read_target(design: Design, name: str, plant: PolytopicModel) -> SteadyTarget | None:
    """The set-point :func:`target_design` wrote, its sizes checked against ``plant``."""
    part = design.optional_part(name)
    if part is None:
        return None
    target = SteadyTarget(part.array("x", 1), part.array("u", 1),
                          part.array("outputs", 2), part.array("reference", 1))
    part.finish()
    n, m = plant.n_states, plant.n_inputs
    if target.x.shape != (n,) or target.u.shape != (m,):
        raise InvalidArgumentError(f"design.{name}", f"x of {n} and u of {m} values",
                                   f"{target.x.shape} and {target.u.shape}")
    return target


def _disturbance(design: Design, name: str) -> tuple[Any, ...] | None:
    """``(E, w_max, lam)`` of the disturbance form, or ``None``."""
    part = design.value(name)
    if part is None:
        return None
    if not isinstance(part, list) or len(part) != 3:
        raise InvalidArgumentError(f"design.{name}", "[E, w_max, lam]", repr(part)[:80])
    values = Design({"E": part[0], "w_max": part[1], "lam": part[2]}, f"design.{name}")
    return (values.array("E", 2), values.number("w_max"), values.optional_number("lam"))


class RMPC(Saveable):
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
        Passed to :class:`lmi.KothareProblem` (with the default form) or
        :class:`lmi.forms.FormProblem` (any other form: ``backend`` ``"ipm"``, ``"clarabel"`` or
        ``"cvxpy"``, ``formulation`` and ``solver`` unused).
    lyapunov : {"common", "vertex", "vertex_pairs", "saturation_dependent"}
        One quadratic Lyapunov function (Kothare), one ``Q_j`` per vertex with a slack ``G``
        (uncertainty constant in time), or every vertex pair (uncertainty that may change at
        every sample); ``"saturation_dependent"``: one ``Q_k`` per sign pattern of the auxiliary
        saturation (Zhang, Wang & Li 2013; only with ``saturation="auxiliary"``).
    cost : {"worst_case", "nominal"}
        The cost bound over every vertex, or on ``plant.nominal`` with robust invariance on
        every vertex (with the vertex Lyapunov forms: Ding et al.'s form; with
        ``"saturation_dependent"``: Zhang et al.'s nominal form).
    free_moves : {0, 1}
        With 1 the first move ``u(k)`` is a free variable (applied by :meth:`step`) and the
        feedback law acts from ``k + 1`` on.
    saturation : {None, "auxiliary"}
        ``"auxiliary"``: the law ``sat(F x)`` (componentwise, ``input_constraint="peak"``) with an
        auxiliary gain ``H`` that carries the bound; :meth:`step` applies the saturated input.
    soft : dict, optional
        ``{"u": w_u, "y": w_y}``: soft input and output bounds, their squared excess paid at
        these weights; per component ``{"u": [w_1, ..., w_m], "y": [...]}`` (one slack per
        component whose weight is ``> 0``, ``0`` keeps it hard), with ``"u_limit"``/``"y_limit"``
        soft limits separate from the hard bounds (MUP's ``*_soft_con`` methods).
    disturbance : (E, w_max) or (E, w_max, lam), optional
        ``x+ = A x + B u + E w`` with ``||w|| <= w_max``; the ellipsoid is kept invariant under
        it (``lam``, the S-procedure's contraction factor, searched when not given).
        The LMIs of every form and the combinations that exist: the page "The field's robust MPC
        forms" of the docs (:mod:`lmi.forms`). The defaults give Kothare's problem.
    horizon : int
        The prediction steps with gains of their own before the terminal invariant ellipsoid,
        from 1 (default: the forms above) to :data:`lmi.forms.MAX_HORIZON` (Shi, Su & Chu 2013:
        ``horizon=N``, chained Lyapunov matrices). The law applied is the first step's; with
        ``horizon > 1`` its ellipsoid contains the state but is not invariant under the first
        gain alone, so ``resolve_threshold`` must be 1.
    step_gains : {"common", "vertex"}
        ``"vertex"``: the second step's gain depends on the first step's vertex (Li, Shi, Sun &
        Wang 2008: with ``horizon=2`` and ``lyapunov="common"`` only).
    unsaturated_weight : float, optional
        ``beta >= 0`` of Huang, Li, Lin & Xi (2011): the cost LMIs of the unsaturated sign pattern
        are bounded by ``gamma_s <= gamma`` and the objective is ``gamma + beta gamma_s`` (only with
        ``saturation="auxiliary"``; ``None``, the default, is Cao & Lin's form, and so is 0).
    offset_free : bool
        Offset-free action on a constant input disturbance: every :meth:`step` takes the
        disturbance estimate ``StepInputs(d_hat=...)`` (from an estimator with
        ``disturbance_model="input"``; :func:`rmpc.simulate` passes it) and applies
        ``u = u_s - d_hat + F (x - x_s)``, so an unmeasured constant load leaves no offset
        once the estimate has converged (see :meth:`set_reference`).
    on_failure : {"fallback", "raise"}
        What to do when a solve gives no usable (certified) answer: keep the last certified
        gain and record the fallback, or raise :class:`~toolkit_common.errors.SolverError`
        (:class:`~rmpc.mpc.fallback.CertifiedGain`). Before any certified gain the fallback is
        ``u = 0``, which no certificate stands behind: the first such step warns
        (:class:`~rmpc.errors.NoCertifiedGainWarning`) with the status and the
        :meth:`diagnose` of the state (which bound blocks, what to try); a raised failure
        carries the same diagnosis.
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
        ``"RMPC"``.
    accepts : frozenset of str
        ``{"u_max"}``: :meth:`step` takes a bound for one step through
        :class:`~rmpc.controller.StepInputs`.
    last : StepInfo or None
        The last step: ``status``, ``solve_time``, ``gamma``, ``iterations``, ``fallback``, and
        ``extra["solution"]`` (the :class:`lmi.LMISolution`, ``None`` if no solve was made).
    certified : CertifiedGain
        The last certified gain, its ellipsoid and bound (:mod:`rmpc.mpc.fallback`).

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

    name: ClassVar[str] = "RMPC"
    accepts: ClassVar[frozenset[str]] = frozenset({"u_max"})

    def __init__(
        self,
        plant: PolytopicModel,
        Q: ArrayLike,
        R: ArrayLike,
        u_max: ArrayLike | None = None,
        input_constraint: Literal["ellipsoid", "peak"] | str | None = "auto",
        *,
        output_matrix: ArrayLike | None = None,
        y_max: ArrayLike | None = None,
        x_ref: ArrayLike | None = None,
        backend: str = "ipm",
        solver: str | None = None,
        solver_options: dict[str, Any] | None = None,
        formulation: Literal["delta", "delta_shared", "standard"] = "delta_shared",
        certificate_tol: float = 1e-7,
        on_failure: Literal["fallback", "raise"] = "fallback",
        hold_radius: float = 1e-9,
        resolve_threshold: float = 1.0,
        lyapunov: Literal["common", "vertex", "vertex_pairs", "saturation_dependent"] = "common",
        cost: Literal["worst_case", "nominal"] = "worst_case",
        free_moves: int = 0,
        saturation: Literal["auxiliary"] | None = None,
        soft: dict[str, float] | None = None,
        disturbance: Any = None,
        offset_free: bool = False,
        horizon: int = 1,
        step_gains: Literal["common", "vertex"] = "common",
        unsaturated_weight: float | None = None,
    ) -> None:
        if not isinstance(plant, PolytopicModel):
            hint = ""
            if type(plant).__name__ in ("StateSpace", "TransferFunction"):
                hint = (" (a python-control system: build the polytope with models.PolytopicModel."
                        "from_statespace([sys_1, ..., sys_k]) from discrete-time vertices)")
            raise ArgumentTypeError("plant", "a models.PolytopicModel" + hint, type(plant).__name__)
        input_constraint = input_constraint_kind(input_constraint, u_max)
        self.plant = plant
        self.form = form_options(
            n_states=plant.n_states, input_constraint=input_constraint, has_output=output_matrix is not None,
            lyapunov=lyapunov, cost=cost, free_moves=free_moves, saturation=saturation, soft=soft,
            disturbance=disturbance, horizon=horizon, step_gains=step_gains,
            unsaturated_weight=unsaturated_weight, n_inputs=plant.n_inputs,
            n_outputs=_output_rows(output_matrix),
        )
        self.problem: KothareProblem | FormProblem
        if self.form.is_kothare:
            self.problem = KothareProblem(
                plant.A, plant.B, Q, R, dt=plant.dt, input_constraint=input_constraint, u_max=u_max,
                output_matrix=output_matrix, y_max=y_max, backend=backend, solver=solver,
                solver_options=solver_options, formulation=formulation, certificate_tol=certificate_tol,
            )
        else:
            if solver not in (None, "CLARABEL", "clarabel"):
                raise InvalidArgumentError(
                    "solver", "None (the forms solve with the ipm, Clarabel or cvxpy: see backend)",
                    repr(solver),
                )
            self.problem = FormProblem(
                plant.A, plant.B, Q, R, dt=plant.dt, input_constraint=input_constraint, u_max=u_max,
                output_matrix=output_matrix, y_max=y_max, nominal=plant.nominal, lyapunov=lyapunov,
                cost=cost, free_moves=free_moves, saturation=saturation, soft=soft, disturbance=disturbance,
                backend=backend, solver_options=solver_options, certificate_tol=certificate_tol,
                horizon=horizon, step_gains=step_gains,
                unsaturated_weight=unsaturated_weight,
            )
        self.certified = CertifiedGain("RMPC", on_failure, hold_radius)
        self.resolve_threshold = check_positive(resolve_threshold, "resolve_threshold")
        if self.resolve_threshold > 1.0:
            raise InvalidArgumentError("resolve_threshold", "a level in (0, 1]", repr(resolve_threshold))
        if self.resolve_threshold < 1.0 and self.form.has_steps:
            raise InvalidArgumentError(
                "resolve_threshold, horizon", "resolve_threshold=1 with horizon > 1 (the first step's "
                "ellipsoid is not invariant under its gain alone)",
                f"resolve_threshold={resolve_threshold!r}, horizon={self.form.horizon!r}")
        n = plant.n_states
        self.x_ref = np.zeros(n) if x_ref is None else as_vector(x_ref, "x_ref", n)
        drift = max(float(np.max(np.abs(a @ self.x_ref - self.x_ref))) for a in plant.A)
        if drift > 1e-9 * max(1.0, float(np.max(np.abs(self.x_ref)))):
            raise InvalidArgumentError(
                "x_ref", "an equilibrium of every vertex with zero input (A_j x_ref = x_ref)",
                f"max |A_j x_ref - x_ref| = {drift:.3g}",
            )
        self.u_ref = np.zeros(plant.n_inputs)
        self.target: SteadyTarget | None = None
        if not isinstance(offset_free, bool | np.bool_):
            raise ArgumentTypeError("offset_free", "a bool", type(offset_free).__name__)
        self.offset_free = bool(offset_free)
        if self.offset_free:
            self.accepts = frozenset({"u_max", "d_hat"})
        self.dt = plant.dt
        self.last: StepInfo | None = None
        disturbance = self.form.disturbance
        # the design as constructed (what save writes; copies, so later changes by the caller do not leak in)
        self._arguments: dict[str, Any] = snapshot({
            "Q": Q, "R": R, "u_max": u_max, "input_constraint": input_constraint,
            "output_matrix": output_matrix, "y_max": y_max, "x_ref": x_ref, "backend": backend,
            "solver": solver, "solver_options": solver_options, "formulation": formulation,
            "certificate_tol": certificate_tol, "on_failure": on_failure, "hold_radius": hold_radius,
            "resolve_threshold": resolve_threshold, "lyapunov": lyapunov, "cost": cost,
            "free_moves": free_moves, "saturation": saturation, "soft": soft,
            "disturbance": (None if disturbance is None
                            else (disturbance.E, disturbance.w_max, disturbance.lam)),
            "offset_free": self.offset_free,
            # the forms with steps, only when set (the designs of the other forms stay as they were)
            **({"horizon": self.form.horizon, "step_gains": self.form.step_gains}
               if self.form.has_steps else {}),
            "unsaturated_weight": unsaturated_weight,
        })

    # -- save and load ---------------------------------------------------------------------
    def _design(self) -> dict[str, Any]:
        """The plant, the constructor's arguments and the set-point (:meth:`set_reference`)."""
        return {
            "plant": plant_design(self.plant),
            "arguments": encode(self._arguments, "RMPC arguments"),
            "reference": target_design(self.target),
        }

    @classmethod
    def _from_design(cls, design: Design) -> RMPC:
        arguments = design.part("arguments")
        ctrl = cls(design.plant(), **rmpc_arguments(arguments))
        arguments.finish()
        ctrl._restore_target(read_target(design, "reference", ctrl.plant))
        return ctrl

    def _restore_target(self, target: SteadyTarget | None) -> None:
        """Hold a saved set-point as :meth:`set_reference` did (nothing solved again)."""
        if target is not None:
            self.target = target
            self.x_ref, self.u_ref = target.x.copy(), target.u.copy()

    def set_reference(self, reference: ArrayLike, outputs: ArrayLike) -> SteadyTarget:
        """Hold the outputs ``C_r x`` (``outputs``) at ``reference`` from the next step on.

        The target ``(x_s, u_s)`` is a steady state of every vertex with ``C_r x_s = r``
        (:func:`rmpc.mpc.setpoint.steady_target`; refused with the reason when there is none);
        the controller then regulates ``x - x_s`` with ``u = u_s + F (x - x_s)``, the input bound
        tightened by ``u_s`` (``|v_i| <= u_max_i - |u_s,i|``, or ``||v|| <= u_max - ||u_s||``) so
        the total input keeps it. With ``offset_free=True`` the step's disturbance estimate
        ``d_hat`` moves the target input to ``u_s - d_hat``.
        """
        target = steady_target(self.plant.A, self.plant.B, reference, outputs)
        self.target = target
        self.x_ref, self.u_ref = target.x.copy(), target.u.copy()
        return target

    @classmethod
    def from_method(cls, key: str, plant: PolytopicModel, **options: Any) -> RMPC:
        """The robust MPC of the literature's method ``key`` (MUP's method keys).

        ``key`` is one of MUP's method keys, :data:`rmpc.mpc.methods.METHODS` (the table there says
        which options each key sets; the ``*_soft_con`` keys need ``soft`` with MUP's soft limits);
        ``options`` are the other arguments of :class:`RMPC` (``Q``, ``R``, ``u_max``, ...). As in
        MUP the input bound is per component (``input_constraint="peak"``) unless
        ``input_constraint`` is given.

        Examples
        --------
        >>> import numpy as np
        >>> from models import PolytopicModel
        >>> from rmpc import RMPC
        >>> plant = PolytopicModel([(np.array([[1.1]]), np.array([[1.0]])),
        ...                         (np.array([[1.1]]), np.array([[0.5]]))], dt=1.0)
        >>> ctrl = RMPC.from_method("cuzzola", plant, Q=np.eye(1), R=np.eye(1), u_max=1.0)
        >>> ctrl.form.lyapunov, ctrl.input_constraint
        ('vertex', 'peak')
        """
        return cls(plant, **method_options(key, options))

    @property
    def input_constraint(self) -> str | None:
        """The kind of input bound, ``"ellipsoid"``, ``"peak"`` or ``None``."""
        return self.problem.data.input_constraint

    @property
    def on_failure(self) -> str:
        """``"fallback"`` or ``"raise"``."""
        return self.certified.on_failure

    @property
    def hold_radius(self) -> float:
        """Below this norm of ``x - x_ref`` the last gain is kept without a solve."""
        return self.certified.hold_radius

    @property
    def gain(self) -> np.ndarray | None:
        """The gain currently applied (the last certified ``F``), or ``None``."""
        return self.certified.gain

    def reset(self) -> None:
        """Forget the last gain and step, and the solver's warm start (:meth:`lmi.KothareProblem.reset`):
        a run after a reset repeats a run of a new controller."""
        self.last = None
        self.certified.reset()
        self.problem.reset()

    def solve(self, x: ArrayLike, u_max: ArrayLike | None = None) -> LMISolution:
        """Solve the LMI problem at ``x`` (the deviation ``x - x_ref`` is used); no side effects.

        ``u_max`` replaces the input bound for this solve (see :meth:`lmi.KothareProblem.solve`).
        """
        x = as_vector(x, "x", self.plant.n_states)
        return self.problem.solve(x - self.x_ref, u_max=u_max)

    def diagnose(self, x: ArrayLike, status: str | None = None) -> FailureDiagnosis:
        """Why there is no certified gain at ``x``, and what to try (:mod:`rmpc.mpc.diagnosis`).

        ``status`` is the failed solve's (solved here when not given). A few more solves at
        ``x``: without bounds, with Kothare's plain problem (for another form), with softened
        bounds.
        """
        x = as_vector(x, "x", self.plant.n_states)
        z = x - self.x_ref
        if status is None:
            status = self.problem.solve(z).status
        return diagnose(self.problem.data, z, status, has_addition=not self.form.is_kothare,
                        backend="clarabel" if self.problem.backend == "clarabel" else "ipm")

    def in_ellipsoid(self, x: ArrayLike) -> bool:
        """Whether ``x - x_ref`` lies in the invariant ellipsoid of the current gain."""
        if self.certified.solution is None:
            return False
        return self.certified.contains(as_vector(x, "x", self.plant.n_states) - self.x_ref)

    def step(self, x: ArrayLike, inputs: StepInputs | None = None) -> np.ndarray:
        """Solve at ``x`` and return ``u = F (x - x_ref)``; see the class notes on failures.

        Parameters
        ----------
        x : (n,) array_like
            The measured state.
        inputs : StepInputs, optional
            ``inputs.u_max``: the input bound for this step instead of the constructed one
            (same kind, checked by :meth:`lmi.KothareProblem.input_bound`). With
            ``resolve_threshold < 1`` a kept gain is re-solved when the requested bound is
            tighter than the one it was certified for. :class:`rmpc.CRMPC` passes what its
            disturbance correction leaves of the torque limit. Other fields are errors.
        """
        x = as_vector(x, "x", self.plant.n_states)
        given = check_step_inputs(inputs, self.accepts, "RMPC")
        u_max = given.u_max
        bound = None if u_max is None else self.problem.input_bound(u_max)
        u_s = self._target_input(given.d_hat)
        if np.any(u_s != 0.0) and self.input_constraint is not None:
            bound = self._tightened(self.problem.data.u_max if bound is None else bound, u_s)
        z = x - self.x_ref
        shape = (self.plant.n_inputs, self.plant.n_states)
        kept = self.certified
        if kept.near_origin(z):
            u, self.last = kept.reuse(z, shape, "near origin")
            return u_s + self._saturate(u, bound)
        tighter = (
            bound is not None and kept.bound is not None
            and bool(np.any(bound < kept.bound * (1.0 - 1e-12)))
        )
        q_inv = kept.q_inv if self.resolve_threshold < 1.0 else None
        if q_inv is not None and not tighter:
            level = float(z @ q_inv @ z)
            if self.resolve_threshold < level <= 1.0:
                u, self.last = kept.reuse(z, shape, "inside ellipsoid", level=level)
                return u_s + self._saturate(u, bound)
        sol = self.problem.solve(z, u_max=bound)
        u, self.last = kept.take(
            sol, z, shape, x=x, bound=self.problem.data.u_max if bound is None else bound,
            failure_extra={"inside_ellipsoid": kept.contains(z)},
            diagnose=lambda: self.diagnose(x, sol.status),
        )
        if sol.u0 is not None and not self.last.fallback:
            u = sol.u0.copy()  # the free first move
        return u_s + self._saturate(u, bound)

    def _target_input(self, d_hat: Any) -> np.ndarray:
        """``u_s`` of the target, less the disturbance estimate with ``offset_free=True``."""
        if not self.offset_free:
            return self.u_ref
        if d_hat is None:
            raise InvalidArgumentError(
                "inputs.d_hat", "the input-disturbance estimate (offset_free=True: give the step "
                "StepInputs(d_hat=est.d_hat), as simulate does with an estimator that has a "
                "disturbance model)", "None",
            )
        return self.u_ref - as_vector(d_hat, "inputs.d_hat", self.plant.n_inputs)

    def _tightened(self, bound: np.ndarray | None, u_s: np.ndarray) -> np.ndarray | None:
        """The bound left to ``u - u_s`` so that ``u`` keeps ``bound`` (``None``: no bound)."""
        kind = self.problem.data.input_constraint
        if kind is None or bound is None:
            return bound
        if kind == "peak":
            left = bound - np.abs(u_s)
        else:
            left = bound - float(np.linalg.norm(u_s))
        return np.maximum(left, 1e-12 * np.maximum(bound, 1.0))  # none left: the solve says infeasible

    def _saturate(self, u: np.ndarray, bound: np.ndarray | None) -> np.ndarray:
        """The componentwise saturation of the auxiliary-gain form (other forms: ``u`` as it is)."""
        if self.form.saturation != "auxiliary":
            return u
        limit = self.problem.data.u_max if bound is None else bound
        return np.clip(u, -limit, limit)
