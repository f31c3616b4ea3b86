"""An attitude law and a vibration law run together on a flexible satellite (paper V's hybrid).

Paper V runs its attitude SMC and its PZT vibration control (AVC) at the same time; the
toolkit fixes the order (**assumed**): each sample the vibration
law computes the PZT command ``v`` first, then the attitude law its hub torque given ``v`` (it
cancels the reaction of ``Gamma_a v`` on the hub), and the plant gets ``[u; v]``.
"""

from __future__ import annotations

import time
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from rmpc.controller import Status, StepInfo, StepInputs, check_step_inputs
from toolkit_common.errors import ArgumentTypeError

__all__ = ["FlexibleHybrid"]


class FlexibleHybrid:
    """Attitude control plus (optional) PZT vibration control, one ``step(x)``.

    Parameters
    ----------
    attitude : Controller
        The attitude law, returning ``[u; v]``. A law whose ``accepts`` holds ``"pzt"``
        (:class:`~rmpc.MTSMC`, :class:`~rmpc.CSMC`, :class:`~rmpc.AttitudePD`,
        :class:`~rmpc.AdaptiveSMC`) gets this sample's PZT command through the step channel,
        ``step(x, StepInputs(pzt=v))``, and cancels its reaction on the hub (PD passes it
        through). Any other law
        (:func:`~rmpc.flexible_lqr`, or one without ``accepts``) is called with ``x`` alone and
        its PZT entries are replaced by ``v``.
    vibration : Controller, optional
        The vibration law: ``step(x)`` returning ``[0; v]`` (:class:`~rmpc.RobustAVC`);
        ``None`` runs the attitude law alone with ``v = 0``.

    Attributes
    ----------
    name : str
        The record name: the attitude law's ``name`` (or class name), ``"+AVC"`` appended with
        vibration control (``"MTSMC"``, ``"CSMC+AVC"``, ``"PD-DOB+AVC"``, ``"LQR+AVC"``).
    accepts : frozenset of str
        None: the hybrid makes the PZT command itself.
    last : StepInfo or None
        The first status of the two laws that is not ``"ok"`` (else ``"ok"``), ``fallback``
        when either law fell back, and both laws' ``extra``.

    Examples
    --------
    >>> from models import FlexibleSatellite
    >>> from rmpc import CSMC, FlexibleHybrid, RobustAVC
    >>> sat = FlexibleSatellite.di_gennaro()
    >>> ctrl = FlexibleHybrid(CSMC(sat, switch="tanh"), RobustAVC(sat))
    >>> ctrl.name, ctrl.step(sat.state(modal=[0.01, 0, 0, 0])).shape
    ('CSMC+AVC', (7,))
    """

    accepts: ClassVar[frozenset[str]] = frozenset()

    def __init__(self, attitude: ArrayLike, vibration: Any = None) -> None:
        if not callable(getattr(attitude, "step", None)):
            expected = "a controller with step(x, inputs=None)"
            raise ArgumentTypeError("attitude", expected, type(attitude).__name__)
        if vibration is not None and not callable(getattr(vibration, "step", None)):
            expected = "None or a controller with step(x)"
            raise ArgumentTypeError("vibration", expected, type(vibration).__name__)
        self._takes_pzt = "pzt" in getattr(attitude, "accepts", frozenset())
        self.attitude = attitude
        self.vibration = vibration
        base = getattr(attitude, "name", None) or type(attitude).__name__
        self.name = base + ("" if vibration is None else "+AVC")
        self.last: StepInfo | None = None

    def reset(self) -> None:
        """Reset both laws."""
        self.attitude.reset()
        if self.vibration is not None:
            self.vibration.reset()
        self.last = None

    def step(self, x: ArrayLike, inputs: StepInputs | None = None) -> np.ndarray:
        """Return ``[u; v]``: ``v`` from the vibration law, then ``u`` given ``v``."""
        start = time.perf_counter()
        check_step_inputs(inputs, self.accepts, self.name)
        v = None
        extra: dict[str, Any] = {}
        if self.vibration is not None:
            out = np.asarray(self.vibration.step(x), dtype=float)
            v = out[3:]
            extra.update(getattr(self.vibration.last, "extra", {}) or {})
        if self._takes_pzt and v is not None:
            u = np.asarray(self.attitude.step(x, StepInputs(pzt=v)), dtype=float)
        else:
            u = np.array(self.attitude.step(x), dtype=float)
            if v is not None:
                u[3:] = v
        extra.update(getattr(self.attitude.last, "extra", {}) or {})
        laws = [c for c in (self.attitude, self.vibration) if c is not None]
        statuses = [getattr(c.last, "status", Status.OK) for c in laws]
        status = next((s for s in statuses if s != Status.OK), Status.OK)
        fallback = any(bool(getattr(c.last, "fallback", False)) for c in laws)
        self.last = StepInfo(
            status=status, solve_time=time.perf_counter() - start, fallback=fallback, extra=extra
        )
        return u

    def __repr__(self) -> str:
        return f"FlexibleHybrid(attitude={self.attitude!r}, vibration={self.vibration!r})"
