"""Seeded random signals of paper W's runs: the S4 wheel-level disturbance and the attitude sensor noise.

Both draw from their own ``np.random.Generator``, re-created from ``seed`` at every
``reset()``, so two runs with the same seed see the same noise.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from models.wheels.array import MAX_WHEELS, _wheel_count
from toolkit_common.errors import ArgumentTypeError
from toolkit_common.validation import as_positive_values, check_positive, check_real

__all__ = ["ANGLE_NOISE_SIGMA", "AttitudeNoiseSensor", "WheelDisturbance"]

#: Standard deviation of the angle noise, rad: paper W's 0.2 deg accuracy (**certain**) as a 1-sigma
#: Gaussian (**assumed**).
ANGLE_NOISE_SIGMA: float = math.radians(0.2)


def _check_seed(seed: Any) -> int | None:
    if seed is None:
        return None
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ArgumentTypeError("seed", "None or an integer >= 0", f"{type(seed).__name__} {seed!r}")
    return int(seed)


class WheelDisturbance:
    """Paper W's S4 disturbance, added to each wheel's command before faults and limits.

    ``d_j(t) = bias + amplitude sin(2 pi t / period) + v_j``, ``v_j`` zero-mean Gaussian with
    ``variance``, drawn once per control sample (40 ms) and held (the
    formula is **certain** as printed; the variance 0.0052 may be a flattened ``0.005^2 =
    2.5e-5``; where it enters and the redraw are **assumed**).

    Parameters
    ----------
    n_wheels : int
        Number of wheels.
    bias, amplitude : float
        N m (defaults 0.001 and 0.05).
    period : float
        Period of the sinusoid (s, default 800).
    variance : float
        Variance of ``v_j`` ((N m)^2, default 0.0052; 0 turns the noise off).
    seed : int or None
        Seed of the generator (default 0).
    max_wheels : int
        The largest ``n_wheels`` accepted (default :data:`~models.wheels.array.MAX_WHEELS`, 1000);
        a larger one is refused with an error naming this limit. Pass a larger value to lift it.

    Examples
    --------
    >>> from models import WheelDisturbance
    >>> dist = WheelDisturbance(4, variance=0.0, seed=1)
    >>> dist.reset()
    >>> noise = dist.draw()  # zero here: variance 0
    >>> round(float(dist(200.0)[0]), 4)  # 0.001 + 0.05 sin(pi / 2)
    0.051
    """

    def __init__(
        self,
        n_wheels: int,
        bias: float = 0.001,
        amplitude: float = 0.05,
        period: float = 800.0,
        variance: float = 0.0052,
        seed: int | None = 0,
        *,
        max_wheels: int = MAX_WHEELS,
    ) -> None:
        self.n_wheels = _wheel_count(n_wheels, max_wheels)
        self.bias = check_real(bias, "bias")
        self.amplitude = check_real(amplitude, "amplitude")
        self.period = check_positive(period, "period")
        self.variance = check_positive(variance, "variance", allow_zero=True)
        self.seed = _check_seed(seed)
        self._rng = np.random.default_rng(self.seed)
        self._noise = np.zeros(self.n_wheels)

    def reset(self) -> None:
        """Re-seed the generator and clear the held noise."""
        self._rng = np.random.default_rng(self.seed)
        self._noise = np.zeros(self.n_wheels)

    def draw(self) -> np.ndarray:
        """Draw this sample's noise ``v`` (held until the next draw) and return it."""
        if self.variance > 0.0:
            self._noise = self._rng.normal(0.0, math.sqrt(self.variance), self.n_wheels)
        return self._noise.copy()

    def deterministic(self, t: float) -> float:
        """``bias + amplitude sin(2 pi t / period)`` (N m, the same on every wheel)."""
        return self.bias + self.amplitude * math.sin(2.0 * math.pi * t / self.period)

    def __call__(self, t: float) -> np.ndarray:
        """The disturbance per wheel at ``t`` with the held noise."""
        return self.deterministic(t) + self._noise

    def settings(self) -> dict[str, Any]:
        """The parameters, for reports."""
        return {
            "bias": self.bias,
            "amplitude": self.amplitude,
            "period": self.period,
            "variance": self.variance,
            "seed": self.seed,
        }

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v}" for k, v in self.settings().items())
        return f"WheelDisturbance(n_wheels={self.n_wheels}, {args})"


class AttitudeNoiseSensor:
    """Measured state = true state with Gaussian noise on the three Euler angles (no rate noise).

    Paper W's sensors are accurate to 0.2 deg (**certain**); the toolkit's model, Gaussian with
    ``sigma = 0.2`` deg on the angles only, drawn at each sample, is **assumed** and off by
    default (pass it as ``simulate(..., sensor=AttitudeNoiseSensor())``).

    Parameters
    ----------
    sigma : float or (3,) array_like
        Standard deviation per angle (rad, default ``radians(0.2)``).
    seed : int or None
        Seed of the generator (default 0); re-used at every :meth:`reset`.

    Examples
    --------
    >>> import numpy as np
    >>> from models import AttitudeNoiseSensor
    >>> sensor = AttitudeNoiseSensor(seed=3)
    >>> sensor.reset()
    >>> y = sensor(0.0, np.zeros(10))
    >>> bool(np.all(y[3:] == 0.0)), bool(np.all(np.abs(y[:3]) < np.radians(1.0)))
    (True, True)
    """

    def __init__(self, sigma: ArrayLike = ANGLE_NOISE_SIGMA, seed: int | None = 0) -> None:
        self.sigma = as_positive_values(
            sigma, "sigma", 3, allow_zero=True, per="axis", what="standard deviations"
        )
        self.seed = _check_seed(seed)
        self._rng = np.random.default_rng(self.seed)

    def reset(self) -> None:
        """Re-seed the generator."""
        self._rng = np.random.default_rng(self.seed)

    def __call__(self, t: float, x: ArrayLike) -> np.ndarray:
        """The measurement of the true state ``x`` at time ``t``."""
        y = np.array(x, dtype=float)
        y[:3] = y[:3] + self._rng.normal(0.0, 1.0, 3) * self.sigma
        return y

    def __repr__(self) -> str:
        return f"AttitudeNoiseSensor(sigma_deg={np.degrees(self.sigma).round(4).tolist()}, seed={self.seed})"
