"""GIPC: incremental (velocity-form) predictive control, the baseline of paper P.

Paper P compares its robust MPC with a "generalized incremental predictive control" but
gives no equations for it. This module implements the standard velocity-form state-space
MPC of L. Wang, *Model Predictive Control System Design and Implementation Using MATLAB*,
Springer 2009, chapters 1-2 (augmented model with embedded integrator, condensed
prediction, input-increment constraints), generalised to weighted outputs and per-input
bounds. That this is what paper P used is an **assumption** (paper P gives no equations for it);
see ``docs/gipc.rst``.

Model (nominal ``(A, B)`` of the plant, outputs ``y = C_y x``)::

    dx(k+1) = A dx(k) + B du(k),        dx(k) = x(k) - x(k-1),  du(k) = u(k) - u(k-1)
    y(k+1)  = y(k) + C_y A dx(k) + C_y B du(k)

so with ``xa = [dx; y]``: ``xa(k+1) = Aa xa(k) + Ba du(k)``, ``y = Ca xa`` and
``Aa = [[A, 0], [C_y A, I]]``, ``Ba = [B; C_y B]``, ``Ca = [0, I]``.

Prediction over ``Np`` steps with ``Nc`` free increments (``du(k+i) = 0`` for ``i >= Nc``)::

    Y = F xa(k) + Phi dU,   F = [Ca Aa; ...; Ca Aa^Np],   Phi[i, j] = Ca Aa^(i-j) Ba (i >= j)

Cost and QP in ``dU`` (``Qbar = I_Np (x) Q_y``, ``Rbar = I_Nc (x) R_du``, ``Rs`` the stacked
reference)::

    J = (Rs - Y)' Qbar (Rs - Y) + dU' Rbar dU
      = 2 (1/2 dU' H dU + g' dU) + const,  H = Phi' Qbar Phi + Rbar,  g = Phi' Qbar (F xa - Rs)

subject to ``|du(k+i)| <= du_max`` (a box on ``dU``) and
``|u(k-1) + du(k) + ... + du(k+i)| <= u_max`` for ``i < Nc``: rows ``C = L (x) I_m`` with ``L``
the lower-triangular matrix of ones, except that the ``i = 0`` rows, parallel to the box of
``du(k)``, are merged into that box (``max(-du_max, -u_max - u(k-1)) <= du(k) <=
min(du_max, u_max - u(k-1))``). ``H`` and ``C`` are built once; per step only ``g`` (from
``xa``) and ``l, u, lb, ub`` (from ``u(k-1)``) change. The first increment is applied:
``u(k) = u(k-1) + du(k)``.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from models import PolytopicModel
from rmpc.controller import Status, StepInfo, StepInputs, check_step_inputs
from rmpc.io.design import Design, encode, plant_design
from rmpc.io.saveable import Saveable
from rmpc.qp import QP, QPBackend, make_backend
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import (
    as_matrix,
    as_optional_limits,
    as_square_matrix,
    as_vector,
    check_count,
)

__all__ = ["GIPC", "MAX_HORIZON", "MAX_PREDICTION_ENTRIES", "prediction_matrices", "velocity_form"]


def velocity_form(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Augmented velocity-form model ``(Aa, Ba, Ca)`` with state ``[dx; y]`` (Wang 2009, ch. 1).

    Examples
    --------
    >>> import numpy as np
    >>> aa, ba, ca = velocity_form(np.eye(1), np.ones((1, 1)), np.eye(1))
    >>> aa.tolist(), ba.ravel().tolist(), ca.tolist()
    ([[1.0, 0.0], [1.0, 1.0]], [1.0, 1.0], [[0.0, 1.0]])
    """
    n, q = a.shape[0], c.shape[0]
    aa = np.zeros((n + q, n + q))
    aa[:n, :n] = a
    aa[n:, :n] = c @ a
    aa[n:, n:] = np.eye(q)
    ba = np.vstack((b, c @ b))
    ca = np.hstack((np.zeros((q, n)), np.eye(q)))
    return aa, ba, ca


def prediction_matrices(
    aa: np.ndarray, ba: np.ndarray, ca: np.ndarray, n_p: int, n_c: int
) -> tuple[np.ndarray, np.ndarray]:
    """Condensed prediction ``Y = F xa + Phi dU`` over ``n_p`` steps, ``n_c`` increments.

    ``F`` is ``(n_p q, na)`` and ``Phi`` is ``(n_p q, n_c m)`` (Wang 2009, ch. 1).
    """
    q, na = ca.shape
    m = ba.shape[1]
    f = np.empty((n_p * q, na))
    markov = np.empty((n_p, q, m))  # Ca Aa^i Ba, i = 0 .. n_p - 1
    power = np.eye(na)
    for i in range(n_p):
        markov[i] = ca @ power @ ba
        power = aa @ power
        f[i * q:(i + 1) * q] = ca @ power
    phi = np.zeros((n_p * q, n_c * m))
    for j in range(n_c):
        for i in range(j, n_p):
            phi[i * q:(i + 1) * q, j * m:(j + 1) * m] = markov[i - j]
    return f, phi


MAX_HORIZON = 20_000
"""Default bound on ``Np``: the prediction matrices grow as ``Np`` squared in time and ``Np x Nc`` in
memory (paper P uses 400); ``GIPC(..., max_horizon=N)`` lifts it."""


MAX_PREDICTION_ENTRIES = 2**27
"""Default bound on the entries of the prediction matrix, ``(Np q) x (Nc m)`` (``q`` outputs, ``m``
inputs): 2^27 float64 entries are 1 GiB (paper P's 400 x 400 horizons at 3 outputs and 3 inputs:
1.4 million). ``Np = Nc = 20000`` within :data:`MAX_HORIZON` would need 29 GB;
``GIPC(..., max_prediction_entries=N)`` lifts it."""


def _horizon(value: Any, name: str, upper: int | None = None, limit: int | None = None) -> int:
    value = check_count(value, name, limit=limit, limit_name="max_horizon", unit=" samples")
    if upper is not None and value > upper:
        raise InvalidArgumentError(name, f"an integer <= Np = {upper}", repr(value))
    return value


class GIPC(Saveable):
    """Incremental (velocity-form) MPC with input and input-increment bounds (paper P's GIPC).

    Parameters
    ----------
    plant : PolytopicModel
        Prediction uses its nominal ``(A, B)`` (discrete time, ``plant.dt``).
    Np : int
        Prediction horizon in samples (default 400, i.e. 4 s at paper P's ``Ts = 0.01``).
    Nc : int
        Control horizon: free increments, ``1 <= Nc <= Np`` (default 4).
    Qy : float, (q,) or (q, q) array_like
        Weight on the tracking error of the outputs, per prediction step, PSD (default 1).
    R_du : float, (m,) or (m, m) array_like
        Weight on the input increments, per step, positive definite (default 1).
    u_max : float, (m,) array_like or None
        ``|u_i| <= u_max_i`` (paper P: 1 N m); ``None`` for no bound.
    du_max : float, (m,) array_like or None
        ``|du_i| <= du_max_i`` per sample (paper P: 0.01 N m); ``None`` for no bound.
    C : (q, n) array_like, optional
        Outputs ``y = C x``. Default: the attitude (first three states) when ``n = 6``,
        else all states.
    backend : {"proxqp", "osqp", "clarabel", "cvxpy"} or QPBackend
        The QP back-end (default ``"proxqp"``: dense, warm-started, duality gap checked).
    solver_options : mapping, optional
        The back-end's settings, passed to :func:`rmpc.qp.make_backend` (unknown names
        raise; ``None`` with a ``QPBackend`` instance, which carries its own).
    x_ref : (n,) array_like, optional
        Reference state; the output reference is ``C x_ref`` (default the origin).
    u0 : (m,) array_like, optional
        The input assumed applied before the first step (default zero).
    max_horizon : int
        The largest ``Np`` accepted (default :data:`MAX_HORIZON`, 20000); a larger ``Np`` is
        refused with an error naming this limit (``Np = 10**6`` ended in a MemoryError).
    max_prediction_entries : int
        The largest prediction matrix accepted, in entries (default
        :data:`MAX_PREDICTION_ENTRIES`, 2^27, 1 GiB); larger horizons are refused naming ``Nc``
        and this limit.

    Attributes
    ----------
    name : str
        ``"GIPC"``, the short name in reports.
    last : StepInfo or None
        The last step: the back-end's status (or ``"bound_violation"``), ``solve_time``,
        ``iterations``, ``fallback`` and ``extra`` (``du``, ``objective``, ``backend``,
        ``raw_status``, ``step_time``).

    Notes
    -----
    *Memory.* ``dx(k)`` needs the previous measured state and ``u(k)`` the previous input.
    After :meth:`reset` the first step assumes the plant was at rest (``dx = 0``) with
    ``u(k-1) = u0``; paper P's satellite starts at rest, so this is exact there.

    *Defaults for paper P's satellite* (``Ts = 0.01`` s, ``|u| <= 1``, ``|du| <= 0.01``):
    the increment bound caps the torque slew rate at 1 N m/s, so the attitude moves on a
    time scale of seconds. ``Np = 400`` (4 s) lets the prediction see a torque change act on
    the attitude (with ``Np = 100``, 1 s, the closed loop was unstable; ``Np = 200`` settled
    as fast with torques up to 0.86 N m); ``Nc = 4`` keeps the QP small (12 variables,
    9 rows and a box) so a warm-started ProxQP solve takes tens of microseconds; ``Qy = 1``
    (rad^-2) and ``R_du = 1`` ((N m)^-2 per sample). Measured on the nonlinear satellite
    from paper P's initial attitude: both bounds hold, all angles are below 1e-3 rad after
    10.4 s and the largest torque is 0.35 N m; with experiment E4's 0.5 N m step disturbance
    from t = 10 s the error peaks at 6.4 deg and is back below 1e-3 rad at t = 20.2 s
    (integral action); with the inertia 0.3 or 1.7 times the model's, at t = 26 s and
    18.7 s. These values are the toolkit's choice (paper P gives none) and are parameters.

    *Failures.* If the QP back-end returns anything but ``"optimal"`` (or an answer that
    breaks the bounds by more than 1e-5 relative), the step holds the previous input
    (``du = 0``, which satisfies both bounds), ``last.fallback`` is ``True`` and
    ``last.status`` is the back-end's status (``"bound_violation"`` for the latter case).
    Every back-end bounds a solve by ``max_iter`` and by ``time_limit`` seconds
    (:data:`rmpc.qp.base.DEFAULT_TIME_LIMIT`, 5 s, by default; ``solver_options``), so a
    step ends with ``"max_iterations"`` or ``"time_limit"`` rather than running on: at a
    state of 1e8 one ProxQP step ran 54-76 s before that bound and ends ``"time_limit"``
    after 7-8 s with it (ProxQP reads the clock only between chunks of outer iterations:
    see :mod:`rmpc.qp.proxqp_backend`).

    Examples
    --------
    >>> import numpy as np
    >>> from models import RigidSatellite
    >>> from rmpc import GIPC
    >>> sat = RigidSatellite.paper_p()
    >>> x0 = sat.initial_state()
    >>> ctrl = GIPC(sat.linear_model(x0, 0.01))
    >>> u = ctrl.step(x0)
    >>> bool(np.all(np.abs(u) <= 0.01 + 1e-9)), ctrl.last.status
    (True, 'optimal')
    """

    name = "GIPC"
    accepts: ClassVar[frozenset[str]] = frozenset()

    def __init__(
        self,
        plant: PolytopicModel,
        Np: int = 400,
        Nc: int = 4,
        Qy: ArrayLike = 1.0,
        R_du: ArrayLike = 1.0,
        u_max: ArrayLike | None = 1.0,
        du_max: ArrayLike | None = 0.01,
        C: ArrayLike | None = None,
        backend: str | QPBackend = "proxqp",
        solver_options: Mapping[str, Any] | None = None,
        x_ref: ArrayLike | None = None,
        u0: ArrayLike | None = None,
        max_horizon: int = MAX_HORIZON,
        max_prediction_entries: int = MAX_PREDICTION_ENTRIES,
    ) -> None:
        if not isinstance(plant, PolytopicModel):
            raise ArgumentTypeError("plant", "a models.PolytopicModel", type(plant).__name__)
        n, m = plant.n_states, plant.n_inputs
        limit = _horizon(max_horizon, "max_horizon")
        self.Np = _horizon(Np, "Np", limit=limit)
        self.Nc = _horizon(Nc, "Nc", self.Np)
        entries_limit = _horizon(max_prediction_entries, "max_prediction_entries")
        if C is None:
            c = np.eye(n)[:3] if n == 6 else np.eye(n)
        else:
            c = as_matrix(C, "C", (None, n))
        q = c.shape[0]
        entries = self.Np * q * self.Nc * m
        if entries > entries_limit:
            raise InvalidArgumentError(
                "Nc", f"horizons whose prediction matrix ({self.Np * q} x {self.Nc * m}) has at most "
                f"max_prediction_entries = {entries_limit} entries (pass a larger "
                "max_prediction_entries to lift it)", f"Np = {self.Np}, Nc = {self.Nc}: {entries} entries",
            )
        self.C = c
        self.Qy = as_square_matrix(Qy, "Qy", q, allow_zero=True, definite="psd")
        self.R_du = as_square_matrix(R_du, "R_du", m)
        self.u_max = as_optional_limits(u_max, "u_max", m, per="input")
        self.du_max = as_optional_limits(du_max, "du_max", m, per="input")
        self.x_ref = np.zeros(n) if x_ref is None else as_vector(x_ref, "x_ref", n)
        self.u0 = np.zeros(m) if u0 is None else as_vector(u0, "u0", m)
        if self.u_max is not None and np.any(np.abs(self.u0) > self.u_max):
            raise InvalidArgumentError("u0", f"|u0| <= u_max = {self.u_max.tolist()}", f"{self.u0.tolist()}")
        if solver_options is not None and not isinstance(solver_options, Mapping):
            raise ArgumentTypeError(
                "solver_options", "a mapping of setting names", type(solver_options).__name__
            )
        if isinstance(backend, QPBackend):
            if solver_options:
                raise InvalidArgumentError(
                    "solver_options", "None when backend is a QPBackend instance",
                    repr(dict(solver_options)),
                )
            self.backend = backend
        elif isinstance(backend, str):
            self.backend = make_backend(backend, argument="backend", **dict(solver_options or {}))
        else:
            raise ArgumentTypeError(
                "backend", "a back-end name or a rmpc.qp.QPBackend", type(backend).__name__
            )
        self.dt = plant.dt
        self.plant = plant
        self._limits = (limit, entries_limit)
        self._n, self._m, self._q = n, m, q
        self.A, self.B = plant.nominal

        # Condensed prediction and QP matrices, built once.
        aa, ba, ca = velocity_form(self.A, self.B, c)
        f, phi = prediction_matrices(aa, ba, ca, self.Np, self.Nc)
        qbar_phi = np.kron(np.eye(self.Np), self.Qy) @ phi  # Qbar Phi
        h = phi.T @ qbar_phi + np.kron(np.eye(self.Nc), self.R_du)
        self.F, self.Phi = f, phi
        self.H = 0.5 * (h + h.T)
        self._g_x = qbar_phi.T @ f                        # g = G_x xa + g_ref
        rs = np.tile(c @ self.x_ref, self.Np)
        self._g_ref = -qbar_phi.T @ rs
        nz = self.Nc * m
        # |u(k+i)| <= u_max for i = 1 .. Nc-1 as rows of cumulative sums; the i = 0 row would
        # be parallel to the box of du(k), so it is merged into that box instead (parallel
        # rows made ProxQP report feasible QPs infeasible).
        n_rows = (self.Nc - 1) * m if self.u_max is not None else 0
        self._cmat = np.kron(np.tril(np.ones((self.Nc, self.Nc))), np.eye(m))[m:m + n_rows]
        self._umax_rep = np.tile(self.u_max, self.Nc - 1) if n_rows else np.zeros(0)
        self._repeat = np.tile(np.eye(m), (self.Nc - 1, 1)) if n_rows else np.zeros((0, m))  # u -> [u; ..; u]
        dmax = np.full(nz, np.inf) if self.du_max is None else np.tile(self.du_max, self.Nc)
        self._lb, self._ub = -dmax, dmax
        # accepted excess of the solver's du(k) over its bounds (then clipped): 1e-5 of the bound
        # (1e-7 N m on paper P's 0.01 N m), round-off and solver tolerance
        bound = self.du_max if self.du_max is not None else self.u_max
        self._slack = np.zeros(m) if bound is None else 1e-5 * bound + 1e-12
        self._setup_done = False
        self.reset()

    # -- the QP -------------------------------------------------------------------------
    def augmented_state(self, x: np.ndarray, x_prev: np.ndarray | None = None) -> np.ndarray:
        """``xa = [x - x_prev; C x]`` (``dx = 0`` when ``x_prev`` is ``None``)."""
        dx = np.zeros(self._n) if x_prev is None else x - x_prev
        return np.concatenate((dx, self.C @ x))

    def _vectors(self, xa: np.ndarray, u_prev: np.ndarray) -> dict[str, np.ndarray]:
        g = self._g_x @ xa + self._g_ref
        if self.u_max is None:
            return {"g": g, "lb": self._lb, "ub": self._ub}
        m = self._m
        lb, ub = self._lb.copy(), self._ub.copy()
        lb[:m] = np.maximum(lb[:m], -self.u_max - u_prev)
        ub[:m] = np.minimum(ub[:m], self.u_max - u_prev)
        shift = self._repeat @ u_prev
        return {"g": g, "l": -self._umax_rep - shift, "u": self._umax_rep - shift, "lb": lb, "ub": ub}

    def qp_at(self, x: ArrayLike, x_prev: ArrayLike | None = None, u_prev: ArrayLike | None = None) -> QP:
        """The (validated) QP the controller solves at state ``x`` with the given memory.

        ``x_prev`` defaults to ``x`` (at rest) and ``u_prev`` to ``u0``. For tests and
        reports; :meth:`step` updates the back-end's vectors without building a ``QP``.
        """
        x = as_vector(x, "x", self._n)
        xp = None if x_prev is None else as_vector(x_prev, "x_prev", self._n)
        up = self.u0 if u_prev is None else as_vector(u_prev, "u_prev", self._m)
        vec = self._vectors(self.augmented_state(x, xp), up)
        return QP(H=self.H, C=self._cmat, **vec)

    # -- the step(x) protocol -------------------------------------------------------------
    def reset(self) -> None:
        """Forget the previous state and input (next step: at rest, ``u(k-1) = u0``)."""
        self._x_prev: np.ndarray | None = None
        self._u_prev = self.u0.copy()
        self.last: StepInfo | None = None

    @property
    def u_prev(self) -> np.ndarray:
        """The input applied at the previous step (``u0`` after :meth:`reset`)."""
        return self._u_prev.copy()

    def step(self, x: ArrayLike, inputs: StepInputs | None = None) -> np.ndarray:
        """Return ``u(k) = u(k-1) + du(k)`` for the measured state ``x``."""
        start = time.perf_counter()
        check_step_inputs(inputs, self.accepts, self.name)
        x = as_vector(x, "x", self._n)
        vec = self._vectors(self.augmented_state(x, self._x_prev), self._u_prev)
        if not self._setup_done:
            self.backend.setup(QP(H=self.H, C=self._cmat, **vec))
            self._setup_done = True
        else:
            self.backend.update(**vec)
        res = self.backend.solve()
        status, fallback = res.status, False
        du = np.zeros(self._m)
        if res.status == Status.OPTIMAL:
            # du(k)'s box already holds both bounds: |du| <= du_max and |u(k-1) + du| <= u_max
            lo, hi = vec["lb"][: self._m], vec["ub"][: self._m]
            cand = res.x[: self._m]
            if ((cand >= lo - self._slack) & (cand <= hi + self._slack)).all():
                du = np.minimum(np.maximum(cand, lo), hi)
            else:
                status, fallback = Status.BOUND_VIOLATION, True
        else:
            fallback = True
        u = self._u_prev + du
        self._x_prev = x
        self._u_prev = u
        self.last = StepInfo(
            status=status, solve_time=res.solve_time, iterations=res.iterations, fallback=fallback,
            extra={"du": du, "objective": res.objective, "backend": self.backend.name,
                   "raw_status": res.raw_status, "step_time": time.perf_counter() - start},
        )
        return u.copy()

    # -- save and load ---------------------------------------------------------------------
    def _design(self) -> dict[str, Any]:
        """The plant, the horizons, weights, bounds, outputs, reference, ``u0`` and the QP back-end
        by name with its settings (a back-end class of :data:`rmpc.qp.BACKENDS` only)."""
        from rmpc.qp.factory import backend_design

        saved_backend = backend_design(self.backend)
        return {"plant": plant_design(self.plant), **encode({
            "Np": self.Np, "Nc": self.Nc, "Qy": self.Qy, "R_du": self.R_du, "u_max": self.u_max,
            "du_max": self.du_max, "C": self.C, **saved_backend, "x_ref": self.x_ref, "u0": self.u0,
            "max_horizon": self._limits[0], "max_prediction_entries": self._limits[1],
        }, "GIPC design")}

    @classmethod
    def _from_design(cls, design: Design) -> GIPC:
        return cls(
            design.plant(), Np=design.integer("Np"), Nc=design.integer("Nc"),
            Qy=design.array("Qy", 2), R_du=design.array("R_du", 2),
            u_max=design.optional_array("u_max", 1), du_max=design.optional_array("du_max", 1),
            C=design.array("C", 2), backend=design.text("backend"),
            solver_options=design.mapping("solver_options"), x_ref=design.array("x_ref", 1),
            u0=design.array("u0", 1), max_horizon=design.integer("max_horizon"),
            max_prediction_entries=design.integer("max_prediction_entries"),
        )

    def settings(self) -> dict[str, Any]:
        """Every parameter of the controller, for reports."""
        return {
            "Np": self.Np, "Nc": self.Nc, "Qy": self.Qy.tolist(), "R_du": self.R_du.tolist(),
            "u_max": None if self.u_max is None else self.u_max.tolist(),
            "du_max": None if self.du_max is None else self.du_max.tolist(),
            "C": self.C.tolist(), "x_ref": self.x_ref.tolist(), "u0": self.u0.tolist(),
            "backend": self.backend.name, "backend_settings": repr(self.backend.settings), "dt": self.dt,
        }

    def __repr__(self) -> str:
        return f"GIPC(Np={self.Np}, Nc={self.Nc}, backend={self.backend.name!r}, dt={self.dt:g})"
