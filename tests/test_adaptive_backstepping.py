"""Paper W's adaptive backstepping compensator (ABFTC): seed checks 6.4-6.6 and the protocol.

The Lyapunov checks integrate controller and plant jointly (the controller's continuous-time
law inside ``solve_ivp``, DOP853 at ``rtol = 1e-10``), continuous time and unsaturated, as in
seed 6.5; the 40 ms sampled controller is what :meth:`AdaptiveBacksteppingFTC.step` runs.
"""

from __future__ import annotations

import inspect
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from models import FaultSchedule, WheelFault, WheelSatellite, paper_w_scenario
from models.attitude.euler_inverse import inverse_kinematics_matrix
from rmpc import AdaptiveBacksteppingFTC, Controller
from rmpc.laws.wheel.adaptive_backstepping import wrap_angle
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError


@pytest.fixture(scope="module")
def sat() -> WheelSatellite:
    return WheelSatellite.paper_w()


def test_alpha1_dot_equals_a_central_difference(sat: WheelSatellite) -> None:  # seed 6.4
    ftc = AdaptiveBacksteppingFTC(sat)
    rng = np.random.default_rng(2)
    for _ in range(10):
        x = np.r_[rng.uniform(-0.6, 0.6, 3), rng.uniform(-0.2, 0.2, 3), np.zeros(4)]
        rates = ftc.law(0.0, x, ftc.g_nom, ftc.theta_hat)
        # alpha1 depends on eta only, and eta' = K(eta) w: differentiate along that flow
        from models.attitude.euler import kinematics_matrix

        eta_dot = kinematics_matrix(x[0], x[1]) @ x[3:6]
        h = 1e-6

        def alpha1(eta: np.ndarray) -> np.ndarray:
            return inverse_kinematics_matrix(eta[0], eta[1]) @ (-ftc.c1 * eta)

        fd = (alpha1(x[:3] + h * eta_dot) - alpha1(x[:3] - h * eta_dot)) / (2 * h)
        np.testing.assert_allclose(rates.alpha1_dot, fd, rtol=1e-6, atol=1e-12)
        np.testing.assert_allclose(rates.alpha1, alpha1(x[:3]), atol=1e-15)


def test_printed_gains_ask_for_13_times_the_wheel_torque(sat: WheelSatellite) -> None:  # seed 6.6
    ftc = AdaptiveBacksteppingFTC(sat)
    nu = ftc.step(paper_w_scenario("S1").initial_state())
    np.testing.assert_allclose(nu, [-0.262, 1.616, 0.640, 1.151], atol=1e-3)
    assert np.max(np.abs(nu)) / 0.123 > 13.0
    for name, peak in (("S2", 1.239), ("S3", 1.184), ("S4", 1.011)):
        ftc.reset()
        np.testing.assert_allclose(
            np.max(np.abs(ftc.step(paper_w_scenario(name).initial_state()))), peak, atol=1e-3
        )
    # S1 also asks for 1.316 N m s of z momentum against the array's 0.986
    rates = ftc.law(0.0, paper_w_scenario("S1").initial_state(), ftc.g_nom, ftc.theta_hat)
    np.testing.assert_allclose((sat.inertia @ rates.alpha1)[2], 1.316, atol=1e-3)
    np.testing.assert_allclose(sat.wheels.momentum_capacity()[2], 0.986, atol=1e-3)


# -- joint integration of controller and plant (seed 6.5) ------------------------------------------
def _pack(x: np.ndarray, g: np.ndarray, theta: list[np.ndarray], integral: float) -> np.ndarray:
    return np.concatenate([x, g.ravel(), *[th.ravel() for th in theta], [integral]])


def _unpack(y: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    theta = [y[19 + 6 * j : 25 + 6 * j].reshape(3, 2) for j in range(4)]
    return y[:10], y[10:19].reshape(3, 3), theta


def _closed_loop(ftc: AdaptiveBacksteppingFTC, sat: WheelSatellite, faults: FaultSchedule, y0, t_span):
    """Plant, estimates and int(c1 |e1|^2 + c2 |e2|^2) dt in one ODE, unsaturated."""

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        x, g, theta = _unpack(y)
        r = ftc.law(t, x, g, theta)
        cost = ftc.c1 * r.e1 @ r.e1 + ftc.c2 * r.e2 @ r.e2
        return _pack(sat.dynamics(x, faults.apply(t, r.nu)), r.g_hat_dot, list(r.theta_hat_dot), cost)

    t_eval = np.arange(t_span[0], t_span[1] + 1e-9, 0.01)
    sol = solve_ivp(rhs, t_span, y0, method="DOP853", rtol=1e-10, atol=1e-12, t_eval=t_eval)
    assert sol.success
    return sol


@pytest.fixture(scope="module")
def lyapunov_setup(sat: WheelSatellite):
    ftc = AdaptiveBacksteppingFTC(sat, gamma_g=1.0, gamma_theta=1.0, g_hat0=1.3 * sat.nominal_gain())
    x0 = sat.state(np.radians([5.0, -3.0, 8.0]), rates=[0.01, 0.0, -0.01])
    y0 = _pack(x0, ftc.g_hat0, [np.zeros((3, 2))] * 4, 0.0)
    return ftc, y0


def _v2(ftc, sol, g_true, theta_true) -> np.ndarray:
    return np.array([ftc.lyapunov(*_unpack(y), g_true, theta_true) for y in sol.y.T])


def test_lyapunov_identity_nominal_unsaturated(sat: WheelSatellite, lyapunov_setup) -> None:  # seed 6.5
    ftc, y0 = lyapunov_setup
    sol = _closed_loop(ftc, sat, FaultSchedule([], 4), y0, (0.0, 30.0))
    g_true, theta_true = ftc.true_parameters(np.ones(4))
    v2 = _v2(ftc, sol, g_true, theta_true)
    np.testing.assert_allclose(v2[0], 5.188, atol=1e-3)
    assert np.max(np.diff(v2)) <= 1e-8 * v2[0]  # non-increasing
    integral = sol.y[-1, -1]
    assert abs(v2[-1] - v2[0] + integral) <= 1e-6 * v2[0]
    nu = np.array([ftc.law(t, *_unpack(y)).nu for t, y in zip(sol.t, sol.y.T, strict=True)])
    assert 0.11 < np.max(np.abs(nu)) < 0.123  # "about 0.117": unsaturated, as the identity needs


def test_lyapunov_jumps_at_a_fault_then_the_identity_holds(sat: WheelSatellite, lyapunov_setup) -> None:
    ftc, y0 = lyapunov_setup
    faults = FaultSchedule([WheelFault(2, "stuck", 5.0, value=0.01)], 4)
    before = _closed_loop(ftc, sat, faults, y0, (0.0, 5.0))
    after = _closed_loop(ftc, sat, faults, before.y[:, -1], (5.0, 30.0))
    healthy = ftc.true_parameters(np.ones(4))
    # wheel 2 stuck at 0.01 N m: sigma_2 = 0, delta_2 = [0.01, 0] in the basis [1, sin 0.2t]
    stuck = ftc.true_parameters([1.0, 0.0, 1.0, 1.0], [[0, 0], [0.01, 0.0], [0, 0], [0, 0]])
    np.testing.assert_allclose(stuck[1][1][:, 0], 0.01 * stuck[0] @ sat.input_matrix[:, 1], atol=1e-15)
    v_before, v_after = _v2(ftc, before, *healthy), _v2(ftc, after, *stuck)
    assert np.max(np.diff(v_before)) <= 1e-8 * v_before[0]
    assert v_after[0] > v_before[-1] * 1.01  # V2 (new G and Theta) jumps up at 5 s
    assert np.max(np.diff(v_after)) <= 1e-8 * v_after[0]
    integral = after.y[-1, -1] - before.y[-1, -1]
    assert abs(v_after[-1] - v_after[0] + integral) <= 1e-6 * v_after[0]


# -- the sampled controller ------------------------------------------------------------------------
def test_step_protocol_clock_and_reset(sat: WheelSatellite) -> None:
    ftc = AdaptiveBacksteppingFTC(sat, basis_frequencies=(0.2, 0.5))
    assert isinstance(ftc, Controller) and ftc.name == "ABFTC"
    x = paper_w_scenario("S2").initial_state()
    first = ftc.step(x)
    assert ftc.last.status == "ok" and ftc.last.extra["t"] == 0.0
    for _ in range(4):
        ftc.step(x)
    assert ftc.t == pytest.approx(5 * 0.04) and ftc.last.extra["t"] == pytest.approx(4 * 0.04)
    # the estimates moved by forward Euler over Ts
    rates = ftc.law(0.0, x, ftc.g_hat0, [np.zeros((3, 3))] * 4)
    fresh = AdaptiveBacksteppingFTC(sat, basis_frequencies=(0.2, 0.5))
    fresh.step(x)
    np.testing.assert_allclose(fresh.g_hat, fresh.g_hat0 + 0.04 * rates.g_hat_dot, atol=1e-15)
    np.testing.assert_allclose(fresh.theta_hat[0], 0.04 * rates.theta_hat_dot[0], atol=1e-15)
    assert fresh.theta_hat[0].shape == (3, 3)  # [1, sin 0.2t, sin 0.5t]
    ftc.reset()
    assert ftc.t == 0.0 and ftc.last is None
    np.testing.assert_array_equal(ftc.step(x), first)
    # it is built from the nominal model and sees only the measured state, never the fault
    assert not any("fault" in p for p in inspect.signature(AdaptiveBacksteppingFTC).parameters)
    assert list(inspect.signature(ftc.step).parameters) == ["x", "inputs"] and ftc.accepts == frozenset()
    # the 6-state measurement gives the same command as the full state
    ftc.reset()
    np.testing.assert_array_equal(ftc.step(x[:6]), first)


def test_yaw_error_is_wrapped(sat: WheelSatellite) -> None:
    assert wrap_angle(math.radians(350.0)) == pytest.approx(math.radians(-10.0))
    assert wrap_angle(-math.pi) == math.pi
    a, b = AdaptiveBacksteppingFTC(sat), AdaptiveBacksteppingFTC(sat)
    x = sat.state(np.radians([5.0, 3.0, 350.0]))
    np.testing.assert_allclose(a.step(x), b.step(sat.state(np.radians([5.0, 3.0, -10.0]))), atol=1e-14)


def test_singular_pitch_is_a_status_not_nan(sat: WheelSatellite) -> None:
    ftc = AdaptiveBacksteppingFTC(sat)
    nu = ftc.step(sat.state(np.radians([0.0, 86.0, 0.0])))
    assert ftc.last.status == "singular" and np.all(nu == 0.0)
    np.testing.assert_array_equal(ftc.g_hat, ftc.g_hat0)
    nu = ftc.step(sat.state(np.radians([0.0, 84.0, 0.0])))
    assert ftc.last.status == "ok" and np.all(np.isfinite(nu))


def test_options_freeze_projection_leakage_gyroscopic(sat: WheelSatellite) -> None:
    x_s1 = paper_w_scenario("S1").initial_state()
    frozen = AdaptiveBacksteppingFTC(sat, freeze=True)
    frozen.step(x_s1)  # commands 13x the limit: the adaptation holds
    assert frozen.last.extra["frozen"]
    np.testing.assert_array_equal(frozen.g_hat, frozen.g_hat0)
    small = sat.state(np.radians([0.5, -0.3, 0.2]))
    frozen.step(small)
    assert not frozen.last.extra["frozen"] and not np.array_equal(frozen.g_hat, frozen.g_hat0)
    at_limit = small.copy()
    at_limit[7] = 0.625
    frozen.step(at_limit)
    assert frozen.last.extra["frozen"]
    # projection keeps the estimates in their balls
    projected = AdaptiveBacksteppingFTC(sat, gamma_g=50.0, gamma_theta=50.0, projection=(0.2, 0.05))
    for _ in range(20):
        projected.step(x_s1)
    assert np.linalg.norm(projected.g_hat - projected.g_hat0) <= 0.2 + 1e-12
    assert max(np.linalg.norm(th) for th in projected.theta_hat) <= 0.05 + 1e-12
    # leakage at the origin (e1 = e2 = 0): G_hat' = -s Gamma0 (G_hat - G_hat(0)), Theta' = -s Gamma Theta
    leaky = AdaptiveBacksteppingFTC(sat, leakage=0.5)
    g = leaky.g_hat0 + np.eye(3)
    theta = [np.ones((3, 2))] * 4
    rates = leaky.law(3.0, np.zeros(10), g, theta)
    np.testing.assert_allclose(rates.g_hat_dot, -0.5 * 0.1 * np.eye(3), atol=1e-15)
    np.testing.assert_allclose(rates.theta_hat_dot[2], -0.5 * 0.1 * np.ones((3, 2)), atol=1e-15)
    # gyroscopic compensation adds -J^-1 (w x D h) to f2
    x = sat.state([0.1, 0.2, 0.3], rates=[0.02, -0.01, 0.03], momenta=[0.3, -0.2, 0.1, 0.4])
    plain = AdaptiveBacksteppingFTC(sat).law(0.0, x, sat.nominal_gain(), theta)
    comp = AdaptiveBacksteppingFTC(sat, gyroscopic_compensation=True).law(0.0, x, sat.nominal_gain(), theta)
    expected = -np.linalg.solve(sat.inertia, np.cross(x[3:6], sat.wheels.D @ x[6:]))
    np.testing.assert_allclose(comp.f2 - plain.f2, expected, atol=1e-15)
    with pytest.raises(InvalidArgumentError, match="x"):
        AdaptiveBacksteppingFTC(sat, gyroscopic_compensation=True).step(x[:6])


def test_divergence_is_a_status(sat: WheelSatellite) -> None:
    ftc = AdaptiveBacksteppingFTC(sat, gamma_g=1e9, divergence_bound=1e6)
    x = paper_w_scenario("S1").initial_state()
    statuses = []
    for _ in range(5):
        nu = ftc.step(x)
        statuses.append(ftc.last.status)
        assert np.all(np.isfinite(nu))
    assert statuses[0] == "diverged" and set(statuses) == {"diverged"}
    assert np.all(nu == 0.0)


def test_bad_arguments_name_themselves(sat: WheelSatellite) -> None:
    with pytest.raises(ArgumentTypeError, match=r"^plant:"):
        AdaptiveBacksteppingFTC(sat.inertia)
    with pytest.raises(InvalidArgumentError, match="c1"):
        AdaptiveBacksteppingFTC(sat, c1=-0.5)
    with pytest.raises(InvalidArgumentError, match="gamma_g"):
        AdaptiveBacksteppingFTC(sat, gamma_g=-np.eye(3))
    with pytest.raises(InvalidArgumentError, match="gamma_theta"):
        AdaptiveBacksteppingFTC(sat, gamma_theta=[0.1, 0.1])
    with pytest.raises(InvalidArgumentError, match="basis_frequencies"):
        AdaptiveBacksteppingFTC(sat, basis_frequencies=[(0.2,), ()])
    with pytest.raises(InvalidArgumentError, match="singular_pitch"):
        AdaptiveBacksteppingFTC(sat, singular_pitch=2.0)
    with pytest.raises(ArgumentTypeError, match="freeze"):
        AdaptiveBacksteppingFTC(sat, freeze="yes")
    with pytest.raises(InvalidArgumentError, match="x"):
        AdaptiveBacksteppingFTC(sat).step(np.zeros(7))
    with pytest.raises(InvalidArgumentError, match="x"):
        AdaptiveBacksteppingFTC(sat).step([np.nan] * 10)
