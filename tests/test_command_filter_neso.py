"""Paper M's command filter and extended state observer against closed forms (seed sections 3, 4, 7.5-7.7).

Outside references: the second-order step response in closed form and python-control's
``step_info``; the observer's error dynamics in the linear zone, solved by hand in the seed
(section 4); the scalar nonlinear-damping lemma of paper M (section 5.2).
"""

from __future__ import annotations

import control
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rmpc import NESO, CommandFilter
from rmpc.laws.mrp.neso import fal
from toolkit_common.errors import InvalidArgumentError

ZETA, WN = 0.5, 2.0


def filter_step_response(filt: CommandFilter, size: float = 1.0, t_end: float = 30.0):
    """The unit (or ``size``) step from rest, by DOP853 on the filter's right-hand side."""
    x0 = np.array([size])

    def rhs(_t: float, q: np.ndarray) -> np.ndarray:
        return filt.derivative(q, x0)

    return solve_ivp(rhs, (0.0, t_end), np.zeros(2), method="DOP853", rtol=1e-12, atol=1e-14,
                     dense_output=True, max_step=0.01)


def test_filter_step_response_closed_forms_and_python_control() -> None:
    filt = CommandFilter(WN, ZETA, size=1)
    sol = filter_step_response(filt)
    t = np.linspace(0.0, 30.0, 300001)
    y = sol.sol(t)[0]
    k_peak = int(np.argmax(y))
    overshoot = 100.0 * (y[k_peak] - 1.0)
    wd = WN * np.sqrt(1.0 - ZETA**2)
    assert overshoot == pytest.approx(100.0 * np.exp(-np.pi * ZETA / np.sqrt(1.0 - ZETA**2)), abs=1e-4)
    assert overshoot == pytest.approx(16.30, abs=0.05)
    assert t[k_peak] == pytest.approx(1.814, abs=0.005)
    assert t[k_peak] == pytest.approx(np.pi / wd, abs=2e-4)
    first_crossing = t[np.argmax(y >= 1.0)]
    assert first_crossing == pytest.approx(1.209, abs=0.005)
    assert first_crossing == pytest.approx((np.pi - np.arccos(ZETA)) / wd, abs=2e-4)
    outside = np.abs(y - 1.0) > 0.02
    settling = t[np.nonzero(outside)[0][-1] + 1]
    assert settling == pytest.approx(4.04, abs=0.02)
    assert y[-1] == pytest.approx(1.0, abs=1e-6)  # DC gain 1
    # the output's derivative is the filter's second state
    np.testing.assert_allclose(np.gradient(y, t)[1000:-1000:1000], sol.sol(t)[1][1000:-1000:1000], atol=1e-6)
    # python-control's step_info of wn^2 / (s^2 + 2 zeta wn s + wn^2) on the same grid
    info = control.step_info(control.tf([WN**2], [1.0, 2 * ZETA * WN, WN**2]), T=t[:100001])
    assert overshoot == pytest.approx(info["Overshoot"], abs=1e-3)
    assert t[k_peak] == pytest.approx(info["PeakTime"], abs=1e-3)
    assert settling == pytest.approx(info["SettlingTime"], abs=1e-3)


def test_sampled_filter_is_rk4_of_the_continuous_one() -> None:
    filt = CommandFilter(WN, ZETA, size=1, dt=0.01)
    filt.step([0.0])  # starts at rest on 0
    samples = np.array([filt.step([1.0])[0] for _ in range(500)])
    exact = filter_step_response(CommandFilter(WN, ZETA, size=1), t_end=5.0).sol(0.01 * np.arange(500))[0]
    np.testing.assert_allclose(samples, exact, atol=1e-9)
    assert filt.last.status == "ok"
    filt.reset()
    np.testing.assert_array_equal(filt.step([0.7]), [0.7])  # restarts at rest on its input


def test_rate_and_magnitude_clips() -> None:
    rate_limit = 0.5
    filt = CommandFilter(WN, ZETA, rate_limit=rate_limit, size=1)
    sol = filter_step_response(filt, size=5.0, t_end=30.0)
    t = np.linspace(0.0, 30.0, 30001)
    q = sol.sol(t)
    assert np.max(np.abs(q[1])) <= rate_limit + 1e-9
    assert np.max(np.abs(q[1])) > 0.99 * rate_limit  # the clip acted
    assert q[0, -1] == pytest.approx(5.0, abs=1e-6)
    sampled = CommandFilter(WN, ZETA, rate_limit=rate_limit, size=1, dt=0.05)
    sampled.step([0.0])
    rates = []
    for _ in range(400):
        sampled.step([5.0])
        rates.append(sampled.last.extra["rate"][0])
    assert np.max(np.abs(rates)) <= rate_limit + 1e-12
    clipped = CommandFilter(WN, ZETA, magnitude_limit=0.8, size=1)
    assert filter_step_response(clipped, size=5.0).y[0, -1] == pytest.approx(0.8, abs=1e-6)


def test_filter_bad_input_names_the_argument() -> None:
    for bad in (0.0, -0.5):
        with pytest.raises(InvalidArgumentError, match="damping"):
            CommandFilter(WN, bad)
    with pytest.raises(InvalidArgumentError, match="natural_frequency"):
        CommandFilter(0.0, ZETA)
    with pytest.raises(InvalidArgumentError, match="rate_limit"):
        CommandFilter(WN, ZETA, rate_limit=[0.5, -1.0, 0.5])


def test_fal_is_continuous_odd_and_linear_for_alpha_one() -> None:
    delta = 0.01
    for alpha in (0.25, 0.5, 1.0):
        inside = fal([delta, -delta], alpha, delta)
        outside = fal(np.array([delta, -delta]) * (1 + 1e-12), alpha, delta)
        np.testing.assert_allclose(inside, outside, rtol=1e-10)
        e = np.linspace(-0.1, 0.1, 201)
        np.testing.assert_allclose(fal(-e, alpha, delta), -fal(e, alpha, delta), atol=0)
    e = np.linspace(-3.0, 3.0, 61)
    np.testing.assert_allclose(fal(e, 1.0, 0.37), e, atol=1e-15)
    for bad in (0.0, 1.5, -0.5):
        with pytest.raises(InvalidArgumentError, match="alpha"):
            fal(0.1, bad, delta)
    with pytest.raises(InvalidArgumentError, match="delta"):
        fal(0.1, 0.5, 0.0)


J0 = np.diag([3.0, 3.0, 2.0])
TD = np.array([0.01, -0.02, 0.005])
W0 = np.array([0.01, -0.02, 0.03])


def observe(neso: NESO, torque: np.ndarray = TD, t_end: float = 2.0):
    """Plant ``J w' = -w x J w + Td`` (``u = 0``, ``J = J0``) and the observer, integrated jointly."""

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        w, z = y[:3], y[3:]
        w_dot = np.linalg.solve(J0, -np.cross(w, J0 @ w) + torque)
        return np.concatenate((w_dot, neso.derivative(z, w, np.zeros(3))))

    y0 = np.concatenate((W0, neso.initial_state(W0)))
    return solve_ivp(rhs, (0.0, t_end), y0, method="DOP853", rtol=1e-12, atol=1e-15, dense_output=True)


def test_neso_follows_the_closed_form_in_its_linear_zone() -> None:
    neso = NESO.from_bandwidth(J0)  # w_o = 10, alpha = (0.5, 0.25), delta = 0.01, B = 0.05
    np.testing.assert_allclose(neso.gain1, 2.0)
    np.testing.assert_allclose(neso.gain2, 3.1623, atol=1e-4)
    sol = observe(neso)
    t = np.linspace(0.0, 2.0, 2001)
    y = sol.sol(t)
    d = np.linalg.solve(J0, TD)
    closed = d[:, None] * (1.0 - (1.0 + 10.0 * t) * np.exp(-10.0 * t))
    assert np.max(np.abs(y[3:6] - y[0:3])) < neso.delta  # e stayed in the linear zone
    assert np.max(np.abs(y[6:9] - closed) / np.abs(d)[:, None]) <= 1e-6
    t_hat = J0 @ y[6:9]
    rel = np.linalg.norm(t_hat - TD[:, None], axis=0) / np.linalg.norm(TD)
    assert np.all(rel[t >= 0.664] <= 0.01)
    assert np.max(np.abs(y[6:9])) <= 0.05  # the box


def test_neso_nonlinear_zone_and_linear_eso() -> None:
    narrow = NESO.from_bandwidth(J0, delta=1e-4)
    t = np.linspace(0.0, 2.0, 2001)
    y = observe(narrow).sol(t)
    assert np.max(np.abs(y[3:6] - y[0:3])) > narrow.delta  # the nonlinear zone is in use
    rel = np.linalg.norm(J0 @ y[6:9] - TD[:, None], axis=0) / np.linalg.norm(TD)
    assert np.all(rel[t >= 0.7] <= 0.01)
    linear = NESO.linear(J0, bandwidth=10.0)
    y = observe(linear).sol(t)
    d = np.linalg.solve(J0, TD)
    closed = d[:, None] * (1.0 - (1.0 + 10.0 * t) * np.exp(-10.0 * t))
    assert np.max(np.abs(y[6:9] - closed) / np.abs(d)[:, None]) <= 1e-6


def test_neso_projection_keeps_the_box() -> None:
    big = np.array([0.3, -0.02, 0.005])  # d_1 = 0.1 rad/s^2 > B = 0.05
    neso = NESO.from_bandwidth(J0)
    y = observe(neso, torque=big, t_end=3.0).sol(np.linspace(0.0, 3.0, 3001))
    assert np.max(np.abs(y[6])) <= 0.05 + 1e-9
    assert y[6, -1] == pytest.approx(0.05, abs=1e-9)  # held at the bound
    z = neso.initial_state(W0)
    w = W0.copy()
    for _ in range(300):
        w = w + 0.01 * np.linalg.solve(J0, -np.cross(w, J0 @ w) + big)
        z = neso.advance(z, w, np.zeros(3), 0.01)
        assert np.all(np.abs(z[3:]) <= neso.bound)


def test_neso_bad_input_names_the_argument() -> None:
    with pytest.raises(InvalidArgumentError, match="bound"):
        NESO.from_bandwidth(J0, bound=0.0)
    with pytest.raises(InvalidArgumentError, match="bound"):
        NESO.from_bandwidth(J0, bound=[0.05, -0.05, 0.05])
    with pytest.raises(InvalidArgumentError, match="alpha1"):
        NESO.from_bandwidth(J0, alpha1=1.2)
    with pytest.raises(InvalidArgumentError, match="alpha2"):
        NESO(J0, 1.0, 1.0, alpha2=0.0)
    with pytest.raises(InvalidArgumentError, match="delta"):
        NESO.from_bandwidth(J0, delta=-0.01)
    with pytest.raises(InvalidArgumentError, match="gain2"):
        NESO(J0, 1.0, [1.0, 0.0, 1.0])
    with pytest.raises(InvalidArgumentError, match="inertia"):
        NESO([3.0, -3.0, 2.0], 1.0, 1.0)


def test_scalar_nonlinear_damping_bound() -> None:
    """Paper M's lemma: x' = f + g u + phi Delta with u = g^-1 (-f - c x - kappa phi^2 x) ends in
    |x| <= |Delta|_inf / (2 sqrt(c kappa)). Here f = x^2, g = 1, phi = 1 + x^2, Delta = sin t,
    c = kappa = 1: the bound is 0.5 (the seed observed 0.451)."""

    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        u = -x**2 - x - x * (1.0 + x**2) ** 2
        return x**2 + u + (1.0 + x**2) * np.sin(t)

    sol = solve_ivp(rhs, (0.0, 50.0), [2.0], method="DOP853", rtol=1e-10, atol=1e-12, dense_output=True)
    x = sol.sol(np.linspace(20.0, 50.0, 30001))[0]
    assert np.max(np.abs(x)) <= 0.5
    assert np.max(np.abs(x)) > 0.4  # the bound is not vacuous
