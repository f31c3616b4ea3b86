"""Estimators against outside references: python-control's ``dlqe`` (Riccati solution and
gain), the error dynamics a placed observer promises (a deadbeat observer is exact after n
samples), the covariance a Kalman filter promises (sampled), and simulate's chain."""

from __future__ import annotations

import control
import numpy as np
import pytest

from models import PolytopicModel
from rmpc import LQR, simulate
from rmpc.estimators import KalmanFilter, Luenberger
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError


def plant_3() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A seeded 3-state, 2-input plant (one unstable mode) measured on 2 outputs."""
    rng = np.random.default_rng(4)
    a = rng.normal(size=(3, 3)) * 0.5 + np.diag([1.05, 0.6, 0.3])
    return a, rng.normal(size=(3, 2)), rng.normal(size=(2, 3))


def test_kalman_gain_and_riccati_equal_python_control_dlqe() -> None:
    a, b, c = plant_3()
    w, v = np.diag([0.1, 0.2, 0.05]), np.diag([0.01, 0.03])
    kf = KalmanFilter((a, b), c, process_noise=w, measurement_noise=v)
    l_pred, p, _ = control.dlqe(a, np.eye(3), c, w, v)
    np.testing.assert_allclose(kf.P, p, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(a @ kf.M, l_pred, rtol=1e-9, atol=1e-12)  # predictor gain L = A M


def test_kalman_error_covariance_is_what_it_promises() -> None:
    """On a scalar plant driven by the stated noises, the a-posteriori error variance over 40000
    samples is ``(1 - M c) P`` within 3 % (the sampling error of the variance is about 1 %)."""
    a, b, c = np.array([[0.95]]), np.array([[1.0]]), np.array([[1.0]])
    kf = KalmanFilter((a, b), c, process_noise=0.04, measurement_noise=0.09)
    rng = np.random.default_rng(7)
    x, errors = np.zeros(1), []
    u_prev = None
    for k in range(40_000):
        y = c @ x + 0.3 * rng.standard_normal(1)
        x_hat = kf.update(y, u_prev)
        if k > 100:
            errors.append(float(x[0] - x_hat[0]))
        u = np.array([0.1 * np.sin(0.01 * k)])
        x = a @ x + b @ u + 0.2 * rng.standard_normal(1)
        u_prev = u
    promised = float((1.0 - kf.M[0, 0] * c[0, 0]) * kf.P[0, 0])
    assert np.var(errors) == pytest.approx(promised, rel=0.03)


def test_deadbeat_observer_is_exact_after_n_samples() -> None:
    """Poles at 0: ``((I - M C) A)^n = 0``, so without noise the estimate equals the state from
    sample n on, whatever the initial guess and the inputs."""
    a, b, c = plant_3()
    obs = Luenberger((a, b), c, poles=[0.0, 1e-3, -1e-3])
    rng = np.random.default_rng(1)
    x, u_prev = rng.normal(size=3), None
    for k in range(8):
        x_hat = obs.update(c @ x, u_prev)
        if k >= 3:
            np.testing.assert_allclose(x_hat, x, atol=1e-6 * np.abs(x).max())
        u_prev = rng.normal(size=2)
        x = a @ x + b @ u_prev


def test_placed_poles_are_the_error_dynamics() -> None:
    a, b, c = plant_3()
    poles = [0.2, 0.3 + 0.1j, 0.3 - 0.1j]
    obs = Luenberger((a, b), c, poles=poles)
    got = np.sort_complex(np.linalg.eigvals(obs.error_dynamics()))
    np.testing.assert_allclose(got, np.sort_complex(np.array(poles)), atol=1e-9)


def test_an_input_disturbance_is_estimated() -> None:
    """A constant input disturbance on the nominal model: ``d_hat`` converges to it."""
    a = np.array([[1.0, 0.1], [0.0, 1.0]])
    b = np.array([[0.005], [0.1]])
    c = np.array([[1.0, 0.0]])
    obs = Luenberger((a, b), c, poles=[0.5, 0.55, 0.6], disturbance_model="input")
    x, u_prev, d = np.array([0.3, 0.0]), None, np.array([0.25])
    for _ in range(200):
        x_hat = obs.update(c @ x, u_prev)
        u_prev = np.array([-0.5 * x[0] - x[1]])
        x_seen, x = x, a @ x + b @ (u_prev + d)
    np.testing.assert_allclose(obs.d_hat, d, atol=1e-9)
    np.testing.assert_allclose(x_hat, x_seen, atol=1e-9)


def test_simulate_feeds_the_applied_input_back_and_logs_the_estimates() -> None:
    """With a limiter the estimator gets the limited input; the log holds one estimate per step."""
    a = np.array([[1.0, 0.1], [0.0, 1.0]])
    b = np.array([[0.005], [0.1]])
    plant = PolytopicModel([(a, b)], dt=0.1)
    seen: list = []

    class Recording(Luenberger):
        def update(self, y, u_prev=None):
            seen.append(None if u_prev is None else np.array(u_prev))
            return super().update(y, u_prev)

    est = Recording(plant, [[1.0, 0.0]], poles=[0.3, 0.4])
    ctrl = LQR(plant, Q=np.eye(2), R=np.eye(1))
    traj = simulate(ctrl, plant, [1.0, 0.0], n_steps=30, measurement=[[1.0, 0.0]], estimator=est,
                    limiter=lambda u: np.clip(u, -0.2, 0.2))
    assert seen[0] is None
    np.testing.assert_array_equal(np.array(seen[1:]), traj.u_applied[:-1])
    assert np.any(traj.u_applied != traj.u_cmd)  # the limiter acted
    assert traj.stage_log["x_hat"].shape == (30, 2)
    np.testing.assert_allclose(traj.stage_log["x_hat"][-1], traj.x[-2], atol=1e-6)


def test_bad_input_names_the_argument() -> None:
    a, b, c = plant_3()
    with pytest.raises(InvalidArgumentError, match=r"C: expected a p x 3 matrix"):
        KalmanFilter((a, b), np.ones((2, 4)), 1.0, 1.0)
    unobservable = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    a_unstable = np.diag([0.5, 0.6, 1.2])
    with pytest.raises(InvalidArgumentError, match=r"C: .*unstable mode.*1\.2"):
        KalmanFilter((a_unstable, b), unobservable, 1.0, 1.0)
    with pytest.raises(InvalidArgumentError, match=r"C: .*observes every mode"):
        Luenberger((a_unstable, b), unobservable, poles=[0.1, 0.2, 0.3])
    with pytest.raises(InvalidArgumentError, match="measurement_noise: expected a positive definite"):
        KalmanFilter((a, b), c, 1.0, 0.0)
    with pytest.raises(InvalidArgumentError, match="poles: expected 3 eigenvalues inside"):
        Luenberger((a, b), c, poles=[0.1, 0.2, 1.5])
    with pytest.raises(InvalidArgumentError, match=r"disturbance_model: .*needs at least 2 outputs"):
        Luenberger((a, b), c[:1], poles=[0.1] * 5, disturbance_model="input")
    with pytest.raises(ArgumentTypeError, match="plant"):
        Luenberger("plant", c, poles=[0.1, 0.2, 0.3])
    plant = PolytopicModel([(a, b)], dt=0.1)
    ctrl = LQR(PolytopicModel([(0.5 * a, b)], dt=0.1), Q=np.eye(3), R=np.eye(2))
    with pytest.raises(InvalidArgumentError, match="noise: expected standard deviations >= 0"):
        simulate(ctrl, plant, np.zeros(3), n_steps=2, measurement=c, noise=-1.0)
    with pytest.raises(InvalidArgumentError, match="estimator: expected measurement=C"):
        simulate(ctrl, plant, np.zeros(3), n_steps=2, estimator=Luenberger((a, b), c, poles=[0.1, 0.2, 0.3]))
    with pytest.raises(InvalidArgumentError, match="poles: expected eigenvalues a gain can place"):
        Luenberger((a, b), c, poles=[0.1] * 3)
    with pytest.raises(InvalidArgumentError, match="measurement: expected a finite p x 3"):
        simulate(ctrl, plant, np.zeros(3), n_steps=2, measurement=np.ones((2, 2)))
