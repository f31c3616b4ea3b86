"""The controller protocol every controller of the toolkit follows, its per-step info and inputs.

A controller is built once, ``reset()`` before a run and called once per sample with the
measured state: ``u = controller.step(x)``. After each call ``controller.last`` is a
:class:`StepInfo` whose ``status`` is a word of the one status vocabulary
(:class:`~toolkit_common.status.Status`, re-exported here).

What a law needs at a sample besides the state goes through one typed channel,
:class:`StepInputs`: ``controller.step(x, StepInputs(pzt=v))`` hands the flexible satellite's
attitude law this sample's piezoelectric command, ``rmpc.step(x, StepInputs(u_max=b))`` gives
robust MPC a bound for this step only. A controller lists the fields it uses in its
``accepts`` attribute; any other field set to a value is an error naming it.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Any, ClassVar, Protocol, runtime_checkable

import numpy as np

from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError
from toolkit_common.status import Status, as_status

__all__ = ["Controller", "Status", "StepInfo", "StepInputs", "check_step_inputs"]


@dataclass(frozen=True)
class StepInfo:
    """What a controller reports about one call of ``step``.

    Attributes
    ----------
    status : Status
        A word of the status vocabulary: ``"optimal"`` or a solver's failure word for a
        controller that solves an optimisation problem, ``"reused"`` when a previous certified
        answer was kept, ``"ok"`` for a law evaluated in closed form (see
        :data:`toolkit_common.status.STATUS_TABLE`). A plain string is converted; a word outside
        the vocabulary is an error.
    solve_time : float
        Time spent in the optimiser during this step (s); for a law without one, the time of
        the step.
    gamma : float or None
        The cost bound of robust MPC, where the controller has one.
    iterations : int or None
        Solver iterations, where reported.
    fallback : bool
        Whether the applied control came from a fallback (an older gain) after a failure.
    extra : dict
        Controller-specific details.
    """

    status: Status
    solve_time: float = 0.0
    gamma: float | None = None
    iterations: int | None = None
    fallback: bool = False
    extra: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "status", as_status(self.status, "StepInfo.status"))


@dataclass(frozen=True)
class StepInputs:
    """What a controller may receive at a sample besides the measured state.

    Attributes
    ----------
    pzt : (n_a,) array_like or None
        This sample's piezoelectric command ``v`` of the flexible satellite (from the vibration
        law); an attitude law that cancels its reaction on the hub uses it.
    u_max : float, array_like or None
        The input bound for this step instead of the controller's own (same kind), e.g. what
        CRMPC's disturbance correction leaves of the torque limit.
    d_hat : (m,) array_like or None
        The estimate of a constant input disturbance (an estimator's ``d_hat``), for a
        controller with offset-free action (:class:`~rmpc.RMPC` with ``offset_free=True``).
    """

    pzt: Any = None
    u_max: Any = None
    d_hat: Any = None

    def given(self) -> tuple[str, ...]:
        """The names of the fields set to a value (not ``None``)."""
        return tuple(f.name for f in fields(self) if getattr(self, f.name) is not None)


def check_step_inputs(inputs: StepInputs | None, accepts: frozenset[str], owner: str) -> StepInputs:
    """Return ``inputs`` (an empty :class:`StepInputs` for ``None``), checking it against ``accepts``.

    Raises
    ------
    ArgumentTypeError
        When ``inputs`` is not a :class:`StepInputs`.
    InvalidArgumentError
        Naming the field when a field outside ``accepts`` is set.
    """
    if inputs is None:
        return _NO_INPUTS
    if not isinstance(inputs, StepInputs):
        raise ArgumentTypeError("inputs", "None or an rmpc.StepInputs", type(inputs).__name__)
    extra = [name for name in inputs.given() if name not in accepts]
    if extra:
        allowed = ", ".join(sorted(accepts)) if accepts else "none"
        raise InvalidArgumentError(
            f"inputs.{extra[0]}", f"only the step inputs {owner} uses ({allowed})",
            f"{extra[0]} set to a value",
        )
    return inputs


_NO_INPUTS = StepInputs()


@runtime_checkable
class Controller(Protocol):
    """The ``step(x)`` protocol.

    A controller is built once, ``reset()`` before a run, and called once per sample with the
    measured state; it returns the control to apply now. After each call ``last`` describes
    that step (see :class:`StepInfo`; its status is a word of the one vocabulary,
    :class:`~toolkit_common.status.Status`); ``name`` is its short name in reports
    (``"RMPC"``, ``"MAB"``, ``"CSMC+AVC"``). ``accepts`` names the :class:`StepInputs` fields
    it uses (a class attribute; a wrapper such as :class:`~rmpc.MappedController` takes its
    inner controller's); ``step`` checks ``inputs`` with :func:`check_step_inputs`, so a field
    outside ``accepts`` is an error naming it.

    Examples
    --------
    >>> import numpy as np
    >>> from models import RigidSatellite
    >>> from rmpc import LQR, Controller, StepInputs
    >>> sat = RigidSatellite.paper_p()
    >>> lqr = LQR(sat.linear_model(sat.initial_state(), 0.01), Q=np.eye(6), R=np.eye(3))
    >>> isinstance(lqr, Controller), lqr.name, lqr.accepts
    (True, 'LQR', frozenset())
    >>> try:
    ...     lqr.step(sat.initial_state(), StepInputs(pzt=[0.1]))
    ... except ValueError as err:
    ...     print(err)
    inputs.pzt: expected only the step inputs LQR uses (none), but found pzt set to a value
    """

    name: str
    last: StepInfo | None
    accepts: ClassVar[frozenset[str]]

    def step(self, x: np.ndarray, inputs: StepInputs | None = None) -> np.ndarray:  # pragma: no cover
        """Return the control to apply for the measured state ``x``."""
        ...

    def reset(self) -> None:  # pragma: no cover - protocol
        """Forget all internal state (memory, adaptation, last solution)."""
        ...
