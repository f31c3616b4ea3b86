"""Everything between the controller's wheel commands and the torques the wheels apply.

One object, :class:`WheelInputStage`, follows the input-stage protocol of
:class:`rmpc.sim.plants.SampledPlant` (``stage(t, x, u_cmd) -> u_applied``, ``reset()``,
``begin_sample(t, x, u_cmd) -> dict``). In order:

1. wheel-level disturbance (S4): ``u = u_cmd + d_w(t)`` (:class:`~models.WheelDisturbance`);
2. faults: ``u_j = lambda_j(t) u_j + b_j(t)`` (:class:`~models.FaultSchedule`);
3. torque limit: ``u_j`` clipped to ``+-torque_max_j``;
4. momentum limit: a wheel at ``|h_j| >= momentum_max_j`` gives no torque that would push
   ``|h_j|`` further out (``u_j h_j < 0``, since ``h_j' = -u_j``), and any torque inward
   (**assumed**).

The limits act after the fault stage, so faulty wheels are limited too (a stuck wheel
reaches its momentum limit). The stage is evaluated inside the integration, so a
limit reached within a sample acts there (with RK4 at 5 ms, ``|h_j|`` overshoots the limit by
at most ``torque_max_j`` times one substep, 0.6 mN m s); the per-sample log
(``Trajectory.stage_log``) records the state at the start of each sample, so such a limit
appears in the log from the next sample.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from models.wheels.array import WheelArray
from models.wheels.faults import FaultSchedule, WheelFault, _as_schedule
from models.wheels.noise import WheelDisturbance
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import check_bool

__all__ = ["WheelInputStage"]


class WheelInputStage:
    """Wheel disturbance, faults, torque and momentum limits between command and wheel torque.

    Parameters
    ----------
    wheels : WheelArray
        The array (its limits; the number of wheels the faults are checked against).
    faults : FaultSchedule, WheelFault or sequence of WheelFault, optional
        The faults of the run (default none).
    wheel_disturbance : WheelDisturbance, optional
        Added to the commands before the faults (S4); its noise is redrawn at every sample.
    torque_limit, momentum_limit : bool
        Apply the per-wheel limits (default ``True`` both; switch off only for analysis,
        e.g. the unsaturated Lyapunov checks).
    momentum_index : int
        Index of ``h_1`` in the state (default 6: ``[eta, w, h]``).

    Examples
    --------
    >>> import numpy as np
    >>> from models import WheelArray, WheelFault, WheelInputStage
    >>> stage = WheelInputStage(WheelArray.paper_w(), faults=[WheelFault(2, "stuck", 8.0, 37.0, value=0.05)])
    >>> x = np.zeros(10)
    >>> stage(10.0, x, np.array([0.5, 0.0, -0.01, 0.0])).tolist()  # clipped; wheel 2 stuck
    [0.123, 0.05, -0.01, 0.0]
    >>> x[6] = 0.7  # wheel 1 beyond its momentum limit: no torque that drives it further
    >>> stage(1.0, x, np.array([-0.1, 0.0, 0.0, 0.0])).tolist()
    [0.0, 0.0, 0.0, 0.0]
    """

    def __init__(
        self,
        wheels: WheelArray,
        faults: FaultSchedule | WheelFault | Any = None,
        wheel_disturbance: WheelDisturbance | None = None,
        *,
        torque_limit: bool = True,
        momentum_limit: bool = True,
        momentum_index: int = 6,
    ) -> None:
        if not isinstance(wheels, WheelArray):
            raise ArgumentTypeError("wheels", "a models.WheelArray", type(wheels).__name__)
        self.wheels = wheels
        m = wheels.n_wheels
        self.faults = _as_schedule(faults, m)
        if wheel_disturbance is not None:
            if not isinstance(wheel_disturbance, WheelDisturbance):
                raise ArgumentTypeError(
                    "wheel_disturbance", "None or a models.WheelDisturbance", type(wheel_disturbance).__name__
                )
            if wheel_disturbance.n_wheels != m:
                raise InvalidArgumentError(
                    "wheel_disturbance",
                    f"a disturbance on {m} wheels",
                    f"{wheel_disturbance.n_wheels} wheels",
                )
        self.wheel_disturbance = wheel_disturbance
        self.torque_limit = check_bool(torque_limit, "torque_limit")
        self.momentum_limit = check_bool(momentum_limit, "momentum_limit")
        if (
            isinstance(momentum_index, bool)
            or not isinstance(momentum_index, int | np.integer)
            or momentum_index < 0
        ):
            raise InvalidArgumentError("momentum_index", "an index >= 0", repr(momentum_index))
        self.momentum_index = int(momentum_index)
        self._tmax = np.asarray(wheels.torque_max)
        self._hmax = np.asarray(wheels.momentum_max)

    def reset(self) -> None:
        """Re-seed the wheel disturbance (called by :func:`rmpc.sim.simulate` before a run)."""
        if self.wheel_disturbance is not None:
            self.wheel_disturbance.reset()

    # -- the stages ------------------------------------------------------------------------------
    def _momenta(self, x: np.ndarray) -> np.ndarray:
        i = self.momentum_index
        h = np.asarray(x, dtype=float)[i : i + self.wheels.n_wheels]
        if h.shape[0] != self.wheels.n_wheels:
            raise InvalidArgumentError(
                "x", f"a state with {self.wheels.n_wheels} wheel momenta from index {i}", f"{len(x)} entries"
            )
        return h

    def faulty_torque(self, t: float, u_cmd: ArrayLike) -> np.ndarray:
        """Stages 1-2: the torques the wheels would give without limits."""
        u = np.asarray(u_cmd, dtype=float)
        if self.wheel_disturbance is not None:
            u = u + self.wheel_disturbance(t)
        return self.faults.apply(t, u)

    def _limits(self, u: np.ndarray, h: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        clipped = np.zeros(u.shape, dtype=bool)
        held = np.zeros(u.shape, dtype=bool)
        if self.torque_limit:
            clipped = np.abs(u) > self._tmax
            u = np.clip(u, -self._tmax, self._tmax)
        if self.momentum_limit:
            held = (np.abs(h) >= self._hmax) & (u * h < 0.0)
            if held.any():
                u = np.where(held, 0.0, u)
        return u, clipped, held

    def __call__(self, t: float, x: np.ndarray, u_cmd: np.ndarray) -> np.ndarray:
        """The torques the wheels apply at ``(t, x)`` for the held commands ``u_cmd``."""
        u = self.faulty_torque(t, u_cmd)
        return self._limits(u, self._momenta(x))[0]

    def begin_sample(self, t: float, x: np.ndarray, u_cmd: np.ndarray) -> dict[str, Any]:
        """Draw this sample's wheel noise; return what is logged for the sample.

        Keys (one entry per wheel): ``wheel_disturbance`` (N m, zeros without one),
        ``u_fault`` (after the faults, before the limits), ``torque_clipped`` and
        ``momentum_limited`` (bool), ``fault_active`` (bool), ``effectiveness``
        (``lambda(t)``) and ``fault_altered`` (an active fault whose torque a limit changed:
        "fault output altered by momentum limit").
        """
        if self.wheel_disturbance is not None:
            self.wheel_disturbance.draw()
            dist = self.wheel_disturbance(t)
        else:
            dist = np.zeros(self.wheels.n_wheels)
        u_fault = self.faulty_torque(t, u_cmd)
        _, clipped, held = self._limits(u_fault, self._momenta(x))
        active = self.faults.active(t)
        return {
            "wheel_disturbance": np.asarray(dist, dtype=float),
            "u_fault": u_fault,
            "torque_clipped": clipped,
            "momentum_limited": held,
            "fault_active": active,
            "effectiveness": self.faults.effectiveness(t),
            "fault_altered": active & (clipped | held),
        }

    def settings(self) -> dict[str, Any]:
        """What the stage does, for reports."""
        return {
            "faults": [repr(f) for f in self.faults.faults],
            "wheel_disturbance": None
            if self.wheel_disturbance is None
            else self.wheel_disturbance.settings(),
            "torque_limit": self.torque_limit,
            "momentum_limit": self.momentum_limit,
            "torque_max": self._tmax.tolist(),
            "momentum_max": self._hmax.tolist(),
        }

    def __repr__(self) -> str:
        return (
            f"WheelInputStage(n_faults={len(self.faults)}, "
            f"wheel_disturbance={self.wheel_disturbance is not None}, "
            f"torque_limit={self.torque_limit}, momentum_limit={self.momentum_limit})"
        )
