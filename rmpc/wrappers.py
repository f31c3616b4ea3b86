"""Controllers built from other controllers.

:class:`MappedController` lets a controller designed on a reduced or transformed state run on
a plant whose state is larger or expressed differently: a robust MPC designed on attitude and
rates (6 states) on the wheel satellite (rates plus four wheel momenta), or on the Euler
angles of an MRP error. It maps the measured state, calls the inner controller and, optionally,
maps its output.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from rmpc.controller import Controller, StepInputs, check_step_inputs
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError

__all__ = ["MappedController"]


class MappedController:
    """Run ``controller`` on ``measure(x)`` and return ``output(u)`` (the ``step(x)`` protocol).

    Parameters
    ----------
    controller : Controller
        The inner controller (at least ``step``; ``reset``, ``last``, ``name`` and ``accepts``
        are used when it has them).
    measure : sequence of int or callable
        Indices of the states the inner controller sees (``x[indices]``), or a function
        ``measure(x) -> z``. An object with a ``reset()`` method is reset with the controller.
    output : callable, optional
        ``output(u) -> u_plant`` applied to the inner controller's output (default: none).
    name : str, optional
        Short name for reports (default: the inner controller's ``name``, else its class name).

    Attributes
    ----------
    last : object
        The inner controller's ``last`` (its :class:`~rmpc.StepInfo`).
    accepts : frozenset of str
        The inner controller's ``accepts`` (none when it has none): the step inputs are passed
        on unchanged.

    Examples
    --------
    >>> import numpy as np
    >>> from rmpc.wrappers import MappedController
    >>> class Gain:
    ...     last = None
    ...     def reset(self): pass
    ...     def step(self, z): return -2.0 * z
    >>> ctrl = MappedController(Gain(), measure=[0, 2])
    >>> ctrl.step(np.array([1.0, 5.0, 3.0])).tolist()
    [-2.0, -6.0]
    """

    def __init__(
        self,
        controller: Controller,
        measure: Sequence[int] | Callable[[np.ndarray], np.ndarray],
        output: Callable[[np.ndarray], np.ndarray] | None = None,
        name: str | None = None,
    ) -> None:
        if not callable(getattr(controller, "step", None)):
            expected = "an object with a step(x) method"
            raise ArgumentTypeError("controller", expected, type(controller).__name__)
        if callable(measure):
            self._measure: Callable[[np.ndarray], np.ndarray] = measure
            self.indices: np.ndarray | None = None
        else:
            if isinstance(measure, str | bytes):
                raise ArgumentTypeError("measure", "a sequence of state indices or a callable", "a string")
            try:
                idx = np.asarray(measure)
            except (TypeError, ValueError):
                raise ArgumentTypeError(
                    "measure", "a sequence of state indices or a callable", type(measure).__name__
                ) from None
            if idx.ndim != 1 or idx.size == 0 or not np.issubdtype(idx.dtype, np.integer) or np.any(idx < 0):
                raise InvalidArgumentError("measure", "a non-empty list of state indices >= 0", repr(measure))
            self.indices = idx.astype(int)
            self._measure = self._select
        if output is not None and not callable(output):
            raise ArgumentTypeError("output", "None or a callable output(u)", type(output).__name__)
        self._output = output
        self.controller = controller
        self.measure = measure
        self.name = name or getattr(controller, "name", None) or type(controller).__name__
        self.accepts: frozenset[str] = frozenset(getattr(controller, "accepts", frozenset()))

    def _select(self, x: np.ndarray) -> np.ndarray:
        assert self.indices is not None
        if self.indices.max() >= x.shape[0]:
            raise InvalidArgumentError(
                "x", f"a state with more than {int(self.indices.max())} entries", f"{x.shape[0]} entries"
            )
        return x[self.indices]

    @property
    def last(self) -> Any:
        """The inner controller's ``last``."""
        return getattr(self.controller, "last", None)

    def reset(self) -> None:
        """Reset the inner controller (and the measurement map when it has ``reset``)."""
        if callable(getattr(self.controller, "reset", None)):
            self.controller.reset()
        if callable(getattr(self.measure, "reset", None)):
            self.measure.reset()

    def step(self, x: ArrayLike, inputs: StepInputs | None = None) -> np.ndarray:
        """``output(controller.step(measure(x), inputs))`` (``inputs`` only when given)."""
        if inputs is not None:
            check_step_inputs(inputs, self.accepts, self.name)
        z = self._measure(np.asarray(x, dtype=float))
        if inputs is None:
            u = np.asarray(self.controller.step(z), dtype=float)
        else:
            u = np.asarray(self.controller.step(z, inputs), dtype=float)
        return u if self._output is None else np.asarray(self._output(u), dtype=float)

    def __repr__(self) -> str:
        return f"MappedController({self.name})"
