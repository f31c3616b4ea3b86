"""Discrete-time LQR state feedback, the reference controller (gain from python-control)."""

from __future__ import annotations

import time
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from models import PolytopicModel
from rmpc.controller import Status, StepInfo, StepInputs, check_step_inputs
from rmpc.io.design import Design, encode, plant_design
from rmpc.io.saveable import Saveable
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.validation import as_matrix, as_vector, check_pd, check_psd

__all__ = ["LQR"]


class LQR(Saveable):
    """Infinite-horizon discrete LQR, ``u = F (x - x_ref)`` with ``F = -K`` from ``control.dlqr``.

    Parameters
    ----------
    plant : PolytopicModel
        The model; the gain is designed on its nominal model or on one vertex.
    Q : (n, n) array_like
        State weight, symmetric positive semidefinite.
    R : (m, m) array_like
        Input weight, symmetric positive definite.
    vertex : int, optional
        Design on this vertex instead of the nominal model.
    x_ref : (n,) array_like, optional
        Reference state (default: the origin).

    Attributes
    ----------
    name : str
        ``"LQR"``, the short name in reports.
    last : StepInfo or None
        The last step: status ``"ok"`` (a fixed gain, nothing solved), ``solve_time`` the
        step's wall time.

    Examples
    --------
    >>> import numpy as np
    >>> from models import RigidSatellite
    >>> from rmpc import LQR
    >>> sat = RigidSatellite.paper_p()
    >>> lqr = LQR(sat.linear_model(sat.initial_state(), 0.01), Q=np.eye(6), R=np.eye(3))
    >>> lqr.F.shape
    (3, 6)
    >>> u = lqr.step(sat.initial_state())
    >>> lqr.last.status
    'ok'
    """

    name = "LQR"
    accepts: ClassVar[frozenset[str]] = frozenset()

    def __init__(
        self,
        plant: PolytopicModel,
        Q: ArrayLike,
        R: ArrayLike,
        vertex: int | None = None,
        x_ref: ArrayLike | None = None,
    ) -> None:
        if not isinstance(plant, PolytopicModel):
            raise ArgumentTypeError("plant", "a models.PolytopicModel", type(plant).__name__)
        n, m = plant.n_states, plant.n_inputs
        self.Q = check_psd(as_matrix(Q, "Q", (n, n)), "Q")
        self.R = check_pd(as_matrix(R, "R", (m, m)), "R")
        if vertex is not None and (
            isinstance(vertex, bool)
            or not isinstance(vertex, int | np.integer)
            or not 0 <= vertex < plant.n_vertices
        ):
            raise InvalidArgumentError(
                "vertex", f"None or an integer in [0, {plant.n_vertices - 1}]", repr(vertex)
            )
        a, b = plant.nominal if vertex is None else plant.vertex(vertex)
        import control  # with matplotlib, ~2 s: imported on first use

        try:
            k, s, _ = control.dlqr(a, b, self.Q, self.R)
        except (ValueError, np.linalg.LinAlgError) as err:
            raise InvalidArgumentError(
                "plant", "a stabilisable (A, B) with detectable (Q, A)", f"dlqr failed: {err}"
            ) from None
        # C order, as a loaded controller's gain: BLAS may round a product differently by layout
        self._set(plant, vertex, np.ascontiguousarray(k), np.ascontiguousarray(s), x_ref)

    def _set(self, plant: PolytopicModel, vertex: int | None, k: np.ndarray, s: np.ndarray,
             x_ref: ArrayLike | None) -> None:
        n = plant.n_states
        self.plant, self.vertex = plant, None if vertex is None else int(vertex)
        self.K = k
        self.P = s
        self.F = -self.K
        self.dt = plant.dt
        self.x_ref = np.zeros(n) if x_ref is None else as_vector(x_ref, "x_ref", n)
        self._n = n
        self.last: StepInfo | None = None

    # -- save and load ---------------------------------------------------------------------
    def _design(self) -> dict[str, Any]:
        """The plant, the weights, the vertex, the reference and the gain with its Riccati solution."""
        return {"plant": plant_design(self.plant), **encode(
            {"Q": self.Q, "R": self.R, "vertex": self.vertex, "x_ref": self.x_ref, "K": self.K, "P": self.P},
            "LQR design")}

    @classmethod
    def _from_design(cls, design: Design) -> LQR:
        """The saved gain as it was (no Riccati equation solved again)."""
        plant = design.plant()
        n, m = plant.n_states, plant.n_inputs
        ctrl = cls.__new__(cls)
        ctrl.Q = check_psd(as_matrix(design.array("Q"), "design.Q", (n, n)), "design.Q")
        ctrl.R = check_pd(as_matrix(design.array("R"), "design.R", (m, m)), "design.R")
        k = as_matrix(design.array("K"), "design.K", (m, n))
        s = as_matrix(design.array("P"), "design.P", (n, n))
        ctrl._set(plant, design.optional_integer("vertex"), k, s, design.array("x_ref", 1))
        return ctrl

    def reset(self) -> None:
        """Nothing to forget but the last step's info."""
        self.last = None

    def step(self, x: ArrayLike, inputs: StepInputs | None = None) -> np.ndarray:
        """Return ``F (x - x_ref)``; ``last.status`` is ``"ok"`` (a fixed gain: nothing is solved)."""
        start = time.perf_counter()
        check_step_inputs(inputs, self.accepts, self.name)
        x = as_vector(x, "x", self._n)
        u = self.F @ (x - self.x_ref)
        self.last = StepInfo(status=Status.OK, solve_time=time.perf_counter() - start)
        return u
