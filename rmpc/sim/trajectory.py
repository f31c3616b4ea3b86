"""A closed-loop run as :func:`~rmpc.simulate` returns it: :class:`Trajectory`."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from toolkit_common.errors import InvalidArgumentError

__all__ = ["Trajectory"]


@dataclass
class Trajectory:
    """A closed-loop run.

    Attributes
    ----------
    t : (N + 1,) ndarray
        Sample times (s), ``t[0] = 0``.
    x : (N + 1, n) ndarray
        States at the sample times, in the plant's own coordinates (Euler angles, MRPs or a
        quaternion for the attitude, whatever the plant uses).
    u_cmd : (N, m) ndarray
        Controller outputs.
    u_applied : (N, m) ndarray
        Inputs applied to the plant (after the limiter, the actuator and, for a
        :class:`~rmpc.sim.plants.SampledPlant` with an input stage, the stage evaluated at the
        start of the sample), without ``d``.
    d : (N, n_d) ndarray
        Disturbance at the start of each sample.
    status : list of str
        Each step's controller status.
    solve_time : (N,) ndarray
        Each step's optimiser time as reported by the controller (s).
    step_time : (N,) ndarray
        Wall time of each ``controller.step`` call (s).
    gamma : (N,) ndarray
        Each step's cost bound where the controller has one, NaN elsewhere.
    info : list
        The controller's ``last`` object after each step.
    plant : str
        ``"linear"`` or ``"nonlinear"``.
    dt : float
        Sample time (s).
    stage_log : dict of ndarray
        What the input stage reported at the start of each sample (``begin_sample``), one
        array per name with the samples along the first axis; empty without a stage.
    attitude_euler : (N + 1, 3) ndarray or None
        Roll, pitch and yaw (rad, 3-2-1 sequence) at every sample, computed by the plant's
        ``attitude_euler(x)`` whatever its attitude representation; ``None`` for a plant
        without attitude (a user's model without ``attitude_euler``, a polytope built with
        ``attitude=None``).
    """

    t: np.ndarray
    x: np.ndarray
    u_cmd: np.ndarray
    u_applied: np.ndarray
    d: np.ndarray
    status: list[str]
    solve_time: np.ndarray
    step_time: np.ndarray
    gamma: np.ndarray
    info: list[Any] = field(repr=False)
    plant: str
    dt: float
    stage_log: dict[str, np.ndarray] = field(default_factory=dict)
    attitude_euler: np.ndarray | None = None

    @property
    def n_steps(self) -> int:
        """Number of controller steps."""
        return int(self.u_cmd.shape[0])

    @property
    def attitude_deg(self) -> np.ndarray:
        """Roll, pitch, yaw in degrees, shape ``(N + 1, 3)``: the plant's own, for every plant.

        Raises
        ------
        InvalidArgumentError
            Naming ``plant`` when the run's plant has no attitude (``attitude_euler`` is ``None``).
        """
        if self.attitude_euler is None:
            raise InvalidArgumentError(
                "plant", "a plant with attitude_euler(x) for Trajectory.attitude_deg",
                "a run whose plant has no attitude (Trajectory.attitude_euler is None)",
            )
        return np.degrees(self.attitude_euler)

    def status_counts(self) -> dict[str, int]:
        """How many steps ended with each status."""
        counts: dict[str, int] = {}
        for s in self.status:
            counts[s] = counts.get(s, 0) + 1
        return counts

    def save_npz(self, path: str) -> None:
        """Write the numeric arrays (and statuses) to a ``.npz`` file.

        The keys are the attribute names, plus ``attitude_deg`` when the plant has an attitude.
        """
        arrays: dict[str, Any] = {
            "t": self.t, "x": self.x, "u_cmd": self.u_cmd, "u_applied": self.u_applied, "d": self.d,
            "solve_time": self.solve_time, "step_time": self.step_time, "gamma": self.gamma,
            "status": np.asarray(self.status), "plant": self.plant, "dt": self.dt,
        }
        if self.attitude_euler is not None:
            arrays["attitude_deg"] = self.attitude_deg
        np.savez_compressed(path, **arrays)
