"""The robust observer: its certified error bound checked outside the LMIs that gave it.

- On one model with noise only, the ellipsoid must contain the smallest invariant set of the error,
  whose support function is the series ``sum_k sum_i |c' Phi^k M_i| v_i`` (computed here, not by
  the design).
- On the vertex plants of a polytope, with the noise picked at every sample to push the error
  furthest out (the worst corner of the noise box, enumerated), the error stays in the ellipsoid;
  an observer designed on the nominal model alone does not pass the same check (the test can fail).
- Robust MPC on the estimate, designed with the observer's disturbance and output margin, keeps the
  true state's output bound and the input bound.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from lmi.observer import design_robust_observer
from models import PolytopicModel
from rmpc import RMPC
from rmpc.errors import InvalidArgumentError
from rmpc.estimators import RobustObserver

A_DI = np.array([[1.0, 0.1], [0.0, 1.0]])
B_DI = np.array([[0.005], [0.1]])


def _damped_polytope() -> PolytopicModel:
    """Kothare's example 1 with a narrower damping range (alpha in [0.5, 2]): the A_j differ."""

    def a_of(alpha: float) -> np.ndarray:
        return np.array([[1.0, 0.1], [0.0, 1.0 - 0.1 * alpha]])

    b = np.array([[0.0], [0.1 * 0.787]])
    return PolytopicModel([(a_of(0.5), b), (a_of(2.0), b)], dt=0.1, nominal=(a_of(1.0), b))


def _adversarial_run(M, P, a0, b0, c, plant_ab, noise, x0, steps, u_of) -> tuple[float, float, float]:
    """The current-form observer against the true plant ``plant_ab`` with the noise corner that
    maximises the next error level; returns (largest level, largest |x|, largest |u|)."""
    a, b = plant_ab
    corners = [np.array(s) * noise for s in itertools.product([-1.0, 1.0], repeat=c.shape[0])]
    x = np.asarray(x0, float)
    # e(0) = (I - M C)(x0 - guess) - M v with the guess = x0: the error starts at -M v
    x_hat = x - M @ max(corners, key=lambda v: float((M @ v) @ P @ (M @ v)))
    worst_level = float((x - x_hat) @ P @ (x - x_hat))
    worst_x = worst_u = 0.0
    for _ in range(steps):
        u = u_of(x)
        worst_u = max(worst_u, float(np.max(np.abs(u))))
        x_next = a @ x + b @ u
        x_bar = a0 @ x_hat + b0 @ u
        residual = x_next - x_bar - M @ (c @ (x_next - x_bar))  # e before the noise: (I - MC)(x - x_bar)

        def level(v: np.ndarray, r: np.ndarray = residual) -> float:
            e = r - M @ v
            return float(e @ P @ e)

        v = max(corners, key=level)
        x_hat = x_bar + M @ (c @ x_next + v - c @ x_bar)
        x = x_next
        e = x - x_hat
        worst_level = max(worst_level, float(e @ P @ e))
        worst_x = max(worst_x, float(np.max(np.abs(x))))
    return worst_level, worst_x, worst_u


def test_the_bound_contains_the_smallest_invariant_set_of_the_error():
    c = np.array([[1.0, 0.0]])
    noise = 2e-3
    obs = RobustObserver((A_DI, B_DI), C=c, noise_bound=noise)
    phi = obs.error_dynamics()
    assert np.max(np.abs(np.linalg.eigvals(phi))) < 1.0
    rng = np.random.default_rng(3)
    p_inv = np.linalg.inv(obs.P)
    for direction in rng.normal(size=(40, 2)):
        support, power = 0.0, np.eye(2)
        for _ in range(2000):
            support += noise * float(np.sum(np.abs(direction @ power @ obs.M)))
            power = phi @ power
            if np.linalg.norm(power) < 1e-14:
                break
        assert np.sqrt(direction @ p_inv @ direction) >= support * (1.0 - 1e-9)


@pytest.mark.parametrize("vertex", [0, 1])
def test_the_error_stays_in_the_bound_on_every_vertex_with_worst_case_noise(vertex):
    plant = _damped_polytope()
    c = np.array([[1.0, 0.0]])
    box, u_bound, noise = np.array([1.0, 1.0]), 2.0, 1e-3
    obs = RobustObserver(plant, C=c, noise_bound=noise, state_bound=box, input_bound=u_bound)
    assert obs.design.certificate.ok
    a0, b0 = plant.nominal
    gain = np.array([[3.0, 4.0]])  # the test's own state feedback keeps the true state in the box

    def u_of(x: np.ndarray) -> np.ndarray:
        return np.clip(-gain @ x, -u_bound, u_bound)

    rng = np.random.default_rng(vertex)
    for x0 in rng.uniform(-0.6, 0.6, size=(6, 2)):
        level, reach, u_max = _adversarial_run(obs.M, obs.P, a0, b0, c, plant.vertices[vertex], noise, x0,
                                               150, u_of)
        assert reach <= box[0] and u_max <= u_bound  # the design's assumptions held
        assert level <= 1.0 + 1e-6


def test_an_observer_designed_on_the_nominal_model_alone_leaves_its_bound_on_a_vertex():
    """The check above has teeth: ignoring the polytope gives a bound the vertices break."""
    plant = _damped_polytope()
    c = np.array([[1.0, 0.0]])
    u_bound, noise = 2.0, 1e-3
    a0, b0 = plant.nominal
    nominal_only = design_robust_observer([(a0, b0)], (a0, b0), c, noise)
    assert nominal_only.ok
    gain = np.array([[3.0, 4.0]])
    worst = 0.0
    for vertex in plant.vertices:
        level, _, _ = _adversarial_run(nominal_only.M, nominal_only.P, a0, b0, c, vertex, noise,
                                       np.array([0.6, 0.6]), 150,
                                       lambda x: np.clip(-gain @ x, -u_bound, u_bound))
        worst = max(worst, level)
    assert worst > 1.5


def test_robust_mpc_on_the_estimate_keeps_the_true_outputs_and_inputs_bounded():
    plant = PolytopicModel([(A_DI, 0.9 * B_DI), (A_DI, 1.1 * B_DI)], dt=0.1, nominal=(A_DI, B_DI))
    c = np.array([[1.0, 0.0]])
    noise, u_max, y_max = 1e-3, 1.0, 1.3
    obs = RobustObserver(plant, C=c, noise_bound=noise, input_bound=u_max)
    margin = obs.output_margin(c)
    assert 0.0 < margin[0] < 0.01
    ctrl = RMPC(plant, Q=np.eye(2), R=np.eye(1), u_max=u_max, output_matrix=c, y_max=y_max - margin,
                disturbance=obs.estimate_disturbance())
    x0 = np.array([1.0, 0.0])
    rng = np.random.default_rng(7)
    for a, b in plant.vertices:
        ctrl.reset()
        obs.reset(x0)
        x, u = x0.copy(), np.zeros(1)
        for k in range(80):
            v = rng.choice([-noise, noise], size=1)
            x_hat = obs.update(c @ x + v, None if k == 0 else u)
            assert obs.error_level(x - x_hat) <= 1.0 + 1e-6
            u = ctrl.step(x_hat)
            assert ctrl.last.status == "optimal"
            assert np.all(np.abs(u) <= u_max * (1.0 + 1e-9))
            x = a @ x + b @ u
            assert abs(float(c[0] @ x)) <= y_max
        assert np.linalg.norm(x) < 0.05


def test_the_contraction_bound_outside_the_ellipsoid():
    obs = RobustObserver((A_DI, B_DI), C=[[1.0, 0.0]], noise_bound=1e-3)
    assert obs.level_after(0, 0.5) == 1.0
    assert obs.level_after(3, 5.0) == pytest.approx(1.0 + (1.0 - obs.alpha) ** 3 * 4.0)
    # a noiseless error from far out obeys it on the nominal model
    e = np.array([0.5, -2.0])
    start = obs.error_level(e)
    phi = obs.error_dynamics()
    for k in range(1, 30):
        e = phi @ e
        assert obs.error_level(e) <= obs.level_after(k, start) + 1e-9


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"noise_bound": 0.0}, "noise_bound"),
        ({"noise_bound": -1e-3}, "noise_bound"),
        ({"noise_bound": [1e-3, 1e-3]}, "noise_bound"),
        ({"noise_bound": 1e-3, "C": [[1.0, 0.0, 0.0]]}, "C"),
        ({"noise_bound": 1e-3, "C": [[0.0, 1.0]]}, "C"),  # the position (an integrator) unseen
        ({"noise_bound": 1e-3, "disturbance_model": "input"}, "disturbance_model"),
    ],
)
def test_bad_input_names_the_argument(kwargs, name):
    args = {"C": [[1.0, 0.0]], **kwargs}
    with pytest.raises(InvalidArgumentError, match=name):
        RobustObserver((A_DI, B_DI), **args)


def test_a_polytope_whose_a_matrices_differ_needs_a_state_bound():
    with pytest.raises(InvalidArgumentError, match="state_bound"):
        RobustObserver(_damped_polytope(), C=[[1.0, 0.0]], noise_bound=1e-3)


def test_simulate_with_uniform_noise_keeps_the_error_in_the_bound():
    """The closed loop of :func:`rmpc.simulate` with bounded (uniform) noise: the logged estimates
    stay within the certified ellipsoid of the true states; Gaussian noise of that size is not
    bounded and the option is checked by name."""
    from rmpc import simulate

    plant = PolytopicModel([(A_DI, 0.9 * B_DI), (A_DI, 1.1 * B_DI)], dt=0.1, nominal=(A_DI, B_DI))
    c = np.array([[1.0, 0.0]])
    obs = RobustObserver(plant, C=c, noise_bound=1e-3, input_bound=1.0, x0=[0.5, 0.0])
    ctrl = RMPC(plant, Q=np.eye(2), R=np.eye(1), u_max=1.0, disturbance=obs.estimate_disturbance())

    class Truth:  # the vertex with the larger input gain, as a continuous-time double integrator
        n_states, n_inputs = 2, 1

        def dynamics(self, x, u=None, d=None):
            u = np.zeros(1) if u is None else np.asarray(u, float)
            return np.array([x[1], 1.1 * u[0]])

    traj = simulate(ctrl, Truth(), np.array([0.5, 0.0]), duration=6.0, dt=0.1, measurement=c, noise=1e-3,
                    noise_kind="uniform", estimator=obs, noise_seed=4)
    x_hat = traj.stage_log["x_hat"]
    levels = [obs.error_level(e) for e in traj.x[: len(x_hat)] - x_hat]
    assert 0.01 < max(levels) <= 1.0 + 1e-6
    with pytest.raises(InvalidArgumentError, match="noise_kind"):
        simulate(ctrl, Truth(), np.zeros(2), duration=0.2, dt=0.1, measurement=c, noise=1e-3,
                 noise_kind="laplace", estimator=obs)


def test_save_and_load_keep_the_gain_and_recheck_the_certificate(tmp_path):
    import json
    import pickle

    import rmpc

    plant = _damped_polytope()
    obs = RobustObserver(plant, C=[[1.0, 0.0]], noise_bound=1e-3, state_bound=[1.0, 1.0], input_bound=2.0)
    path = obs.save(tmp_path / "observer.rmpc")
    loaded = rmpc.load(path)
    copied = pickle.loads(pickle.dumps(obs))
    for other in (loaded, copied):
        assert type(other) is RobustObserver and other.design.certificate.ok
        assert np.array_equal(other.M, obs.M) and np.array_equal(other.P, obs.P)
        assert np.array_equal(other.estimate_disturbance()[1], obs.estimate_disturbance()[1])
    ys = np.random.default_rng(2).normal(size=(20, 1))
    obs.reset()
    loaded.reset()
    for k, y in enumerate(ys):
        u = None if k == 0 else np.array([0.1])
        assert np.array_equal(loaded.update(y, u), obs.update(y, u))
    # a file whose bound no longer holds for its gain (a smaller P, checksum rewritten) is refused
    from rmpc.io.format import read_file

    doc = json.loads(path.read_text())
    doc["design"]["P"] = (0.5 * np.asarray(obs.P)).tolist()
    tampered = tmp_path / "tampered.rmpc"
    from rmpc.io import format as file_format

    doc["sha256"] = file_format.checksum({k: v for k, v in doc.items() if k != "sha256"})
    tampered.write_text(json.dumps(doc))
    read_file(tampered)  # the envelope is intact
    with pytest.raises(InvalidArgumentError, match="certificate"):
        rmpc.load(tampered)
