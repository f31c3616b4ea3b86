"""A robust observer for the polytope: an LMI design with a certified bound on the estimation error.

The observer is the current-form estimator of :mod:`rmpc.estimators.linear` on the nominal model;
its gain comes from :func:`lmi.observer.design_robust_observer`, which also gives an ellipsoid
``{e : e' P e <= 1}`` the estimation error ``e = x - x_hat`` never leaves once inside, for every
model of the polytope, every measurement noise ``|v_i| <= noise_bound_i`` and every state and
input within the bounds the design assumed (:mod:`lmi.observer` states the LMIs).

Robust MPC on the estimate
--------------------------
The estimate follows the polytope with an additive disturbance: from ``x = x_hat + e``,
``x_hat(k+1) = A x_hat(k) + B u(k) + w(k)`` with ``w(k) = A e(k) - e(k+1)``, and
``||w|| <= max_j ||A_j P^-1/2|| + ||P^-1/2||`` (:meth:`RobustObserver.estimate_disturbance`). An
:class:`rmpc.RMPC` designed with ``disturbance=obs.estimate_disturbance()`` keeps ``x_hat`` in its
invariant ellipsoid ``E_Q``; the true state lies in ``E_Q + {e : e' P e <= 1}``, so an output
bound ``|c_i x| <= y_max_i`` holds for the true state when the controller is given
``y_max_i - sqrt(c_i P^-1 c_i')`` (:meth:`RobustObserver.output_margin`), and the state bound the
observer's design assumed holds when ``sqrt(Q_ii) + sqrt((P^-1)_ii) <= state_bound_i``
(:meth:`RobustObserver.covers`). The input is computed from ``x_hat`` and is bounded exactly.
"""

from __future__ import annotations

from typing import Any, Self

import numpy as np
from numpy.typing import ArrayLike

from lmi.certificate import Certificate
from lmi.observer import ObserverDesign, certify_observer, design_robust_observer
from lmi.status import OPTIMAL
from models import PolytopicModel
from rmpc.estimators.linear import LinearEstimator, _unobservable_modes
from rmpc.io.design import Design, encode
from toolkit_common.errors import InvalidArgumentError, SolverError

__all__ = ["RobustObserver"]


def _vertices(plant: Any, nominal: tuple[np.ndarray, np.ndarray]) -> list[tuple[np.ndarray, np.ndarray]]:
    if isinstance(plant, PolytopicModel):
        return [(np.asarray(a, float), np.asarray(b, float)) for a, b in plant.vertices]
    return [nominal]


class RobustObserver(LinearEstimator):
    """An observer whose estimation error has a certified bound over the whole polytope.

    Parameters
    ----------
    plant : PolytopicModel or (A, B)
        The polytope (the observer runs on its nominal model; the bound covers every vertex).
    C : (p, n) array_like
        The measurement matrix, ``y = C x + v``.
    noise_bound : float or (p,) array_like
        ``|v_i| <= noise_bound_i``, > 0.
    state_bound : float or (n,) array_like, optional
        ``|x_i| <= state_bound_i`` along the run; required when the vertices' ``A_j`` differ
        (the model mismatch grows with the state).
    input_bound : float or (m,) array_like, optional
        ``|u_i| <= input_bound_i``; required when the vertices' ``B_j`` differ.
    x0 : (n,) array_like, optional
        The initial guess (default zero).

    Attributes
    ----------
    P : ndarray
        The error ellipsoid ``{e : e' P e <= 1}``.
    alpha : float
        The contraction: ``e' P e - 1`` shrinks at least by ``1 - alpha`` per sample outside it.
    design : ObserverDesign
        The LMI answer with its certificate.

    Raises
    ------
    InvalidArgumentError
        For bounds that are not positive, a missing bound the polytope needs, a measurement of
        the wrong shape or one that does not see every unstable mode.
    SolverError
        When no gain with a certified bound is found (the message says what the solver said and
        what to try).

    Examples
    --------
    >>> import numpy as np
    >>> from rmpc.estimators import RobustObserver
    >>> A, B = np.array([[1.0, 0.1], [0.0, 1.0]]), np.array([[0.005], [0.1]])
    >>> obs = RobustObserver((A, B), C=[[1.0, 0.0]], noise_bound=1e-3)
    >>> bool(np.all(obs.half_widths < 0.05)), obs.design.certificate.ok
    (True, True)
    """

    kind = "robust"

    def __init__(self, plant: Any, C: ArrayLike, noise_bound: ArrayLike, *,
                 state_bound: ArrayLike | None = None, input_bound: ArrayLike | None = None,
                 disturbance_model: str | None = None, x0: ArrayLike | None = None) -> None:
        if disturbance_model is not None:
            raise InvalidArgumentError(
                "disturbance_model", "None (the robust observer bounds the state's estimation error; "
                "for offset-free estimation use KalmanFilter or Luenberger)", repr(disturbance_model))
        super().__init__(plant, C, None, x0)
        unseen = _unobservable_modes(self.A, self.C, only_unstable=True)
        if unseen:
            raise InvalidArgumentError(
                "C", "a measurement that sees every unstable mode (a detectable pair)",
                f"unseen modes {[complex(round(z.real, 9), round(z.imag, 9)) for z in unseen]}",
            )
        self.vertices = _vertices(plant, (self.A, self.B))
        design = design_robust_observer(self.vertices, (self.A, self.B), self.C, noise_bound,
                                        state_bound, input_bound)
        self._keep_bounds(noise_bound, state_bound, input_bound)
        if not design.ok:
            raise SolverError(
                f"RobustObserver: no gain with a certified error bound ({design.status}: "
                f"{design.solver_status}). Try smaller state_bound / input_bound (the model "
                "mismatch the observer must absorb grows with them), a smaller polytope, or more "
                "measured outputs."
            )
        self.design: ObserverDesign = design
        self.M = design.M
        self.P = design.P
        self.alpha = design.alpha

    def _keep_bounds(self, noise_bound: ArrayLike, state_bound: ArrayLike | None,
                     input_bound: ArrayLike | None) -> None:
        """The design's bounds as arrays (they were checked by the design)."""
        def vector(value: ArrayLike | None, size: int) -> np.ndarray | None:
            return None if value is None else np.broadcast_to(np.asarray(value, dtype=float), (size,)).copy()

        self.noise_bound = vector(noise_bound, self.n_outputs)
        self.state_bound = vector(state_bound, self.n_states)
        self.input_bound = vector(input_bound, self.n_inputs)

    # -- save and load: the gain and the bound as designed, their certificate checked again --
    def _design(self) -> dict[str, Any]:
        base = super()._design()
        extra = {
            "vertices_A": np.stack([a for a, _ in self.vertices]),
            "vertices_B": np.stack([b for _, b in self.vertices]),
            "noise_bound": self.noise_bound, "state_bound": self.state_bound,
            "input_bound": self.input_bound, "P": self.P, "alpha": self.alpha,
            "mu": self.design.mu, "Z": self.design.Z,
        }
        return {**base, **encode(extra, "RobustObserver design")}

    @classmethod
    def _from_design(cls, design: Design) -> Self:
        est = super()._from_design(design)
        est.vertices = list(zip(design.array("vertices_A", 3), design.array("vertices_B", 3), strict=True))
        est._keep_bounds(design.array("noise_bound", 1), design.optional_array("state_bound", 1),
                         design.optional_array("input_bound", 1))
        est.P, est.alpha = design.array("P", 2), design.number("alpha")
        mu, z_mat = design.array("mu", 1), design.array("Z", 2)
        cert: Certificate = certify_observer(
            est.vertices, (est.A, est.B), est.C, est.noise_bound, est.state_bound, est.input_bound,
            est.alpha, est.P, est.M, mu, z_mat)
        if not cert.ok:
            raise InvalidArgumentError(
                "design", "a robust observer whose certificate holds at the saved gain and bound",
                f"worst relative margin {cert.worst:.3g}")
        est.design = ObserverDesign(OPTIMAL, est.M, est.P, est.alpha, cert, "loaded", 0.0, (est.A, est.B),
                                    est.C, mu, z_mat)
        return est

    @property
    def half_widths(self) -> np.ndarray:
        """The largest ``|e_i|`` on the error ellipsoid, per state: ``sqrt(diag(P^-1))``."""
        return self.design.half_widths

    def error_level(self, e: ArrayLike) -> float:
        """``e' P e`` (at most 1 inside the certified bound)."""
        e = np.asarray(e, dtype=float)
        return float(e @ self.P @ e)

    def level_after(self, steps: int, initial_level: float) -> float:
        """The certified bound on ``e' P e`` after ``steps`` samples from ``initial_level``:
        ``1 + (1 - alpha)^steps (initial_level - 1)`` above 1, and 1 once inside."""
        if initial_level <= 1.0:
            return 1.0
        return 1.0 + (1.0 - self.alpha) ** int(steps) * (float(initial_level) - 1.0)

    def estimate_disturbance(self) -> tuple[np.ndarray, float]:
        """``(E, w_max)`` for :class:`rmpc.RMPC`'s ``disturbance=``: the estimate's own dynamics
        ``x_hat+ = A x_hat + B u + w`` with ``w = A e - e+`` and ``||w|| <= w_max`` (``E = I``)."""
        lam, vec = np.linalg.eigh(self.P)
        root = vec @ np.diag(lam ** -0.5) @ vec.T  # P^-1/2
        worst = max(float(np.linalg.norm(a @ root, 2)) for a, _ in self.vertices)
        return np.eye(self.n_states), worst + float(np.linalg.norm(root, 2))

    def output_margin(self, C_y: ArrayLike) -> np.ndarray:
        """The largest ``|c_i e|`` on the error ellipsoid for each row ``c_i`` of ``C_y``: what an
        output bound on the estimate must leave so that it holds for the true state."""
        c_y = np.atleast_2d(np.asarray(C_y, dtype=float))
        if c_y.ndim != 2 or c_y.shape[1] != self.n_states:
            raise InvalidArgumentError("C_y", f"a q x {self.n_states} matrix", f"shape {c_y.shape}")
        return np.sqrt(np.einsum("ij,jk,ik->i", c_y, np.linalg.inv(self.P), c_y))

    def covers(self, Q: ArrayLike) -> bool:
        """Whether the controller's invariant ellipsoid ``{x : x' Q^-1 x <= 1}`` of the estimate,
        widened by the error ellipsoid, lies inside the state box this observer was designed for
        (``sqrt(Q_ii) + sqrt((P^-1)_ii) <= state_bound_i``; ``True`` without a state bound)."""
        if self.state_bound is None:
            return True
        q = np.asarray(Q, dtype=float)
        if q.shape != (self.n_states, self.n_states):
            raise InvalidArgumentError("Q", f"an {self.n_states} x {self.n_states} matrix",
                                       f"shape {q.shape}")
        reach = np.sqrt(np.clip(np.diag(q), 0.0, None)) + self.half_widths
        return bool(np.all(reach <= self.state_bound))
