"""The Python API's bad and edge inputs: every public constructor and entry point, argument by argument.

Each target is a function that builds the object (or makes the call) from keyword overrides of a
valid set of arguments; each argument gets the bad values of its kind (a weight matrix, a positive
number, a count, a choice, a state vector...), minus the values that argument legitimately
accepts. A few probes outside that grid reproduce single reports (a callback returning NaN inside
``simulate``, a huge state for the QP controllers).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

import numpy as np

from dev.robustness.probe import Probe

NAN = float("nan")
INF = float("inf")


# --- valid objects (built inside the child process) ------------------------------------------------


def small_plant() -> Any:
    """Two vertices of a 2-state, 1-input double integrator (dt = 0.1)."""
    from models import PolytopicModel

    a1 = np.array([[1.0, 0.1], [0.0, 1.0]])
    a2 = np.array([[1.0, 0.1], [0.0, 0.95]])
    b = np.array([[0.005], [0.1]])
    return PolytopicModel(vertices=[(a1, b), (a2, b)], dt=0.1)


def satellite() -> Any:
    """Paper P's rigid satellite."""
    from models import RigidSatellite

    return RigidSatellite(inertia=[1.2928, 1.2928, 4.2953])


def satellite_polytope() -> Any:
    """Paper P's inertia polytope at the rest state (6 states, 3 inputs, dt = 0.1)."""
    return satellite().polytope(np.zeros(6), dt=0.1, spread=0.3)


def rmpc_controller() -> Any:
    from rmpc import RMPC

    return RMPC(small_plant(), Q=np.eye(2), R=np.eye(1), u_max=1.0)


# --- bad values by kind ----------------------------------------------------------------------------


def weight_values(n: int) -> dict[str, Any]:
    """Bad values for an n x n weight (symmetric, positive semi-definite or definite)."""
    eye = np.eye(n)
    nonsym = eye.copy()
    nonsym[0, -1] = 0.5 if n > 1 else 0.0
    if n == 1:
        nonsym = np.array([[1.0, 0.5]])
    indefinite = eye.copy()
    indefinite[0, 0] = -1.0
    return {
        "nan": np.where(eye > 0, NAN, 0.0),
        "inf": np.where(eye > 0, INF, 0.0),
        "complex": eye * (1 + 1j),
        "shape": np.eye(n + 1),
        "string": "eye",
        "None": None,
        "empty": np.zeros((0, 0)),
        "3-d": np.ones((n, n, 1)),
        "non-symmetric": nonsym,
        "indefinite": indefinite,
        "negative scalar": -1.0,
    }


def positive_values() -> dict[str, Any]:
    """Bad values for a positive number."""
    return {
        "zero": 0.0,
        "negative": -1.0,
        "nan": NAN,
        "inf": INF,
        "string": "1.0",
        "complex": 1.0 + 1.0j,
        "list": [1.0, 2.0, 3.0, 4.0, 5.0],
    }


def count_values(huge: int = 10**9) -> dict[str, Any]:
    """Bad values for a positive integer count."""
    return {"zero": 0, "negative": -1, "float": 2.5, "string": "3", "huge": huge, "nan": NAN}


def choice_values() -> dict[str, Any]:
    """Bad values for a choice among words."""
    return {"unknown": "nonsense", "number": 3, "empty": ""}


def vector_values(n: int) -> dict[str, Any]:
    """Bad values for a state-like vector of length n."""
    return {
        "nan": np.full(n, NAN),
        "inf": np.full(n, INF),
        "complex": np.ones(n) * (1 + 1j),
        "length": np.ones(n + 1),
        "string": "zeros",
        "matrix": np.ones((n, 2)),
        "empty": np.zeros(0),
        "None": None,
    }


FOUND_WORDS: dict[str, tuple[str, ...]] = {
    "nan": ("nan",),
    "inf": ("inf",),
    "complex": ("complex",),
    "None": ("none",),
    "string": ("str",),
}
"""Per kind of bad value, the words one of which a clear message uses to say what it found."""


def _found_words(label: str, value: Any) -> tuple[str, ...]:
    """What a clear message says it found: the kind's words, and a string's value in quotes."""
    words = FOUND_WORDS.get(label, ())
    if isinstance(value, str):
        words = (*words, repr(value))
    return words


# --- the grid of targets x arguments x values ------------------------------------------------------


def _grid(
    target: str,
    build: Callable[..., Any],
    arguments: dict[str, dict[str, Any]],
    accepted: Iterable[tuple[str, str]] = (),
) -> list[Probe]:
    """Probes ``build(**{argument: value})`` for every bad value of every argument, less ``accepted``."""
    skip = set(accepted)
    probes = []
    for argument, values in arguments.items():
        for label, value in values.items():
            if (argument, label) in skip:
                continue

            def call(argument: str = argument, value: Any = value) -> Any:
                return build(**{argument: value})

            probes.append(
                Probe(
                    id=f"{target}.{argument}:{label}",
                    group="api",
                    names=(argument,),
                    found=_found_words(label, value),
                    call=call,
                    kind=label,
                )
            )
    return probes


def _target(
    name: str,
    build: Callable[..., Any],
    arguments: dict[str, dict[str, Any]],
    accepted: Iterable[tuple[str, str]] = (),
) -> Target:
    return name, build, arguments, list(accepted)


def grid_probes() -> list[Probe]:
    """The argument-by-argument grid over :func:`targets`."""
    probes: list[Probe] = []
    for name, build, arguments, accepted in targets():
        probes += _grid(name, build, arguments, accepted)
    return probes


def _polytopic_model(**kw: Any) -> Any:
    from models import PolytopicModel

    a = np.array([[1.0, 0.1], [0.0, 1.0]])
    b = np.array([[0.005], [0.1]])
    args: dict[str, Any] = {"vertices": [(a, b), (a, b)], "dt": 0.1}
    args.update(kw)
    return PolytopicModel(**args)


def _vertices_values() -> dict[str, Any]:
    a = np.array([[1.0, 0.1], [0.0, 1.0]])
    b = np.array([[0.005], [0.1]])
    return {
        "empty": [],
        "nan": [(a * NAN, b)],
        "inf": [(a, b * INF)],
        "complex": [(a * (1 + 1j), b)],
        "mismatched": [(a, b), (np.eye(3), np.ones((3, 1)))],
        "B rows": [(a, np.ones((3, 1)))],
        "A not square": [(np.ones((2, 3)), b)],
        "zero inputs": [(a, np.zeros((2, 0)))],
        "zero states": [(np.zeros((0, 0)), np.zeros((0, 1)))],
        "not pairs": [a, b],
        "string": "AB",
        "None": None,
    }


def _rigid(**kw: Any) -> Any:
    from models import RigidSatellite

    args = {"inertia": [1.2928, 1.2928, 4.2953]}
    args.update(kw)
    return RigidSatellite(**args)


def _inertia_values() -> dict[str, Any]:
    return {
        "None": None,
        "nan": [NAN, 1.0, 1.0],
        "inf": [INF, 1.0, 1.0],
        "zero": [0.0, 1.0, 1.0],
        "negative": [-1.0, 1.0, 1.0],
        "complex": [1.0 + 1j, 1.0, 1.0],
        "length": [1.0, 1.0],
        "shape": np.eye(4),
        "non-symmetric": np.array([[1.0, 0.2, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
        "indefinite": np.diag([1.0, 1.0, -1.0]),
        "triangle": [1.0, 1.0, 5.0],
        "string": "diag",
    }


def _polytope(**kw: Any) -> Any:
    args: dict[str, Any] = {"x_op": np.zeros(6), "dt": 0.1, "spread": 0.3}
    args.update(kw)
    return satellite().polytope(**args)


def _dynamics(**kw: Any) -> Any:
    args: dict[str, Any] = {"x": np.zeros(6), "u": np.zeros(3)}
    args.update(kw)
    return satellite().dynamics(**args)


def _rmpc(**kw: Any) -> Any:
    from rmpc import RMPC

    args: dict[str, Any] = {"plant": small_plant(), "Q": np.eye(2), "R": np.eye(1), "u_max": 1.0}
    args.update(kw)
    return RMPC(**args)


def _rmpc_solve(**kw: Any) -> Any:
    args: dict[str, Any] = {"x": np.array([1.0, 0.0])}
    args.update(kw)
    return rmpc_controller().solve(**args)


def _offline(**kw: Any) -> Any:
    from rmpc import OfflineRMPC

    args: dict[str, Any] = {
        "plant": small_plant(),
        "Q": np.eye(2),
        "R": np.eye(1),
        "u_max": 1.0,
        "n_ellipsoids": 3,
    }
    args.update(kw)
    return OfflineRMPC(**args)


def _gipc(**kw: Any) -> Any:
    from rmpc import GIPC

    args: dict[str, Any] = {"plant": satellite_polytope(), "Np": 20, "Nc": 2}
    args.update(kw)
    return GIPC(**args)


def _crmpc(**kw: Any) -> Any:
    from rmpc import CRMPC

    args: dict[str, Any] = {"plant": satellite_polytope(), "Q": np.eye(6), "R": np.eye(3), "u_max": 1.0}
    args.update(kw)
    return CRMPC(**args)


def _lqr(**kw: Any) -> Any:
    from rmpc import LQR

    args: dict[str, Any] = {"plant": small_plant(), "Q": np.eye(2), "R": np.eye(1)}
    args.update(kw)
    return LQR(**args)


def _simulate(**kw: Any) -> Any:
    from rmpc import LQR, simulate

    plant = small_plant()
    args: dict[str, Any] = {
        "controller": LQR(plant, Q=np.eye(2), R=np.eye(1)),
        "plant": plant,
        "x0": np.array([1.0, 0.0]),
        "duration": 1.0,
    }
    if "n_steps" in kw:
        del args["duration"]
    args.update(kw)
    return simulate(**args)


def _limiter(**kw: Any) -> Any:
    from models import TorqueLimiter

    args: dict[str, Any] = {"u_max": 1.0}
    args.update(kw)
    return TorqueLimiter(**args)


def _actuator(**kw: Any) -> Any:
    from models import ReactionWheelActuator

    return ReactionWheelActuator(**kw)


def _kothare(**kw: Any) -> Any:
    from lmi import KothareProblem

    a = np.array([[[1.0, 0.1], [0.0, 1.0]], [[1.0, 0.1], [0.0, 0.95]]])
    b = np.array([[[0.005], [0.1]]] * 2)
    args: dict[str, Any] = {"A": a, "B": b, "Q": np.eye(2), "R": np.eye(1), "u_max": 1.0}
    args.update(kw)
    return KothareProblem(**args)


def _wheel_fault(**kw: Any) -> Any:
    from models import WheelFault

    args: dict[str, Any] = {"wheel": 1, "kind": "stuck", "t_on": 1.0, "value": 0.05}
    args.update(kw)
    return WheelFault(**args)


def _mrp(**kw: Any) -> Any:
    from models import MRPSatellite

    args: dict[str, Any] = {"inertia": [20.0, 17.0, 15.0]}
    args.update(kw)
    return MRPSatellite(**args)


def _disturbance(kind: str) -> Callable[..., Any]:
    def build(**kw: Any) -> Any:
        import rmpc

        cls = getattr(rmpc, kind)
        args: dict[str, Any] = (
            {"magnitude": [0.1, 0.0, 0.0]}
            if kind != "SineDisturbance"
            else {"amplitude": [0.1, 0.0, 0.0], "frequency": 0.5}
        )
        args.update(kw)
        return cls(**args)(1.0)

    return build


Target = tuple[str, Callable[..., Any], dict[str, dict[str, Any]], list[tuple[str, str]]]
"""(name, builder, bad values per argument, (argument, value label) pairs the argument accepts)."""


def targets() -> list[Target]:
    """The public constructors and entry points with the bad values of each argument."""
    w2, w1, w6, w3 = weight_values(2), weight_values(1), weight_values(6), weight_values(3)
    pos = positive_values()
    found: list[Target] = []
    found.append(
        _target(
            "PolytopicModel",
            _polytopic_model,
            {"vertices": _vertices_values(), "dt": pos, "attitude": choice_values()},
            accepted=[("attitude", "empty")],
        )
    )
    # principal inertias that break the triangle inequality (J3 > J1 + J2) are no rigid body, but
    # paper P's own satellite (1.2928, 1.2928, 4.2953) breaks it: accepted (and reported)
    found.append(_target("RigidSatellite", _rigid, {"inertia": _inertia_values()}, [("inertia", "triangle")]))
    found.append(
        _target(
            "RigidSatellite.polytope",
            _polytope,
            {
                "x_op": vector_values(6),
                "dt": pos,
                "spread": {"negative": -0.1, "one": 1.0, "nan": NAN, "string": "0.3"},
                "mode": choice_values(),
                "attitude_range": {
                    "negative": [-0.1, 0.1, 0.1],
                    "nan": [NAN, 0.1, 0.1],
                    "length": [0.1, 0.1],
                },
            },
            accepted=[("x_op", "None")],
        )
    )
    found.append(
        _target(
            "RigidSatellite.dynamics",
            _dynamics,
            {
                "x": vector_values(6),
                "u": vector_values(3),
                "d": {"nan": [NAN, 0.0, 0.0], "length": [0.0, 0.0]},
            },
            accepted=[("u", "None")],
        )
    )
    found.append(
        _target(
            "RMPC",
            _rmpc,
            {
                "plant": {"None": None, "string": "plant", "matrix": np.eye(2)},
                "Q": w2,
                "R": w1,
                "u_max": pos,
                "input_constraint": choice_values(),
                "backend": choice_values(),
            },
            accepted=[("input_constraint", "None")],
        )
    )
    found.append(_target("RMPC.solve", _rmpc_solve, {"x": vector_values(2)}))
    found.append(
        _target(
            "OfflineRMPC",
            _offline,
            {
                "Q": w2,
                "R": w1,
                "u_max": pos,
                "n_ellipsoids": count_values(10**7),
                "input_constraint": choice_values(),
            },
        )
    )
    found.append(
        _target(
            "GIPC",
            _gipc,
            {
                "Np": count_values(10**6),
                "Nc": count_values(10**6),
                "Qy": {"nan": NAN, "negative": -1.0, "string": "1"},
                "R_du": {"nan": NAN, "negative": -1.0, "zero": 0.0},
                "u_max": pos,
                "du_max": pos,
                "backend": choice_values(),
            },
        )
    )
    found.append(_target("CRMPC", _crmpc, {"Q": w6, "R": w3, "u_max": pos}))
    found.append(
        _target(
            "LQR",
            _lqr,
            {"Q": w2, "R": w1, "vertex": {"negative": -1, "out of range": 5, "float": 0.5, "string": "0"}},
        )
    )
    found.append(
        _target(
            "simulate",
            _simulate,
            {
                "x0": vector_values(2),
                "duration": {**pos, "huge": 1e12, "below dt": 0.01},
                "dt": pos,
                "n_steps": count_values(10**12),
            },
            accepted=[("duration", "list")],
        )
    )
    found.append(
        _target(
            "TorqueLimiter", _limiter, {"u_max": pos, "kind": choice_values()}, accepted=[("u_max", "list")]
        )
    )
    found.append(
        _target(
            "ReactionWheelActuator",
            _actuator,
            {"n_axes": count_values(10**9), "a": pos, "b": pos, "c": pos},
            accepted=[("a", "zero")],  # a = 0: a lag much shorter than the sample (a one-sample delay)
        )
    )
    found.append(
        _target(
            "KothareProblem",
            _kothare,
            {
                "A": {"nan": np.full((2, 2, 2), NAN), "shape": np.ones((2, 3, 3)), "None": None},
                "Q": w2,
                "R": w1,
                "u_max": pos,
                "input_constraint": choice_values(),
                "backend": choice_values(),
                "dt": pos,
            },
        )
    )
    found.append(
        _target(
            "WheelFault",
            _wheel_fault,
            {
                "wheel": {"negative": -1, "float": 1.5, "string": "1"},
                "kind": choice_values(),
                "t_on": {"nan": NAN, "negative": -1.0, "string": "1"},
                "t_off": {"before t_on": 0.5, "nan": NAN},
            },
        )
    )
    found.append(
        _target(
            "MRPSatellite",
            _mrp,
            {"inertia": _inertia_values(), "altitude": {"negative": -1.0, "nan": NAN}},
            accepted=[("inertia", "triangle")],
        )
    )
    for kind in ("ConstantDisturbance", "StepDisturbance"):
        found.append(
            _target(
                kind,
                _disturbance(kind),
                {"magnitude": {"nan": [NAN, 0.0, 0.0], "string": "x", "complex": [1j, 0.0, 0.0]}},
            )
        )
    found.append(
        _target(
            "SineDisturbance",
            _disturbance("SineDisturbance"),
            {
                "amplitude": {"nan": [NAN, 0.0, 0.0], "string": "x"},
                "frequency": {"nan": NAN, "negative": -1.0, "string": "1"},
            },
        )
    )
    return found


# --- single reports outside the grid ---------------------------------------------------------------


def _nan_callback_simulation(where: str) -> Any:
    from models import TorqueLimiter
    from rmpc import LQR, simulate

    class NaNLimiter(TorqueLimiter):
        def __call__(self, u: Any) -> np.ndarray:
            return np.full(np.shape(u), NAN)

    sat = satellite()
    poly = sat.polytope(np.zeros(6), dt=0.1, spread=0.3)
    ctrl = LQR(poly, Q=np.eye(6), R=np.eye(3))
    x0 = np.array([0.1, 0.1, 0.1, 0.0, 0.0, 0.0])
    plant = sat if where != "linear limiter" else poly
    kwargs: dict[str, Any] = {}
    if where == "disturbance":
        kwargs["disturbance"] = lambda t: np.full(3, NAN)
    else:
        kwargs["limiter"] = NaNLimiter(1.0)
    return simulate(ctrl, plant, x0, 1.0, dt=0.1, **kwargs)


def _gipc_huge_state(backend: str) -> Any:
    """One GIPC step at a state of 1e8: the input, the step's status and whether it fell back."""
    from rmpc import GIPC

    ctrl = GIPC(satellite_polytope(), Np=400, Nc=4, backend=backend)
    u = ctrl.step(np.full(6, 1e8))
    if not np.all(np.isfinite(u)):
        raise AssertionError(f"non-finite input at a huge state (status {ctrl.last.status})")
    return {"u": u.tolist(), "status": str(ctrl.last.status), "fallback": ctrl.last.fallback}


def _rmpc_tiny_state() -> Any:
    sol = rmpc_controller().solve(np.array([1e-300, 0.0]))
    if not np.all(np.isfinite(sol.F)):
        raise AssertionError(f"non-finite gain at a tiny state (status {sol.status})")
    return sol


def _flexible_zero_quaternion() -> Any:
    from models import FlexibleSatellite

    sat = FlexibleSatellite.di_gennaro()
    x = np.zeros(sat.n_states)
    return sat.dynamics(x, np.zeros(sat.n_inputs))


def _rigid_none() -> Any:
    from models import RigidSatellite

    return RigidSatellite(None)


def single_probes() -> list[Probe]:
    """Reports outside the grid: callbacks returning NaN, huge states, zero quaternions, tiny states."""
    return [
        Probe(
            "simulate.disturbance:nan (rigid)",
            "api",
            ("disturbance",),
            call=lambda: _nan_callback_simulation("disturbance"),
            kind="nan callback",
        ),
        Probe(
            "simulate.limiter:nan (rigid)",
            "api",
            ("limiter",),
            call=lambda: _nan_callback_simulation("limiter"),
            kind="nan callback",
        ),
        Probe(
            "simulate.limiter:nan (linear)",
            "api",
            ("limiter",),
            call=lambda: _nan_callback_simulation("linear limiter"),
            kind="nan callback",
        ),
        Probe(
            "GIPC.step:1e8 (proxqp)",
            "api",
            ("x", "state"),
            call=lambda: _gipc_huge_state("proxqp"),
            expect="either",
            kind="huge state",
        ),
        Probe(
            "GIPC.step:1e8 (osqp)",
            "api",
            ("x", "state"),
            call=lambda: _gipc_huge_state("osqp"),
            expect="either",
            kind="huge state",
        ),
        Probe("RMPC.solve:1e-300", "api", ("x",), call=_rmpc_tiny_state, expect="either", kind="tiny state"),
        Probe(
            "FlexibleSatellite.dynamics:zero quaternion",
            "api",
            ("quaternion", "x"),
            call=_flexible_zero_quaternion,
            kind="zero quaternion",
        ),
        Probe("RigidSatellite:None positional", "api", ("inertia",), call=_rigid_none, kind="None"),
    ]


def api_probes() -> list[Probe]:
    """Every API probe."""
    return grid_probes() + single_probes()
