"""The sinusoidal disturbance profile, by hand and through the simulator in closed form.

``SineDisturbance(amplitude, frequency, phase)`` is ``amplitude sin(2 pi frequency t + phase)``
with ``frequency`` in Hz. At ``frequency = 0.5`` Hz and ``phase = pi/6`` the argument at
``t = 0, 0.5, 1, 1.5, 2`` s is ``pi/6`` plus a quarter turn per half second: the sines are
``1/2, sqrt(3)/2, -1/2, -sqrt(3)/2, 1/2`` (asserted to 1e-15, the rounding of ``sin``).

Through :func:`rmpc.simulate`: a torque on the roll axis alone of the satellite at rest spins it
about that principal axis, where the gyroscopic term vanishes, so
``p(t) = a / (J_xx w) (cos(phase) - cos(w t + phase))`` and ``phi(t)`` its integral
(``w = 2 pi frequency``). Measured: the simulated roll rate and roll angle agree with these
to 2.1e-15 and 1.9e-15 relative to their peaks (DOP853 at rtol 1e-10); asserted 1e-12.
"""

from __future__ import annotations

import numpy as np
import pytest

from models import RigidSatellite
from rmpc import SineDisturbance, simulate

AMPLITUDE = np.array([0.1, -0.2, 0.3])
HALF = 0.5
ROOT3_HALF = np.sqrt(3.0) / 2.0


@pytest.mark.parametrize(
    ("t", "sine"),
    [(0.0, HALF), (0.5, ROOT3_HALF), (1.0, -HALF), (1.5, -ROOT3_HALF), (2.0, HALF)],
)
def test_sine_at_hand_computed_instants(t, sine):
    d = SineDisturbance(AMPLITUDE, frequency=0.5, phase=np.pi / 6)
    np.testing.assert_allclose(d(t), sine * AMPLITUDE, rtol=0, atol=1e-15)


def test_default_phase_is_zero_and_frequency_is_in_hertz():
    d = SineDisturbance([1.0, 2.0, 0.0], frequency=2.0)
    np.testing.assert_allclose(d(0.0), [0.0, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(d(0.125), [1.0, 2.0, 0.0], atol=1e-15)  # a quarter period of 0.5 s
    np.testing.assert_allclose(d(0.375), [-1.0, -2.0, 0.0], atol=1e-15)
    assert d.breakpoints() == ()  # smooth: nothing for the integrator to stop at


class _Zero:
    """Applies no torque."""

    last = None

    def step(self, x: np.ndarray) -> np.ndarray:
        return np.zeros(3)


def test_simulated_roll_under_a_sine_torque_is_the_closed_form():
    sat = RigidSatellite.paper_p()
    a, freq, phase = 0.02, 0.3, 0.4
    d = SineDisturbance([a, 0.0, 0.0], freq, phase)
    traj = simulate(_Zero(), sat, np.zeros(6), duration=5.0, dt=0.1, disturbance=d)
    w, j = 2.0 * np.pi * freq, sat.inertia[0, 0]
    t = traj.t
    p = a / (j * w) * (np.cos(phase) - np.cos(w * t + phase))
    phi = a / (j * w) * (t * np.cos(phase) - (np.sin(w * t + phase) - np.sin(phase)) / w)
    np.testing.assert_allclose(traj.x[:, 3], p, rtol=0, atol=1e-12 * np.max(np.abs(p)))
    np.testing.assert_allclose(traj.x[:, 0], phi, rtol=0, atol=1e-12 * np.max(np.abs(phi)))
    np.testing.assert_array_equal(traj.x[:, [1, 2, 4, 5]], 0.0)  # only the roll axis moves
    np.testing.assert_allclose(traj.d, np.array([d(tk) for tk in t[:-1]]), rtol=0, atol=0)
