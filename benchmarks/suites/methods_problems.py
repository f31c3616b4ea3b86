"""The problems of ``rmpc bench methods``: the field's test systems and the toolkit's satellites.

Each builder returns a :class:`MethodsProblem`: the polytope, the weights and bounds, the start
state, the plant the closed loop runs on and what the suite varies around them. The values come
from the publications (Kothare's examples, MUP's demo system) or from the toolkit's suites
(paper P's, paper W's and the flexible satellite's weights in ``benchmarks/families``); what the
suite adds is listed in :data:`SUITE_CHOICES`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = [
    "DISTURBANCE_FRACTION",
    "GRAVITY_GRADIENT_ALTITUDE",
    "HOLD_FRACTION",
    "PROBLEMS",
    "SHORT_PROBLEMS",
    "SUITE_CHOICES",
    "MethodsProblem",
    "build_problem",
    "gravity_gradient_bound",
]

#: The disturbance of the "disturbance" method: ``E`` = the nominal ``B`` (an input-channel
#: disturbance), ``w_max`` = this fraction of the input bound.
DISTURBANCE_FRACTION: float = 0.05


@dataclass(frozen=True)
class MethodsProblem:
    """One test problem of the methods suite.

    Attributes
    ----------
    name, title, source : str
        Key, one-line description and where the data come from.
    plant : models.PolytopicModel
        The polytope the controllers are designed on (its ``nominal`` is the nominal model).
    Q, R : ndarray
        State and input weights.
    u_max : float
        The input bound.
    input_constraint : str
        ``"peak"`` or ``"ellipsoid"``.
    x0 : ndarray
        The start state (gamma, the closed loop, and the unit of the region's multiples).
    true_plant : (A, B)
        The fixed plant of the closed loop (an interior plant of the polytope).
    steps : int
        Closed-loop horizon (samples).
    region_scale : ndarray
        Per-state scale of the region's directions (directions are uniform in scaled coordinates).
    output_matrix, y_max : ndarray or None
        Output bounds ``|C x| <= y_max``, where the problem has them.
    w_box : ndarray or None
        An additive disturbance ``x+ = A x + B u + E d``, ``|d_i| <= w_box_i``, where the problem has
        one: the violation runs push by it; with ``w_matrix`` ``None`` (``E = I``, a box ``W`` in the
        state space) it is also the tube's ``W`` and, as the ellipsoid ``||w|| <= ||w_box||``, the
        "disturbance" method's bound.
    w_matrix : ndarray or None
        ``E`` (``None``: the identity); the satellites' torque disturbance enters through the
        nominal input matrix.
    """

    name: str
    title: str
    source: str
    plant: Any
    Q: np.ndarray
    R: np.ndarray
    u_max: float
    input_constraint: str
    x0: np.ndarray
    true_plant: tuple[np.ndarray, np.ndarray]
    steps: int
    region_scale: np.ndarray
    output_matrix: np.ndarray | None = None
    y_max: np.ndarray | None = None
    notes: tuple[str, ...] = field(default_factory=tuple)
    w_box: np.ndarray | None = None
    w_matrix: np.ndarray | None = None

    @property
    def n_states(self) -> int:
        """Number of states."""
        return int(self.plant.n_states)

    @property
    def disturbance(self) -> tuple[np.ndarray, float]:
        """``(E, w_max)`` of the "disturbance" method: the nominal ``B`` and a fraction of ``u_max``;
        on one plant with an additive box ``w_box`` (the tube's problems), ``E`` (the identity
        without ``w_matrix``) and the ball around the box."""
        if self.w_box is not None and (self.w_matrix is None or self.plant.n_vertices == 1):
            e_mat = np.eye(self.n_states) if self.w_matrix is None else np.asarray(self.w_matrix)
            return e_mat, float(np.linalg.norm(self.w_box))
        return np.asarray(self.plant.nominal[1]), DISTURBANCE_FRACTION * float(self.u_max)


def _kothare_ex1() -> MethodsProblem:
    from models import PolytopicModel

    def a_of(alpha: float) -> np.ndarray:
        return np.array([[1.0, 0.1], [0.0, 1.0 - 0.1 * alpha]])

    b = np.array([[0.0], [0.1 * 0.787]])
    plant = PolytopicModel([(a_of(0.1), b), (a_of(10.0), b)], dt=0.1, nominal=(a_of(1.0), b))
    return MethodsProblem(
        name="kothare_ex1",
        title="Kothare's example 1: angular positioning, alpha in [0.1, 10]",
        source="Kothare, Balakrishnan & Morari, Automatica 32(10), 1996, example 1",
        plant=plant,
        Q=np.diag([1.0, 0.0]),
        R=np.array([[2e-5]]),
        u_max=2.0,
        input_constraint="peak",
        x0=np.array([0.05, 0.0]),
        true_plant=plant.nominal,
        steps=40,
        region_scale=np.array([1.0, 1.0]),
    )


def _kothare_ex2() -> MethodsProblem:
    from models import PolytopicModel

    def a_of(k: float) -> np.ndarray:
        return np.array(
            [
                [1.0, 0.0, 0.1, 0.0],
                [0.0, 1.0, 0.0, 0.1],
                [-0.1 * k, 0.1 * k, 1.0, 0.0],
                [0.1 * k, -0.1 * k, 0.0, 1.0],
            ]
        )

    b = np.array([[0.0], [0.0], [0.1], [0.0]])
    plant = PolytopicModel([(a_of(0.5), b), (a_of(10.0), b)], dt=0.1, nominal=(a_of(1.0), b))
    return MethodsProblem(
        name="kothare_ex2",
        title="Kothare's example 2: two masses and a spring, k in [0.5, 10]",
        source=(
            "Kothare, Balakrishnan & Morari, Automatica 32(10), 1996, example 2 "
            "(as MUP's benchmark writes it)"
        ),
        plant=plant,
        Q=np.eye(4),
        R=np.eye(1),
        u_max=1.0,
        input_constraint="peak",
        x0=np.array([1.0, 1.0, 0.0, 0.0]),
        true_plant=plant.nominal,
        steps=40,
        region_scale=np.ones(4),
    )


def _mup_demo() -> MethodsProblem:
    from models import PolytopicModel

    b = np.array([[-1.45], [-0.70]])
    a1 = np.array([[0.93, 0.51], [0.38, 0.83]])
    a2 = np.array([[0.06, 0.26], [1.80, 0.87]])
    a3 = np.array([[0.50, 0.39], [1.10, 0.85]])
    plant = PolytopicModel([(a1, b), (a2, b)], dt=1.0, nominal=(a3, b))
    return MethodsProblem(
        name="mup_demo",
        title="MUP's demo system: two vertices, |u| <= 10, |x_i| <= 10",
        source="Oravec & Bakosova's MUP toolbox, demo system (vertices A1, A2; nominal A3)",
        plant=plant,
        Q=np.eye(2),
        R=np.eye(1),
        u_max=10.0,
        input_constraint="peak",
        x0=np.array([3.0, 0.0]),
        true_plant=plant.nominal,
        steps=20,
        region_scale=np.array([1.0, 1.0]),
        output_matrix=np.eye(2),
        y_max=np.array([10.0, 10.0]),
        notes=("the nominal A3 lies close to (not exactly on) the segment between A1 and A2",),
    )


def _paper_p(mode: str) -> MethodsProblem:
    from benchmarks.families.rigid import defaults
    from models import RigidSatellite

    sat = RigidSatellite.paper_p()
    x0 = sat.initial_state()
    plant = sat.polytope(x0, dt=defaults.DT, spread=defaults.SPREAD, mode=mode)
    s = defaults.CONTROLLER_DEFAULTS["RMPC"]
    n_v = plant.n_vertices
    inertias = np.diag(np.asarray(sat.inertia, dtype=float))
    torque = gravity_gradient_bound(
        np.concatenate([inertias * (1 - defaults.SPREAD), inertias * (1 + defaults.SPREAD)])
    )
    return MethodsProblem(
        name=f"paper_p_{n_v}v",
        title=f"Paper P's rigid satellite, inertia +-{defaults.SPREAD:g} ({mode!r}, {n_v} vertices)",
        source="paper P's satellite and start state; weights of benchmarks/families/rigid",
        plant=plant,
        Q=np.diag(s["Q_diag"]),
        R=np.diag(s["R_diag"]),
        u_max=float(defaults.U_MAX),
        input_constraint=str(s["input_constraint"]),
        x0=np.asarray(x0, dtype=float),
        true_plant=plant.nominal,
        steps=150,
        region_scale=np.array([1.0, 1.0, 1.0, 0.1, 0.1, 0.1]),
        w_box=np.full(3, torque),
        w_matrix=np.asarray(plant.nominal[1], dtype=float),
    )


#: The start of the satellite's attitude-hold problem as a fraction of paper P's start state: inside
#: the tube's region at its horizon (measured: 0.3 feasible, 0.5 not at 9 samples of 0.01 s).
HOLD_FRACTION: float = 0.25


def _paper_p_hold() -> MethodsProblem:
    from benchmarks.families.rigid import defaults
    from models import PolytopicModel, RigidSatellite

    sat = RigidSatellite.paper_p()
    x_op = sat.initial_state()
    nominal = sat.polytope(x_op, dt=defaults.DT, spread=defaults.SPREAD, mode="scalar").nominal
    plant = PolytopicModel([nominal], dt=defaults.DT, nominal=nominal)
    s = defaults.CONTROLLER_DEFAULTS["RMPC"]
    torque = gravity_gradient_bound(np.diag(np.asarray(sat.inertia, dtype=float)))
    return MethodsProblem(
        name="paper_p_hold",
        title=(f"Paper P's rigid satellite holding attitude (nominal inertia, one plant) under a "
               f"gravity-gradient torque |d_i| <= {torque:.2g} N m, from {HOLD_FRACTION:g} x paper P's "
               "start"),
        source=("paper P's satellite; the gravity-gradient bound at 650 km; weights of "
                "benchmarks/families/rigid"),
        plant=plant,
        Q=np.diag(s["Q_diag"]),
        R=np.diag(s["R_diag"]),
        u_max=float(defaults.U_MAX),
        input_constraint="peak",
        x0=HOLD_FRACTION * np.asarray(x_op, dtype=float),
        true_plant=nominal,
        steps=150,
        region_scale=np.array([1.0, 1.0, 1.0, 0.1, 0.1, 0.1]),
        w_box=np.full(3, torque),
        w_matrix=np.asarray(nominal[1], dtype=float),
        notes=("one plant with an additive torque entering through B: the problem of tube MPC; the "
               "LMI forms' polytope has one vertex",
               "the peak bound |u_l| <= u_max (paper P bounds ||u||_2): the QP families solve the same "
               "problem, so their costs compare"),
    )


#: The orbit of the gravity-gradient torque bound of the satellites' violation runs: the 650 km
#: circular orbit of Paper M (:data:`models.mrp.satellite.PAPER_M_ALTITUDE`; paper P states none).
GRAVITY_GRADIENT_ALTITUDE: float = 650e3


def gravity_gradient_bound(inertias: np.ndarray, altitude: float = GRAVITY_GRADIENT_ALTITUDE) -> float:
    """The largest gravity-gradient torque on a body of principal inertias ``inertias`` (kg m^2,
    every vertex's): ``|3 n^2 c x (J c)| <= 3 n^2 (J_max - J_min) / 2`` over unit nadir directions
    ``c`` (``n`` the circular orbit's mean motion at ``altitude``), per axis at most that."""
    from models.mrp.satellite import EARTH_MU, EARTH_RADIUS

    n = float(np.sqrt(EARTH_MU / (EARTH_RADIUS + altitude) ** 3))
    j = np.asarray(inertias, dtype=float)
    return 1.5 * n**2 * float(np.max(j) - np.min(j))


def _paper_w() -> MethodsProblem:
    from benchmarks.families.wheel import defaults
    from models import WheelSatellite
    from models.wheels.scenarios import paper_w_scenario

    sat = WheelSatellite.paper_w()
    plant = sat.polytope(dt=defaults.DT, effectiveness="single_outage")
    s = defaults.CONTROLLER_DEFAULTS["RMPC"]
    x0 = paper_w_scenario("S1").initial_state()[:6]
    return MethodsProblem(
        name="paper_w",
        title=f"Paper W's wheel satellite, single-outage polytope ({plant.n_vertices} vertices)",
        source="paper W's satellite, scenario S1's start attitude; weights of benchmarks/families/wheel",
        plant=plant,
        Q=np.diag(s["Q_diag"]),
        R=np.diag(s["R_diag"]),
        u_max=float(defaults.U_MAX),
        input_constraint=str(s["input_constraint"]),
        x0=np.asarray(x0, dtype=float),
        true_plant=plant.nominal,
        steps=100,
        region_scale=np.array([1.0, 1.0, 1.0, 0.1, 0.1, 0.1]),
    )


def _flexible() -> MethodsProblem:
    from benchmarks.families.flexible import defaults
    from benchmarks.families.flexible.controllers import linear_weights
    from models import FlexibleSatellite
    from models.attitude.quaternion import quat_from_axis_angle

    sat = FlexibleSatellite.di_gennaro()
    dt = defaults.LINEAR_PERIOD
    plant = sat.polytope(dt=dt, attitude="quaternion", mode="groups")
    s = defaults.CONTROLLER_DEFAULTS["RMPC"]
    Q, R = linear_weights(s, sat.n_modes)
    angle = defaults.EXPERIMENT_ANGLES["small"]
    q = quat_from_axis_angle(np.ones(3) / np.sqrt(3.0), np.deg2rad(angle))
    x0 = sat.linear_state(sat.state(q))
    n = plant.n_states
    return MethodsProblem(
        name=f"flexible_{plant.n_vertices}v",
        title=f"The flexible satellite, {n} states, 'groups' polytope ({plant.n_vertices} vertices)",
        source="Di Gennaro's 4 modes; the polytope, weights, period and small slew of the flexible family",
        plant=plant,
        Q=Q,
        R=R,
        u_max=float(defaults.U_MAX),
        input_constraint=str(s["input_constraint"]),
        x0=np.asarray(x0, dtype=float),
        true_plant=plant.nominal,
        steps=40,
        region_scale=np.array([1.0] * 3 + [0.1] * 3 + [0.1] * (n - 6)),
    )


def _double_integrator() -> MethodsProblem:
    from models import PolytopicModel
    from rmpc.mpc.tube_runs import double_integrator

    data = double_integrator()
    a, b = data["A"], data["B"]
    plant = PolytopicModel([(a, b)], dt=1.0, nominal=(a, b))
    return MethodsProblem(
        name="double_integrator",
        title="The double integrator of the tube literature: |u| <= 1, |x_i| <= 10, |w_i| <= 0.1",
        source="Mayne, Seron & Rakovic, Automatica 41(2), 2005 (weights, horizon); the box |x_i| <= 10",
        plant=plant,
        Q=np.eye(2),
        R=np.array([[0.01]]),
        u_max=1.0,
        input_constraint="peak",
        x0=np.array([-5.0, -2.0]),
        true_plant=(a, b),
        steps=30,
        region_scale=np.array([1.0, 1.0]),
        output_matrix=np.eye(2),
        y_max=np.array([10.0, 10.0]),
        w_box=np.array([0.1, 0.1]),
        notes=("one plant with an additive disturbance: the LMI forms' polytope has one vertex",),
    )


#: Problem name -> builder, in the report's order.
PROBLEMS: dict[str, Callable[[], MethodsProblem]] = {
    "kothare_ex1": _kothare_ex1,
    "kothare_ex2": _kothare_ex2,
    "mup_demo": _mup_demo,
    "paper_p_2v": lambda: _paper_p("scalar"),
    "paper_p_8v": lambda: _paper_p("box"),
    "paper_p_hold": _paper_p_hold,
    "paper_w": _paper_w,
    "flexible_8v": _flexible,
    "double_integrator": _double_integrator,
}

#: The problems of ``--short``.
SHORT_PROBLEMS: tuple[str, ...] = (
    "kothare_ex1", "kothare_ex2", "mup_demo", "paper_p_2v", "paper_p_hold", "double_integrator",
)


def build_problem(name: str) -> MethodsProblem:
    """The problem called ``name`` (a key of :data:`PROBLEMS`)."""
    problem = PROBLEMS[name]()
    if problem.name != name:  # the names are the contract of the records
        raise AssertionError(f"problem {name!r} built as {problem.name!r}")
    return problem


#: What the suite chooses (setting, value, why), for the report's settings table.
SUITE_CHOICES: tuple[tuple[str, str, str], ...] = (
    (
        "closed-loop plant",
        "the polytope's nominal model (Kothare's alpha = 1 and k = 1, MUP's A3, the satellites' own)",
        "a fixed interior plant, the same for every method",
    ),
    (
        "switching plant",
        "a vertex drawn at every sample (seeded), the same sequence for every method",
        "the time-varying uncertainty the vertex-pair form is made for",
    ),
    (
        "disturbance method",
        f"E = nominal B, w_max = {DISTURBANCE_FRACTION:g} u_max (on one plant with an additive box, the "
        "tube's problems: that box's E and the ball around it); the closed loop itself runs without it",
        "one size relative to each problem's own input bound (where no gain carries it, the report says so)",
    ),
    (
        "soft method",
        "weights 1e3 on the input slack (and the output slack where there are output bounds)",
        "large enough for the hard answer where the hard problem is feasible",
    ),
    (
        "auxiliary saturation",
        "peak bound |u_l| <= u_max; where the problem bounds ||u||_2 the record is marked not comparable",
        "sat(F x) is componentwise",
    ),
)
