"""Fuzzing the public constructors, ``simulate`` and the sweep-file reader (hypothesis).

The property is the API contract for bad input: whatever the arguments, a call returns or raises
a toolkit error (a ``ValueError`` / ``TypeError`` subclass whose message starts with the argument
it names); never another exception (``IndexError``, ``LinAlgError``, ``RecursionError``,
``MemoryError``...), never a result with NaN in it, and an argument that is NaN, infinite,
complex, text or None is refused. 200 small examples per test, derandomised, so the file runs in
seconds and the same on every machine; on the code before these checks it failed four tests
(complex inertias, a bool B matrix, an array as a choice, simulate's unbounded length).
"""

from __future__ import annotations

import math
import tomllib
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from benchmarks.core.sweep_spec import parse_sweep
from models import PolytopicModel, RigidSatellite, TorqueLimiter
from rmpc import LQR, simulate
from toolkit_common.errors import ToolkitError

FUZZ = settings(max_examples=200, deadline=None, database=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow])

FLOATS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True, width=64),
    st.sampled_from([0.0, -0.0, 1e-300, -1e-300, 1e300, 1.0, -1.0, 0.5]),
)
VALUES = st.one_of(
    FLOATS,
    st.integers(min_value=-(10**12), max_value=10**12),
    st.none(),
    st.booleans(),
    st.text(max_size=4),
    st.complex_numbers(max_magnitude=10.0),
    hnp.arrays(np.float64, hnp.array_shapes(min_dims=0, max_dims=3, min_side=0, max_side=4), elements=FLOATS),
    hnp.arrays(np.complex128, hnp.array_shapes(min_dims=1, max_dims=2, min_side=1, max_side=6),
               elements=st.complex_numbers(max_magnitude=10.0)),
    st.lists(FLOATS, max_size=7),
)


def _poisoned(value: Any, none_ok: bool = False) -> bool:
    """Whether no numeric argument could legitimately be ``value``: NaN, inf, a non-real complex,
    text, a bool, or None (unless ``none_ok``)."""
    if value is None:
        return not none_ok
    if isinstance(value, str | bool):
        return True
    arr = np.asarray(value)
    if np.iscomplexobj(arr):
        return bool(np.any(np.imag(arr) != 0)) or not np.all(np.isfinite(np.real(arr)))
    return arr.dtype.kind == "f" and not np.all(np.isfinite(arr))


def _check_outcome(call: Any, must_refuse: bool = False) -> Any:
    """Run ``call``: a toolkit error naming its argument first is fine; anything else fails the test.

    With ``must_refuse`` (a poisoned argument was given) the call must raise.
    """
    try:
        result = call()
    except ToolkitError as err:
        assert isinstance(err, ValueError | TypeError | ArithmeticError), type(err)
        argument = getattr(err, "argument", None)
        if argument is not None:
            assert str(err).startswith(f"{argument}:"), str(err)
        return None
    assert not must_refuse, f"accepted a poisoned argument: {result!r}"
    return result


@FUZZ
@given(inertia=VALUES)
def test_rigid_satellite_inertia(inertia):
    sat = _check_outcome(lambda: RigidSatellite(inertia), _poisoned(inertia))
    if sat is not None:
        assert np.all(np.linalg.eigvalsh(sat.inertia) > 0)


@FUZZ
@given(x=VALUES, u=VALUES)
def test_rigid_satellite_dynamics(x, u):
    sat = RigidSatellite.paper_p()
    dx = _check_outcome(lambda: sat.dynamics(x, u), _poisoned(x) or _poisoned(u, none_ok=True))
    if dx is not None:
        assert dx.shape == (6,) and np.all(np.isfinite(dx))


@FUZZ
@given(a=VALUES, b=VALUES, dt=VALUES)
def test_polytopic_model(a, b, dt):
    poisoned = _poisoned(a) or _poisoned(b) or _poisoned(dt)
    model = _check_outcome(lambda: PolytopicModel([(a, b)], dt=dt), poisoned)
    if model is not None:
        assert model.n_states >= 1 and model.n_inputs >= 1 and model.dt > 0


@FUZZ
@given(q=VALUES, r=VALUES, vertex=st.one_of(st.none(), st.integers(-3, 3), VALUES))
def test_lqr(q, r, vertex):
    a2, b2 = np.array([[1.0, 0.1], [0.0, 1.0]]), np.array([[0.0], [0.1]])
    plant = PolytopicModel([(a2, b2), (a2, 2 * b2)], dt=0.1)
    index_ok = isinstance(vertex, int) and not isinstance(vertex, bool) and 0 <= vertex < 2
    bad_vertex = vertex is not None and not index_ok
    ctrl = _check_outcome(lambda: LQR(plant, q, r, vertex=vertex), _poisoned(q) or _poisoned(r) or bad_vertex)
    if ctrl is not None:
        assert np.all(np.isfinite(ctrl.K))


@FUZZ
@given(u_max=VALUES, kind=st.one_of(st.sampled_from(["box", "norm"]), VALUES), u=VALUES)
def test_torque_limiter(u_max, kind, u):
    limiter = _check_outcome(lambda: TorqueLimiter(u_max, kind=kind), _poisoned(u_max))
    if limiter is not None:
        out = _check_outcome(lambda: limiter(u), _poisoned(u))
        if out is not None:
            assert np.all(np.isfinite(out))


@FUZZ
@given(x0=VALUES, duration=VALUES, dt=st.one_of(st.none(), VALUES), disturbance=st.sampled_from(
    [None, "nan", "inf", "wrong size", "number"]))
def test_simulate(x0, duration, dt, disturbance):
    a2, b2 = np.array([[1.0, 0.1], [0.0, 1.0]]), np.array([[0.0], [0.1]])
    plant = PolytopicModel([(a2, b2), (a2, 2 * b2)], dt=0.1)
    lqr = LQR(plant, np.eye(2), np.eye(1))
    d = {None: None, "nan": lambda t: np.array([math.nan]), "inf": lambda t: np.array([math.inf]),
         "wrong size": lambda t: np.zeros(3), "number": 0.1}[disturbance]
    poisoned = _poisoned(x0) or _poisoned(duration) or _poisoned(dt, none_ok=True) or disturbance is not None
    traj = _check_outcome(
        lambda: simulate(lqr, plant, x0, duration, dt=dt, disturbance=d, max_steps=2000), poisoned
    )
    if traj is not None:
        assert np.all(np.isfinite(traj.x)) and traj.x.shape[0] <= 2001


SWEEP_TEXT = st.text(
    alphabet=st.sampled_from(list('[]{}=".,\n #abcdeilmnoprstuvxyz0123456789-+_')), max_size=120
)


@FUZZ
@given(text=SWEEP_TEXT)
def test_sweep_reader_on_arbitrary_text(text):
    try:
        data = tomllib.loads(text)
    except (tomllib.TOMLDecodeError, RecursionError):
        return  # load_sweep turns these into ConfigError; tested in test_bench_cli_refusals.py
    _check_outcome(lambda: parse_sweep(data))


SWEEP_FIELDS = st.sampled_from(
    ["plant", "controller", "saturation", "spread", "mode", "u_max", "ic_scale", "duration", "dt",
     "disturbance", "disturbance_start", "disturbance_axes", "true_inertia", "settings", "nonsense"]
)


@FUZZ
@given(
    base=st.dictionaries(SWEEP_FIELDS, VALUES.map(lambda v: v.tolist() if isinstance(v, np.ndarray) else v),
                         max_size=4),
    grid=st.dictionaries(
        SWEEP_FIELDS, st.lists(st.one_of(FLOATS, st.text(max_size=3)), max_size=3), max_size=2
    ),
    n=st.one_of(st.none(), st.integers(-2, 10**15)),
)
def test_sweep_reader_on_arbitrary_tables(base, grid, n):
    data: dict[str, Any] = {"name": "fuzz", "base": base, "grid": grid}
    if n is not None:
        data["montecarlo"] = {"n": n, "seed": 1}
    _check_outcome(lambda: parse_sweep(data))


def test_the_fuzz_checker_lets_other_exceptions_through():
    """The checker itself: an exception that is not the toolkit's escapes it (so the fuzz tests can fail)."""
    with pytest.raises(IndexError):
        _check_outcome(lambda: np.zeros(1)[3])
