"""State estimators for a plant measured through ``y = C x + v``: Luenberger and steady-state Kalman.

Both run in the *current* (filter) form on the nominal model of the polytope, with the input
applied at the previous sample fed back::

    predict:  x_bar(k) = A x_hat(k-1) + B u(k-1)          (x_bar(0) = the initial guess)
    correct:  x_hat(k) = x_bar(k) + M (y(k) - C x_bar(k))

so the estimate at a sample already uses that sample's measurement, and the estimation error
evolves as ``e(k) = (I - M C) A e(k-1)`` (without noise, on the model). With
``disturbance_model="input"`` the state is augmented with a constant input disturbance
``d`` (``x+ = A x + B (u + d)``, ``d+ = d``) whose estimate :attr:`LinearEstimator.d_hat`
offset-free control uses; the augmented pair must be observable (detectable for Kalman), which
needs ``rank [[A - I, B], [C, 0]] = n + m`` and at least as many outputs as inputs.

- :class:`Luenberger`: ``M`` places the error's eigenvalues (``eig((I - M C) A)``) where asked
  (python-control's ``place`` on ``(A', (C A)')``).
- :class:`KalmanFilter`: the steady-state gain ``M = P C' (C P C' + V)^-1`` from the a-priori
  covariance ``P`` of the discrete Riccati equation (python-control's ``dlqe`` gives the same
  ``P`` and the predictor gain ``L = A M``).
"""

from __future__ import annotations

from typing import Any, ClassVar, Self

import numpy as np
from numpy.typing import ArrayLike

from models import PolytopicModel
from models.linear import unreachable_modes
from rmpc.io.design import Design, encode
from rmpc.io.saveable import Saveable
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import as_vector

__all__ = ["DISTURBANCE_MODELS", "KalmanFilter", "LinearEstimator", "Luenberger"]

#: The disturbance models an estimator may carry.
DISTURBANCE_MODELS = (None, "input")


def _nominal(plant: Any) -> tuple[np.ndarray, np.ndarray, float | None]:
    """``(A, B, dt)`` of the model the estimator runs on."""
    if isinstance(plant, PolytopicModel):
        a, b = plant.nominal
        return np.asarray(a, float), np.asarray(b, float), plant.dt
    if isinstance(plant, tuple) and len(plant) == 2:
        a, b = (np.atleast_2d(np.asarray(m, dtype=float)) for m in plant)
        if a.ndim != 2 or a.shape[0] != a.shape[1] or b.ndim != 2 or b.shape[0] != a.shape[0]:
            raise InvalidArgumentError("plant", "(A, B) with A n x n and B n x m",
                                       f"shapes {a.shape} and {b.shape}")
        return a, b, None
    raise ArgumentTypeError("plant", "a models.PolytopicModel or an (A, B) pair", type(plant).__name__)


def _output_matrix(C: ArrayLike, n: int) -> np.ndarray:
    try:
        c = np.atleast_2d(np.asarray(C))
    except (TypeError, ValueError) as err:
        raise InvalidArgumentError("C", "a real p x n matrix", f"{err}") from None
    if np.iscomplexobj(c) or c.dtype == object:
        raise InvalidArgumentError("C", "a real p x n matrix", f"dtype {c.dtype}")
    c = np.ascontiguousarray(c, dtype=float)
    if c.ndim != 2 or c.shape[1] != n or c.shape[0] < 1:
        raise InvalidArgumentError("C", f"a p x {n} matrix (the plant has {n} states)", f"shape {c.shape}")
    if not np.all(np.isfinite(c)):
        raise InvalidArgumentError("C", "finite entries", "NaN or inf")
    return c


def _unobservable_modes(a: np.ndarray, c: np.ndarray, only_unstable: bool) -> list[complex]:
    """The eigenvalues of ``a`` that ``c`` does not see (PBH by duality: ``rank [a - lambda I; c] < n``)."""
    return unreachable_modes(a.T, c.T, only_unstable=only_unstable)


class LinearEstimator(Saveable):
    """The current-form estimator shared by :class:`Luenberger` and :class:`KalmanFilter`.

    Attributes
    ----------
    A, B, C : ndarray
        The model of the plant the estimator runs on (the polytope's nominal model).
    A_aug, B_aug, C_aug : ndarray
        The same with the disturbance states appended (equal to ``A, B, C`` without one).
    M : ndarray
        The correction gain, ``(n + n_d) x p``.
    x_hat, d_hat : ndarray
        The last state and disturbance estimates (``d_hat`` empty without a disturbance model).
    """

    kind: ClassVar[str] = "estimator"

    def __init__(self, plant: Any, C: ArrayLike, disturbance_model: str | None = None,
                 x0: ArrayLike | None = None) -> None:
        self.A, self.B, self.dt = _nominal(plant)
        n, m = self.B.shape
        self.C = _output_matrix(C, n)
        if disturbance_model not in DISTURBANCE_MODELS:
            raise InvalidArgumentError("disturbance_model", f"one of {DISTURBANCE_MODELS}",
                                       repr(disturbance_model))
        self.disturbance_model = disturbance_model
        self.n_states, self.n_inputs, self.n_outputs = n, m, self.C.shape[0]
        n_d = m if disturbance_model == "input" else 0
        self.n_disturbances = n_d
        self.A_aug = np.block([[self.A, self.B[:, :n_d]], [np.zeros((n_d, n)), np.eye(n_d)]])
        self.B_aug = np.vstack([self.B, np.zeros((n_d, m))])
        self.C_aug = np.hstack([self.C, np.zeros((self.n_outputs, n_d))])
        if n_d:
            steady = np.block([[self.A - np.eye(n), self.B], [self.C, np.zeros((self.n_outputs, m))]])
            rank = np.linalg.matrix_rank(steady)
            if rank < n + m:
                raise InvalidArgumentError(
                    "disturbance_model",
                    f"an input disturbance the outputs can tell apart from the state (rank [[A - I, B], "
                    f"[C, 0]] = n + m = {n + m}; needs at least {m} outputs)",
                    f"rank {rank} with {self.n_outputs} outputs",
                )
        self._x0 = np.zeros(n) if x0 is None else as_vector(x0, "x0", n)
        self.M = np.zeros((n + n_d, self.n_outputs))
        self.reset()

    # -- save and load ---------------------------------------------------------------------
    #: What a subclass adds to the saved design (attribute names of arrays), read back as they were.
    _saved_arrays: ClassVar[tuple[str, ...]] = ()

    def _design(self) -> dict[str, Any]:
        """The model, the measurement, the disturbance model, the initial guess and the gain ``M``
        (with :attr:`_saved_arrays`): the gain as computed, not computed again on loading."""
        extra = {name: getattr(self, name) for name in self._saved_arrays}
        return encode({
            "A": self.A, "B": self.B, "dt": self.dt, "C": self.C, "disturbance_model": self.disturbance_model,
            "x0": self._x0, "M": self.M, **extra,
        }, f"{type(self).__name__} design")

    @classmethod
    def _from_design(cls, design: Design) -> Self:
        est = cls.__new__(cls)
        LinearEstimator.__init__(est, (design.array("A", 2), design.array("B", 2)), design.array("C", 2),
                                 design.optional_text("disturbance_model"), design.array("x0", 1))
        est.dt = design.optional_number("dt")
        gain = design.array("M", 2)
        if gain.shape != est.M.shape:
            raise InvalidArgumentError("design.M", f"shape {est.M.shape}", f"shape {gain.shape}")
        est.M = gain
        for name in cls._saved_arrays:
            setattr(est, name, design.array(name, 2))
        return est

    def reset(self, x0: ArrayLike | None = None) -> None:
        """Start again from ``x0`` (default: the constructor's guess) and zero disturbance."""
        start = self._x0 if x0 is None else as_vector(x0, "x0", self.n_states)
        self._z = np.concatenate([start, np.zeros(self.n_disturbances)])
        self._started = False

    @property
    def x_hat(self) -> np.ndarray:
        """The last state estimate (a copy)."""
        return self._z[: self.n_states].copy()

    @property
    def d_hat(self) -> np.ndarray:
        """The last input-disturbance estimate (a copy; empty without a disturbance model)."""
        return self._z[self.n_states:].copy()

    def update(self, y: ArrayLike, u_prev: ArrayLike | None = None) -> np.ndarray:
        """Predict with the input applied at the previous sample, correct with ``y``; return ``x_hat``.

        ``u_prev`` is ignored at the first call after :meth:`reset` (the prediction is the
        initial guess) and required after it.
        """
        y = as_vector(y, "y", self.n_outputs)
        if self._started:
            if u_prev is None:
                raise InvalidArgumentError("u_prev", "the input applied at the previous sample", "None")
            u = as_vector(u_prev, "u_prev", self.n_inputs)
            z_bar = self.A_aug @ self._z + self.B_aug @ u
        else:
            z_bar = self._z
        self._z = z_bar + self.M @ (y - self.C_aug @ z_bar)
        self._started = True
        return self.x_hat

    def error_dynamics(self) -> np.ndarray:
        """``(I - M C) A`` of the augmented model: the noiseless estimation error's map."""
        size = self.A_aug.shape[0]
        return (np.eye(size) - self.M @ self.C_aug) @ self.A_aug


class Luenberger(LinearEstimator):
    """An observer whose estimation error has the eigenvalues ``poles`` (or the gain ``gain``).

    Parameters
    ----------
    plant : PolytopicModel or (A, B)
        The model (a polytope's nominal model).
    C : (p, n) array_like
        The measurement matrix, ``y = C x + v``.
    poles : sequence of complex, optional
        The eigenvalues of ``(I - M C) A`` (augmented: ``n + n_d`` of them, inside the unit
        circle; complex ones in conjugate pairs).
    gain : (n + n_d, p) array_like, optional
        ``M`` itself, instead of ``poles``.
    disturbance_model : {None, "input"}
        ``"input"``: estimate a constant input disturbance too.
    x0 : (n,) array_like, optional
        The initial guess (default zero).

    Examples
    --------
    >>> import numpy as np
    >>> from rmpc.estimators import Luenberger
    >>> A, B = np.array([[1.0, 0.1], [0.0, 1.0]]), np.array([[0.005], [0.1]])
    >>> obs = Luenberger((A, B), C=[[1.0, 0.0]], poles=[0.5, 0.6])
    >>> np.round(np.sort(np.linalg.eigvals(obs.error_dynamics()).real), 6)
    array([0.5, 0.6])
    """

    kind = "luenberger"

    def __init__(self, plant: Any, C: ArrayLike, poles: ArrayLike | None = None, *,
                 gain: ArrayLike | None = None, disturbance_model: str | None = None,
                 x0: ArrayLike | None = None) -> None:
        super().__init__(plant, C, disturbance_model, x0)
        size = self.A_aug.shape[0]
        if (poles is None) == (gain is None):
            raise InvalidArgumentError("poles", "exactly one of poles or gain",
                                       f"poles={poles!r}, gain={gain!r}")
        if gain is not None:
            m_mat = np.atleast_2d(np.asarray(gain, dtype=float))
            if m_mat.shape != (size, self.n_outputs) or not np.all(np.isfinite(m_mat)):
                raise InvalidArgumentError("gain", f"a finite {size} x {self.n_outputs} matrix",
                                           f"shape {m_mat.shape}")
            self.M = np.ascontiguousarray(m_mat)
            return
        wanted = np.asarray(poles, dtype=complex).reshape(-1)
        if wanted.size != size or np.any(np.abs(wanted) >= 1.0):
            raise InvalidArgumentError("poles", f"{size} eigenvalues inside the unit circle",
                                       repr(np.asarray(poles).tolist()))
        unseen = _unobservable_modes(self.A_aug, self.C_aug @ self.A_aug, only_unstable=False)
        if unseen:
            raise InvalidArgumentError(
                "C", "a measurement that observes every mode (to place every pole)",
                f"unobservable modes {[complex(round(z.real, 9), round(z.imag, 9)) for z in unseen]}",
            )
        import control

        try:
            k_mat = control.place(self.A_aug.T, (self.C_aug @ self.A_aug).T, wanted)
        except ValueError as err:  # repeated beyond the outputs' rank, unpaired complex, ...
            raise InvalidArgumentError("poles", "eigenvalues a gain can place (python-control place)",
                                       f"{np.asarray(poles).tolist()}: {err}") from None
        # C order, as a loaded estimator's gain: BLAS may round a product differently by layout
        self.M = np.ascontiguousarray(np.asarray(k_mat).T)


class KalmanFilter(LinearEstimator):
    """The steady-state Kalman filter for ``x+ = A x + B u + w``, ``y = C x + v``.

    Parameters
    ----------
    plant : PolytopicModel or (A, B)
        The model (a polytope's nominal model).
    C : (p, n) array_like
        The measurement matrix.
    process_noise : (n, n) array_like or float
        The covariance ``W`` of ``w`` (a float: ``W = w I``).
    measurement_noise : (p, p) array_like or float
        The covariance ``V`` of ``v`` (positive definite).
    disturbance_model : {None, "input"}
        ``"input"``: estimate a constant input disturbance, driven by ``disturbance_noise``.
    disturbance_noise : (m, m) array_like or float
        The covariance of the disturbance's random walk (default ``1e-6 I``; larger tracks a
        changing disturbance faster and noisier).
    x0 : (n,) array_like, optional
        The initial guess (default zero).

    Attributes
    ----------
    P : ndarray
        The a-priori error covariance of the steady state (the Riccati solution).
    """

    kind = "kalman"
    _saved_arrays = ("P", "W", "V")

    def __init__(self, plant: Any, C: ArrayLike, process_noise: ArrayLike | float,
                 measurement_noise: ArrayLike | float, *, disturbance_model: str | None = None,
                 disturbance_noise: ArrayLike | float = 1e-6, x0: ArrayLike | None = None) -> None:
        super().__init__(plant, C, disturbance_model, x0)
        w = _covariance(process_noise, self.n_states, "process_noise", definite=False)
        v = _covariance(measurement_noise, self.n_outputs, "measurement_noise", definite=True)
        if self.n_disturbances:
            wd = _covariance(disturbance_noise, self.n_disturbances, "disturbance_noise", definite=True)
            w = np.block([[w, np.zeros((self.n_states, self.n_disturbances))],
                          [np.zeros((self.n_disturbances, self.n_states)), wd]])
        unseen = _unobservable_modes(self.A_aug, self.C_aug, only_unstable=True)
        if unseen:
            raise InvalidArgumentError(
                "C", "a measurement that sees every unstable mode (a detectable pair)",
                f"unseen modes {[complex(round(z.real, 9), round(z.imag, 9)) for z in unseen]}",
            )
        import scipy.linalg as sla

        self.P = sla.solve_discrete_are(self.A_aug.T, self.C_aug.T, w, v)
        s = self.C_aug @ self.P @ self.C_aug.T + v
        # C order, as Luenberger's gain
        self.M = np.ascontiguousarray(np.linalg.solve(s, self.C_aug @ self.P).T)
        self.W, self.V = w, v


def _covariance(value: ArrayLike | float, size: int, name: str, *, definite: bool) -> np.ndarray:
    mat = np.asarray(value, dtype=float)
    if mat.ndim == 0:
        mat = float(mat) * np.eye(size)
    if mat.shape != (size, size) or not np.all(np.isfinite(mat)):
        raise InvalidArgumentError(name, f"a finite {size} x {size} covariance or a scalar",
                                   f"shape {mat.shape}")
    mat = 0.5 * (mat + mat.T)
    low = float(np.linalg.eigvalsh(mat)[0])
    if low < 0.0 or (definite and low <= 0.0):
        need = "positive definite" if definite else "positive semidefinite"
        raise InvalidArgumentError(name, f"a {need} covariance", f"smallest eigenvalue {low:.3g}")
    return mat
