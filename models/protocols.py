"""The protocols every plant of the toolkit follows: :class:`Plant` and :class:`InputStage`.

A *plant* is a continuous-time model ``x' = f(x, u, d)``: paper P's rigid satellite, paper W's
wheel satellite, paper M's satellite in MRPs, the flexible satellite, or a user's own. The
simulator (:func:`rmpc.simulate`) integrates any object that follows :class:`Plant`; reports
read its attitude through :meth:`Plant.attitude_euler`, whatever the attitude representation
of its state (Euler angles, a quaternion, MRPs).

An *input stage* models what happens to the held command inside the actuators while the plant
moves (faults, per-actuator limits, actuator noise); the simulator calls it inside the
integration.

Examples
--------
>>> from models import FlexibleSatellite, MRPSatellite, RigidSatellite, WheelSatellite
>>> from models.protocols import Plant
>>> sats = (RigidSatellite.paper_p(), WheelSatellite.paper_w(), MRPSatellite.paper_m(),
...         FlexibleSatellite.di_gennaro())
>>> all(isinstance(sat, Plant) for sat in sats)
True
>>> [(sat.n_states, sat.n_inputs) for sat in sats]
[(6, 3), (10, 4), (6, 3), (15, 7)]
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import as_matrix, as_vector

__all__ = ["InputStage", "Plant", "map_states"]


@runtime_checkable
class Plant(Protocol):
    """A continuous-time plant ``x' = dynamics(x, u, d)``.

    Attributes
    ----------
    n_states, n_inputs : int
        Sizes of ``x`` and ``u``.
    state_names, input_names : tuple of str
        One name per state and per input, for reports and plots.

    Notes
    -----
    Optional members, used when present:

    - ``n_disturbances`` (int): the size of ``d`` (default ``n_inputs``);
    - ``normalize_state(x) -> x``: applied by the integrators after every step (the MRP
      shadow-set switch, the renormalisation of a quaternion);
    - ``dynamics_unchecked(x, u, d) -> x'``: the same right-hand side without argument checks,
      for the inner loop of an integrator, which calls it thousands of times per run; ``x``
      and ``u`` are finite float arrays of sizes ``n_states`` and ``n_inputs``, ``d`` is
      ``None`` or of size ``n_disturbances``;
    - ``second_order_layout`` (mapping of ``"quaternion"``, ``"rate"``, ``"position"``,
      ``"velocity"`` to index slices): the second-order structure Newmark-beta needs
      (:class:`rmpc.sim.integrators.Newmark`).
    """

    n_states: int
    n_inputs: int
    state_names: tuple[str, ...]
    input_names: tuple[str, ...]

    def dynamics(
        self,
        x: ArrayLike,
        u: ArrayLike | None = None,
        d: ArrayLike | None = None,
    ) -> np.ndarray:  # pragma: no cover
        """The state derivative at ``x`` with input ``u`` and disturbance ``d`` (both default zero)."""
        ...

    def attitude_euler(self, x: ArrayLike) -> np.ndarray:  # pragma: no cover
        """Roll, pitch and yaw (rad, 3-2-1 sequence) of the attitude held in the state ``x``.

        ``x`` is one state ``(n_states,)`` (the result has shape ``(3,)``) or a trajectory of
        states, one per row, ``(k, n_states)`` (the result ``(k, 3)``). The plant's docstring
        says which frame the angles are relative to.
        """
        ...


@runtime_checkable
class InputStage(Protocol):
    """What the actuators do to the held command while the plant moves (faults, limits, noise).

    ``stage(t, x, u)`` returns the input the plant receives at time ``t`` in state ``x`` when
    ``u`` is the held command of the current sample. It must be a pure function of its
    arguments and of the stage's per-sample state, since the integrator calls it many times per
    sample. Optional methods, used when present:

    - ``reset()``: called by :func:`~rmpc.simulate` before a run (re-seed noise, clear state);
    - ``begin_sample(t, x, u) -> dict``: called once at the start of each sample, before the
      integration (draw this sample's noise, say); the returned mapping of names to arrays or
      numbers is logged per sample in :attr:`rmpc.Trajectory.stage_log`.
    """

    def __call__(self, t: float, x: np.ndarray, u: np.ndarray) -> np.ndarray:  # pragma: no cover
        ...


def map_states(convert: Callable[[np.ndarray], np.ndarray], x: ArrayLike, n_states: int) -> np.ndarray:
    """Apply ``convert`` (one state to a vector) to one state or to every row of a trajectory.

    The shared body of the plants' :meth:`Plant.attitude_euler`.

    Parameters
    ----------
    convert : callable
        Maps one checked state ``(n_states,)`` to a result vector.
    x : array_like, shape (n_states,) or (k, n_states)
        One state, or ``k`` states as rows.
    n_states : int
        The plant's state size.

    Returns
    -------
    ndarray
        ``convert(x)`` for one state; the results stacked as rows for a trajectory.

    Raises
    ------
    InvalidArgumentError
        Naming ``x`` on a wrong width, more than two dimensions, NaN or inf.

    Examples
    --------
    >>> import numpy as np
    >>> from models.protocols import map_states
    >>> map_states(lambda s: s[:2], np.arange(6.0).reshape(2, 3), 3).tolist()
    [[0.0, 1.0], [3.0, 4.0]]
    """
    try:
        ndim = 2 if isinstance(x, str | bytes) else np.ndim(x)
    except ValueError:  # ragged: as_matrix names it
        ndim = 2
    if ndim == 1:
        return convert(as_vector(x, "x", n_states))
    if ndim != 2:
        raise InvalidArgumentError(
            "x", f"one state of length {n_states} or a (k, {n_states}) array of states", f"{ndim}-D input"
        )
    rows = as_matrix(x, "x", (None, n_states))
    return np.array([convert(row) for row in rows]).reshape(rows.shape[0], -1)
