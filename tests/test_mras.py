"""The MIT rule (rmpc.mpc.adaptation, rmpc.mpc.mras) against Astrom & Wittenmark's example 5.2 and a
continuous solution.

Example 5.2 (Astrom & Wittenmark, *Adaptive Control*, 2nd ed.): plant ``y' = -y + 0.5 u``,
model ``ym' = -2 ym + 2 uc``, ``u = theta1 uc - theta2 y``, square-wave command of period
20 s. The gains converge to ``theta1 = 4`` and ``theta2 = 2`` (``-2`` in the form
``u = theta1 uc + k_y y``); the sampled loop (``dt = 0.01``) converges to the exact
discrete-time matching gains 3.980 and 1.980, which differ from 4 and 2 by ``O(dt)``.
"""

from __future__ import annotations

import numpy as np
import pytest
from mras_example_5_2 import EXAMPLE_5_2_GAINS, example_5_2
from scipy.integrate import solve_ivp

from rmpc.errors import ArgumentTypeError, InvalidArgumentError
from rmpc.mpc.adaptation import MITRule
from rmpc.mpc.mras import ParameterIntegrator, SensitivityFilter


def _continuous_example_5_2(gamma: float, duration: float, period: float = 20.0) -> np.ndarray:
    """The continuous-time MRAS of example 5.2 (the book's ODEs), solved by scipy; theta at ``duration``.

    States: ``y, ym, f_uc, f_y, theta1, theta2`` with ``f = am / (p + am)`` applied to ``uc``
    and ``y``; the square wave is integrated half-period by half-period (no discontinuity
    inside an integration interval).
    """
    a, b, am, bm = 1.0, 0.5, 2.0, 2.0

    def rhs(_t: float, s: np.ndarray, uc: float) -> list[float]:
        y, ym, f_uc, f_y, th1, th2 = s
        u = th1 * uc - th2 * y
        e = y - ym
        return [-a * y + b * u, -am * ym + bm * uc, am * (uc - f_uc), am * (y - f_y),
                -gamma * e * f_uc, gamma * e * f_y]

    state = np.zeros(6)
    t, half, sign = 0.0, 0.5 * period, 1.0
    while t < duration - 1e-12:
        t_end = min(t + half, duration)
        sol = solve_ivp(rhs, (t, t_end), state, args=(sign,), rtol=1e-10, atol=1e-12, method="DOP853")
        state = sol.y[:, -1]
        t, sign = t_end, -sign
    return state[4:]


def test_example_5_2_converges_to_4_and_2_with_gamma_1() -> None:
    run = example_5_2(gamma=1.0, duration=600.0)
    assert run.target == EXAMPLE_5_2_GAINS == (4.0, 2.0)
    # theta2 multiplies -y: the feedback gain in u = theta1 uc + k_y y is k_y = -theta2 -> -2.
    theta_100, theta_600 = run.theta[10_000], run.theta[-1]
    # Measured: (3.248, 1.248) at 100 s, (3.655, 1.655) at 200 s, (3.959, 1.959) at 600 s.
    assert np.all(np.abs(theta_100 - [4.0, 2.0]) > 0.5)
    assert np.all(np.abs(theta_600 - [4.0, 2.0]) < 0.045)
    assert np.all(np.abs(theta_600 - run.target_sampled) < 0.025)
    assert 500.0 < run.settling_time(0.05) < 560.0  # measured 543 s
    assert np.all(np.diff(run.theta[::2000, 0]) > 0.0)  # theta1 creeps up, period after period
    # The model is followed: the error over the last period is small against |ym| ~ 1.
    last = run.t >= 580.0
    assert np.max(np.abs(run.y[last] - run.ym[last])) < 0.01  # measured 0.0045


@pytest.mark.parametrize("gamma", [1.0, 5.0])
def test_example_5_2_matches_the_continuous_time_solution(gamma: float) -> None:
    """At t = 100 s the sampled rule follows the book's ODEs, with an O(dt) difference."""
    reference = _continuous_example_5_2(gamma=gamma, duration=100.0)
    coarse = np.max(np.abs(example_5_2(gamma=gamma, duration=100.0, dt=0.01).theta[-1] - reference))
    fine = np.max(np.abs(example_5_2(gamma=gamma, duration=100.0, dt=0.001).theta[-1] - reference))
    # Measured: gamma = 1: (3.248, 1.248), coarse 2e-5, fine 3e-6;
    #           gamma = 5: (3.974, 1.974), coarse 0.017, fine 0.0017.
    assert coarse < 0.02
    assert fine < 0.25 * coarse
    if gamma == 1.0:
        assert 3.2 < reference[0] < 3.3 and 1.2 < reference[1] < 1.3
    else:
        assert np.all(np.abs(reference - [4.0, 2.0]) < 0.03)


def test_sampled_loop_converges_to_its_matching_gains() -> None:
    """The sampled loop converges to its own matching gains, which tend to 4 and 2 as dt -> 0."""
    run = example_5_2(gamma=5.0, duration=200.0, dt=0.01)
    a_d, am_d = np.exp(-0.01), np.exp(-0.02)
    b_d, bm_d = 0.5 * (1.0 - a_d), 1.0 - am_d
    assert run.target_sampled == pytest.approx((bm_d / b_d, (a_d - am_d) / b_d), rel=1e-12)
    assert run.target_sampled == pytest.approx((3.9801, 1.9801), abs=1e-4)
    assert np.all(np.abs(run.theta[-1] - run.target_sampled) < 1e-3)
    assert run.settling_time(1e-3, sampled=True) < 190.0  # measured 180.7 s
    assert run.settling_time(1e-3) == float("inf")  # never within 1e-3 of the continuous 4, 2


@pytest.mark.parametrize("normalized", [False, True])
def test_plain_and_normalised_rules_both_converge_for_a_small_gain(normalized: bool) -> None:
    run = example_5_2(gamma=1.0, duration=600.0, normalized=normalized)
    assert np.all(np.abs(run.theta[-1] - run.target_sampled) < 0.025)
    assert np.max(np.abs(run.theta)) < 4.5  # no overshoot worth the name


def test_normalised_rule_survives_a_large_command_where_the_plain_rule_does_not() -> None:
    """Amplitude 10: the plain rule's speed grows with uc^2 and it goes unstable (A & W, chapter 5)."""
    plain = example_5_2(gamma=1.0, duration=300.0, amplitude=10.0)
    normalised = example_5_2(gamma=1.0, duration=300.0, amplitude=10.0, normalized=True)
    assert np.max(np.abs(plain.theta)) > 50.0  # measured 240
    assert np.all(np.abs(normalised.theta[-1] - normalised.target_sampled) < 0.03)
    assert np.max(np.abs(normalised.theta)) < 4.5


def test_normalised_rule_is_amplitude_invariant() -> None:
    small = example_5_2(gamma=1.0, duration=200.0, amplitude=1.0, normalized=True, alpha=1e-9)
    large = example_5_2(gamma=1.0, duration=200.0, amplitude=10.0, normalized=True, alpha=1e-9)
    np.testing.assert_allclose(large.theta, small.theta, atol=1e-6)
    np.testing.assert_allclose(large.y, 10.0 * small.y, rtol=1e-5, atol=1e-8)


# -- the pieces -------------------------------------------------------------------------


def test_mit_rule_is_the_gradient_of_e2_over_2_through_an_integrator() -> None:
    rule = MITRule(gain=3.0, normalized=False)
    # dyadic data: sens' e is exact however the BLAS sums it (with e = [0.2, -0.4, 0.1] its first
    # entry, 0 in exact arithmetic, came out -1.9e-18 in the test's product and 0 in the rule's)
    sens = np.array([[1.0, 2.0], [0.5, -1.0], [0.0, 4.0]])
    e = np.array([0.25, -0.5, 0.125])
    integrator = ParameterIntegrator(2, dt=0.1)
    theta = integrator.step(rule.rate(e, sens))
    np.testing.assert_allclose(theta, -3.0 * 0.1 * sens.T @ e)
    normalised = MITRule(gain=3.0, normalized=True, alpha=0.5)
    np.testing.assert_allclose(
        ParameterIntegrator(2, dt=0.1).step(normalised.rate(e, sens)),
        -3.0 * 0.1 * sens.T @ e / (0.5 + np.sum(sens**2)),
    )
    integrator.reset()
    np.testing.assert_array_equal(integrator.theta, [0.0, 0.0])


def test_mit_rule_projection_clips_theta() -> None:
    rule = MITRule(gain=100.0, normalized=False)
    theta = ParameterIntegrator(2, dt=0.1, bound=[0.5, 2.0]).step(rule.rate([1.0], [[-1.0, 1.0]]))
    np.testing.assert_array_equal(theta, [0.5, -2.0])


def test_sensitivity_filter_columns_and_time_varying_matrix() -> None:
    filt = SensitivityFilter([[0.5]], [[1.0, 0.0]], columns=2)
    filt.advance([[1.0, 2.0], [3.0, 4.0]])
    np.testing.assert_array_equal(filt.output(), [[1.0, 2.0]])
    filt.advance([[0.0, 0.0], [0.0, 0.0]], a=[[0.25]])
    np.testing.assert_array_equal(filt.output(), [[0.25, 0.5]])
    filt.reset()
    np.testing.assert_array_equal(filt.state, [[0.0, 0.0]])


@pytest.mark.parametrize(
    ("make", "argument"),
    [
        (lambda: ParameterIntegrator(0, dt=0.1), "n_params"),
        (lambda: MITRule(gain=-1.0), "gain"),
        (lambda: ParameterIntegrator(2, dt=0.0), "dt"),
        (lambda: MITRule(gain=1.0, normalized=True, alpha=0.0), "alpha"),
        (lambda: ParameterIntegrator(2, dt=0.1, bound=[1.0, -1.0]), "bound"),
        (lambda: ParameterIntegrator(2, dt=0.1, theta0=[1.0]), "theta0"),
        (lambda: MITRule(gain=1.0).rate([1.0, 2.0], np.ones((3, 2))), "sensitivity"),
        (lambda: MITRule(gain=1.0).rate([np.nan], np.ones((1, 2))), "error"),
        (lambda: ParameterIntegrator(2, dt=0.1).step([1.0, 2.0, 3.0]), "rate"),
        (lambda: SensitivityFilter([[1.0, 0.0]], [[1.0]]), "a"),
        (lambda: SensitivityFilter.first_order(pole=-2.0, dt=0.01), "pole"),
        (lambda: example_5_2(gamma=-1.0), "gamma"),
        (lambda: example_5_2(b=0.0), "b"),
    ],
)
def test_bad_arguments_name_the_argument(make: object, argument: str) -> None:
    with pytest.raises(InvalidArgumentError) as info:
        make()  # type: ignore[operator]
    assert info.value.argument == argument
    assert str(info.value).startswith(f"{argument}: expected ")


def test_bad_types_name_the_argument() -> None:
    with pytest.raises(ArgumentTypeError, match=r"^gain: expected a real number"):
        MITRule(gain="fast")  # type: ignore[arg-type]


def test_lyapunov_rule_over_actuated_uses_the_minimum_norm_rate():
    """Four inputs through a rank-3 input matrix (paper W's wheels): no singular solve."""
    from rmpc.mpc.adaptation import LyapunovRule

    d = np.array([[1.0, 0, 0, 1], [0, 1.0, 0, 1], [0, 0, 1.0, 1]]) / np.array([1, 1, 1, np.sqrt(3)])
    b = np.vstack([np.zeros((3, 4)), d])
    rng = np.random.default_rng(4)
    m = rng.standard_normal((6, 6))
    p = m @ m.T + 6 * np.eye(6)
    e = rng.standard_normal(6)
    rule = LyapunovRule(gain=100.0)
    rate = rule.rate(e, b, p)
    expected = 100.0 * np.linalg.pinv(b.T @ p @ b) @ b.T @ p @ e
    np.testing.assert_allclose(rate, expected, rtol=1e-9, atol=1e-12)
    null = np.linalg.svd(d)[2][-1]  # the wheel combination D maps to zero
    assert abs(null @ rate) < 1e-9 * np.linalg.norm(rate)
