"""What the flexible-satellite control laws know about the plant, and the pieces they share.

:class:`FlexibleTerms` reads a measured state ``x = [q, w, eta, eta']`` of
:class:`models.FlexibleSatellite`, forms the attitude error against a reference quaternion and
evaluates the model terms the laws cancel::

    gyroscopic:      w x (J w + delta' eta')              (w x J w without flex feed-forward)
    modal reaction:  delta' M^-1 (C eta' + K eta - Gamma_a v)   (zero without flex feed-forward)

so that ``J_mb w' = -gyroscopic + modal reaction + u + d - delta' M^-1 d_f`` on the plant.
:func:`switching` is the switching function of the sliding-mode laws.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from models import FlexibleSatellite
from models.attitude.quaternion import quat_error, unit_quaternion
from models.attitude.vectors import cross3
from toolkit_common.errors import ArgumentTypeError
from toolkit_common.validation import as_square_matrix, as_vector, check_bool, check_choice

__all__ = ["AttitudeError", "FlexibleTerms", "SwitchKind", "gain_matrix", "switching"]

SwitchKind = Literal["sign", "tanh"]


def switching(sigma: np.ndarray, eps: float, kind: SwitchKind) -> np.ndarray:
    """``tanh(sigma / eps)`` (a boundary layer of width ``eps``) or ``sign(sigma)``."""
    if kind == "tanh":
        return np.tanh(sigma / eps)
    return np.sign(sigma)


def gain_matrix(value: Any, name: str) -> np.ndarray:
    """A gain of the flexible laws as a read-only 3 x 3 matrix: a scalar, 3 per-axis values or in full.

    The scalar and the per-axis values are >= 0; a full matrix is taken as given (finite).
    One reading, :func:`toolkit_common.validation.as_square_matrix`, with the flexible laws' options.
    """
    mat = as_square_matrix(value, name, 3, allow_zero=True, definite=None, entries="gains")
    mat.setflags(write=False)
    return mat


@dataclass(frozen=True)
class AttitudeError:
    """The attitude error of one measured state.

    Attributes
    ----------
    q0 : float
        Scalar part of the error quaternion ``q_ref^-1 * q`` (``>= 0``).
    qv : (3,) ndarray
        Its vector part, ``sin(a/2) e``.
    qv_dot : (3,) ndarray
        ``q_v' = (q0 I + [q_v x]) w / 2`` (the reference is at rest).
    angle : float
        The rotation error ``a`` (rad).
    """

    q0: float
    qv: np.ndarray
    qv_dot: np.ndarray
    angle: float


class FlexibleTerms:
    """The model terms of a :class:`models.FlexibleSatellite` used by the control laws.

    Parameters
    ----------
    plant : FlexibleSatellite
        The controller's model (nominal parameters).
    q_ref : (4,) array_like, optional
        Reference attitude (unit quaternion, at rest); default the identity.
    flex_feedforward : bool
        Use the modal state (``eta, eta'``, idealised full-state measurement as in paper V) to
        cancel the modal reaction; ``False`` drops every ``eta`` term.
    """

    def __init__(
        self,
        plant: FlexibleSatellite,
        q_ref: ArrayLike | None = None,
        flex_feedforward: bool = True,
    ) -> None:
        if not isinstance(plant, FlexibleSatellite):
            raise ArgumentTypeError("plant", "a models.FlexibleSatellite", type(plant).__name__)
        self.plant = plant
        self.q_ref = np.array([1.0, 0.0, 0.0, 0.0]) if q_ref is None else unit_quaternion(q_ref, "q_ref")
        self.flex_feedforward = check_bool(flex_feedforward, "flex_feedforward")
        self.n_modes = plant.n_modes
        self.n_pzt = plant.n_pzt
        self.inertia = plant.inertia
        self.hub_inertia = plant.hub_inertia
        self._delta_t = plant.coupling.T
        self._couple = plant.coupling.T @ np.linalg.inv(plant.modal_mass) if self.n_modes else (
            np.zeros((3, 0)))
        self._c = np.diag(plant.damping_matrix)
        self._k = np.diag(plant.stiffness)
        self._gamma = plant.pzt_matrix

    def split(self, x: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(q, w, eta, eta')`` of a measured state (checked: length ``7 + 2N``, finite)."""
        x = as_vector(x, "x", self.plant.n_states)
        n = self.n_modes
        return x[:4], x[4:7], x[7:7 + n], x[7 + n:]

    def error(self, q: np.ndarray, w: np.ndarray) -> AttitudeError:
        """The attitude error of ``q`` against the reference and its rate."""
        err = quat_error(q / np.linalg.norm(q), self.q_ref)
        q0, qv = float(err[0]), err[1:]
        qv_dot = 0.5 * (q0 * w + cross3(qv, w))
        angle = 2.0 * float(np.arctan2(np.linalg.norm(qv), q0))
        return AttitudeError(q0=q0, qv=qv, qv_dot=qv_dot, angle=angle)

    def gyroscopic(self, w: np.ndarray, eta_dot: np.ndarray) -> np.ndarray:
        """``w x (J w + delta' eta')`` (``w x J w`` without flex feed-forward)."""
        h = self.inertia @ w
        if self.flex_feedforward and self.n_modes:
            h = h + self._delta_t @ eta_dot
        return cross3(w, h)

    def modal_reaction(self, eta: np.ndarray, eta_dot: np.ndarray, v: np.ndarray | None) -> np.ndarray:
        """``delta' M^-1 (C eta' + K eta - Gamma_a v)`` (zero without flex feed-forward)."""
        if not self.flex_feedforward or self.n_modes == 0:
            return np.zeros(3)
        force = self._c * eta_dot + self._k * eta
        if v is not None:
            force = force - self._gamma @ v
        return self._couple @ force

    def sliding_torque(
        self,
        w: np.ndarray,
        eta: np.ndarray,
        eta_dot: np.ndarray,
        v: np.ndarray | None,
        sigma: np.ndarray,
        surface_rate: np.ndarray,
        k_s: np.ndarray,
        w_s: float,
        eps: float,
        switch: SwitchKind,
    ) -> np.ndarray:
        """The sliding-mode torque (before saturation)::

            u = w x (J w + delta' eta') - delta' M^-1 (C eta' + K eta - Gamma_a v)
                - J_mb surface_rate - K_s sigma - W_s switch(sigma, eps)

        ``surface_rate`` is ``sigma' - w'`` (``alpha' q_v + alpha q_v' + k_I z'``), so that on
        the exact model ``J_mb sigma' = -K_s sigma - W_s switch(sigma) + d - delta' M^-1 d_f``.
        """
        return (
            self.gyroscopic(w, eta_dot)
            - self.modal_reaction(eta, eta_dot, v)
            - self.hub_inertia @ surface_rate
            - k_s @ sigma
            - w_s * switching(sigma, eps, switch)
        )

    def pzt(self, pzt: Any) -> np.ndarray | None:
        """Check this sample's PZT command (``None``: no command)."""
        if pzt is None:
            return None
        return as_vector(pzt, "pzt", self.n_pzt)

    def command(self, u: np.ndarray, pzt: Any) -> np.ndarray:
        """``[u; v]``: the hub torque ``u`` and this sample's PZT command ``v`` (checked by
        :meth:`pzt`; zeros when there is none), the output of every flexible law's ``step``."""
        v_out = np.zeros(self.n_pzt) if pzt is None else self.pzt(pzt)
        return np.concatenate((u, v_out))


def check_switch(value: Any) -> SwitchKind:
    """``"sign"`` or ``"tanh"``."""
    return check_choice(value, "switch", ("sign", "tanh"))
