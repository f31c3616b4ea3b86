"""Static command-filtered backstepping ("BS") for the MRP satellite of paper M.

Farrell, Polycarpou, Sharma & Dong, "Command filtered backstepping", IEEE Trans. Automatic
Control 54(6), 2009, applied as in paper M
(structure **certain**, paper M's equations 51, 52 and 56 survive; details **likely**).

Strict-feedback form: ``x1 = se`` (the MRP error, :func:`models.attitude.mrp.mrp_error`), ``x2 = w``,
``u = Tc``; ``x1' = f1 + g1 x2`` with ``g1 = N(se)``, ``f1 = n N(se) c2(sigma)``, and
``x2' = f2 + J0^-1 u + d``. With ``C1 = c1 I``, ``C2 = c2 I``::

    z1 = se;   alpha1 = -N(se)^-1 C1 se - n c2(sigma) = -4 c1 se / (1 + |se|^2) - n c2(sigma)
    x0 = alpha1 - chi2;   (x_c, x_c') = filter(x0);   z2 = w - x_c
    zb1 = z1 - chi1;   zb2 = z2 - chi2
    u0 = w x J0 w + J0 (x_c' - C2 z2 - N(se)' zb1);   u = sat(u0)
    chi1' = -C1 chi1 + N(se) (x_c - x0);   chi2' = -C2 chi2 + J0^-1 (u - u0);   chi(0) = 0

With ``V = (|zb1|^2 + |zb2|^2) / 2``, ``J = J0`` and ``d = 0``:
``zb1' = -C1 zb1 + N zb2``, ``zb2' = -C2 zb2 - N' zb1`` and ``V' = -c1 |zb1|^2 - c2 |zb2|^2``
whatever the filter and the clip do (**certain**). With ``d != 0``, ``V'`` gains ``zb2' d``:
boundedness only, a steady error under paper M's disk. Gains ``c1 = 0.5``, ``c2 = 2`` 1/s
(**assumed**; keep ``c1`` well below the filter's ``wn``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from models import MRPSatellite
from models.attitude.vectors import cross3
from models.mrp.tracking import MRPTrackingError, tracking_error
from rmpc.laws.continuous import ContinuousTimeController, LawOutput
from rmpc.laws.mrp.command_filter import CommandFilter
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import as_vector, check_positive

__all__ = ["CFBackstepping"]


@dataclass(frozen=True)
class _Pieces:
    """The law's intermediate signals at one ``(x, z)``."""

    alpha1: np.ndarray
    x0: np.ndarray
    z2: np.ndarray
    zb1: np.ndarray
    zb2: np.ndarray
    u0: np.ndarray


class CFBackstepping(ContinuousTimeController):
    """Command-filtered backstepping on ``x = [sigma, w]`` of :class:`models.MRPSatellite`.

    Parameters
    ----------
    plant : MRPSatellite
        The controller's model: its inertia is ``J0`` and its orbit rate ``n``. The simulated
        satellite may differ (paper M's M3 simulates ``1.3 J0``).
    target : (3,) array_like, optional
        The target attitude, an MRP relative to the orbital frame, fixed there (default 0).
    c1, c2 : float
        Backstepping gains (1/s), > 0. Defaults 0.5 and 2 (**assumed**).
    command_filter : CommandFilter, optional
        The filter of the virtual rate (default ``CommandFilter(2.0, 0.5)``, paper M's
        ``wn = 2`` rad/s and ``zeta = 0.5``, no clips). Only its :meth:`~CommandFilter.derivative`
        is used; the controller integrates it with its own ``dt``.
    dt : float
        Sample time (s) of :meth:`step` (paper M's was lost; **assumed**).
    u_max : float, (3,) array_like or None
        Per-axis torque limit (N m); the clipped torque enters ``chi2``. Default none.

    Notes
    -----
    Internal state ``z = [q1, q2, chi1, chi2]`` (12 entries): the filter state and the
    compensating signals. At the first sample ``q1 = S_M(x0)``, ``q2 = 0``, ``chi = 0``
    (**assumed**). ``last.extra`` holds ``"attitude_error"`` (``se``), ``"error_angle"``
    (rad), ``"filter_input"`` (``x0``), ``"filter_output"`` (``x_c``), ``"filter_rate"``
    (``x_c'``), ``"chi1"``, ``"chi2"`` and ``"u_unclipped"`` (``u0``).

    Shadow sets (paper M never mentions them): ``se`` is always the short set, so
    at an error of 180 deg ``se``, ``alpha1`` and the filter input jump while the filter
    output stays continuous; ``chi1`` is not remapped.

    Examples
    --------
    >>> import numpy as np
    >>> from models import MRPSatellite, paper_m_scenario
    >>> from rmpc import CFBackstepping, simulate
    >>> from rmpc.sim.plants import SampledPlant
    >>> m1 = paper_m_scenario("M1")
    >>> bs = CFBackstepping(m1.model(), target=m1.sigma_ref, dt=0.05)
    >>> plant = SampledPlant(m1.true_satellite(), 0.05, integrator="RK4")
    >>> traj = simulate(bs, plant, m1.initial_state(), duration=20.0)
    >>> bool(np.degrees(traj.info[-1].extra["error_angle"]) < 0.1)
    True
    """

    name = "BS"

    def __init__(
        self,
        plant: MRPSatellite,
        target: ArrayLike | None = None,
        *,
        c1: float = 0.5,
        c2: float = 2.0,
        command_filter: CommandFilter | None = None,
        dt: float = 0.01,
        u_max: ArrayLike | None = None,
    ) -> None:
        super().__init__(dt, u_max)
        if not isinstance(plant, MRPSatellite):
            raise ArgumentTypeError("plant", "a models.MRPSatellite", type(plant).__name__)
        self.plant = plant
        self._j0 = plant.inertia
        self._j0_inv = plant.inertia_inv
        self.mean_motion = plant.mean_motion
        self.target = np.zeros(3) if target is None else as_vector(target, "target", 3).copy()
        self.target.setflags(write=False)
        self.c1 = check_positive(c1, "c1")
        self.c2 = check_positive(c2, "c2")
        if command_filter is None:
            command_filter = CommandFilter(2.0, 0.5, size=3, dt=self.dt)
        if not isinstance(command_filter, CommandFilter):
            found = type(command_filter).__name__
            raise ArgumentTypeError("command_filter", "None or an rmpc.CommandFilter", found)
        if command_filter.size != 3:
            found = f"size {command_filter.size}"
            raise InvalidArgumentError("command_filter", "a filter of size 3 (a body rate)", found)
        self.command_filter = command_filter
        self.n_internal = 12

    def __repr__(self) -> str:
        return f"{type(self).__name__}(c1={self.c1!r}, c2={self.c2!r}, dt={self.dt!r}, u_max={self.u_max})"

    def settings(self) -> dict[str, Any]:
        """Every parameter, for reports (gains, filter, sample time, limit, model, target)."""
        out = super().settings()
        out.update(
            c1=self.c1, c2=self.c2, target=self.target.tolist(),
            model_inertia=self._j0.tolist(), mean_motion=self.mean_motion,
            command_filter=self.command_filter.settings(),
        )
        return out

    # -- the law -----------------------------------------------------------------------------------
    def _geometry(self, x: np.ndarray) -> MRPTrackingError:
        return tracking_error(x, self.target, self.mean_motion)

    def virtual_rate(self, error: MRPTrackingError) -> np.ndarray:
        """``alpha1 = -N(se)^-1 C1 se - n c2(sigma) = -4 c1 se / (1 + |se|^2) - n c2``."""
        se = error.se
        return -4.0 * self.c1 * se / (1.0 + float(se @ se)) - self.mean_motion * error.c2

    def _extra_torque(self, x: np.ndarray, z: np.ndarray, zb2: np.ndarray) -> np.ndarray | None:
        """Terms a subclass adds to ``u0`` (MAB: damping and the estimate); none here."""
        return None

    def _pieces(self, x: np.ndarray, z: np.ndarray, g: MRPTrackingError) -> _Pieces:
        w = x[3:6]
        q1, q2, chi1, chi2 = z[0:3], z[3:6], z[6:9], z[9:12]
        alpha1 = self.virtual_rate(g)
        z2 = w - q1
        zb1 = g.se - chi1
        zb2 = z2 - chi2
        u0 = cross3(w, self._j0 @ w) + self._j0 @ (q2 - self.c2 * z2 - g.kinematics.T @ zb1)
        extra = self._extra_torque(x, z, zb2)
        if extra is not None:
            u0 = u0 + extra
        return _Pieces(alpha1=alpha1, x0=alpha1 - chi2, z2=z2, zb1=zb1, zb2=zb2, u0=u0)

    def initial_internal(self, x: ArrayLike) -> np.ndarray:
        """``[S_M(alpha1(x)), 0, 0, 0]``: the filter at rest on its first input, ``chi = 0``."""
        x = as_vector(x, "x", 6)
        alpha1 = self.virtual_rate(self._geometry(x))
        return np.concatenate((self.command_filter.initial_state(alpha1), np.zeros(6)))

    def _evaluate(self, x: np.ndarray, z: np.ndarray, g: MRPTrackingError) -> LawOutput:
        p = self._pieces(x, z, g)
        u = self._clip(p.u0)
        extra = {
            "attitude_error": g.se.copy(),
            "error_angle": 4.0 * float(np.arctan(np.linalg.norm(g.se))),
            "filter_input": p.x0,
            "filter_output": z[0:3].copy(),
            "filter_rate": z[3:6].copy(),
            "chi1": z[6:9].copy(),
            "chi2": z[9:12].copy(),
            "u_unclipped": p.u0,
        }
        return LawOutput(u=u, u_unclipped=p.u0, extra=extra)

    def _derivative(self, x: np.ndarray, z: np.ndarray, u: np.ndarray, g: MRPTrackingError) -> np.ndarray:
        p = self._pieces(x, z, g)
        q_dot = self.command_filter.derivative(z[0:6], p.x0)
        chi1_dot = -self.c1 * z[6:9] + g.kinematics @ (z[0:3] - p.x0)
        chi2_dot = -self.c2 * z[9:12] + self._j0_inv @ (u - p.u0)
        return np.concatenate((q_dot, chi1_dot, chi2_dot))

    # -- analysis ----------------------------------------------------------------------------------
    def compensated_errors(self, x: ArrayLike, z: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """``(zb1, zb2)``: the tracking errors with the filter's effect removed."""
        x, z = self._checked(x, z)
        p = self._pieces(x, z, self._geometry(x))
        return p.zb1, p.zb2

    def lyapunov(self, x: ArrayLike, z: ArrayLike) -> float:
        """``V = (|zb1|^2 + |zb2|^2) / 2``."""
        zb1, zb2 = self.compensated_errors(x, z)
        return 0.5 * float(zb1 @ zb1 + zb2 @ zb2)
