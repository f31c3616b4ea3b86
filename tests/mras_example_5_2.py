"""Astrom & Wittenmark's example 5.2 (Adaptive Control, 2nd ed.): the textbook check of the MIT rule.

A reproduction for the tests of :class:`rmpc.mpc.adaptation.MITRule` (its rate),
:class:`~rmpc.mpc.mras.ParameterIntegrator` and :class:`~rmpc.mpc.mras.SensitivityFilter` (the
outside reference of the MIT rule): the
adaptation of a feedforward and a feedback gain for a first-order plant, whose gains converge to
4 and 2.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from rmpc.mpc.adaptation import MITRule
from rmpc.mpc.mras import ParameterIntegrator, SensitivityFilter
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import check_positive, check_real

#: The gains of example 5.2 at convergence, ``(theta1, theta2) = (bm / b, (am - a) / b)``
#: for ``u = theta1 uc - theta2 y``; in the form ``u = theta1 uc + k_y y`` (python-control's
#: ``kx``) the feedback gain is ``k_y = -theta2 = -2``.
EXAMPLE_5_2_GAINS: tuple[float, float] = (4.0, 2.0)


@dataclass(frozen=True)
class Example52Result:
    """A run of :func:`example_5_2`.

    Attributes
    ----------
    t : (N + 1,) ndarray
        Sample times (s).
    uc : (N + 1,) ndarray
        The command (square wave).
    y, ym : (N + 1,) ndarray
        Plant and reference-model outputs.
    u : (N + 1,) ndarray
        The control ``u = theta1 uc - theta2 y`` (the last entry is computed, not applied).
    theta : (N + 1, 2) ndarray
        ``[theta1, theta2]`` at each sample (Astrom & Wittenmark's sign convention).
    target : tuple of float
        The ideal gains of the continuous-time loop, ``(bm / b, (am - a) / b)``.
    target_sampled : tuple of float
        The gains that match the sampled plant to the sampled model exactly (zero-order
        hold at ``dt``): ``(bm_d / b_d, (a_d - am_d) / b_d)`` with ``y(k+1) = a_d y(k) +
        b_d u(k)`` and ``ym(k+1) = am_d ym(k) + bm_d uc(k)``. They differ from ``target`` by
        ``O(dt)`` (3.980 and 1.980 at ``dt = 0.01``); this is where the sampled loop converges.
    gamma, dt : float
        Adaptation gain and sample time.
    normalized : bool
        Whether the normalised MIT rule was used.
    """

    t: np.ndarray
    uc: np.ndarray
    y: np.ndarray
    ym: np.ndarray
    u: np.ndarray
    theta: np.ndarray
    target: tuple[float, float]
    target_sampled: tuple[float, float]
    gamma: float
    dt: float
    normalized: bool

    def settling_time(self, tol: float, sampled: bool = False) -> float:
        """The first time after which both gains stay within ``tol`` of the target (inf if never).

        ``sampled=True`` measures against ``target_sampled`` instead of ``target``.
        """
        target = self.target_sampled if sampled else self.target
        err = np.max(np.abs(self.theta - np.asarray(target)), axis=1)
        outside = np.nonzero(err > tol)[0]
        if outside.size == 0:
            return float(self.t[0])
        last = int(outside[-1])
        return float("inf") if last == err.size - 1 else float(self.t[last + 1])


def example_5_2(
    gamma: float = 1.0,
    duration: float = 100.0,
    *,
    dt: float = 0.01,
    period: float = 20.0,
    amplitude: float = 1.0,
    normalized: bool = False,
    alpha: float = 0.01,
    a: float = 1.0,
    b: float = 0.5,
    am: float = 2.0,
    bm: float = 2.0,
    theta0: Any = (0.0, 0.0),
) -> Example52Result:
    """Astrom & Wittenmark's example 5.2: MIT-rule adaptation of a feedforward and a feedback gain.

    Plant ``y' = -a y + b u``, reference model ``ym' = -am ym + bm uc``, controller
    ``u = theta1 uc - theta2 y`` and ``e = y - ym``. With ``theta`` frozen the closed loop is
    ``y = b theta1 / (p + a + b theta2) uc``, so::

        de/dtheta1 =  b / (p + a + b theta2) uc   ~  (b / am) * am / (p + am) uc
        de/dtheta2 = -b / (p + a + b theta2) y    ~ -(b / am) * am / (p + am) y

    where the approximation replaces the unknown closed-loop pole by the model's ``am`` (the
    book's choice) and the unknown ``b / am`` is absorbed into ``gamma``. The MIT rule is then
    ``dtheta1/dt = -gamma e (am / (p + am)) uc``, ``dtheta2/dt = gamma e (am / (p + am)) y``,
    and the gains converge to ``theta1 = bm / b = 4`` and ``theta2 = (am - a) / b = 2``
    (:data:`EXAMPLE_5_2_GAINS`).

    Discretisation: the plant, the model and the two filters ``am / (p + am)`` are sampled
    exactly with a zero-order hold at ``dt``; the control is held over each sample; the
    gains follow :meth:`MITRule.rate`, integrated by a :class:`ParameterIntegrator`
    (``Ts / (1 - z^-1)``).

    Parameters
    ----------
    gamma : float
        Adaptation gain (the book shows 0.2, 1 and 5).
    duration : float
        Simulated time (s).
    dt : float
        Sample time (s).
    period, amplitude : float
        The command ``uc`` is a square wave of this period (s) and amplitude, ``+amplitude``
        over the first half period.
    normalized : bool
        Use the normalised MIT rule with regularisation ``alpha``.
    a, b, am, bm : float
        Plant and model parameters (the book's 1, 0.5, 2, 2).
    theta0 : array_like
        Initial gains.

    Returns
    -------
    Example52Result

    Examples
    --------
    >>> from mras_example_5_2 import example_5_2
    >>> run = example_5_2(gamma=5.0, duration=200.0)
    >>> [round(float(g), 3) for g in run.theta[-1]]
    [3.98, 1.98]
    >>> [round(g, 3) for g in run.target], [round(g, 3) for g in run.target_sampled]
    ([4.0, 2.0], [3.98, 1.98])
    """
    gamma = check_positive(gamma, "gamma", allow_zero=True)
    duration = check_positive(duration, "duration")
    dt = check_positive(dt, "dt")
    period = check_positive(period, "period")
    amplitude = check_real(amplitude, "amplitude")
    a = check_real(a, "a")
    b = check_real(b, "b")
    if b == 0.0:
        raise InvalidArgumentError("b", "a non-zero input gain", "0.0")
    am = check_positive(am, "am")
    bm = check_real(bm, "bm")
    n_steps = round(duration / dt)
    if n_steps < 1:
        raise InvalidArgumentError("duration", f"at least one sample of dt = {dt:g}", repr(duration))

    plant_a = float(np.exp(-a * dt))
    plant_b = b * dt if a == 0.0 else b * (1.0 - plant_a) / a
    model_a = float(np.exp(-am * dt))
    model_b = bm * (1.0 - model_a) / am
    rule = MITRule(gamma, normalized=normalized, alpha=alpha)
    gains = ParameterIntegrator(2, dt, theta0=theta0)
    filt_uc = SensitivityFilter.first_order(am, dt)
    filt_y = SensitivityFilter.first_order(am, dt)

    sens = np.zeros((1, 2))
    t = np.arange(n_steps + 1) * dt
    uc = np.where(np.mod(t, period) < 0.5 * period, amplitude, -amplitude)
    y = np.zeros(n_steps + 1)
    ym = np.zeros(n_steps + 1)
    u = np.zeros(n_steps + 1)
    theta = np.zeros((n_steps + 1, 2))
    for k in range(n_steps + 1):
        if k > 0:
            # The sensitivities of e(k): filtered uc and y up to k - 1, with their signs.
            sens[0, 0] = filt_uc.c[0, 0] * filt_uc._state[0]
            sens[0, 1] = -filt_y.c[0, 0] * filt_y._state[0]
            gains._integrate(rule._rate(np.array([y[k] - ym[k]]), sens))
        theta[k] = gains._theta
        u[k] = theta[k, 0] * uc[k] - theta[k, 1] * y[k]
        if k == n_steps:
            break
        y[k + 1] = plant_a * y[k] + plant_b * u[k]
        ym[k + 1] = model_a * ym[k] + model_b * uc[k]
        filt_uc._state = filt_uc.a @ filt_uc._state + filt_uc.b[:, 0] * uc[k]
        filt_y._state = filt_y.a @ filt_y._state + filt_y.b[:, 0] * y[k]
    return Example52Result(
        t=t, uc=uc, y=y, ym=ym, u=u, theta=theta, target=(bm / b, (am - a) / b),
        target_sampled=(model_b / plant_b, (plant_a - model_a) / plant_b),
        gamma=gamma, dt=dt, normalized=bool(normalized),
    )
