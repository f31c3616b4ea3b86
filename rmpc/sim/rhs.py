"""The right-hand side of a plant for the integrators: the model's dynamics plus the disturbance.

One helper for every place that integrates a plant: :class:`~rmpc.sim.plants.SampledPlant`
(the closed loop, sampled) and :meth:`rmpc.laws.continuous.ContinuousTimeController.closed_loop_rhs`
(the continuous-time closed loop). It calls the model's optional ``dynamics_unchecked(x, u, d)``
when the model offers one (the same right-hand side without argument checks, for the inner
loop of an integrator; see :class:`models.protocols.Plant`) and ``dynamics(x, u, d)`` otherwise.

Examples
--------
>>> import numpy as np
>>> from models import RigidSatellite
>>> from rmpc import ConstantDisturbance
>>> from rmpc.sim.rhs import model_dynamics, plant_derivative
>>> sat = RigidSatellite.paper_p()
>>> f = model_dynamics(sat)
>>> x, u = sat.initial_state(), np.array([0.1, 0.0, 0.0])
>>> bool(np.array_equal(plant_derivative(f, 0.0, x, u, ConstantDisturbance([0.1, 0.0, 0.0])),
...                     sat.dynamics(x, 2.0 * u)))
True
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from rmpc.sim.disturbances import DisturbanceFn, disturbance_at
from toolkit_common.errors import ArgumentTypeError

__all__ = ["ModelDynamics", "model_dynamics", "plant_derivative"]

#: ``f(x, u, d) -> x'`` of a model (``d`` may be ``None``).
ModelDynamics = Callable[[np.ndarray, np.ndarray, "np.ndarray | None"], np.ndarray]


def model_dynamics(model: Any) -> ModelDynamics:
    """The model's ``dynamics_unchecked`` when it offers one, else its ``dynamics``.

    Raises
    ------
    ArgumentTypeError
        Naming ``plant`` when ``model`` has no ``dynamics(x, u, d=None)``.
    """
    if not callable(getattr(model, "dynamics", None)):
        raise ArgumentTypeError("plant", "a model with dynamics(x, u, d=None)", type(model).__name__)
    fast = getattr(model, "dynamics_unchecked", None)
    return fast if callable(fast) else model.dynamics


def plant_derivative(
    dynamics: ModelDynamics, t: float, x: np.ndarray, u: np.ndarray, disturbance: DisturbanceFn | None
) -> np.ndarray:
    """``x' = dynamics(x, u, d(t, x))`` (``d`` is ``None`` without a disturbance)."""
    d = None if disturbance is None else disturbance_at(disturbance, t, x)
    return dynamics(x, u, d)
