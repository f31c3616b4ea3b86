"""The single-axis transfer function and paper S's picture (seed papers-S-V-flexible.md, checks 1-2).

Expected values are closed forms in the parameters (zeros at the constrained modes, the
high-frequency gain identity) and the seed's arithmetic on table 2.5 (the free-free poles).
"""

from __future__ import annotations

import control
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from models import FlexibleSatellite
from models.flexible.single_axis import REGIME_LABELS, flexible_factor, regime
from toolkit_common.errors import InvalidArgumentError

#: Single-axis free-free frequencies of seed 2.5 (rad/s), per axis.
SEED_POLES = {
    0: [0.8180, 1.1070, 1.8772, 2.5561],
    1: [0.7704, 1.1055, 1.8947, 2.5858],
    2: [0.7775, 1.1124, 1.8769, 2.5586],
}


@pytest.fixture(scope="module")
def sat() -> FlexibleSatellite:
    return FlexibleSatellite.di_gennaro()


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_zeros_are_the_constrained_modes(sat: FlexibleSatellite, axis: int) -> None:
    g = sat.single_axis_tf(axis=axis)
    zeros = np.asarray(g.zeros())
    zeros = np.sort_complex(zeros[zeros.imag > 0])
    lam, xi = sat.frequencies, sat.damping
    expected = np.sort_complex(-xi * lam + 1j * lam * np.sqrt(1.0 - xi**2))
    np.testing.assert_allclose(zeros, expected, rtol=1e-9)


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_undamped_poles_interlace_and_the_gain_identity_holds(sat: FlexibleSatellite, axis: int) -> None:
    undamped = FlexibleSatellite(sat.inertia, sat.frequencies, np.zeros(4), sat.coupling)
    w_u, zeta_u = undamped.single_axis_modes(axis)
    lam = sat.frequencies
    np.testing.assert_allclose(w_u, SEED_POLES[axis], rtol=1e-3)
    np.testing.assert_allclose(zeta_u, 0.0, atol=1e-9)
    assert np.all(lam < w_u) and np.all(w_u[:-1] < lam[1:])  # Lambda_1 < w_u1 < Lambda_2 < ...
    j_aa = sat.inertia[axis, axis]
    total = float(np.sum(sat.coupling[:, axis] ** 2))
    assert np.prod((w_u / lam) ** 2) == pytest.approx(j_aa / (j_aa - total), rel=1e-9)
    # the damped poles (seed 2.5 lists them too) agree to the same digits
    np.testing.assert_allclose(sat.single_axis_modes(axis)[0], SEED_POLES[axis], rtol=1e-3)


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_low_and_high_frequency_gains(sat: FlexibleSatellite, axis: int) -> None:
    g = sat.single_axis_tf(axis=axis)
    j_aa = sat.inertia[axis, axis]
    total = float(np.sum(sat.coupling[:, axis] ** 2))
    s = 1e-7j
    assert abs(j_aa * s**2 * g(s) - 1.0) < 1e-9          # J_aa s^2 G(s) -> 1
    s = 1e7j  # the next term of the expansion is O(c_i / s) ~ 5e-10 here
    assert (j_aa - total) * s**2 * g(s) == pytest.approx(1.0, rel=1e-8)


def test_an_uncoupled_mode_cancels(sat: FlexibleSatellite) -> None:
    delta = sat.coupling.copy()
    delta[2, 1] = 0.0  # mode 3 does not couple to y
    partial = FlexibleSatellite(sat.inertia, sat.frequencies, sat.damping, delta)
    full = partial.single_axis_tf(axis=1, cancel_uncoupled=False)
    p3 = np.roots([1.0, 2 * sat.damping[2] * sat.frequencies[2], sat.frequencies[2] ** 2])
    for root in p3:  # pair 3 is both a pole and a zero
        assert np.min(np.abs(np.asarray(full.poles()) - root)) < 1e-9
        assert np.min(np.abs(np.asarray(full.zeros()) - root)) < 1e-9
    reduced = partial.single_axis_tf(axis=1)
    keep = [0, 1, 3]
    without = FlexibleSatellite(sat.inertia, sat.frequencies[keep], sat.damping[keep], sat.coupling[keep])
    ref = without.single_axis_tf(axis=1)
    for s in (0.3j, 1.0j, 2.2j, 10.0j):
        assert reduced(s) == pytest.approx(ref(s), rel=1e-12)
        assert full(s) == pytest.approx(ref(s), rel=1e-9)


def test_paper_s_flexible_factor() -> None:
    g = flexible_factor([3.0], [3.3], 0.01, 0.01)
    assert abs(g(0.0)) == pytest.approx(1.0, abs=1e-15)
    assert abs(g(1e4j)) == pytest.approx(1.21, rel=1e-6)    # (w_u / w_c)^2
    w = np.linspace(2.5, 4.0, 30001)
    peaks = [np.max(np.abs(flexible_factor([3.0], [3.3], z, z)(1j * w))) for z in (0.04, 0.02, 0.01)]
    assert peaks[0] < peaks[1] < peaks[2]                      # the peak grows as zeta falls


def test_paper_s_single_mode_under_a_hub_acceleration_step() -> None:
    # one mode xi = 0.08, Lambda = 10 rad/s, delta = 1 on a huge hub driven at w' = a by u = J a
    big = 1e9
    sat = FlexibleSatellite(np.diag([big, big, big]), [10.0], [0.08], [[1.0, 0.0, 0.0]])
    a = 0.01
    u = np.array([big * a, 0.0, 0.0])
    sol = solve_ivp(lambda t, y: sat.dynamics(y, u), (0.0, 8.0), sat.state(), method="DOP853",
                    rtol=1e-11, atol=1e-15, dense_output=True)
    t = np.linspace(0.0, 8.0, 80001)
    eta = sol.sol(t)[7]
    first = int(np.argmax(np.diff(np.sign(np.diff(eta))) != 0)) + 1  # first extremum
    static = -a / 100.0                                              # -delta a / Lambda^2
    assert eta[first] / static == pytest.approx(1.7771, rel=1e-3)
    assert eta[-1] == pytest.approx(static, rel=1e-3)
    # and the same number from python-control's step response of -delta / (s^2 + 2 xi L s + L^2)
    resp = control.step_response(control.tf([-a], [1.0, 1.6, 100.0]), T=np.linspace(0, 1, 10001))
    assert np.min(resp.outputs) / static == pytest.approx(1.7771, rel=1e-3)


def test_regime_labels(sat: FlexibleSatellite) -> None:
    w1 = sat.frequencies[0]
    assert sat.regime(0.99 * w1 / 3) == REGIME_LABELS[0] == "rigid-like"
    assert sat.regime(w1 / 3) == sat.regime(w1 / 2) == "flexible"
    assert sat.regime(1.01 * w1 / 2) == "flexible-hard"
    assert regime(0.0, 1.0) == "rigid-like"
    with pytest.raises(InvalidArgumentError, match="bandwidth"):
        regime(-1.0, 1.0)
    with pytest.raises(InvalidArgumentError, match="axis"):
        sat.single_axis_tf(axis=3)
    with pytest.raises(InvalidArgumentError, match="unconstrained"):
        flexible_factor([3.0], [3.3, 4.0], 0.01, 0.01)
