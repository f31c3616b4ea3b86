"""``rmpc.export_c`` of an on-line robust MPC: the two files, compiled, against ``RMPC.step``.

The export is one header and one source (the C core of :mod:`lmi.ccore` and the controller
interface in one translation unit), compiled here with ``cc -std=c99 -O2 -Wall -Wextra -Werror
-pedantic`` and loaded with ctypes, as an outside check would. Along closed loops the step's
status, gamma (1e-6 relative) and command (1e-6, scaled by the input bound) follow the Python
controller; a proved infeasibility gives its code and the same fallback command as Python; a
NaN state a status and a finite command; a form the C solver does not carry is refused by name;
a build with ``-fsanitize=address,undefined`` runs a loop clean.
"""

from __future__ import annotations

import ctypes
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from models import PolytopicModel
from rmpc import RMPC, export_c
from rmpc.export.c_writer import STATUS_CODES
from toolkit_common.errors import InvalidArgumentError

CC = shutil.which("cc")
pytestmark = pytest.mark.skipif(CC is None, reason="no C compiler (cc) on this machine")


@pytest.fixture(autouse=True)
def _numba_reference(monkeypatch):
    """The Python controllers compared with the export run the numba kernels: an implementation
    independent of the C core (which the package's own solves run by default)."""
    from lmi.backends.ipm import DEFAULT_IPM_OPTIONS

    monkeypatch.setitem(DEFAULT_IPM_OPTIONS, "core", "numba")
STRICT = ["-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-pedantic"]
CODE = {code.word: code.value for code in STATUS_CODES}
_D = ctypes.POINTER(ctypes.c_double)


class Exported:
    """The compiled export of one controller."""

    def __init__(self, ctrl: RMPC, folder: Path, flags: tuple[str, ...] = ()) -> None:
        self.result = export_c(ctrl, folder)
        lib_path = folder / "librmpc.so"
        subprocess.run([CC, *STRICT, *flags, "-shared", "-fPIC", "-o", str(lib_path), str(self.result.source),
                        "-lm"], check=True, capture_output=True, text=True)
        self.lib = ctypes.CDLL(str(lib_path))
        self.lib.rmpc_last_gamma.restype = ctypes.c_double
        self.lib.rmpc_solver_workspace_bytes.restype = ctypes.c_ulong
        self.nu = self.result.nu
        assert self.lib.rmpc_init() == 0

    def step(self, x: np.ndarray) -> tuple[int, np.ndarray, float, int]:
        x = np.ascontiguousarray(x, dtype=float)
        u = np.full(self.nu, np.nan)
        code = self.lib.rmpc_step(x.ctypes.data_as(_D), u.ctypes.data_as(_D))
        return code, u, self.lib.rmpc_last_gamma(), self.lib.rmpc_last_iterations()


def _paper_p_e1() -> tuple[RMPC, PolytopicModel, np.ndarray]:
    from benchmarks.families.rigid import defaults
    from models import RigidSatellite

    sat = RigidSatellite.paper_p()
    x0 = sat.initial_state()
    plant = sat.polytope(x0, defaults.DT, defaults.SPREAD, defaults.MODE)
    return RMPC(plant, np.diag([1.0, 1.0, 1.0, 0.1, 0.1, 0.1]), np.diag([0.01] * 3)), plant, x0


def _kothare_ex1(kind: str = "peak") -> tuple[RMPC, PolytopicModel, np.ndarray]:
    from benchmarks.suites.methods_problems import build_problem

    p = build_problem("kothare_ex1")
    return RMPC(p.plant, p.Q, p.R, u_max=p.u_max, input_constraint=kind), p.plant, p.x0


def _follow(ctrl: RMPC, plant: PolytopicModel, x0: np.ndarray, exported: Exported, steps: int,
            u_scale: float) -> None:
    a, b = plant.nominal
    x = x0.copy()
    for _ in range(steps):
        u_py = ctrl.step(x)
        code, u, gamma, iterations = exported.step(x)
        assert iterations > 0
        assert code == CODE["optimal / ok"] and ctrl.last.status == "optimal"
        assert abs(gamma - ctrl.last.gamma) <= 1e-6 * ctrl.last.gamma
        # two answers within the solver's tolerance (closer where the iterates track, by an amount
        # that depends on the BLAS kernels' rounding: see tests/test_ccore_kothare.py)
        assert np.max(np.abs(u - u_py)) <= 1e-4 * u_scale
        x = a @ x + b @ u_py


def test_paper_p_e1_loop_follows_the_python_controller(tmp_path: Path) -> None:
    ctrl, plant, x0 = _paper_p_e1()
    exported = Exported(ctrl, tmp_path)
    _follow(ctrl, plant, x0, exported, 20, 1.0)
    zero = np.zeros(6)  # within the hold radius: no solve, the last gain, as Python's "reused"
    code, u, gamma, iterations = exported.step(zero)
    assert code == CODE["reused"] and np.array_equal(u, ctrl.step(zero)) and ctrl.last.status == "reused"
    assert np.isnan(gamma) and iterations == 0
    assert exported.lib.rmpc_solver_workspace_bytes() > 0


@pytest.mark.parametrize("kind", ["peak", "ellipsoid"])
def test_kothare_example_1_with_an_input_bound_follows_python(tmp_path: Path, kind: str) -> None:
    ctrl, plant, x0 = _kothare_ex1(kind)
    _follow(ctrl, plant, x0, Exported(ctrl, tmp_path), 20, float(ctrl.problem.data.u_max[0]))


def test_a_proved_infeasibility_keeps_the_last_certified_gain_as_python_does(tmp_path: Path) -> None:
    b = np.array([[0.0], [0.1]])
    plant = PolytopicModel([(np.array([[1.0, 0.1], [0.2, 1.0]]), b),
                            (np.array([[1.0, 0.1], [0.4, 1.0]]), b)], dt=0.1)
    ctrl = RMPC(plant, np.eye(2), np.eye(1), u_max=1.0)
    exported = Exported(ctrl, tmp_path)
    near = np.array([0.2, 0.0])
    u_py = ctrl.step(near)
    code, u, _, _ = exported.step(near)
    assert code == CODE["optimal / ok"] and np.max(np.abs(u - u_py)) <= 1e-6
    far = np.array([80.0, 0.0])
    u_py = ctrl.step(far)  # Python applies the last certified gain (a gain exists: no warning)
    code, u, gamma, _ = exported.step(far)
    assert ctrl.last.status == "infeasible" and code == CODE["infeasible"]
    assert np.isnan(gamma)
    np.testing.assert_allclose(u, u_py, rtol=1e-6, atol=1e-9)


def test_a_non_finite_state_gives_a_status_and_a_finite_command(tmp_path: Path) -> None:
    ctrl, _, x0 = _kothare_ex1()
    exported = Exported(ctrl, tmp_path)
    assert exported.step(x0)[0] == CODE["optimal / ok"]
    for bad in (np.array([np.nan, 0.0]), np.array([np.inf, 1.0])):
        code, u, _, _ = exported.step(bad)
        assert code == STATUS_CODES[2].value and np.all(u == 0.0)
    code, u, _, _ = exported.step(np.array([1e300, 1e300]))  # finite, but its norm overflows
    assert code > 0 and np.all(np.isfinite(u))


@pytest.mark.parametrize(
    ("options", "named"),
    [
        ({"lyapunov": "vertex"}, "Kothare's form"),
        ({"cost": "nominal"}, "Kothare's form"),
        ({"backend": "clarabel"}, "backend"),
        ({"offset_free": True}, "offset-free"),
    ],
)
def test_what_the_c_solver_does_not_carry_is_refused_by_name(tmp_path: Path, options, named) -> None:
    from benchmarks.suites.methods_problems import build_problem

    p = build_problem("kothare_ex1")
    ctrl = RMPC(p.plant, p.Q, p.R, u_max=p.u_max, **options)
    with pytest.raises(InvalidArgumentError, match=named):
        export_c(ctrl, tmp_path)
    assert not (tmp_path / "rmpc_controller.c").exists()


DRIVER = r"""
#include <stdio.h>
#include "rmpc_controller.h"
int main(int argc, char **argv)
{
    double x[RMPC_NX], u[RMPC_NU];
    FILE *f = fopen(argv[1], "r");
    int i, j, code;
    (void)argc;
    rmpc_init();
    for (;;) {
        for (i = 0; i < RMPC_NX; ++i) {
            if (fscanf(f, "%lf", &x[i]) != 1) {
                fclose(f);
                return 0;
            }
        }
        code = rmpc_step(x, u);
        printf("%d %.17g", code, rmpc_last_gamma());
        for (j = 0; j < RMPC_NU; ++j) {
            printf(" %.17g", u[j]);
        }
        printf("\n");
    }
}
"""


def test_sanitizer_build_runs_a_loop_clean(tmp_path: Path) -> None:
    ctrl, plant, x0 = _paper_p_e1()
    result = export_c(ctrl, tmp_path)
    a, b = plant.nominal
    states, x = [], x0.copy()
    for _ in range(8):
        states.append(x)
        x = a @ x + b @ ctrl.step(x)
    states.append(np.zeros(6))
    (tmp_path / "states.txt").write_text("\n".join(" ".join(repr(float(v)) for v in s) for s in states))
    (tmp_path / "driver.c").write_text(DRIVER)
    exe = tmp_path / "driver"
    subprocess.run([CC, *STRICT, "-g", "-fsanitize=address,undefined", "-fno-omit-frame-pointer",
                    "-fno-sanitize-recover=all", "-I", str(tmp_path), "-o", str(exe),
                    str(tmp_path / "driver.c"), str(result.source), "-lm"],
                   check=True, capture_output=True, text=True)
    run = subprocess.run([str(exe), str(tmp_path / "states.txt")], capture_output=True, text=True,
                         env={"ASAN_OPTIONS": "detect_leaks=1", "UBSAN_OPTIONS": "print_stacktrace=1"})
    assert run.returncode == 0, run.stderr
    assert "runtime error" not in run.stderr and "AddressSanitizer" not in run.stderr
    codes = [int(line.split()[0]) for line in run.stdout.splitlines()]
    assert codes == [CODE["optimal / ok"]] * 8 + [CODE["reused"]]
