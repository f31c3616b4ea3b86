"""The C core called from Python (:mod:`lmi.ccore.runtime`): the extension ``pip install .`` builds.

:class:`lmi.backends.ipm.IPMKothare` runs its on-line solves in the C core (``core="auto"``),
the source an exported controller compiles. Checked here against the numba kernels of
:class:`lmi.ipm.BlockLMISolver` (``core="numba"``), an independent implementation of the same
method: same statuses and iterations, gamma within 1e-6 relative, ``u`` within the solver's
tolerance (1e-4 of the input scale) along paper P's E1 closed loop and on Kothare's examples; a
proved infeasibility at a far-out state; a pickled controller that resumes its warm start; no
numba import on the way; the build matches the package's C sources.
"""

from __future__ import annotations

import pickle
import shutil
import subprocess
import sys
import warnings

import numpy as np
import pytest

from lmi.ccore import runtime
from toolkit_common.errors import InvalidArgumentError

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler: pip builds no C core")


def _paper_p_e1(core: str, vertices: int = 2):
    """Paper P's E1 robust MPC (its weights, no input bound) over 2 or 8 inertia vertices."""
    from benchmarks.timing.common import polytope
    from models import RigidSatellite
    from rmpc import RMPC

    plant = polytope(vertices)
    ctrl = RMPC(plant, np.diag([1.0, 1.0, 1.0, 0.1, 0.1, 0.1]), np.diag([0.01] * 3),
                solver_options={"core": core})
    return ctrl, plant, RigidSatellite.paper_p().initial_state()


def _closed_loop(ctrl, plant, x0, steps: int):
    x, rows = x0.copy(), []
    for _ in range(steps):
        u = ctrl.step(x)
        info = ctrl.last
        rows.append((str(info.status), info.gamma, info.iterations, u.copy()))
        x = plant.A[0] @ x + plant.B[0] @ u
    return rows


def test_the_build_is_current():
    """``pip install .`` built the extension from the C sources this package ships."""
    assert runtime.core_library() is not None, runtime.core_status()
    import _lmi_ccore

    assert _lmi_ccore.SOURCE_HASH == runtime.source_hash()


@pytest.mark.parametrize("vertices", [2, 8])
def test_c_core_agrees_with_numba_on_paper_p(vertices):
    """Paper P's E1 robust MPC along 40 samples, the C core against the numba kernels."""
    runs = {}
    for core in ("c", "numba"):
        ctrl, plant, x0 = _paper_p_e1(core, vertices)
        assert ctrl.problem._backend.core == core
        runs[core] = _closed_loop(ctrl, plant, x0, 40)
    for (s_c, g_c, it_c, u_c), (s_n, g_n, it_n, u_n) in zip(runs["c"], runs["numba"], strict=True):
        assert s_c == s_n == "optimal"
        assert abs(g_c / g_n - 1.0) <= 1e-6
        assert np.max(np.abs(u_c - u_n)) <= 1e-4 * max(1.0, float(np.max(np.abs(u_n))))
        assert abs(it_c - it_n) <= 3  # the same method; rounding may shift a stopping test by a step


@pytest.mark.parametrize("name", ["kothare_ex1", "kothare_ex2"])
def test_c_core_agrees_with_numba_on_kothares_examples(name):
    """Kothare, Balakrishnan and Morari's examples 1 and 2 (the methods suite's closed loops, 40
    samples, input bound as there), both cores solving at the same states: those of the C core's
    closed loop, each core warm-starting from its own previous solve. gamma within 1e-7 relative
    (the solves' relative gap is 1e-8; measured worst 3.2e-9 and 4.8e-9). Two closed loops, each
    on its own moves, drift apart on example 2 (the moves agree to 1e-4 of the bound, the lightly
    damped masses carry the difference): gamma's 1.4e-8 at the fourth sample grew to 1.1e-6 by the
    fortieth, which says nothing of the solvers."""
    from benchmarks.suites.methods_problems import build_problem
    from models import PolytopicModel
    from rmpc import RMPC

    pb = build_problem(name)
    true_plant = PolytopicModel([pb.true_plant], dt=pb.plant.dt)
    ctrls = {}
    for core in ("c", "numba"):
        ctrls[core] = RMPC(pb.plant, pb.Q, pb.R, u_max=pb.u_max, input_constraint=pb.input_constraint,
                           solver_options={"core": core})
        assert ctrls[core].problem._backend.core == core
    x = pb.x0.copy()
    for _ in range(40):
        u_c = ctrls["c"].step(x)
        s_c, g_c = str(ctrls["c"].last.status), ctrls["c"].last.gamma
        u_n = ctrls["numba"].step(x)
        s_n, g_n = str(ctrls["numba"].last.status), ctrls["numba"].last.gamma
        assert s_c == s_n
        if g_n is not None and np.isfinite(g_n):
            assert abs(g_c / g_n - 1.0) <= 1e-7
        assert np.max(np.abs(u_c - u_n)) <= 1e-4 * max(1.0, float(np.max(np.abs(u_n))))
        x = true_plant.A[0] @ x + true_plant.B[0] @ u_c


def test_far_out_state_is_proved_infeasible_by_the_c_core():
    """An open-loop-unstable plant with a unit input bound, far out: the C core's run ends with a
    Farkas ray that :func:`lmi.infeasibility.check_farkas` accepts, as the numba run does."""
    from models import PolytopicModel
    from rmpc import RMPC

    b = np.array([[0.0], [0.1]])
    plant = PolytopicModel([(np.array([[1.0, 0.1], [0.2, 1.0]]), b), (np.array([[1.0, 0.1], [0.3, 1.0]]), b)],
                           dt=0.1)
    answers = {}
    for core in ("c", "numba"):
        ctrl = RMPC(plant, np.eye(2), np.eye(1), u_max=1.0, solver_options={"core": core})
        sol = ctrl.problem.solve(np.array([1e4, 1e4]))
        answers[core] = sol
        assert str(sol.status) == "infeasible"
        assert sol.infeasibility is not None and sol.infeasibility.ok
    assert answers["c"].solver_status.startswith("ipm infeasible")


def test_pickled_controller_resumes_the_warm_start():
    """A copy taken mid-run (the core's workspace bytes) steps as the original does, bit for bit."""
    ctrl, plant, x0 = _paper_p_e1("c")
    x = x0.copy()
    for _ in range(5):
        x = plant.A[0] @ x + plant.B[0] @ ctrl.step(x)
    twin = pickle.loads(pickle.dumps(ctrl))
    for _ in range(5):
        u, u_twin = ctrl.step(x), twin.step(x)
        assert np.array_equal(u, u_twin)
        assert ctrl.last.iterations == twin.last.iterations
        x = plant.A[0] @ x + plant.B[0] @ u


def test_no_numba_on_the_c_path():
    """An on-line robust MPC run by the C core imports no numba (nothing to compile on first use)."""
    code = (
        "import sys, numpy as np\n"
        "from benchmarks.families.rigid import defaults\n"
        "from models import RigidSatellite\n"
        "from rmpc import RMPC\n"
        "sat = RigidSatellite.paper_p(); x0 = sat.initial_state()\n"
        "plant = sat.polytope(x0, defaults.DT, defaults.SPREAD, defaults.MODE)\n"
        "ctrl = RMPC(plant, np.diag([1.0, 1.0, 1.0, 0.1, 0.1, 0.1]), np.diag([0.01] * 3))\n"
        "[ctrl.step(x0) for _ in range(3)]\n"
        "assert ctrl.problem._backend.core == 'c'\n"
        "print('numba' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_core_setting_is_checked():
    from lmi.backends.ipm import IPMKothare

    ctrl, _, _ = _paper_p_e1("auto")
    data = ctrl.problem._backend.original_data
    with pytest.raises(InvalidArgumentError, match=r"solver_options\['core'\]"):
        IPMKothare(data, {"core": "fortran"})
    with pytest.raises(InvalidArgumentError, match="nesting block"):
        IPMKothare(data, {"core": "c"}, nesting=True)
    assert IPMKothare(data, {"core": "auto"}, nesting=True).core == "numba"


def test_a_stale_build_is_refused(monkeypatch):
    """A build from other C sources than the package's: a warning, and the numba kernels run."""
    monkeypatch.setattr(runtime, "source_hash", lambda: "0" * 64)
    runtime._load.cache_clear()
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            assert runtime.core_library() is None
        assert any(issubclass(w.category, runtime.StaleCoreWarning) for w in caught)
        assert "stale" in runtime.core_status()
        ctrl, _, _ = _paper_p_e1("auto")
        assert ctrl.problem._backend.core == "numba"
    finally:
        monkeypatch.undo()
        runtime._load.cache_clear()
    assert runtime.core_library() is not None
