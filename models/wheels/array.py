"""A reaction-wheel array: distribution matrix, per-wheel limits, redundancy (paper W).

Wheel ``j`` spins about the unit axis ``D[:, j]`` (body frame). Its torque on the platform is
``u_j D[:, j]`` and its momentum ``h_j`` along that axis obeys ``h_j' = -u_j``, so the array
puts the body torque ``D u`` on the platform. The array spans three axes when
``rank(D) = 3``; with wheel effectiveness ``Lambda = diag(lambda_j)`` (``0`` = outage) the
condition of paper W (eq. 17) is ``rank(D Lambda) = 3``.

Paper W's array (**certain**): wheels 1-3 on
the body axes and wheel 4 along ``(1, 1, 1)/sqrt(3)``, 54.7356 deg from every axis;
``|u_j| <= 0.123`` N m, ``|h_j| <= 0.625`` N m s, wheel inertia 0.0123 kg m^2.

Wheels are numbered from 1 in paper W's text and in :class:`~models.WheelFault`; arrays
(``D[:, j]``, ``u[j]``) are indexed from 0, so wheel ``k`` is column ``k - 1``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import as_matrix, as_positive_values, as_vector, check_count

__all__ = [
    "MAX_WHEELS",
    "PAPER_W_MOMENTUM_MAX",
    "PAPER_W_TORQUE_MAX",
    "PAPER_W_WHEEL_INERTIA",
    "RANK_TOL",
    "WheelArray",
]

#: Per-wheel torque limit of paper W, N m (**certain**).
PAPER_W_TORQUE_MAX: float = 0.123
#: Per-wheel momentum limit of paper W, N m s (**certain**; 50.8 rad/s, 485 rpm).
PAPER_W_MOMENTUM_MAX: float = 0.625
#: Axial inertia of each wheel of paper W, kg m^2 (**certain**).
PAPER_W_WHEEL_INERTIA: float = 0.0123
#: Singular values below ``RANK_TOL * max(1, sigma_max)`` count as zero in rank checks.
RANK_TOL: float = 1e-9

MAX_WHEELS = 1_000
"""Default bound on a number of wheels given as an integer (:class:`~models.WheelDisturbance`,
:class:`~models.FaultSchedule`): a spacecraft has 3 to 6, and the per-wheel arrays are allocated
at once (``n_wheels = 10**12`` ended in a MemoryError); ``max_wheels=N`` lifts it."""

#: Tolerance on ``|D[:, j]| = 1``.
_UNIT_TOL = 1e-9


class WheelArray:
    """Reaction wheels along the unit columns of ``D`` (3 x m), with per-wheel limits.

    Parameters
    ----------
    D : (3, m) array_like
        Distribution matrix: column ``j`` is the spin axis of wheel ``j + 1`` in body axes,
        a unit vector. It must span three axes (``rank(D) = 3``, so ``m >= 3``).
    torque_max : float or (m,) array_like
        Torque limit per wheel ``|u_j| <= torque_max_j`` (N m, > 0; ``inf`` for none).
    momentum_max : float or (m,) array_like
        Momentum limit per wheel ``|h_j| <= momentum_max_j`` (N m s, > 0; ``inf`` for none).
    wheel_inertia : float or (m,) array_like
        Axial inertia of each wheel (kg m^2, > 0); used for the wheel speed
        ``h_j / wheel_inertia_j`` (friction, reports).

    Raises
    ------
    InvalidArgumentError
        Naming ``D`` when a column is not a unit vector or the columns do not span three
        axes; naming the limit when one is not positive.

    Examples
    --------
    >>> import numpy as np
    >>> from models import WheelArray
    >>> wheels = WheelArray.paper_w()
    >>> wheels.n_wheels, wheels.torque_max.tolist()
    (4, [0.123, 0.123, 0.123, 0.123])
    >>> round(float(np.degrees(np.arccos(wheels.D[0, 3]))), 4)  # the skew wheel
    54.7356
    >>> wheels.rank([1, 0, 1, 1]), wheels.rank([0, 0, 1, 1])  # wheel 2 out; wheels 1, 2 out
    (3, 2)
    """

    def __init__(
        self,
        D: ArrayLike,
        torque_max: ArrayLike = PAPER_W_TORQUE_MAX,
        momentum_max: ArrayLike = PAPER_W_MOMENTUM_MAX,
        wheel_inertia: ArrayLike = PAPER_W_WHEEL_INERTIA,
    ) -> None:
        d = as_matrix(D, "D", (3, None))
        norms = np.linalg.norm(d, axis=0)
        bad = np.flatnonzero(np.abs(norms - 1.0) > _UNIT_TOL)
        if bad.size:
            j = int(bad[0])
            raise InvalidArgumentError(
                "D",
                "unit columns (each column a wheel's spin axis)",
                f"|D[:, {j}]| = {norms[j]:.6g} (wheel {j + 1})",
            )
        rank = _rank(d)
        if rank < 3:
            raise InvalidArgumentError(
                "D", "columns that span three axes (rank(D) = 3)", f"rank {rank} with {d.shape[1]} wheels"
            )
        m = d.shape[1]
        self._d = d
        limits = {"allow_inf": True, "per": "wheel", "what": "limits"}
        self._torque_max = as_positive_values(torque_max, "torque_max", m, **limits)
        self._momentum_max = as_positive_values(momentum_max, "momentum_max", m, **limits)
        self._wheel_inertia = as_positive_values(wheel_inertia, "wheel_inertia", m, per="wheel")
        for arr in (self._d, self._torque_max, self._momentum_max, self._wheel_inertia):
            arr.setflags(write=False)

    @classmethod
    def paper_w(cls) -> WheelArray:
        """Paper W's array: three wheels on the body axes and one along ``(1, 1, 1)/sqrt(3)``.

        ``D = [I3 | 1/sqrt(3) (1, 1, 1)']``, limits 0.123 N m and 0.625 N m s, wheel inertia
        0.0123 kg m^2 (all **certain**).
        """
        skew_axis = np.full((3, 1), 1.0 / np.sqrt(3.0))
        return cls(np.hstack((np.eye(3), skew_axis)))

    # -- data ------------------------------------------------------------------------------
    @property
    def D(self) -> np.ndarray:
        """The distribution matrix (3 x m, unit columns, read-only)."""
        return self._d

    @property
    def n_wheels(self) -> int:
        """Number of wheels ``m``."""
        return int(self._d.shape[1])

    @property
    def torque_max(self) -> np.ndarray:
        """Per-wheel torque limits (N m, read-only)."""
        return self._torque_max

    @property
    def momentum_max(self) -> np.ndarray:
        """Per-wheel momentum limits (N m s, read-only)."""
        return self._momentum_max

    @property
    def wheel_inertia(self) -> np.ndarray:
        """Per-wheel axial inertias (kg m^2, read-only)."""
        return self._wheel_inertia

    def axis_authority(self) -> np.ndarray:
        """Largest torque each body axis gets with every wheel at its limit (N m).

        ``sum_j |D[i, j]| torque_max_j``: 0.123 (1 + 1/sqrt(3)) = 0.194 N m per axis for
        paper W's array.
        """
        return np.abs(self._d) @ self._torque_max

    def momentum_capacity(self) -> np.ndarray:
        """Largest momentum the array stores along each body axis (N m s), as :meth:`axis_authority`."""
        return np.abs(self._d) @ self._momentum_max

    # -- redundancy ------------------------------------------------------------------------
    def _effectiveness(self, effectiveness: ArrayLike) -> np.ndarray:
        lam = as_vector(effectiveness, "effectiveness", self.n_wheels)
        if np.any((lam < 0.0) | (lam > 1.0)):
            raise InvalidArgumentError(
                "effectiveness", "values in [0, 1] (1 healthy, 0 outage), one per wheel", repr(lam.tolist())
            )
        return lam

    def effective_matrix(self, effectiveness: ArrayLike) -> np.ndarray:
        """``D Lambda`` for the per-wheel effectiveness ``lambda_j`` in [0, 1]."""
        return self._d * self._effectiveness(effectiveness)

    def rank(self, effectiveness: ArrayLike | None = None) -> int:
        """``rank(D Lambda)`` (default: all wheels healthy)."""
        lam = np.ones(self.n_wheels) if effectiveness is None else self._effectiveness(effectiveness)
        return _rank(self._d * lam)

    def spans_three_axes(self, effectiveness: ArrayLike | None = None) -> bool:
        """Whether ``rank(D Lambda) = 3`` (paper W's redundancy condition, eq. 17)."""
        return self.rank(effectiveness) == 3

    def __repr__(self) -> str:
        return (
            f"WheelArray(n_wheels={self.n_wheels}, torque_max={self._torque_max.tolist()}, "
            f"momentum_max={self._momentum_max.tolist()})"
        )


def _wheel_count(n_wheels: Any, max_wheels: Any) -> int:
    """``n_wheels`` as an int in ``[1, max_wheels]``, else an error naming it (or ``max_wheels``)."""
    limit = check_count(max_wheels, "max_wheels")
    return check_count(n_wheels, "n_wheels", limit=limit, limit_name="max_wheels", unit=" wheels",
                       expected="a positive number of wheels")


def _rank(mat: np.ndarray) -> int:
    """Numerical rank with the module tolerance :data:`RANK_TOL`."""
    s = np.linalg.svd(mat, compute_uv=False)
    if s.size == 0:
        return 0
    return int(np.sum(s > RANK_TOL * max(1.0, float(s[0]))))
