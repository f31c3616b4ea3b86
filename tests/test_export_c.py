"""The C99 export (``rmpc.export_c``) against the Python controllers, compiled with the system ``cc``.

Each controller is exported, compiled with ``cc -std=c99 -O2 -Wall -Wextra -Werror -pedantic
-shared -fPIC``, loaded with ctypes and stepped on seeded states next to its Python ``step``:

- *axis states* (one non-zero entry; for LQR ``x - x_ref`` has one): every dot product has one
  non-zero term, so the dot products are exact whatever order BLAS sums them in, and the rest
  of the step (numpy's pairwise sum of the levels, the binary search, ``alpha``, the
  interpolation) must agree **bit for bit**: commands, statuses, indices, ``alpha``, ``gamma``;
- *general states*, inside and outside the outermost ellipsoid: statuses, indices and ``gamma``
  identical, and the commands within the rounding of the dot products. numpy's ``@`` calls
  BLAS (OpenBLAS here), whose kernel sums in an order of its own (measured on this machine's
  SkylakeX kernel: four FMA lanes combined as ``(l0 + l2) + (l1 + l3)``, then the tail), while the
  C sums in index order; both are within ``gamma_n sum |a_j x_j|`` of the exact sum, so the bound
  below is twice that, carried through the levels, ``alpha`` and the interpolation.

A second build with ``-fsanitize=address,undefined`` runs a small C driver on the same states
(and NaN, inf, overflow, null pointers, overlapping x and u) and must agree with the ctypes build
bit for bit with a clean exit.
"""

from __future__ import annotations

import ctypes
import os
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from models import PolytopicModel, RigidSatellite
from rmpc import LQR, RMPC, OfflineRMPC, export_c
from rmpc.export import c_offline
from rmpc.export.c_writer import STATUS_CODES
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError, ToolkitError

CC = shutil.which("cc")
pytestmark = pytest.mark.skipif(CC is None, reason="no C compiler: `cc` is not on PATH")

STRICT = ["-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-pedantic"]
CODE = {code.name: code.value for code in STATUS_CODES}
PYTHON_CODE = {"optimal": CODE["RMPC_OK"], "ok": CODE["RMPC_OK"], "outside": CODE["RMPC_STATUS_OUTSIDE"]}
N_STATES = 10_000
UNIT = 2.0**-53  # unit roundoff of a double
_P = ctypes.POINTER(ctypes.c_double)


def _gamma(n: int) -> float:
    """Higham's gamma_n = n u / (1 - n u): a sum of n rounded terms is within gamma_n sum |terms|."""
    return n * UNIT / (1.0 - n * UNIT)


# -- controllers ---------------------------------------------------------------------------------
def _kothare_plant() -> PolytopicModel:
    """Kothare (1996) example 1: the two vertices alpha = 0.1 and 10."""
    def ab(alpha: float) -> tuple[np.ndarray, np.ndarray]:
        return np.array([[1.0, 0.1], [0.0, 1.0 - 0.1 * alpha]]), np.array([[0.0], [0.1 * 0.787]])

    return PolytopicModel([ab(0.1), ab(10.0)], dt=0.1)


def _chain_plant(n: int = 9) -> PolytopicModel:
    """A chain of ``n`` integrators with two inputs: ``n >= 8`` takes numpy's 8-lane pairwise sum."""
    def ab(k: float) -> tuple[np.ndarray, np.ndarray]:
        a = np.eye(n) + 0.1 * (np.diag(np.ones(n - 1), 1) * k - 0.05 * np.eye(n))
        b = np.zeros((n, 2))
        b[-1, 0] = b[n // 2, 1] = 0.1
        return a, b

    return PolytopicModel([ab(0.8), ab(1.2)], dt=0.1)


def _satellite_plant() -> PolytopicModel:
    sat = RigidSatellite.paper_p()
    return sat.polytope(sat.initial_state(), 0.01, 0.3, "scalar")


def _build_controller(which: str):
    """The controllers compared (Clarabel designs: the lookup does not depend on the back-end)."""
    if which in ("kothare", "kothare_plain"):
        return OfflineRMPC(_kothare_plant(), np.diag([1.0, 0.0]), [[2e-5]], u_max=2.0,
                           input_constraint="peak",
                           x_design=[0.05, 0.0], n_ellipsoids=10, backend="clarabel",
                           interpolate=which == "kothare")
    if which == "satellite":
        x0 = RigidSatellite.paper_p().initial_state()
        return OfflineRMPC(_satellite_plant(), np.diag([1, 1, 1, 0.1, 0.1, 0.1]), np.eye(3), u_max=1.0,
                           x_design=x0, n_ellipsoids=6, backend="clarabel")
    if which == "chain9":
        return OfflineRMPC(_chain_plant(), np.eye(9), np.eye(2), x_design=np.linspace(1, -1, 9) * 0.3,
                           n_ellipsoids=4, backend="clarabel")
    if which == "lqr":
        return LQR(_satellite_plant(), np.diag([1, 1, 1, 0.1, 0.1, 0.1]), np.eye(3),
                   x_ref=[0.01, 0.02, -0.01, 0.0, 0.0, 0.0])
    raise AssertionError(which)


OFFLINE = ("kothare", "kothare_plain", "satellite", "chain9")


@dataclass
class Steps:
    """One run over states: status codes, commands, ``gamma`` (NaN for none), index, ``alpha``."""

    status: np.ndarray
    u: np.ndarray
    gamma: np.ndarray
    index: np.ndarray
    alpha: np.ndarray


class Compiled:
    """An exported controller compiled into a shared library and loaded with ctypes."""

    def __init__(self, ctrl, folder: Path) -> None:
        self.result = export_c(ctrl, folder)
        self.folder = folder
        self.library = folder / "librmpc.so"
        command = [CC, *STRICT, "-shared", "-fPIC", "-o", str(self.library), str(self.result.source), "-lm"]
        subprocess.run(command, check=True, capture_output=True, text=True)
        lib = ctypes.CDLL(str(self.library))
        lib.rmpc_step.argtypes = [_P, _P]
        lib.rmpc_step.restype = ctypes.c_int
        lib.rmpc_last_gamma.restype = ctypes.c_double
        self.offline = hasattr(lib, "rmpc_last_index")
        if self.offline:
            lib.rmpc_last_alpha.restype = ctypes.c_double
        self.lib = lib
        assert lib.rmpc_init() == 0

    def run(self, states: np.ndarray) -> Steps:
        lib, nu = self.lib, self.result.nu
        count = states.shape[0]
        out = Steps(np.zeros(count, int), np.zeros((count, nu)), np.zeros(count), np.zeros(count, int),
                    np.ones(count))
        u = np.zeros(nu)
        for k, x in enumerate(np.ascontiguousarray(states, dtype=float)):
            out.status[k] = lib.rmpc_step(x.ctypes.data_as(_P), u.ctypes.data_as(_P))
            out.u[k] = u
            out.gamma[k] = lib.rmpc_last_gamma()
            if self.offline:
                out.index[k] = lib.rmpc_last_index()
                out.alpha[k] = lib.rmpc_last_alpha()
        return out


def python_run(ctrl, states: np.ndarray) -> Steps:
    count = states.shape[0]
    nu = ctrl.F.shape[0] if isinstance(ctrl, LQR) else ctrl.plant.n_inputs
    out = Steps(np.zeros(count, int), np.zeros((count, nu)),
                np.zeros(count), np.zeros(count, int), np.ones(count))
    for k, x in enumerate(states):
        out.u[k] = ctrl.step(x)
        last = ctrl.last
        out.status[k] = PYTHON_CODE[last.status]
        out.gamma[k] = np.nan if last.gamma is None else last.gamma
        if isinstance(ctrl, OfflineRMPC):
            out.index[k] = last.extra["index"]
            out.alpha[k] = last.extra["alpha"]
    return out


@pytest.fixture(scope="module")
def controllers():
    return {which: _build_controller(which) for which in (*OFFLINE, "lqr")}


@pytest.fixture(scope="module")
def compiled(controllers, tmp_path_factory) -> dict[str, Compiled]:
    return {which: Compiled(ctrl, tmp_path_factory.mktemp(which)) for which, ctrl in controllers.items()}


# -- seeded states -----------------------------------------------------------------------------
def axis_states(ctrl, count: int, seed: int) -> np.ndarray:
    """States with one non-zero entry at levels ``2^-(2N+4) .. 2`` of the outermost ellipsoid."""
    rng = np.random.default_rng(seed)
    if isinstance(ctrl, LQR):
        n = ctrl.x_ref.size
        out = np.tile(ctrl.x_ref, (count, 1))
        out[np.arange(count), rng.integers(0, n, count)] += rng.standard_normal(count)
        return out
    q1_inv = np.linalg.inv(ctrl.table.ellipsoids[0].Q)
    n = q1_inv.shape[0]
    axis = rng.integers(0, n, count)
    level = 2.0 ** rng.uniform(-2 * ctrl.table.n_ellipsoids - 4, 1.0, count)
    out = np.zeros((count, n))
    out[np.arange(count), axis] = rng.choice([-1.0, 1.0], count) * np.sqrt(level / q1_inv[axis, axis])
    return out


def general_states(ctrl, count: int, seed: int) -> np.ndarray:
    """Random directions at levels ``2^-(2N+4) .. 2`` of the outermost ellipsoid (LQR: a wide cloud)."""
    rng = np.random.default_rng(seed)
    if isinstance(ctrl, LQR):
        return rng.standard_normal((count, ctrl.x_ref.size)) * 10.0 ** rng.uniform(-3, 1, (count, 1))
    q1 = ctrl.table.ellipsoids[0].Q
    direction = rng.standard_normal((count, q1.shape[0]))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    level = 2.0 ** rng.uniform(-2 * ctrl.table.n_ellipsoids - 4, 1.0, count)
    return (direction @ np.linalg.cholesky(q1).T) * np.sqrt(level)[:, None]


def _coverage(ctrl, got: Steps) -> None:
    """The states reach outside, several ellipsoids and (when on) interpolation."""
    outside = np.count_nonzero(got.status == CODE["RMPC_STATUS_OUTSIDE"])
    inside = got.status == CODE["RMPC_OK"]
    assert outside >= 200 and np.count_nonzero(inside) >= 5000
    assert len(set(got.index[inside].tolist())) >= min(4, ctrl.table.n_ellipsoids)
    if ctrl.interpolate:
        assert np.count_nonzero(got.alpha < 1.0) >= 1000
    else:
        assert np.all(got.alpha == 1.0)


def _assert_identical(got: Steps, want: Steps) -> None:
    np.testing.assert_array_equal(got.status, want.status)
    np.testing.assert_array_equal(got.index, want.index)
    np.testing.assert_array_equal(got.alpha, want.alpha)
    np.testing.assert_array_equal(got.gamma, want.gamma)  # NaN where Python's gamma is None
    np.testing.assert_array_equal(got.u, want.u)


# -- bit for bit where the dot products are exact ------------------------------------------------
@pytest.mark.parametrize("which", [*OFFLINE, "lqr"])
def test_axis_states_agree_bit_for_bit(which, controllers, compiled) -> None:
    ctrl = controllers[which]
    states = axis_states(ctrl, N_STATES, seed=1)
    got, want = compiled[which].run(states), python_run(ctrl, states)
    _assert_identical(got, want)
    if isinstance(ctrl, OfflineRMPC):
        _coverage(ctrl, got)


# -- within the rounding of the dot products elsewhere ---------------------------------------------
def _dot_error(mats: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Twice gamma_n sum_j |M_ij z_j| per row: how far two summation orders of M z may differ."""
    return 2.0 * _gamma(z.size) * (np.abs(mats) @ np.abs(z))


def _level_error(chol: np.ndarray, z: np.ndarray) -> tuple[float, float]:
    """The level ``||C' z||^2`` and how far its two computations may differ."""
    y = chol @ z
    e = _dot_error(chol, z)
    squares = (2.0 * np.abs(y) + e) * e + 2.0 * UNIT * y * y
    return float(y @ y), float(squares.sum() + 2.0 * _gamma(z.size) * (y @ y))


def offline_bound(
    ctrl: OfflineRMPC, z: np.ndarray, got_alpha: float, want: Steps, k: int
) -> tuple[float, np.ndarray]:
    """The bounds on ``|alpha_C - alpha_Python|`` and ``|u_C - u_Python|`` at state ``z``.

    First order in the rounding errors, doubled for the second-order terms.
    """
    table = ctrl.table
    chol = [np.linalg.cholesky(np.linalg.inv(e.Q)).T for e in table.ellipsoids]
    i = int(want.index[k])
    f_i = table.ellipsoids[i].F
    alpha = float(want.alpha[k])
    if want.status[k] != CODE["RMPC_OK"] or (alpha == 1.0 and got_alpha == 1.0):
        return 0.0, 2.0 * _dot_error(f_i, z)
    f_k = table.ellipsoids[i + 1].F
    a, da = _level_error(chol[i], z)
    b, db = _level_error(chol[i + 1], z)
    t = (b - 1.0) / (b - a)
    d_alpha = 2.0 * ((abs(b - 1.0) * da + abs(1.0 - a) * db) / (b - a) ** 2 + 6.0 * UNIT * abs(t))
    u_i, u_k = f_i @ z, f_k @ z
    d_u = (alpha * _dot_error(f_i, z) + (1.0 - alpha) * _dot_error(f_k, z)
           + abs(got_alpha - alpha) * np.abs(u_i - u_k)
           + 4.0 * UNIT * (np.abs(alpha * u_i) + np.abs((1.0 - alpha) * u_k)))
    return d_alpha, 2.0 * d_u


@pytest.mark.parametrize("which", OFFLINE)
def test_general_states_agree_within_rounding(which, controllers, compiled) -> None:
    ctrl = controllers[which]
    states = general_states(ctrl, N_STATES, seed=2)
    got, want = compiled[which].run(states), python_run(ctrl, states)
    np.testing.assert_array_equal(got.status, want.status)
    np.testing.assert_array_equal(got.index, want.index)
    np.testing.assert_array_equal(got.gamma, want.gamma)
    _coverage(ctrl, got)
    for k, z in enumerate(states):
        d_alpha, d_u = offline_bound(ctrl, z, float(got.alpha[k]), want, k)
        assert abs(got.alpha[k] - want.alpha[k]) <= d_alpha, (k, got.alpha[k], want.alpha[k], d_alpha)
        assert np.all(np.abs(got.u[k] - want.u[k]) <= d_u), (k, got.u[k], want.u[k], d_u)


def test_lqr_general_states_within_rounding(controllers, compiled) -> None:
    ctrl = controllers["lqr"]
    states = general_states(ctrl, N_STATES, seed=3)
    got, want = compiled["lqr"].run(states), python_run(ctrl, states)
    np.testing.assert_array_equal(got.status, want.status)
    assert np.all(got.status == 0) and np.all(np.isnan(got.gamma))
    d = states - ctrl.x_ref
    bound = 2.0 * _gamma(d.shape[1]) * (np.abs(d) @ np.abs(ctrl.F).T)
    assert np.all(np.abs(got.u - want.u) <= bound)


# -- non-finite input, overflow, null pointers ---------------------------------------------------
@pytest.mark.parametrize("which", ["satellite", "lqr"])
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_state_gives_a_status_and_zero(which, bad, controllers, compiled) -> None:
    lib, nx, nu = compiled[which].lib, compiled[which].result.nx, compiled[which].result.nu
    x = np.full(nx, 0.01)
    x[nx - 1] = bad
    u = np.full(nu, np.nan)
    assert lib.rmpc_step(x.ctypes.data_as(_P), u.ctypes.data_as(_P)) == CODE["RMPC_STATUS_BAD_STATE"]
    assert np.all(u == 0.0) and np.isnan(lib.rmpc_last_gamma())
    with pytest.raises(InvalidArgumentError, match="x: expected finite values"):
        controllers[which].step(x)  # Python refuses the state; C returns its code


def test_overflow_gives_a_status_and_zero(controllers, compiled) -> None:
    """A finite state whose command overflows: Python returns inf/NaN, the C code 3 and u = 0."""
    x = np.full(2, 1.7e308)
    with np.errstate(over="ignore", invalid="ignore"):
        assert not np.all(np.isfinite(controllers["kothare"].step(x)))
    lib = compiled["kothare"].lib
    u = np.full(1, np.nan)
    assert lib.rmpc_step(x.ctypes.data_as(_P), u.ctypes.data_as(_P)) == CODE["RMPC_STATUS_OVERFLOW"]
    assert u[0] == 0.0 and lib.rmpc_last_index() == -1 and lib.rmpc_last_iterations() == 0


def test_null_pointers_and_overlapping_buffers(controllers, compiled) -> None:
    comp = compiled["satellite"]
    lib = comp.lib
    u = np.full(3, np.nan)
    assert lib.rmpc_step(None, u.ctypes.data_as(_P)) == CODE["RMPC_STATUS_NULL_ARGUMENT"] and np.all(u == 0)
    x = RigidSatellite.paper_p().initial_state() * 0.3
    assert lib.rmpc_step(x.ctypes.data_as(_P), None) == CODE["RMPC_STATUS_NULL_ARGUMENT"]
    want = controllers["satellite"].step(x)
    buf = x.copy()  # u written over x: the C copies x before it writes u
    assert lib.rmpc_step(buf.ctypes.data_as(_P), buf.ctypes.data_as(_P)) == 0
    np.testing.assert_allclose(buf[:3], want, rtol=1e-13, atol=0)
    assert lib.rmpc_init() == 0 and lib.rmpc_last_index() == -1 and np.isnan(lib.rmpc_last_gamma())
    assert lib.rmpc_last_iterations() == 0


def test_iterations_are_the_binary_search_probes(controllers, compiled) -> None:
    lib = compiled["satellite"].lib
    count = controllers["satellite"].table.n_ellipsoids
    probes = set()
    for x in general_states(controllers["satellite"], 200, seed=4):
        lib.rmpc_step(np.ascontiguousarray(x).ctypes.data_as(_P), np.zeros(3).ctypes.data_as(_P))
        probes.add(lib.rmpc_last_iterations())
    assert probes and max(probes) <= int(np.ceil(np.log2(count + 1))) and min(probes) >= 1


# -- the sanitizer build -----------------------------------------------------------------------
DRIVER = r"""
#include <stdio.h>
#include "rmpc_controller.h"

/* reads: count, then count states; writes per state: status, gamma, u (binary doubles) */
int main(int argc, char **argv)
{
    FILE *in;
    FILE *out;
    double count;
    double x[RMPC_NX];
    double u[RMPC_NU];
    double both[RMPC_NX > RMPC_NU ? RMPC_NX : RMPC_NU];
    long k;
    int j;
    if (argc != 3 || (in = fopen(argv[1], "rb")) == NULL || (out = fopen(argv[2], "wb")) == NULL) {
        return 2;
    }
    if (fread(&count, sizeof count, 1, in) != 1 || rmpc_init() != RMPC_OK) {
        return 3;
    }
    for (k = 0; k < (long)count; ++k) {
        double record[2];
        if (fread(x, sizeof x, 1, in) != 1) {
            return 4;
        }
        record[0] = (double)rmpc_step(x, u);
        record[1] = rmpc_last_gamma();
        fwrite(record, sizeof record, 1, out);
        fwrite(u, sizeof u, 1, out);
    }
    /* null pointers and overlapping buffers, checked in C */
    if (rmpc_step(NULL, u) != RMPC_STATUS_NULL_ARGUMENT || rmpc_step(x, NULL) != RMPC_STATUS_NULL_ARGUMENT) {
        return 5;
    }
    for (j = 0; j < RMPC_NX; ++j) {
        both[j] = x[j];
    }
    if (rmpc_step(both, both) != rmpc_step(x, u)) {
        return 6;
    }
    for (j = 0; j < RMPC_NU; ++j) {
        if (both[j] != u[j]) {
            return 7;
        }
    }
    (void)rmpc_last_iterations();
    fclose(in);
    fclose(out);
    return 0;
}
"""


@pytest.mark.parametrize("which", ["satellite", "lqr"])
def test_sanitizer_build_agrees_and_runs_clean(which, controllers, compiled, tmp_path) -> None:
    comp = compiled[which]
    (tmp_path / "driver.c").write_text(DRIVER)
    for name in ("rmpc_controller.h", "rmpc_controller.c"):
        shutil.copy(comp.folder / name, tmp_path / name)
    exe = tmp_path / "driver"
    flags = ["-std=c99", "-O1", "-g", "-Wall", "-Wextra", "-Werror", "-pedantic",
             "-fsanitize=address,undefined", "-fno-omit-frame-pointer", "-fno-sanitize-recover=all"]
    build = subprocess.run([CC, *flags, "-o", str(exe), "driver.c", "rmpc_controller.c", "-lm"],
                           cwd=tmp_path, capture_output=True, text=True)
    if build.returncode != 0 and "sanitize" in build.stderr and "cannot find" in build.stderr:
        pytest.skip(f"the sanitizer runtime is not installed: {build.stderr.strip()[:200]}")
    assert build.returncode == 0, build.stderr
    ctrl = controllers[which]
    states = np.vstack([axis_states(ctrl, 2000, seed=5), general_states(ctrl, 2000, seed=6),
                        np.full((1, comp.result.nx), np.nan), np.full((1, comp.result.nx), 1e308)])
    states[-3, 0] = np.inf
    (tmp_path / "states.bin").write_bytes(np.concatenate([[float(len(states))], states.ravel()]).tobytes())
    env = {**os.environ, "ASAN_OPTIONS": "detect_leaks=1:abort_on_error=0",
           "UBSAN_OPTIONS": "print_stacktrace=1:halt_on_error=1"}
    run = subprocess.run([str(exe), "states.bin", "out.bin"], cwd=tmp_path, capture_output=True, text=True,
                         env=env, timeout=60)
    assert run.returncode == 0 and run.stderr == "", (run.returncode, run.stderr)
    rows = np.frombuffer((tmp_path / "out.bin").read_bytes()).reshape(len(states), 2 + comp.result.nu)
    ref = comp.run(states)
    np.testing.assert_array_equal(rows[:, 0].astype(int), ref.status)
    np.testing.assert_array_equal(rows[:, 1], ref.gamma)
    np.testing.assert_array_equal(rows[:, 2:], ref.u)
    assert set(ref.status[-3:].tolist()) >= {CODE["RMPC_STATUS_BAD_STATE"]}


# -- the files and what the result says ----------------------------------------------------------
def test_result_reports_files_and_static_memory(compiled) -> None:
    comp = compiled["satellite"]
    res = comp.result
    assert res.sizes == {p.name: p.stat().st_size for p in res.paths}
    header = res.header.read_text()
    for line in ("#define RMPC_NX 6", "#define RMPC_NU 3", "int rmpc_init(void);",
                 "int rmpc_step(const double *x, double *u);", "double rmpc_last_gamma(void);",
                 "int rmpc_last_iterations(void);", *(f"#define {n} {v}" for n, v in CODE.items())):
        assert line in header, line
    source = res.source.read_text()
    for word in ("malloc", "free(", "#include <stdio.h>", "#include <stdlib.h>"):
        assert word not in source
    nm = shutil.which("nm")
    if nm is None:
        pytest.skip("no `nm` to read the object's symbol sizes")
    obj = comp.folder / "rmpc_controller.o"
    subprocess.run([CC, *STRICT, "-c", "-o", str(obj), str(res.source)], check=True)
    sizes = {}
    listing = subprocess.run([nm, "-S", str(obj)], capture_output=True, text=True, check=True).stdout
    for line in listing.splitlines():
        parts = line.split()
        if len(parts) == 4:
            sizes[parts[3]] = int(parts[1], 16)
    tables = ("rmpc_chol", "rmpc_gain", "rmpc_gamma", "rmpc_interpolable")
    assert res.table_bytes == sum(sizes[name] for name in tables)
    assert res.workspace_bytes == sizes["rmpc_ws"]
    assert res.static_bytes == res.table_bytes + res.workspace_bytes


@pytest.mark.parametrize("which", ["chain9", "lqr"])
def test_stricter_warnings_are_clean(which, compiled) -> None:
    """The warnings flight-software rules often add (conversions, shadowing, float equality...)."""
    extra = ["-Wconversion", "-Wshadow", "-Wcast-qual", "-Wstrict-prototypes", "-Wmissing-prototypes",
             "-Wdouble-promotion", "-Wfloat-equal", "-Wundef", "-Wvla"]
    source = compiled[which].result.source
    command = [CC, *STRICT, *extra, "-c", "-o", os.devnull, str(source)]
    run = subprocess.run(command, capture_output=True, text=True)
    assert run.returncode == 0 and run.stderr == "", run.stderr


def test_constants_round_trip_bit_for_bit(controllers, compiled) -> None:
    """Every table entry of the C source reads back as the Python double."""
    ctrl = controllers["satellite"]
    source = compiled["satellite"].result.source.read_text()
    body = source.split("rmpc_gain[", 1)[1].split("{", 1)[1].split("}", 1)[0]
    values = np.array([float.fromhex(v.strip()) for v in body.split(",")])
    gains = np.concatenate([e.F.ravel() for e in ctrl.table.ellipsoids])
    assert values.tobytes() == gains.tobytes()


# -- bad input -----------------------------------------------------------------------------------
def test_undesigned_and_empty_tables_are_refused(tmp_path) -> None:
    auto = OfflineRMPC(_kothare_plant(), np.diag([1.0, 0.0]), [[2e-5]], u_max=2.0, backend="clarabel")
    with pytest.raises(InvalidArgumentError, match=r"controller: .*no table: the controller has not been"):
        export_c(auto, tmp_path)
    unstable = PolytopicModel([([[1.5]], [[1.0]])], dt=1.0)
    empty = OfflineRMPC(unstable, [[1.0]], [[1.0]], u_max=1.0, x_design=[10.0], n_ellipsoids=3,
                        backend="clarabel")
    with pytest.raises(InvalidArgumentError, match=r"at least one certified ellipsoid.*an empty table"):
        export_c(empty, tmp_path)
    assert not any(tmp_path.iterdir())


def test_unsupported_controllers_are_named(controllers, tmp_path) -> None:
    with pytest.raises(ArgumentTypeError, match=r"controller: expected a controller with a C export "
                                                r"\(LQR, OfflineRMPC, RMPC\), but found dict"):
        export_c({}, tmp_path)

    class MyLQR(LQR):
        pass

    sub = MyLQR.__new__(MyLQR)
    with pytest.raises(ArgumentTypeError, match="found MyLQR"):
        export_c(sub, tmp_path)
    rmpc_ctrl = RMPC(_kothare_plant(), np.diag([1.0, 0.0]), [[2e-5]], u_max=2.0, lyapunov="vertex")
    with pytest.raises(InvalidArgumentError, match="Kothare's form"):
        export_c(rmpc_ctrl, tmp_path)


def test_sizes_beyond_the_limits_are_refused(controllers, tmp_path, monkeypatch) -> None:
    big = _build_controller("lqr")
    big.F = np.zeros((3, 65))
    big.x_ref = np.zeros(65)
    with pytest.raises(InvalidArgumentError,
                       match=r"RMPC_NX between 1 and 64 \(the export's limit\), but found RMPC_NX = 65"):
        export_c(big, tmp_path)
    monkeypatch.setattr(c_offline, "MAX_ELLIPSOIDS", 3)
    with pytest.raises(InvalidArgumentError, match=r"a table of at most 3 ellipsoids .* found 10 ellipsoids"):
        export_c(controllers["kothare"], tmp_path)


def test_bad_output_folders_are_named(controllers, tmp_path) -> None:
    ctrl = controllers["lqr"]
    a_file = tmp_path / "file.txt"
    a_file.write_text("x")
    with pytest.raises(InvalidArgumentError, match=r"out_dir: expected a directory .* which is a file"):
        export_c(ctrl, a_file)
    with pytest.raises(InvalidArgumentError, match="out_dir: expected a directory that can be created"):
        export_c(ctrl, a_file / "sub")
    blocked = tmp_path / "blocked"
    (blocked / "rmpc_controller.h").mkdir(parents=True)  # a folder where the header must go
    with pytest.raises(InvalidArgumentError, match="out_dir: expected a writable directory"):
        export_c(ctrl, blocked)
    assert sorted(p.name for p in blocked.iterdir()) == ["rmpc_controller.h"]  # nothing half-written
    with pytest.raises(ArgumentTypeError, match="out_dir: expected a path"):
        export_c(ctrl, 3)
    assert issubclass(InvalidArgumentError, ToolkitError)


# -- the timing script ---------------------------------------------------------------------------
def test_timing_section_times_both_and_agrees(controllers) -> None:
    """benchmarks.timing.c_export on Kothare's table: both timed, same statuses, sizes reported."""
    from benchmarks.timing.c_export import time_c_export

    ctrl = controllers["kothare"]
    states = general_states(ctrl, 300, seed=7)
    rec = time_c_export(ctrl, states, batches=5, calls=200)
    assert rec["same_statuses"] and rec["states"] == 300 and rec["n_ellipsoids"] == 10
    assert 0.0 < rec["c_p50_s"] <= rec["c_p95_s"] and rec["python_p50_s"] > 0.0
    assert rec["max_abs_diff_u"] <= 1e-12 * rec["max_u"]
    assert rec["static_bytes"] == rec["table_bytes"] + rec["workspace_bytes"] > 0
    assert rec["object_file_bytes"] > 0
