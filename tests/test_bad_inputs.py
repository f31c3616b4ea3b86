"""Bad input raises a toolkit error (ValueError / TypeError subclass) naming the argument.

Contract (API.md): the message names the argument, what was expected and what was found.
The Euler singularity raises :class:`SingularityError` naming ``theta``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from models import (
    FaultSchedule,
    FlexibleSatellite,
    PolytopicModel,
    ReactionWheelActuator,
    RigidSatellite,
    TorqueLimiter,
    WheelDisturbance,
    kinematics_matrix,
    zoh,
)
from rmpc import GIPC, LQR, OfflineRMPC, SineDisturbance, StepDisturbance, simulate
from toolkit_common.errors import InvalidArgumentError, SingularityError, ToolkitError

NAN, INF = float("nan"), float("inf")
SAT = RigidSatellite.paper_p()
X0 = SAT.initial_state()
POLY = SAT.polytope(X0, dt=0.01, spread=0.3, mode="scalar")
Q6, R3 = np.eye(6), np.eye(3)
LQR_CTRL = LQR(POLY, Q6, R3)
A2, B2 = np.array([[1.0, 0.1], [0.0, 1.0]]), np.array([[0.0], [0.1]])
PLANT2 = PolytopicModel([(A2, B2), (A2, 2 * B2)], dt=0.1)


class NanController:
    last = None

    def step(self, x):
        return np.full(3, np.nan)


def _sim(**kw):
    """simulate(LQR, polytope, X0, 0.05) with keyword overrides."""
    args = {"controller": LQR_CTRL, "plant": POLY, "x0": X0, "duration": 0.05}
    args.update(kw)
    return lambda: simulate(**args)


def _x(**kw) -> np.ndarray:
    x = X0.copy()
    for k, v in kw.items():
        x["phi theta psi p q r".split().index(k)] = v
    return x


# (id, call, argument name)
CASES: list[tuple[str, Callable[[], object], str]] = [
    # --- inertia -----------------------------------------------------------------------
    ("inertia-length-2", lambda: RigidSatellite([1.0, 2.0]), "inertia"),
    ("inertia-length-4", lambda: RigidSatellite([1.0, 2.0, 3.0, 4.0]), "inertia"),
    ("inertia-3x4", lambda: RigidSatellite(np.ones((3, 4))), "inertia"),
    ("inertia-3d", lambda: RigidSatellite(np.ones((3, 3, 3))), "inertia"),
    ("inertia-scalar", lambda: RigidSatellite(2.0), "inertia"),
    ("inertia-nan", lambda: RigidSatellite([1.0, NAN, 2.0]), "inertia"),
    ("inertia-inf-full", lambda: RigidSatellite([[1.0, 0, 0], [0, INF, 0], [0, 0, 1.0]]), "inertia"),
    ("inertia-zero-diag", lambda: RigidSatellite([1.0, 0.0, 2.0]), "inertia"),
    ("inertia-negative-diag", lambda: RigidSatellite([1.0, -2.0, 3.0]), "inertia"),
    ("inertia-zero-matrix-entry", lambda: RigidSatellite(np.diag([1.0, 0.0, 2.0])), "inertia"),
    ("inertia-negative-matrix", lambda: RigidSatellite(-np.eye(3)), "inertia"),
    ("inertia-non-symmetric",
     lambda: RigidSatellite([[2.0, 0.5, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 3.0]]), "inertia"),
    ("inertia-indefinite",  # eigenvalues 3, -1, 1
     lambda: RigidSatellite([[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]]), "inertia"),
    ("inertia-strings", lambda: RigidSatellite(["a", "b", "c"]), "inertia"),
    ("inertia-ragged", lambda: RigidSatellite([[1.0, 2.0], [3.0]]), "inertia"),
    ("inertia-string", lambda: RigidSatellite("diag"), "inertia"),
    # --- states, inputs, operating points ------------------------------------------------
    ("x-length-5", lambda: SAT.dynamics(np.zeros(5)), "x"),
    ("x-matrix", lambda: SAT.dynamics(np.zeros((6, 2))), "x"),
    ("x-nan", lambda: SAT.dynamics(_x(p=NAN)), "x"),
    ("x-inf", lambda: SAT.dynamics(_x(psi=-INF)), "x"),
    ("x-string", lambda: SAT.dynamics("x0"), "x"),
    ("u-length-2", lambda: SAT.dynamics(X0, u=[1.0, 2.0]), "u"),
    ("u-nan", lambda: SAT.dynamics(X0, u=[0.0, NAN, 0.0]), "u"),
    ("d-inf", lambda: SAT.dynamics(X0, d=[INF, 0.0, 0.0]), "d"),
    ("energy-x-length", lambda: SAT.kinetic_energy(np.zeros(3)), "x"),
    ("momentum-x-nan", lambda: SAT.angular_momentum_inertial(_x(q=NAN)), "x"),
    ("x_op-length", lambda: SAT.linearize(np.zeros(4)), "x_op"),
    ("x_op-nan", lambda: SAT.polytope(_x(phi=NAN), 0.01, 0.3), "x_op"),
    ("u_op-nan", lambda: SAT.linearize(X0, [NAN, 0.0, 0.0]), "u_op"),
    ("scale-string", lambda: SAT.initial_state("big"), "scale"),
    # --- sample time ------------------------------------------------------------------
    ("discretize-dt-zero", lambda: SAT.discretize(X0, 0.0), "dt"),
    ("discretize-dt-negative", lambda: SAT.discretize(X0, -0.01), "dt"),
    ("discretize-dt-nan", lambda: SAT.discretize(X0, NAN), "dt"),
    ("discretize-dt-string", lambda: SAT.discretize(X0, "0.01"), "dt"),
    ("linear-model-dt-zero", lambda: SAT.linear_model(X0, 0.0), "dt"),
    ("polytope-dt-negative", lambda: SAT.polytope(X0, -0.01, 0.3), "dt"),
    ("zoh-dt-zero", lambda: zoh(A2, B2, 0.0), "dt"),
    ("polytopic-dt-zero", lambda: PolytopicModel([(A2, B2)], dt=0.0), "dt"),
    ("polytopic-dt-negative", lambda: PolytopicModel([(A2, B2)], dt=-0.1), "dt"),
    ("polytopic-dt-inf", lambda: PolytopicModel([(A2, B2)], dt=INF), "dt"),
    # --- polytope options ---------------------------------------------------------------
    ("spread-negative", lambda: SAT.polytope(X0, 0.01, -0.1), "spread"),
    ("spread-one", lambda: SAT.polytope(X0, 0.01, 1.0), "spread"),
    ("spread-large", lambda: SAT.polytope(X0, 0.01, 1.5, mode="box"), "spread"),
    ("spread-nan", lambda: SAT.polytope(X0, 0.01, NAN), "spread"),
    ("spread-vertices", lambda: SAT.inertia_vertices(-0.5), "spread"),
    ("mode-unknown", lambda: SAT.polytope(X0, 0.01, 0.3, mode="ellipse"), "mode"),
    ("mode-case", lambda: SAT.inertia_vertices(0.3, mode="Box"), "mode"),
    # --- zoh matrices -------------------------------------------------------------------
    ("zoh-a-not-square", lambda: zoh(np.ones((2, 3)), B2, 0.1), "a"),
    ("zoh-a-nan", lambda: zoh([[NAN, 0.0], [0.0, 1.0]], B2, 0.1), "a"),
    ("zoh-b-rows", lambda: zoh(A2, np.ones((3, 1)), 0.1), "b"),
    # --- vertices -----------------------------------------------------------------------
    ("vertices-empty-list", lambda: PolytopicModel([], dt=0.1), "vertices"),
    ("vertices-empty-tuple", lambda: PolytopicModel((), dt=0.1), "vertices"),
    ("vertices-different-n",
     lambda: PolytopicModel([(A2, B2), (np.eye(3), np.ones((3, 1)))], dt=0.1), "vertices"),
    ("vertices-different-m", lambda: PolytopicModel([(A2, B2), (A2, np.ones((2, 2)))], dt=0.1), "vertices"),
    ("vertices-b-rows", lambda: PolytopicModel([(A2, B2), (A2, np.ones((3, 1)))], dt=0.1), "vertices"),
    ("vertices-a-not-square", lambda: PolytopicModel([(np.ones((2, 3)), B2)], dt=0.1), "vertices"),
    ("vertices-not-pair", lambda: PolytopicModel([(A2, B2), (A2,)], dt=0.1), "vertices"),
    ("vertices-ndarray", lambda: PolytopicModel(np.stack([A2, A2]), dt=0.1), "vertices"),
    ("vertices-nan", lambda: PolytopicModel([(A2, [[0.0], [NAN]])], dt=0.1), "vertices"),
    ("nominal-shape", lambda: PolytopicModel([(A2, B2)], dt=0.1, nominal=(np.eye(3), B2)), "nominal"),
    ("state-names-count", lambda: PolytopicModel([(A2, B2)], dt=0.1, state_names=["x"]), "state_names"),
    ("weights-sum", lambda: PLANT2.combination([0.5, 0.6]), "weights"),
    ("weights-negative", lambda: PLANT2.combination([-0.5, 1.5]), "weights"),
    ("weights-length", lambda: PLANT2.combination([1.0]), "weights"),
    ("vertex-index", lambda: PLANT2.vertex(2), "index"),
    ("systems-empty", lambda: PolytopicModel.from_statespace([]), "systems"),
    # --- LQR weights --------------------------------------------------------------------
    ("lqr-Q-not-psd", lambda: LQR(POLY, np.diag([1.0, 1, 1, 1, 1, -0.5]), R3), "Q"),
    ("lqr-Q-indefinite-full",
     lambda: LQR(POLY, np.block([[np.eye(3), 2 * np.eye(3)], [2 * np.eye(3), np.eye(3)]]), R3), "Q"),
    ("lqr-Q-non-symmetric", lambda: LQR(POLY, np.eye(6) + np.triu(np.ones((6, 6)), 1), R3), "Q"),
    ("lqr-Q-shape", lambda: LQR(POLY, np.eye(5), R3), "Q"),
    ("lqr-Q-nan", lambda: LQR(POLY, np.diag([1.0, 1, NAN, 1, 1, 1]), R3), "Q"),
    ("lqr-R-zero", lambda: LQR(POLY, Q6, np.zeros((3, 3))), "R"),
    ("lqr-R-psd-singular", lambda: LQR(POLY, Q6, np.diag([1.0, 1.0, 0.0])), "R"),
    ("lqr-R-negative", lambda: LQR(POLY, Q6, -np.eye(3)), "R"),
    ("lqr-R-non-symmetric", lambda: LQR(POLY, Q6, [[1.0, 0.5, 0], [0, 1.0, 0], [0, 0, 1.0]]), "R"),
    ("lqr-R-shape", lambda: LQR(POLY, Q6, np.eye(2)), "R"),
    ("lqr-plant-type", lambda: LQR(SAT, Q6, R3), "plant"),
    ("lqr-vertex-range", lambda: LQR(POLY, Q6, R3, vertex=5), "vertex"),
    ("lqr-x_ref-length", lambda: LQR(POLY, Q6, R3, x_ref=np.zeros(3)), "x_ref"),
    ("lqr-step-x", lambda: LQR_CTRL.step(np.zeros(5)), "x"),
    # --- simulate -----------------------------------------------------------------------
    ("simulate-x0-length", _sim(x0=np.zeros(5)), "x0"),
    ("simulate-x0-nan", _sim(x0=_x(theta=NAN)), "x0"),
    ("simulate-x0-nonlinear-length", _sim(plant=SAT, dt=0.01, x0=np.zeros(7)), "x0"),
    ("true_plant-string", _sim(true_plant="worst"), "true_plant"),
    ("true_plant-float", _sim(true_plant=1.5), "true_plant"),
    ("true_plant-dict", _sim(true_plant={"vertex": 0}), "true_plant"),
    ("true_plant-index-range", _sim(true_plant=7), "true_plant"),
    ("true_plant-bad-weights", _sim(true_plant=[0.5, 0.6]), "true_plant"),
    ("true_plant-weights-length", _sim(true_plant=np.ones(3) / 3), "true_plant"),
    ("true_plant-pair-shape", _sim(true_plant=(np.eye(6), np.ones((6, 1)))), "true_plant"),
    ("true_plant-pair-nan", _sim(true_plant=(np.full((6, 6), NAN), np.ones((6, 3)))), "true_plant"),
    ("true_plant-nonlinear", _sim(plant=SAT, dt=0.01, true_plant=0), "true_plant"),
    ("duration-and-n_steps", _sim(n_steps=5), "duration"),
    ("neither-duration-nor-n_steps", _sim(duration=None), "duration"),
    ("duration-zero", _sim(duration=0.0), "duration"),
    ("duration-negative", _sim(duration=-1.0), "duration"),
    ("n_steps-zero", _sim(duration=None, n_steps=0), "n_steps"),
    ("n_steps-float", _sim(duration=None, n_steps=2.5), "n_steps"),
    ("simulate-dt-missing-nonlinear", _sim(plant=SAT), "dt"),
    ("simulate-dt-zero-nonlinear", _sim(plant=SAT, dt=0.0), "dt"),
    ("simulate-dt-mismatch", _sim(dt=0.02), "dt"),
    ("simulate-controller", _sim(controller=object()), "controller"),
    ("simulate-controller-nan", _sim(controller=NanController()), "controller"),
    ("simulate-plant", _sim(plant="satellite"), "plant"),
    ("simulate-disturbance-size", _sim(disturbance=StepDisturbance([1.0, 2.0])), "disturbance"),
    ("simulate-disturbance-type", _sim(disturbance=0.1), "disturbance"),
    ("simulate-actuator-axes", _sim(actuator=ReactionWheelActuator(n_axes=2)), "actuator"),
    ("simulate-limiter", _sim(limiter=1.0), "limiter"),
    ("simulate-dt-nan", _sim(dt=NAN), "dt"),
    ("simulate-dt-string", _sim(dt="0.01"), "dt"),
    ("simulate-duration-below-dt", _sim(duration=0.004), "duration"),
    ("simulate-duration-beyond-max_steps", _sim(duration=1e12), "duration"),
    ("simulate-n_steps-beyond-max_steps", _sim(duration=None, n_steps=11, max_steps=10), "n_steps"),
    ("simulate-max_steps-zero", _sim(max_steps=0), "max_steps"),
    ("simulate-disturbance-nan-rigid", _sim(plant=SAT, dt=0.01, disturbance=lambda t: np.full(3, NAN)),
     "disturbance"),
    ("simulate-disturbance-nan-later", _sim(disturbance=lambda t: np.full(3, NAN if t > 0.02 else 0.0)),
     "disturbance"),
    ("simulate-limiter-nan-rigid", _sim(plant=SAT, dt=0.01, limiter=lambda u: np.full(3, NAN)), "limiter"),
    ("simulate-limiter-nan-linear", _sim(limiter=lambda u: np.full(3, NAN)), "limiter"),
    ("simulate-limiter-length", _sim(limiter=lambda u: np.zeros(2)), "limiter"),
    ("simulate-sensor-nan", _sim(sensor=lambda t, x: np.full(6, NAN)), "sensor"),
    ("gipc-backend-unknown", lambda: GIPC(POLY, Np=20, Nc=2, backend="nonsense"), "backend"),
    ("lqr-vertex-negative", lambda: LQR(POLY, Q6, R3, vertex=-1), "vertex"),
    ("vertex-index-negative", lambda: PLANT2.vertex(-1), "index"),
    ("vertices-zero-states",
     lambda: PolytopicModel([(np.zeros((0, 0)), np.zeros((0, 1)))], dt=0.1), "vertices"),
    ("vertices-zero-inputs", lambda: PolytopicModel([(A2, np.zeros((2, 0)))], dt=0.1), "vertices"),
    ("flexible-zero-quaternion",
     lambda: FlexibleSatellite.di_gennaro().dynamics(np.zeros(15), np.zeros(3)), "x"),
    ("gipc-Np-beyond-max_horizon", lambda: GIPC(POLY, Np=10**6), "Np"),
    ("gipc-Np-beyond-lifted-max_horizon", lambda: GIPC(POLY, Np=11, Nc=2, max_horizon=10), "Np"),
    ("gipc-max_horizon-zero", lambda: GIPC(POLY, max_horizon=0), "max_horizon"),
    # Np = Nc = 20000 is within max_horizon but the prediction matrix would take 29 GB
    ("gipc-prediction-matrix-too-large", lambda: GIPC(POLY, Np=20_000, Nc=20_000), "Nc"),
    ("gipc-prediction-limit-lowered", lambda: GIPC(POLY, Np=20, Nc=10, max_prediction_entries=100), "Nc"),
    ("gipc-prediction-limit-zero", lambda: GIPC(POLY, max_prediction_entries=0), "max_prediction_entries"),
    ("offline-n_ellipsoids-beyond-shrink", lambda: OfflineRMPC(POLY, Q6, R3, u_max=1.0, n_ellipsoids=10**7),
     "n_ellipsoids"),
    ("offline-n_ellipsoids-41-at-half", lambda: OfflineRMPC(POLY, Q6, R3, u_max=1.0, n_ellipsoids=41),
     "n_ellipsoids"),
    ("Q-complex", lambda: LQR(POLY, Q6 * (1 + 1j), R3), "Q"),
    ("Q-None", lambda: LQR(POLY, None, R3), "Q"),
    # --- disturbances and actuators -----------------------------------------------------
    ("step-magnitude-nan", lambda: StepDisturbance([NAN, 0.0, 0.0]), "magnitude"),
    ("step-t_start-negative", lambda: StepDisturbance([0.1, 0.0, 0.0], t_start=-1.0), "t_start"),
    ("sine-frequency-zero", lambda: SineDisturbance([0.1, 0.0, 0.0], frequency=0.0), "frequency"),
    ("limiter-u_max-zero", lambda: TorqueLimiter(0.0), "u_max"),
    ("limiter-u_max-negative-axis", lambda: TorqueLimiter([1.0, -1.0, 1.0]), "u_max"),
    ("limiter-kind", lambda: TorqueLimiter(1.0, kind="soft"), "kind"),
    ("wheel-unstable-pole", lambda: ReactionWheelActuator(a=1.0), "a"),
    ("wheel-pole-negative", lambda: ReactionWheelActuator(a=-0.5), "a"),  # |a| < 1 but a sign flip per sample
    ("wheel-b-zero", lambda: ReactionWheelActuator(b=0.0), "b"),
    ("wheel-b-negative", lambda: ReactionWheelActuator(b=-0.0093), "b"),
    ("wheel-c-zero", lambda: ReactionWheelActuator(c=0.0), "c"),
    ("wheel-c-negative", lambda: ReactionWheelActuator(c=-14.28), "c"),
    ("wheel-b-and-c-negative", lambda: ReactionWheelActuator(b=-0.0093, c=-14.28), "b"),  # DC gain > 0 still
    ("wheel-n_axes", lambda: ReactionWheelActuator(n_axes=0), "n_axes"),
    ("wheel-n_axes-bool", lambda: ReactionWheelActuator(n_axes=True), "n_axes"),
    ("wheel-n_axes-beyond-max_axes", lambda: ReactionWheelActuator(n_axes=10**9), "n_axes"),
    ("wheel-n_axes-beyond-lifted-max_axes", lambda: ReactionWheelActuator(n_axes=11, max_axes=10), "n_axes"),
    ("wheel-max_axes-zero", lambda: ReactionWheelActuator(max_axes=0), "max_axes"),
    ("wheel-disturbance-n_wheels-beyond-max_wheels", lambda: WheelDisturbance(10**12), "n_wheels"),
    ("wheel-disturbance-max_wheels-zero", lambda: WheelDisturbance(4, max_wheels=0), "max_wheels"),
    ("fault-schedule-n_wheels-beyond-max_wheels", lambda: FaultSchedule([], 10**12), "n_wheels"),
    ("fault-schedule-n_wheels-beyond-lifted", lambda: FaultSchedule([], 5, max_wheels=4), "n_wheels"),
    ("wheel-command-length", lambda: ReactionWheelActuator().step([1.0, 2.0]), "command"),
]


def _root(argument: str) -> str:
    """``"vertices[1] B"`` -> ``"vertices"``, ``"systems[0].dt"`` -> ``"systems"``."""
    for sep in ("[", " ", "."):
        argument = argument.split(sep)[0]
    return argument


@pytest.mark.parametrize(("call", "argument"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_input_raises_toolkit_error_naming_the_argument(call, argument):
    with pytest.raises((ValueError, TypeError)) as info:
        call()
    err = info.value
    assert isinstance(err, ToolkitError), f"{type(err).__name__} is not a ToolkitError: {err}"
    message = str(err)
    assert argument in message
    # the structured fields: the named argument is the offending one, and the message says
    # what was expected and what was found
    assert _root(err.argument) == argument, err.argument
    assert message.startswith(f"{err.argument}:")
    assert err.expected and err.expected in message
    assert err.found and err.found in message


def test_case_ids_are_unique():
    ids = [c[0] for c in CASES]
    assert len(ids) == len(set(ids))


@pytest.mark.parametrize("kw", [{"n_steps": 5}, {"duration": None}], ids=["both", "neither"])
def test_duration_xor_n_steps_message_names_both(kw):
    with pytest.raises(ValueError) as info:
        _sim(**kw)()
    assert "duration" in str(info.value) and "n_steps" in str(info.value)


# --- Euler singularity ----------------------------------------------------------------

SINGULAR_PITCHES = [np.pi / 2, -np.pi / 2, np.pi / 2 + 1e-5, 3 * np.pi / 2]


@pytest.mark.parametrize("theta", SINGULAR_PITCHES)
@pytest.mark.parametrize(
    "call",
    [
        lambda x: SAT.dynamics(x),
        lambda x: SAT.dynamics(x, u=[0.1, 0.0, 0.0]),
        lambda x: SAT.linearize(x),
        lambda x: SAT.discretize(x, 0.01),
        lambda x: SAT.polytope(x, 0.01, 0.3),
        lambda x: kinematics_matrix(x[0], x[1]),
    ],
    ids=["dynamics", "dynamics-u", "linearize", "discretize", "polytope", "kinematics_matrix"],
)
def test_pitch_of_90_degrees_raises_singularity_error_naming_theta(call, theta):
    x = np.array([0.3, theta, -0.2, 0.1, 0.2, -0.1])
    with pytest.raises(SingularityError) as info:
        call(x)
    assert isinstance(info.value, ToolkitError)
    assert "theta" in str(info.value)


def test_close_to_but_not_at_90_degrees_is_finite():
    x = np.array([0.3, np.radians(89.5), -0.2, 0.1, 0.2, -0.1])
    xdot = SAT.dynamics(x)
    assert np.all(np.isfinite(xdot))
    # the kinematics blow up like 1 / cos(theta) there, as they should
    assert abs(xdot[2]) > 10 * np.linalg.norm(x[3:])


def test_simulation_through_gimbal_lock_raises_instead_of_returning_nan():
    """Pitch 85 deg with a pitch rate of 1 rad/s reaches 90 deg within 0.1 s."""

    class Zero:
        last = None

        def step(self, x):
            return np.zeros(3)

    x0 = np.array([0.0, np.radians(85.0), 0.0, 0.0, 1.0, 0.0])
    with pytest.raises(SingularityError, match="theta"):
        simulate(Zero(), SAT, x0, duration=0.5, dt=0.01)


def test_gipc_prediction_bound_is_the_matrix_size():
    """The bound counts the prediction matrix's entries, (Np q) x (Nc m): at exactly that many a
    GIPC is built, one fewer is refused naming Nc and the limit."""
    entries = 20 * 3 * 10 * 3  # Np = 20, q = 3 outputs, Nc = 10, m = 3 inputs
    assert GIPC(POLY, Np=20, Nc=10, max_prediction_entries=entries).Nc == 10
    with pytest.raises(InvalidArgumentError, match="max_prediction_entries = 1799"):
        GIPC(POLY, Np=20, Nc=10, max_prediction_entries=entries - 1)
