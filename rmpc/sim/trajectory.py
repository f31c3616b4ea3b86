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
    state_names, input_names : tuple of str
        The plant's names of its states and inputs (python-control's signal names for a
        polytope built by :meth:`models.PolytopicModel.from_statespace`); empty when the plant
        gives none.
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
    state_names: tuple[str, ...] = ()
    input_names: tuple[str, ...] = ()

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

    def names(self, kind: str = "state") -> tuple[str, ...]:
        """The plant's state (``kind="state"``) or input names, ``x[i]`` / ``u[i]`` where it gave none."""
        if kind not in ("state", "input"):
            raise InvalidArgumentError("kind", "'state' or 'input'", repr(kind))
        given, size, letter = ((self.state_names, self.x.shape[1], "x") if kind == "state"
                               else (self.input_names, self.u_cmd.shape[1], "u"))
        return tuple(given) if len(given) == size else tuple(f"{letter}[{i}]" for i in range(size))

    def plot(self, u_max: Any = None, states: Any = None) -> Any:
        """The run as a matplotlib figure: states, inputs (with the bounds), solve time, status.

        Parameters
        ----------
        u_max : float or (m,) array_like, optional
            Input bounds to draw as dashed lines (``+-u_max``).
        states : sequence of int, optional
            Which states to draw (default all), labelled with the plant's names.

        Returns
        -------
        matplotlib.figure.Figure
            Four panels: the states, the applied inputs (and commands where they differ), each
            step's solve time (ms, log scale), and each step's status (a row per status word).
        """
        import matplotlib.pyplot as plt

        state_names, input_names = self.names("state"), self.names("input")
        picks = list(range(self.x.shape[1])) if states is None else [int(i) for i in states]
        for i in picks:
            if not 0 <= i < self.x.shape[1]:
                raise InvalidArgumentError("states", f"indices in [0, {self.x.shape[1]})", repr(list(states)))
        fig, axes = plt.subplots(4, 1, figsize=(8, 9), sharex=True,
                                 gridspec_kw={"height_ratios": [3, 3, 1.5, 1.2]})
        for i in picks:
            axes[0].plot(self.t, self.x[:, i], label=state_names[i])
        axes[0].set_ylabel("state")
        axes[0].legend(loc="best", fontsize="small", ncol=min(3, max(1, len(picks))))
        t_u = self.t[:-1]
        for j, name in enumerate(input_names):
            line, = axes[1].step(t_u, self.u_applied[:, j], where="post", label=f"{name} applied")
            if not np.allclose(self.u_applied[:, j], self.u_cmd[:, j]):
                axes[1].step(t_u, self.u_cmd[:, j], where="post", linestyle=":", color=line.get_color(),
                             label=f"{name} commanded")
        if u_max is not None:
            bound = np.broadcast_to(np.asarray(u_max, dtype=float), (len(input_names),))
            for level in np.unique(bound):
                for sign in (1.0, -1.0):
                    axes[1].axhline(sign * level, color="grey", linestyle="--", linewidth=0.8)
        axes[1].set_ylabel("input")
        axes[1].legend(loc="best", fontsize="small")
        positive = self.solve_time > 0
        axes[2].semilogy(t_u[positive], 1e3 * self.solve_time[positive], ".", markersize=2)
        axes[2].set_ylabel("solve (ms)")
        words = sorted(set(self.status))
        axes[3].plot(t_u, [words.index(s) for s in self.status], "|", markersize=6)
        axes[3].set_yticks(range(len(words)), words, fontsize="small")
        axes[3].set_ylim(-0.5, len(words) - 0.5)
        axes[3].set_ylabel("status")
        axes[3].set_xlabel("time (s)")
        fig.suptitle(f"Closed loop on the {self.plant} plant: {self.n_steps} steps of {self.dt:g} s")
        fig.tight_layout()
        return fig

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
