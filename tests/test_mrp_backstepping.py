"""Paper M's three backstepping controllers: Lyapunov identities and the scenario outcomes.

The Lyapunov checks integrate plant and controller jointly (``closed_loop_rhs`` with DOP853):
they test the identities of seed sections 5.1-5.3, which hold in continuous time. The scenario
checks are seed section 7.9. Run lengths: the continuous M1 and M2 runs use the seed's 100 s
and window [50, 100] s (joint integration takes under 4 s); the *sampled* runs (the ``step``
protocol through :func:`rmpc.sim.simulate`, RK4 plant at 0.01 s) are shortened to 60 s with the
window [30, 60] s. On the full 100 s (script outside the repository, see the closing report)
the sampled windows [30, 60] and [50, 100] gave the same maxima to 0.1 %: the transients are
over by 15 s and the window holds more than one period (20.9 s) of the disk's speed.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from benchmarks.families.mrp.family import chattering
from models import MRPSatellite, paper_m_scenario
from models.attitude.mrp import mrp_error_angle
from rmpc import MAB, NESO, CFBackstepping, CommandFilter, ConstantDisturbance, TuningFunctionAB, simulate
from rmpc.sim.plants import SampledPlant
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError

CONTROLLERS = {"BS": CFBackstepping, "MAB": MAB, "TFAB": TuningFunctionAB}


def joint_run(controller, scenario, t_end: float, disturbance=None, plant=None, rtol: float = 1e-10,
              atol: float = 1e-12, dt: float = 0.01):
    """Plant and controller integrated jointly; returns the sample grid and the joint states."""
    plant = scenario.true_satellite() if plant is None else plant
    x0 = scenario.initial_state()
    y0 = np.concatenate((x0, controller.initial_internal(x0)))
    sol = solve_ivp(controller.closed_loop_rhs(plant, disturbance), (0.0, t_end), y0, method="DOP853",
                    rtol=rtol, atol=atol, dense_output=True)
    assert sol.success
    t = np.arange(0.0, t_end + 0.5 * dt, dt)
    return t, sol.sol(t)


def error_angles_deg(rows: np.ndarray, sigma_ref: np.ndarray) -> np.ndarray:
    """Phi_e = 4 atan|se| (deg) for each row ``[sigma, ...]``."""
    return np.degrees([mrp_error_angle(s[:3], sigma_ref) for s in rows])


@pytest.fixture(scope="module")
def m1():
    return paper_m_scenario("M1")


@pytest.fixture(scope="module")
def m2():
    return paper_m_scenario("M2")


def test_bs_lyapunov_identity(m1) -> None:
    """BS on M1 (J = J0, d = 0): V' = -c1 |zb1|^2 - c2 |zb2|^2, with and without a torque clip."""
    for u_max in (None, 1.0):
        bs = CFBackstepping(m1.model(), target=m1.sigma_ref, u_max=u_max)
        t, y = joint_run(bs, m1, 20.0, rtol=1e-12, atol=1e-14)
        v = np.array([bs.lyapunov(y[:6, k], y[6:, k]) for k in range(t.size)])
        zb = [bs.compensated_errors(y[:6, k], y[6:, k]) for k in range(t.size)]
        rate = np.array([-bs.c1 * z1 @ z1 - bs.c2 * z2 @ z2 for z1, z2 in zb])
        assert np.all(np.diff(v) < 0.0)
        central = (v[2:] - v[:-2]) / (t[2:] - t[:-2])
        np.testing.assert_allclose(central, rate[1:-1], rtol=1e-3)
        u = np.array([bs.law(y[:6, k], y[6:, k]) for k in range(0, t.size, 10)])
        if u_max is not None:
            assert np.abs(u).max() <= 1.0 and np.abs(y[15:18]).max() > 1e-3  # clip acted, chi2 moved
        else:
            np.testing.assert_allclose(y[15:18], 0.0, atol=1e-12)  # chi2 = 0 without a clip


def test_mab_without_estimator_is_iss(m1) -> None:
    """Constant Td = [0.05, -0.05, 0.05] N m, damping only: limsup |zb| <= sup|Tt| / (2 sqrt(c_min kappa))."""
    mab = MAB(m1.model(), target=m1.sigma_ref, estimator=None)
    td = np.array([0.05, -0.05, 0.05])
    t, y = joint_run(mab, m1, 100.0, disturbance=ConstantDisturbance(td))
    bound = np.linalg.norm(td) / (2.0 * np.sqrt(min(mab.c1, mab.c2) * mab.kappa))
    assert bound == pytest.approx(0.0354, abs=1e-4)
    late = t >= 80.0
    norms = [np.linalg.norm(np.concatenate(mab.compensated_errors(y[:6, k], y[6:, k])))
             for k in np.nonzero(late)[0]]
    assert max(norms) <= bound
    assert max(norms) > 0.1 * bound  # the disturbance did act (the seed observed 0.0145)


def test_tfab_lyapunov_and_virtual_rate_derivative(m1) -> None:
    """TF-AB, constant Td, J = J0: V = (|z1|^2 + |z2|^2 + Tt' Gamma^-1 Tt)/2 has V' = -c1|z1|^2 - c2|z2|^2."""
    tfab = TuningFunctionAB(m1.model(), target=m1.sigma_ref)
    td = np.array([0.05, -0.05, 0.05])
    t, y = joint_run(tfab, m1, 30.0, disturbance=ConstantDisturbance(td), rtol=1e-12, atol=1e-14)
    v = np.array([tfab.lyapunov(y[:6, k], y[6:, k], td) for k in range(t.size)])
    assert np.all(np.diff(v) <= 0.0)
    errs = [tfab.errors(y[:6, k]) for k in range(t.size)]
    rate = np.array([-tfab.c1 * z1 @ z1 - tfab.c2 * z2 @ z2 for z1, z2 in errs])
    central = (v[2:] - v[:-2]) / (t[2:] - t[:-2])
    np.testing.assert_allclose(central, rate[1:-1], rtol=1e-3)
    np.testing.assert_allclose(y[6:9, -1], td, atol=2e-3)  # the estimate converged
    # alpha1' against a central difference of alpha1 along the plant's vector field
    sat = m1.model()
    for k in (0, 150, 700):
        x = y[:6, k]
        geometry = tfab._geometry(x)
        _, alpha1_dot = tfab.virtual_rate(geometry)
        x_dot = sat.dynamics(x, tfab.law(x, y[6:, k]), td)
        h = 1e-6
        ahead = tfab.virtual_rate(tfab._geometry(x + h * x_dot))[0]
        behind = tfab.virtual_rate(tfab._geometry(x - h * x_dot))[0]
        np.testing.assert_allclose((ahead - behind) / (2 * h), alpha1_dot, rtol=0, atol=1e-7)


def test_m1_converges_and_the_estimate_stays_zero(m1) -> None:
    """Seed 7.9, M1 by joint integration: every controller below 1e-6 deg on [50, 100] s and
    MAB's estimate below 1e-9 N m (observer and plant see the same rates exactly)."""
    for name, cls in CONTROLLERS.items():
        ctrl = cls(m1.model(), target=m1.sigma_ref)
        t, y = joint_run(ctrl, m1, 100.0, rtol=1e-12, atol=1e-14, dt=0.1)
        phi = error_angles_deg(y[:, t >= 50.0].T, m1.sigma_ref)
        assert phi.max() < 1e-6, name
        if name == "MAB":
            t_hat = np.array([ctrl.torque_estimate(y[6:, k]) for k in range(t.size)])
            assert np.abs(t_hat).max() < 1e-9


@pytest.fixture(scope="module")
def m2_continuous(m2):
    """The three controllers on M2 by joint integration, 100 s (seed metric window [50, 100] s)."""
    out = {}
    disk = m2.disturbance()
    for name, cls in CONTROLLERS.items():
        ctrl = cls(m2.model(), target=m2.sigma_ref)
        t, y = joint_run(ctrl, m2, 100.0, disturbance=disk)
        out[name] = (ctrl, t, y, error_angles_deg(y.T, m2.sigma_ref))
    return out


def test_m2_outcomes_continuous(m2, m2_continuous) -> None:
    """Seed 7.9, M2: BS keeps >= 0.2 deg, MAB <= 0.05 deg, BS/MAB >= 10, TF-AB/MAB >= 3, and the
    NESO's torque within 2e-3 N m of the disk's from 20 s (seed table: 8.3e-4)."""
    worst = {name: phi[t >= 50.0].max() for name, (_, t, _, phi) in m2_continuous.items()}
    assert worst["BS"] >= 0.2
    assert worst["MAB"] <= 0.05
    assert worst["BS"] / worst["MAB"] >= 10.0
    assert worst["TFAB"] / worst["MAB"] >= 3.0
    mab, t, y, _ = m2_continuous["MAB"]
    disk = m2.disturbance()
    late = np.nonzero(t >= 20.0)[0]
    est_err = max(np.abs(mab.torque_estimate(y[6:, k]) - disk.torque(t[k], y[:6, k])).max() for k in late)
    assert est_err <= 2e-3


@pytest.fixture(scope="module")
def m2_sampled(m2):
    """The step protocol through simulate on M2, 60 s, at Ts = 0.01 s and 0.05 s (RK4 plant, 0.01 s)."""
    out = {}
    for dt in (0.01, 0.05):
        sc = paper_m_scenario("M2", duration=60.0, dt=dt)
        for name, cls in CONTROLLERS.items():
            ctrl = cls(sc.model(), target=sc.sigma_ref, dt=dt)
            plant = SampledPlant(sc.true_satellite(), dt, integrator="RK4", substep=0.01)
            out[name, dt] = simulate(ctrl, plant, sc.initial_state(), duration=sc.duration,
                                     disturbance=sc.disturbance())
    return out


def test_m2_sampled_runs_match_the_continuous_ones(m2, m2_continuous, m2_sampled) -> None:
    for (name, dt), traj in m2_sampled.items():
        _, t, _, phi = m2_continuous[name]
        continuous = phi[(t >= 30.0) & (t <= 60.0 + 1e-9)].max()
        sampled = error_angles_deg(traj.x, m2.sigma_ref)[traj.t >= 30.0].max()
        assert sampled == pytest.approx(continuous, rel=0.05), (name, dt)


def test_m2_no_chattering_and_step_info(m2, m2_sampled) -> None:
    """Total variation of the torque on [20, 60] s within 1.5 x that of the disk's (seed: 1.00-1.07),
    measured by the suite's own metric (:func:`benchmarks.families.mrp.family.chattering`)."""
    for (name, dt), traj in m2_sampled.items():
        if dt != 0.01:
            continue
        assert chattering(traj.t, traj.u_applied, traj.d, 20.0)["chatter_ratio"] <= 1.5, name
        assert traj.status_counts() == {"ok": traj.n_steps}
        assert "torque_estimate" in traj.info[-1].extra or name == "BS"
    mab = m2_sampled["MAB", 0.01]
    t_hat = np.array([info.extra["torque_estimate"] for info in mab.info])
    late = mab.t[:-1] >= 20.0
    assert np.abs(t_hat[late] - mab.d[late]).max() <= 2e-3


def test_m3_torque_limit_and_model_error() -> None:
    """M3 (true inertia 1.3 J0 and 0.7 J0, 1 N m limit), sampled, 40 s: the clip holds and MAB keeps
    the disk's error small (seed table: 0.0194 deg on [50, 100] s at 1.3 J0)."""
    for scale in (1.3, 0.7):
        sc = paper_m_scenario("M3", inertia_scale=scale, duration=40.0, dt=0.05)
        mab = MAB(sc.model(), target=sc.sigma_ref, dt=sc.dt, u_max=sc.u_max)
        plant = SampledPlant(sc.true_satellite(), sc.dt, integrator="RK4", substep=0.01)
        traj = simulate(mab, plant, sc.initial_state(), duration=sc.duration, disturbance=sc.disturbance())
        assert np.abs(traj.u_applied).max() <= 1.0
        assert traj.info[0].extra["saturated"]
        assert error_angles_deg(traj.x, sc.sigma_ref)[traj.t >= 20.0].max() <= 0.05


def test_step_is_the_law_then_rk4_with_x_and_u_held(m2) -> None:
    sc = m2
    x0 = sc.initial_state()
    for cls in CONTROLLERS.values():
        ctrl = cls(sc.model(), target=sc.sigma_ref, dt=0.05, u_max=1.0)
        u = ctrl.step(x0)
        z0 = ctrl.initial_internal(x0)
        np.testing.assert_array_equal(u, ctrl.law(x0, z0))
        h = 0.05
        k1 = ctrl.internal_derivative(x0, z0, u)
        k2 = ctrl.internal_derivative(x0, z0 + 0.5 * h * k1, u)
        k3 = ctrl.internal_derivative(x0, z0 + 0.5 * h * k2, u)
        k4 = ctrl.internal_derivative(x0, z0 + h * k3, u)
        expected = ctrl.project_internal(z0 + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4))
        np.testing.assert_allclose(ctrl.internal, expected, rtol=0, atol=1e-15)
        assert ctrl.last.status == "ok" and ctrl.last.extra["saturated"]
        assert np.abs(u).max() == 1.0
        ctrl.reset()
        assert ctrl.internal is None and ctrl.last is None


def test_estimators_are_pluggable(m2) -> None:
    j0 = m2.model().inertia
    linear = MAB(m2.model(), estimator=NESO.linear(j0, bandwidth=10.0))
    assert linear.settings()["estimator"]["estimator"] == "linear ESO"
    none = MAB(m2.model(), estimator=None)
    assert none.n_internal == 12 and none.settings()["estimator"] is None
    assert MAB(m2.model()).settings()["estimator"]["bandwidth"] == 10.0
    assert TuningFunctionAB(m2.model()).settings()["gamma"] == [10.0, 10.0, 10.0]


def test_bad_input_names_the_argument() -> None:
    sat = MRPSatellite.paper_m()
    with pytest.raises(ArgumentTypeError, match=r"^plant:"):
        CFBackstepping(np.eye(3))
    for cls in CONTROLLERS.values():
        with pytest.raises(InvalidArgumentError, match="c1"):
            cls(sat, c1=0.0)
        with pytest.raises(InvalidArgumentError, match="u_max"):
            cls(sat, u_max=[1.0, -1.0, 1.0])
        with pytest.raises(InvalidArgumentError, match="target"):
            cls(sat, target=[0.1, 0.2])
        with pytest.raises(InvalidArgumentError, match="dt"):
            cls(sat, dt=0.0)
    with pytest.raises(InvalidArgumentError, match="kappa"):
        MAB(sat, kappa=-3.0)
    with pytest.raises(ArgumentTypeError, match="estimator"):
        MAB(sat, estimator="kalman")
    with pytest.raises(InvalidArgumentError, match="gamma"):
        TuningFunctionAB(sat, gamma=0.0)
    with pytest.raises(InvalidArgumentError, match="command_filter"):
        CFBackstepping(sat, command_filter=CommandFilter(size=2))
    with pytest.raises(InvalidArgumentError, match="x"):
        CFBackstepping(sat).step([0.1, 0.2, 0.3])
