"""``rmpc timing --out DIR``: the solver timing report (SPEC 2.1, 2.3, 2.4 and 5; API.md).

On paper P's satellite (``Ts = 0.01`` s, inertia spread 0.3, ``Q1 = diag(1, 1, 1, 0.1, 0.1, 0.1)``,
``R = I``, ``||u|| <= 1``) it times, in one run:

- **RMPC** (Kothare 1996, one SDP per step) for 2, 4 and 8 polytope vertices, every path on the
  same states, interleaved state by state (so load changes of a shared machine hit every path
  alike): the toolkit's own interior-point method (:mod:`lmi.ipm`, the default back-end) warm-
  and cold-started, Clarabel's own API with the ``delta_shared``, ``delta`` and ``standard``
  formulations, cvxpy built once with parameters, cvxpy rebuilt at every step (a few states:
  the slow path, for the rebuild/fast ratio) and cvxpy with SCS (a few states). The states are
  those of the closed loop driven by the default path (``ipm``, ``delta_shared``) on vertex 0.
  Accuracy: ``gamma`` against a high-accuracy reference (cvxpy + Clarabel at tolerances 1e-10)
  and the smallest recomputed LMI margin. ``F`` is never compared: it is not unique at the optimum (SPEC 2.1).
- **OfflineRMPC** (Wan & Kothare 2003): the per-step lookup, with and without interpolation, at
  the states of its own closed loop; its design time; ``gamma_1`` (the outermost ellipsoid,
  designed at ``x0``) against the online reference ``gamma(x0)``.
- **GIPC** (velocity-form MPC, SPEC 2.3): the per-step QP (``update`` + ``solve``) of each QP
  back-end on the QPs of one closed loop (with experiment E4's step disturbance half-way), the
  objective against a high-accuracy reference (cvxpy + Clarabel at 1e-10) and the KKT residual.

The 4-vertex polytope is 4 of the box's 8 corners: ``Ixx = Iyy`` scaled together by ``1 +- s``
(the satellite stays axisymmetric, as paper P's is) and ``Izz`` by ``1 +- s`` independently.

Times are wall-clock per step and reported as percentiles (p50, p95, max), never means, with
the machine, its load average at the start and at the end, and the package versions. Writes
``DIR/timing.json`` (the API contract), ``DIR/timing.md``, ``DIR/timing.png`` and the raw
per-step times ``DIR/timing_samples.npz``.
"""

from __future__ import annotations

import argparse
import json
import math
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from benchmarks.core.machine import machine_info, package_versions, percentiles
from toolkit_common.errors import InvalidArgumentError

# The solvers, models and controllers are imported where they are used, so that registering the
# sub-command (add_timing_parser) costs the ``rmpc`` command line nothing at start-up.
if TYPE_CHECKING:
    from benchmarks.core.progress import CaseProgress
    from lmi import KothareProblem, LMISolution
    from models import PolytopicModel

__all__ = [
    "PROBLEMS",
    "VERTEX_COUNTS",
    "TimingConfig",
    "add_timing_parser",
    "format_markdown",
    "polytope",
    "run_timing",
    "run_timing_command",
]

PROBLEMS: tuple[str, ...] = ("RMPC", "OfflineRMPC", "GIPC")
#: Problems a run may ask for: the default three and the scale section (:mod:`benchmarks.timing.scale`,
#: flexible satellite with 6-20 states; opt-in with ``--problems Scale``: Clarabel alone takes seconds
#: per solve at 14-20 states).
OPTIONAL_PROBLEMS: tuple[str, ...] = ("Scale",)
VERTEX_COUNTS: tuple[int, ...] = (2, 4, 8)
SPREAD = 0.3
TIGHT = 1e-10
#: Cheap problems (OfflineRMPC lookups, GIPC QPs: microseconds to a millisecond) follow this many
#: times more states than RMPC, so their percentiles rest on enough samples.
CHEAP_FACTOR = 25
#: SCS at its own default tolerances: the toolkit's defaults (1e-9, 100 000 iterations) take
#: 25-80 s per solve here; this row shows what a user who just picks SCS gets.
SCS_OPTIONS: dict[str, Any] = {"eps_abs": 1e-4, "eps_rel": 1e-4}
POLYTOPE_NAMES = {2: "scalar", 4: "axisymmetric", 8: "box"}
REBUILD = "cvxpy-rebuild:CLARABEL"
NO_REFERENCE = "none optimal (state left out of the errors)"
GIPC_DU_MAX = 0.01
#: The RMPC reference: cvxpy + Clarabel, candidates in order of preference. At 1e-10 Clarabel
#: often stops with AlmostSolved (reduced tolerances, ~1e-7 off) on the delta form; the
#: delta_shared form at 1e-9 converges on nearly every state here.
REFERENCES: tuple[tuple[str, float], ...] = (
    ("delta", 1e-10), ("delta_shared", 1e-10), ("delta_shared", 1e-9),
)


# -- configuration -------------------------------------------------------------------------------
@dataclass(frozen=True)
class TimingConfig:
    """What one run measures (see :func:`run_timing_command` for the defaults)."""

    out: Path
    steps: int = 40
    vertices: tuple[int, ...] = VERTEX_COUNTS
    problems: tuple[str, ...] = PROBLEMS
    rebuild_steps: int = 10
    scs_steps: int = 5
    n_ellipsoids: int = 15
    lookup_repeats: int = 5
    quick: bool = False
    progress: bool | None = None
    scale_steps: int = 10
    scale_sizes: tuple[int, ...] = (6, 10, 14, 20)
    scale_scs_steps: int = 1
    scale_cvxpy_steps: int = 2

    @property
    def cheap_steps(self) -> int:
        return max(CHEAP_FACTOR * self.steps, 2)


def _int_option(value: Any, option: str, minimum: int) -> int:
    if isinstance(value, bool):
        raise InvalidArgumentError(option, f"an integer >= {minimum}", repr(value))
    try:
        number = int(value)
        exact = float(value) == number if not isinstance(value, str) else True
    except (TypeError, ValueError):
        raise InvalidArgumentError(option, f"an integer >= {minimum}", repr(value)) from None
    if not exact or number < minimum:
        raise InvalidArgumentError(option, f"an integer >= {minimum}", repr(value))
    return number


def _vertices_option(values: Any) -> tuple[int, ...]:
    items = [values] if isinstance(values, str | int) else list(values or [])
    if not items:
        raise InvalidArgumentError("--vertices", "one or more of 2, 4, 8", "nothing")
    out: list[int] = []
    for item in items:
        try:
            count = int(item)
        except (TypeError, ValueError):
            count = -1
        if count not in VERTEX_COUNTS or isinstance(item, bool):
            raise InvalidArgumentError("--vertices", "vertex counts among 2, 4, 8", repr(item))
        if count not in out:
            out.append(count)
    return tuple(sorted(out))


def _problems_option(values: Any) -> tuple[str, ...]:
    items = [values] if isinstance(values, str) else list(values or [])
    known = PROBLEMS + OPTIONAL_PROBLEMS
    if not items:
        raise InvalidArgumentError("--problems", f"one or more of {', '.join(known)}", "nothing")
    lookup = {p.lower(): p for p in known}
    out: list[str] = []
    for item in items:
        name = lookup.get(str(item).lower())
        if name is None:
            raise InvalidArgumentError("--problems", f"problems among {', '.join(known)}", repr(item))
        if name not in out:
            out.append(name)
    return tuple(p for p in known if p in out)


def _sizes_option(values: Any) -> tuple[int, ...]:
    from benchmarks.timing.scale import SCALE_SIZES

    items = [values] if isinstance(values, str | int) else list(values or [])
    out: list[int] = []
    for item in items:
        try:
            size = int(item)
        except (TypeError, ValueError):
            size = -1
        if size not in SCALE_SIZES or isinstance(item, bool):
            raise InvalidArgumentError("--scale-sizes", f"state dimensions among {SCALE_SIZES}", repr(item))
        if size not in out:
            out.append(size)
    if not out:
        raise InvalidArgumentError("--scale-sizes", f"one or more of {SCALE_SIZES}", "nothing")
    return tuple(sorted(out))


def config_from_args(args: argparse.Namespace) -> TimingConfig:
    """Validate the parsed options; a bad value raises :class:`InvalidArgumentError` naming it."""
    out = getattr(args, "out", None)
    if out is None or str(out).strip() == "":
        raise InvalidArgumentError("--out", "an output directory", repr(out))
    quick = bool(getattr(args, "quick", False))
    steps = getattr(args, "steps", None)
    steps = (3 if quick else 40) if steps is None else _int_option(steps, "--steps", 1)
    rebuild = getattr(args, "rebuild_steps", None)
    rebuild = (2 if quick else 10) if rebuild is None else _int_option(rebuild, "--rebuild-steps", 1)
    scs = getattr(args, "scs_steps", None)
    scs = (1 if quick else 5) if scs is None else _int_option(scs, "--scs-steps", 0)
    vertices = getattr(args, "vertices", None)
    problems = getattr(args, "problems", None)
    scale_steps = getattr(args, "scale_steps", None)
    scale_steps = ((2 if quick else 10) if scale_steps is None
                   else _int_option(scale_steps, "--scale-steps", 1))
    scale_cvxpy = getattr(args, "scale_cvxpy_steps", None)
    scale_cvxpy = ((0 if quick else 2) if scale_cvxpy is None
                   else _int_option(scale_cvxpy, "--scale-cvxpy-steps", 0))
    sizes = getattr(args, "scale_sizes", None)
    sizes = ((6,) if quick else (6, 10, 14, 20)) if sizes is None else _sizes_option(sizes)
    return TimingConfig(
        out=Path(out),
        steps=steps,
        vertices=VERTEX_COUNTS if vertices is None else _vertices_option(vertices),
        problems=PROBLEMS if problems is None else _problems_option(problems),
        rebuild_steps=min(rebuild, steps),
        scs_steps=min(scs, steps),
        n_ellipsoids=5 if quick else 15,
        lookup_repeats=2 if quick else 5,
        quick=quick,
        progress=False if getattr(args, "no_progress", False) else None,
        scale_steps=scale_steps,
        scale_sizes=sizes,
        scale_scs_steps=0 if quick else 1,
        scale_cvxpy_steps=min(scale_cvxpy, scale_steps),
    )


# -- plants ---------------------------------------------------------------------------------------
def polytope(n_vertices: int, spread: float = SPREAD) -> PolytopicModel:
    """Paper P's linearisation over an inertia polytope with 2, 4 or 8 vertices.

    2: ``J = c J0`` with ``c`` in ``1 +- s`` (``RigidSatellite.polytope`` mode ``"scalar"``);
    8: each principal inertia in ``(1 +- s) J_i`` independently (mode ``"box"``);
    4: ``Ixx = Iyy`` scaled together by ``1 +- s``, ``Izz`` independently (4 of the box's corners:
    the satellite stays axisymmetric). ``B`` is linear in ``J^-1`` at zero rates, so the corners in
    ``J`` span the exact set (see :meth:`models.RigidSatellite.inertia_vertices`).
    """
    from models import INPUT_NAMES, PAPER_P_SAMPLE_TIME, STATE_NAMES, PolytopicModel, RigidSatellite

    sat = RigidSatellite.paper_p()
    x0 = sat.initial_state()
    if n_vertices == 2:
        return sat.polytope(x0, PAPER_P_SAMPLE_TIME, spread, "scalar")
    if n_vertices == 8:
        return sat.polytope(x0, PAPER_P_SAMPLE_TIME, spread, "box")
    if n_vertices != 4:
        raise InvalidArgumentError("n_vertices", "2, 4 or 8", repr(n_vertices))
    j0 = np.diag(sat.inertia)
    verts = [
        RigidSatellite(j0 * np.array([a, a, c])).discretize(x0, PAPER_P_SAMPLE_TIME)
        for a in (1.0 + spread, 1.0 - spread)
        for c in (1.0 + spread, 1.0 - spread)
    ]
    return PolytopicModel(verts, PAPER_P_SAMPLE_TIME, nominal=sat.discretize(x0, PAPER_P_SAMPLE_TIME),
                          state_names=STATE_NAMES, input_names=INPUT_NAMES)


# -- helpers --------------------------------------------------------------------------------------
def _finite(value: Any) -> float | None:
    """A float for JSON (NaN and inf become ``None``)."""
    if value is None:
        return None
    value = float(value)
    return value if math.isfinite(value) else None


def _count(counts: dict[str, int], word: str) -> None:
    counts[word] = counts.get(word, 0) + 1


def _rel_err(values: Sequence[float], refs: Sequence[float], floor: float = 0.0) -> float | None:
    vals, ref = np.asarray(values, dtype=float), np.asarray(refs, dtype=float)
    ok = np.isfinite(vals) & np.isfinite(ref)
    if not np.any(ok):
        return None
    return float(np.max(np.abs(vals[ok] - ref[ok]) / np.maximum(np.abs(ref[ok]), floor)))


def _median_int(values: Sequence[int | None]) -> float | None:
    vals = [v for v in values if v is not None and v >= 0]
    return float(np.median(vals)) if vals else None


# -- RMPC -----------------------------------------------------------------------------------------
@dataclass
class _Path:
    """One RMPC solve path and what it measured."""

    backend: str
    formulation: str
    make: Callable[[], KothareProblem]
    limit: int
    rebuild: bool = False
    settings: str = ""
    problem: KothareProblem | None = None
    setup_s: float = float("nan")
    times: list[float] = field(default_factory=list)
    solver_times: list[float] = field(default_factory=list)
    iterations: list[int | None] = field(default_factory=list)
    gammas: list[float] = field(default_factory=list)
    margins: list[float] = field(default_factory=list)
    statuses: dict[str, int] = field(default_factory=dict)
    ok: list[bool] = field(default_factory=list)

    def run(self, x: np.ndarray) -> LMISolution:
        start = time.perf_counter()
        prob = self.make() if self.rebuild else self.problem
        assert prob is not None
        sol = prob.solve(x)
        self.times.append(time.perf_counter() - start)
        self.solver_times.append(sol.solve_time)
        self.iterations.append(sol.iterations)
        self.gammas.append(sol.gamma)
        self.margins.append(sol.certificate.worst if sol.certificate is not None else float("nan"))
        _count(self.statuses, sol.status)
        self.ok.append(sol.ok)
        return sol


def _rmpc_paths(poly: PolytopicModel, cfg: TimingConfig) -> tuple[list[_Path], list[_Path]]:
    from benchmarks.timing.rmpc import Q1, U_MAX, R
    from lmi import KothareProblem

    def maker(backend: str, formulation: str, solver: str | None = None,
              opts: dict[str, Any] | None = None) -> Callable[[], KothareProblem]:
        return lambda: KothareProblem(
            poly.A, poly.B, Q1, R, dt=poly.dt, u_max=U_MAX, backend=backend, solver=solver,
            formulation=formulation, solver_options=opts,
        )

    n = cfg.steps
    paths = [
        _Path("ipm", "delta_shared", maker("ipm", "delta_shared"), n,
              settings="defaults (residuals and relative gap 1e-8), warm-started from the previous solve"),
        _Path("ipm-cold", "delta_shared", maker("ipm", "delta_shared", opts={"warm_start": False}), n,
              settings="defaults (residuals and relative gap 1e-8), every solve from the default "
                       "initial point"),
        _Path("clarabel", "delta_shared", maker("clarabel", "delta_shared"), n, settings="defaults (1e-8)"),
        _Path("clarabel", "delta", maker("clarabel", "delta"), n, settings="defaults (1e-8)"),
        _Path("clarabel", "standard", maker("clarabel", "standard"), n, settings="defaults (1e-8)"),
        _Path("cvxpy:CLARABEL", "delta", maker("cvxpy", "delta", "CLARABEL"), n,
              settings="built once, parameters (DPP); Clarabel 1e-8"),
        _Path(REBUILD, "delta", maker("cvxpy", "delta", "CLARABEL"), cfg.rebuild_steps, rebuild=True,
              settings="new cvxpy problem built and solved every step; Clarabel 1e-8"),
    ]
    if cfg.scs_steps:
        paths.append(_Path("cvxpy:SCS", "delta", maker("cvxpy", "delta", "SCS", SCS_OPTIONS), cfg.scs_steps,
                           settings=f"built once, parameters; SCS {SCS_OPTIONS}"))
    refs = [
        _Path("cvxpy:CLARABEL", formulation, maker("cvxpy", formulation, "CLARABEL", _tol(tol)), n,
              settings=f"{formulation} tol {tol:g}")
        for formulation, tol in REFERENCES
    ]
    return paths, refs


def _tol(tol: float) -> dict[str, float]:
    return {"tol_gap_abs": tol, "tol_gap_rel": tol, "tol_feas": tol}


def _reference_gamma(refs: list[_Path], k: int) -> tuple[float, str, float | None]:
    """The reference at state ``k``, which candidate it is, and the spread of the optimal candidates.

    The first candidate of :data:`REFERENCES` that is optimal (converged to its tolerances and
    certified); if none is, NaN: an answer that met only reduced tolerances can be ~1e-7 off,
    as far as the paths under test, so that state is left out of the errors.
    """
    good = [(r.gammas[k], r.settings) for r in refs if r.ok[k] and math.isfinite(r.gammas[k])]
    spread = None
    if len(good) > 1:
        vals = np.array([g for g, _ in good])
        spread = float((vals.max() - vals.min()) / abs(vals.min()))
    if good:
        return good[0][0], good[0][1], spread
    return float("nan"), NO_REFERENCE, None


def time_rmpc(poly: PolytopicModel, cfg: TimingConfig, bar: CaseProgress | None = None) -> dict[str, Any]:
    """Time every RMPC path at the states of one closed loop; return records and samples."""
    from models import RigidSatellite

    paths, refs = _rmpc_paths(poly, cfg)
    x = RigidSatellite.initial_state()
    for path in paths + refs:
        if not path.rebuild:
            start = time.perf_counter()
            path.problem = path.make()
            # Warm-up, not timed: first-call set-up (cvxpy compiles here). At another state (E6's
            # 1.3 x0), so that a solver cvxpy warm-starts (SCS) does not start from the answer.
            path.problem.solve(1.3 * x)
            path.setup_s = time.perf_counter() - start
    fast = paths[0]
    a0, b0 = poly.vertex(0)
    gain = np.zeros((poly.n_inputs, poly.n_states))
    ref_gammas, ref_used, spreads = [], {}, []
    for k in range(cfg.steps):
        shift = k % len(paths)
        fast_sol = None
        for path in paths[shift:] + paths[:shift] + refs:  # rotate the order: no path always first
            if k >= path.limit:
                continue
            sol = path.run(x)
            if path is fast:
                fast_sol = sol
        gamma_ref, used, spread = _reference_gamma(refs, k)
        ref_gammas.append(gamma_ref)
        _count(ref_used, used)
        if spread is not None:
            spreads.append(spread)
        if fast_sol is not None and fast_sol.F is not None and fast_sol.ok:
            gain = fast_sol.F
        x = a0 @ x + b0 @ (gain @ x)
        if bar is not None:
            bar.advance(f"RMPC {poly.n_vertices} vertices, state {k + 1}/{cfg.steps}")
    records, samples = [], {}
    for path in paths:
        n = len(path.times)
        rec = {
            "problem": "RMPC", "formulation": path.formulation, "backend": path.backend,
            "vertices": poly.n_vertices, "polytope": POLYTOPE_NAMES[poly.n_vertices], "steps": n,
            **percentiles(path.times),
            "solver_p50_s": percentiles(path.solver_times)["p50_s"],
            "iterations_p50": _median_int(path.iterations),
            "status_counts": dict(path.statuses),
            "max_rel_err": _rel_err(path.gammas, ref_gammas[:n]),
            "compared_steps": int(np.sum(np.isfinite(path.gammas) & np.isfinite(ref_gammas[:n]))),
            "min_margin": _finite(np.nanmin(path.margins)) if np.any(np.isfinite(path.margins)) else None,
            "setup_s": _finite(path.setup_s),
            "settings": path.settings,
        }
        records.append(rec)
        samples[_sample_key(rec)] = np.asarray(path.times)
    rebuild = next(p for p in paths if p.rebuild)
    param = next(p for p in paths if p.backend == "cvxpy:CLARABEL")
    m = len(rebuild.times)
    ratio = {
        "vertices": poly.n_vertices, "steps": m,
        "rebuild_p50_s": float(np.median(rebuild.times)), "fast_p50_s": float(np.median(fast.times[:m])),
        "cvxpy_param_p50_s": float(np.median(param.times[:m])),
    }
    ratio["rebuild_over_fast"] = ratio["rebuild_p50_s"] / ratio["fast_p50_s"]
    ratio["rebuild_over_cvxpy_param"] = ratio["rebuild_p50_s"] / ratio["cvxpy_param_p50_s"]
    reference = {
        "vertices": poly.n_vertices, "steps": cfg.steps, "backend": "cvxpy:CLARABEL",
        "used": ref_used,
        "status_counts": {r.settings: dict(r.statuses) for r in refs},
        "p50_s": {r.settings: percentiles(r.times)["p50_s"] for r in refs},
        "min_margin": {r.settings: _finite(np.nanmin(r.margins)) for r in refs},
        "spread_between_optimal_references": max(spreads) if spreads else None,
        "states_with_several_optimal": len(spreads),
    }
    return {"records": records, "samples": samples, "ratio": ratio, "reference": reference,
            "gamma_x0": ref_gammas[0] if ref_gammas else float("nan")}


def reference_gamma_at(poly: PolytopicModel, x: np.ndarray) -> float:
    """``gamma(x)`` from the first optimal candidate of :data:`REFERENCES` (NaN if none is)."""
    from benchmarks.timing.rmpc import Q1, U_MAX, R
    from lmi import KothareProblem

    for formulation, tol in REFERENCES:
        sol = KothareProblem(poly.A, poly.B, Q1, R, dt=poly.dt, u_max=U_MAX, backend="cvxpy",
                             solver="CLARABEL", formulation=formulation, solver_options=_tol(tol)).solve(x)
        if sol.ok:
            return sol.gamma
    return float("nan")


# -- OfflineRMPC ----------------------------------------------------------------------------------
def time_offline(poly: PolytopicModel, cfg: TimingConfig, gamma_x0: float | None) -> dict[str, Any]:
    """Design OfflineRMPC at ``x0``, then time its lookups at the states of its own closed loop."""
    from benchmarks.timing.offline import reference_u
    from benchmarks.timing.rmpc import Q1, U_MAX, R
    from models import RigidSatellite
    from rmpc import OfflineRMPC, simulate

    x0 = RigidSatellite.initial_state()
    start = time.perf_counter()
    ctrl = OfflineRMPC(poly, Q1, R, u_max=U_MAX, x_design=x0, n_ellipsoids=cfg.n_ellipsoids)
    design_time = time.perf_counter() - start
    if gamma_x0 is None or not math.isfinite(gamma_x0):
        gamma_x0 = reference_gamma_at(poly, x0)
    table = ctrl.table
    gamma_1 = float(table.gammas[0]) if table is not None and table.n_ellipsoids else float("nan")
    err = abs(gamma_1 / gamma_x0 - 1.0) if math.isfinite(gamma_1) and math.isfinite(gamma_x0) else None
    states = simulate(ctrl, poly, x0, n_steps=cfg.cheap_steps).x[:-1]
    records, samples = [], {}
    for interpolate in (True, False):
        ctrl.interpolate = interpolate
        ctrl.step(states[0])  # the first step of a run is not a plain lookup
        wall, reported, statuses = [], [], {}
        for _ in range(cfg.lookup_repeats):
            for x in states:
                t0 = time.perf_counter()
                ctrl.step(x)
                wall.append(time.perf_counter() - t0)
                reported.append(ctrl.last.solve_time)
                _count(statuses, ctrl.last.status)
        err_u = 0.0
        if table is not None:
            for x in states:
                u, ref = ctrl.step(x), reference_u(ctrl, x)
                err_u = max(err_u, float(np.linalg.norm(u - ref) / max(np.linalg.norm(ref), 1e-300)))
        rec = {
            "problem": "OfflineRMPC", "formulation": "lookup" + ("+interpolation" if interpolate else ""),
            "backend": "numpy", "vertices": poly.n_vertices, "polytope": POLYTOPE_NAMES[poly.n_vertices],
            "steps": len(wall), **percentiles(wall),
            "solver_p50_s": percentiles(reported)["p50_s"], "iterations_p50": None,
            "status_counts": statuses, "max_rel_err": _finite(err),
            "max_rel_err_u_lookup": _finite(err_u) if table is not None else None,
            "design_time_s": design_time,
            "n_ellipsoids": table.n_ellipsoids if table is not None else 0,
            "gamma_1": _finite(gamma_1), "gamma_ref_x0": _finite(gamma_x0),
            "settings": f"{cfg.n_ellipsoids} ellipsoids along the ray of x0 (shrink 0.5), design by "
                        "cvxpy + Clarabel (delta_shared); lookups at the states of its closed loop, "
                        f"{cfg.lookup_repeats} passes",
        }
        records.append(rec)
        samples[_sample_key(rec)] = np.asarray(wall)
    return {"records": records, "samples": samples}


# -- GIPC -----------------------------------------------------------------------------------------
GIPC_BACKENDS: tuple[tuple[str, str, dict[str, Any]], ...] = (
    ("proxqp", "proxqp", {}),
    ("osqp", "osqp", {}),
    ("clarabel", "clarabel", {}),
    ("cvxpy:CLARABEL", "cvxpy", {"tol": 1e-8}),
)


def time_gipc(cfg: TimingConfig, bar: CaseProgress | None = None) -> dict[str, Any]:
    """Time ``update + solve`` of every QP back-end on the QPs of one GIPC closed loop."""
    from models import PAPER_P_SAMPLE_TIME, RigidSatellite
    from rmpc import GIPC, StepDisturbance, simulate
    from rmpc.qp import QP, kkt_residuals, make_backend

    sat = RigidSatellite.paper_p()
    x0 = sat.initial_state()
    model = sat.linear_model(x0, PAPER_P_SAMPLE_TIME)
    ctrl = GIPC(model, du_max=GIPC_DU_MAX)
    n = cfg.cheap_steps
    t_dist = min(10.0, 0.5 * n * PAPER_P_SAMPLE_TIME)
    traj = simulate(ctrl, model, x0, n_steps=n, disturbance=StepDisturbance([0.5, 0.5, 0.5], t_dist))
    qps: list[QP] = []
    for k in range(traj.n_steps):
        prev = (None, None) if k == 0 else (traj.x[k - 1], traj.u_cmd[k - 1])
        qps.append(ctrl.qp_at(traj.x[k], *prev))
    vectors = [{"g": qp.g, "l": qp.l, "u": qp.u, "lb": qp.lb, "ub": qp.ub} for qp in qps]
    ref = make_backend("cvxpy", solver="CLARABEL", tol=TIGHT)
    ref.setup(qps[0])
    ref_obj, ref_status = [], {}
    for vec in vectors:
        ref.update(**vec)
        res = ref.solve()
        ref_obj.append(res.objective if res.status == "optimal" else float("nan"))
        _count(ref_status, res.status)
    warm = ctrl.qp_at(1.3 * x0)  # warm-up QP (not timed), unlike the first one: no free warm start
    backends = []
    for label, name, settings in GIPC_BACKENDS:
        be = make_backend(name, **settings)
        start = time.perf_counter()
        be.setup(warm)
        be.solve()
        backends.append({"label": label, "be": be, "setup_s": time.perf_counter() - start, "times": [],
                         "solver": [], "iters": [], "obj": [], "kkt": [], "status": {}})
    for k, vec in enumerate(vectors):
        shift = k % len(backends)
        for b in backends[shift:] + backends[:shift]:
            t0 = time.perf_counter()
            b["be"].update(**vec)
            res = b["be"].solve()
            b["times"].append(time.perf_counter() - t0)
            b["solver"].append(res.solve_time)
            b["iters"].append(res.iterations)
            b["obj"].append(res.objective)
            _count(b["status"], res.status)
            if res.status in ("optimal", "inaccurate"):
                b["kkt"].append(kkt_residuals(qps[k], res).max())
    if bar is not None:
        bar.advance("GIPC")
    records, samples = [], {}
    for b in backends:
        rec = {
            "problem": "GIPC", "formulation": f"velocity-form QP (Np={ctrl.Np}, Nc={ctrl.Nc})",
            "backend": b["label"], "vertices": 1, "polytope": "nominal", "steps": len(b["times"]),
            **percentiles(b["times"]),
            "solver_p50_s": percentiles(b["solver"])["p50_s"],
            "iterations_p50": _median_int(b["iters"]),
            "status_counts": b["status"],
            "max_rel_err": _rel_err(b["obj"], ref_obj, floor=1e-12),
            "max_kkt_residual": _finite(max(b["kkt"])) if b["kkt"] else None,
            "setup_s": b["setup_s"],
            "settings": repr(b["be"].settings),
        }
        records.append(rec)
        samples[_sample_key(rec)] = np.asarray(b["times"])
    reference = {"backend": "cvxpy:CLARABEL", "tol": TIGHT, "status_counts": ref_status,
                 "disturbance_start_s": t_dist, "controller": ctrl.settings()}
    return {"records": records, "samples": samples, "reference": reference}


# -- the run --------------------------------------------------------------------------------------
def _sample_key(rec: dict[str, Any]) -> str:
    return f"{rec['problem']}|{rec['backend']}|{rec['formulation']}|{rec['vertices']}"


def run_timing(cfg: TimingConfig) -> dict[str, Any]:
    """Measure everything ``cfg`` asks for; return the report (``timing.json``) and the samples.

    cvxpy's "Solution may be inaccurate" warnings are silenced here: each such solve is counted
    as ``inaccurate`` in its record's ``status_counts``.
    """
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Solution may be inaccurate", category=UserWarning)
        return _run(cfg)


def _run(cfg: TimingConfig) -> dict[str, Any]:
    from benchmarks.core.progress import CaseProgress
    from benchmarks.timing.rmpc import Q1, U_MAX, R
    from models import PAPER_P_SAMPLE_TIME, RigidSatellite

    start = time.perf_counter()
    machine = machine_info()
    machine["load_average_start"] = machine.pop("load_average")
    units = (cfg.steps * len(cfg.vertices) if "RMPC" in cfg.problems else 0) + (
        len(cfg.vertices) if "OfflineRMPC" in cfg.problems else 0) + (1 if "GIPC" in cfg.problems else 0) + (
        2 * len(cfg.scale_sizes) if "Scale" in cfg.problems else 0)
    records: list[dict[str, Any]] = []
    samples: dict[str, np.ndarray] = {}
    ratios, references = [], []
    gipc_ref = None
    with CaseProgress(units, "rmpc timing", enabled=cfg.progress) as bar:
        for count in cfg.vertices:
            poly = polytope(count)
            gamma_x0 = None
            if "RMPC" in cfg.problems:
                res = time_rmpc(poly, cfg, bar)
                records += res["records"]
                samples.update(res["samples"])
                ratios.append(res["ratio"])
                references.append(res["reference"])
                gamma_x0 = res["gamma_x0"]
            if "OfflineRMPC" in cfg.problems:
                res = time_offline(poly, cfg, gamma_x0)
                records += res["records"]
                samples.update(res["samples"])
                bar.advance(f"OfflineRMPC {count} vertices")
        if "GIPC" in cfg.problems:
            res = time_gipc(cfg, bar)
            records += res["records"]
            samples.update(res["samples"])
            gipc_ref = res["reference"]
        if "Scale" in cfg.problems:
            from benchmarks.timing.scale import time_scale

            res = time_scale(cfg.scale_steps, cfg.scale_sizes, scs_steps=cfg.scale_scs_steps, progress=bar,
                             cvxpy_steps=cfg.scale_cvxpy_steps)
            records += res["records"]
            samples.update(res["samples"])
    end_load = machine_info()["load_average"]
    machine["load_average_end"] = end_load
    report = {
        "machine": machine,
        "versions": package_versions(),
        "records": records,
        "rebuild_over_fast": ratios,
        "reference": {"RMPC": references, "GIPC": gipc_ref},
        "settings": {
            "steps": cfg.steps, "cheap_steps": cfg.cheap_steps, "rebuild_steps": cfg.rebuild_steps,
            "scs_steps": cfg.scs_steps, "vertices": list(cfg.vertices), "problems": list(cfg.problems),
            "quick": cfg.quick, "spread": SPREAD, "dt": PAPER_P_SAMPLE_TIME, "Q1": np.diag(Q1).tolist(),
            "R": np.diag(R).tolist(), "u_max": U_MAX, "input_constraint": "ellipsoid (||u||_2 <= u_max)",
            "x0": RigidSatellite.initial_state().tolist(), "n_ellipsoids": cfg.n_ellipsoids,
            "lookup_repeats": cfg.lookup_repeats, "scale_steps": cfg.scale_steps,
            "scale_sizes": list(cfg.scale_sizes), "scale_scs_steps": cfg.scale_scs_steps,
            "scale_cvxpy_steps": cfg.scale_cvxpy_steps,
        },
        "wall_time_s": time.perf_counter() - start,
    }
    return {"report": _json_safe(report), "samples": samples}


def _json_safe(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {str(k): _json_safe(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_json_safe(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _json_safe(obj.tolist())
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, float | np.floating):
        return _finite(obj)
    return obj


# -- Markdown -------------------------------------------------------------------------------------
def _ms(value: float | None, digits: int = 2) -> str:
    return "n/a" if value is None else f"{1e3 * value:.{digits}f}"


def _us(value: float | None) -> str:
    return "n/a" if value is None else f"{1e6 * value:.1f}"


def _sci(value: float | None) -> str:
    return "n/a" if value is None else f"{value:.1e}"


def _statuses(counts: dict[str, int]) -> str:
    return ", ".join(f"{k} {v}" for k, v in sorted(counts.items()))


def format_markdown(report: dict[str, Any], plot_name: str | None = "timing.png") -> str:
    """``timing.md``: the tables, the machine, the package versions and how to read them."""
    m, s = report["machine"], report["settings"]
    lines = [
        "# Solver timing report", "",
        f"Paper P's satellite: Ts = {s['dt']} s, inertia spread {s['spread']}, Q1 = diag({s['Q1']}), "
        f"R = diag({s['R']}), {s['input_constraint']} with u_max = {s['u_max']}, x0 = {s['x0']}. "
        f"Wall time of the run: {report['wall_time_s']:.1f} s"
        + (" (quick run: small sizes, for tests)." if s["quick"] else "."), "",
        "Times are wall-clock per step, reported as percentiles (p50 = median, p95, max), not means. "
        "The machines are shared: compare rows of one report, interleaved state by state, rather "
        "than reports of different runs.", "",
        "## Machine", "",
        f"- platform: {m['platform']}; processor: {m['processor']}; CPUs (os.cpu_count): {m['cpu_count']}; "
        f"Python {m['python']}",
        f"- load average (1, 5, 15 min): {m['load_average_start']} at the start, "
        f"{m['load_average_end']} at the end", "",
        "| package | version |", "| --- | --- |",
        *[f"| {k} | {v} |" for k, v in report["versions"].items()], "",
    ]
    recs = report["records"]
    rmpc = [r for r in recs if r["problem"] == "RMPC"]
    if rmpc:
        lines += [
            "## RMPC (one SDP per step)", "",
            f"{s['steps']} states per vertex count: the closed loop of the default path (ipm, "
            "delta_shared) from x0 on vertex 0, every path solved at the same states, interleaved. "
            "Time = `KothareProblem.solve` (scaling, solver, certificate, F); for cvxpy-rebuild also "
            "the construction of the cvxpy problem. Error = max |gamma / gamma_ref - 1| over the states "
            "compared (in brackets: those with a gamma and an optimal reference); margin = the "
            "smallest recomputed relative LMI margin (>= -1e-7 counts as certified). F is not "
            "compared: it is not unique at the optimum.", "",
            "| vertices | backend | formulation | steps | p50 (ms) | p95 (ms) | max (ms) | solver p50 (ms) "
            "| iterations p50 | statuses | max rel err gamma | min margin |",
            "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
        ]
        for r in rmpc:
            it = "n/a" if r["iterations_p50"] is None else f"{r['iterations_p50']:g}"
            lines.append(
                f"| {r['vertices']} | {r['backend']} | {r['formulation']} | {r['steps']} | {_ms(r['p50_s'])} "
                f"| {_ms(r['p95_s'])} | {_ms(r['max_s'])} | {_ms(r['solver_p50_s'])} | {it} "
                f"| {_statuses(r['status_counts'])} | {_sci(r['max_rel_err'])} ({r['compared_steps']}) "
                f"| {_sci(r['min_margin'])} |"
            )
        lines += ["", "### Rebuilding the cvxpy problem every step vs the fast path", "",
                  "Medians over the same first states (the rebuild path is slow, so it runs on a few). "
                  "Fast path = the toolkit's interior-point method (lmi.ipm), delta_shared, data built once, "
                  "warm-started. Target: >= 20x.", "",
                  "| vertices | steps | rebuild p50 (ms) | fast p50 (ms) | rebuild / fast "
                  "| cvxpy param p50 (ms) | rebuild / cvxpy param |",
                  "| --- | --- | --- | --- | --- | --- | --- |"]
        for q in report["rebuild_over_fast"]:
            lines.append(
                f"| {q['vertices']} | {q['steps']} | {_ms(q['rebuild_p50_s'])} | {_ms(q['fast_p50_s'])} "
                f"| {q['rebuild_over_fast']:.1f}x | {_ms(q['cvxpy_param_p50_s'])} "
                f"| {q['rebuild_over_cvxpy_param']:.1f}x |"
            )
        lines += ["", "### The reference", "",
                  "cvxpy + Clarabel, three candidates solved at every state; per state the first that is "
                  "optimal (converged to its tolerances and certified) is the reference. The spread is "
                  "the largest relative disagreement of the optimal candidates at one state: errors "
                  "below it cannot be read.", "",
                  "| vertices | candidate | statuses | used as reference |", "| --- | --- | --- | --- |"]
        for ref in report["reference"]["RMPC"]:
            for cand, counts in ref["status_counts"].items():
                used = ref["used"].get(cand, 0)
                lines.append(f"| {ref['vertices']} | {cand} | {_statuses(counts)} | {used} |")
            other = {k: v for k, v in ref["used"].items() if k not in ref["status_counts"]}
            if other:
                lines.append(f"| {ref['vertices']} | (no optimal candidate) | | {_statuses(other)} |")
        lines += ["", "| vertices | spread between optimal references | states with several optimal |",
                  "| --- | --- | --- |"]
        for ref in report["reference"]["RMPC"]:
            lines.append(f"| {ref['vertices']} | {_sci(ref['spread_between_optimal_references'])} "
                         f"| {ref['states_with_several_optimal']} |")
        lines.append("")
    off = [r for r in recs if r["problem"] == "OfflineRMPC"]
    if off:
        lines += [
            "## OfflineRMPC (Wan & Kothare 2003: lookup per step)", "",
            "Lookups at the states of its own closed loop (nominal linear model), several passes. "
            "Error = |gamma_1 / gamma_ref(x0) - 1| (the outermost ellipsoid is designed at x0, where it "
            "is the online problem); u err = the lookup against a direct evaluation of the table.", "",
            "| vertices | lookup | ellipsoids | design (s) | calls | p50 (us) | p95 (us) | max (us) "
            "| statuses | max rel err gamma_1 | max rel err u |",
            "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
        ]
        for r in off:
            lines.append(
                f"| {r['vertices']} | {r['formulation']} | {r['n_ellipsoids']} | {r['design_time_s']:.2f} "
                f"| {r['steps']} | {_us(r['p50_s'])} | {_us(r['p95_s'])} | {_us(r['max_s'])} "
                f"| {_statuses(r['status_counts'])} | {_sci(r['max_rel_err'])} "
                f"| {_sci(r['max_rel_err_u_lookup'])} |"
            )
        lines.append("")
    gipc = [r for r in recs if r["problem"] == "GIPC"]
    if gipc:
        ref = report["reference"]["GIPC"] or {}
        lines += [
            "## GIPC (velocity-form MPC: one QP per step)", "",
            f"The QPs of one closed loop (nominal linear model, {s['cheap_steps']} steps, 0.5 N m step "
            f"disturbance from t = {ref.get('disturbance_start_s', float('nan')):g} s); every back-end "
            "solves the same QPs, interleaved, warm-started from its previous solve. Time = `update` + "
            "`solve`. Error = max |objective / objective_ref - 1| against cvxpy + Clarabel at 1e-10 "
            f"(reference statuses: {_statuses(ref.get('status_counts', {}))}); KKT = the largest "
            "recomputed KKT residual. The QP uses the nominal model: the vertex count does not enter.", "",
            "| backend | steps | p50 (us) | p95 (us) | max (us) | solver p50 (us) | iterations p50 "
            "| statuses | max rel err objective | max KKT residual |",
            "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
        ]
        for r in gipc:
            it = "n/a" if r["iterations_p50"] is None else f"{r['iterations_p50']:g}"
            lines.append(
                f"| {r['backend']} | {r['steps']} | {_us(r['p50_s'])} | {_us(r['p95_s'])} "
                f"| {_us(r['max_s'])} | {_us(r['solver_p50_s'])} | {it} | {_statuses(r['status_counts'])} "
                f"| {_sci(r['max_rel_err'])} | {_sci(r['max_kkt_residual'])} |"
            )
        lines.append("")
    scale = [r for r in recs if r["problem"] == "Scale"]
    if scale:
        from benchmarks.timing.scale import format_scale_markdown

        lines += format_scale_markdown(scale, "timing_scale.png" if plot_name else None)
    if plot_name:
        lines += ["## Distributions", "", f"![per-step time distributions]({plot_name})", ""]
    return "\n".join(lines)


def write_report(result: dict[str, Any], out: Path) -> list[Path]:
    """Write ``timing.json``, ``timing.md``, ``timing.png`` and ``timing_samples.npz`` into ``out``."""
    from benchmarks.timing.plots import plot_distributions

    out.mkdir(parents=True, exist_ok=True)
    report = result["report"]
    paths = [out / "timing.json", out / "timing.md", out / "timing.png", out / "timing_samples.npz"]
    paths[0].write_text(json.dumps(report, indent=2, allow_nan=False) + "\n", encoding="utf-8")
    plot_distributions(report, result["samples"], paths[2])
    paths[1].write_text(format_markdown(report, paths[2].name), encoding="utf-8")
    np.savez_compressed(paths[3], **{k: v for k, v in result["samples"].items()})
    scale = [r for r in report["records"] if r["problem"] == "Scale"]
    if scale:
        from benchmarks.timing.scale import plot_scale

        paths.append(plot_scale(scale, out / "timing_scale.png"))
    return paths


# -- the command ----------------------------------------------------------------------------------
def run_timing_command(args: argparse.Namespace) -> int:
    """``rmpc timing``: validate the options, measure, write the files; returns 0.

    Bad option values raise :class:`~toolkit_common.errors.InvalidArgumentError` naming the
    option (the CLI turns it into exit status 2).
    """
    cfg = config_from_args(args)
    if cfg.out.exists() and not cfg.out.is_dir():
        raise InvalidArgumentError("--out", "a directory (created if missing)", f"the file {str(cfg.out)!r}")
    cfg.out.mkdir(parents=True, exist_ok=True)  # fail before minutes of measuring, not after
    result = run_timing(cfg)
    write_report(result, cfg.out)
    report = result["report"]
    print(f"rmpc timing: {len(report['records'])} records in {report['wall_time_s']:.1f} s; "
          f"report in {cfg.out}/timing.md")
    for q in report["rebuild_over_fast"]:
        ratio = q["rebuild_over_fast"]
        print(f"  {q['vertices']} vertices: rebuild-per-step / fast path (p50) = {ratio:.1f}x")
    for r in report["records"]:
        if r["problem"] == "Scale" and r["backend"] == "ipm":
            print(f"  scale {r['n_states']} states, {r['vertices']} vertices: ipm p50 "
                  f"{1e3 * r['p50_s']:.1f} ms, {r['status_counts']}")
    return 0


def add_timing_parser(subparsers: Any) -> None:
    """Register ``rmpc timing`` on an ``argparse`` sub-parser collection (``func=run_timing_command``)."""
    parser = subparsers.add_parser(
        "timing",
        help="the solver timing report (timing.json, timing.md, timing.png)",
        description="Time RMPC (every LMI back-end and formulation), OfflineRMPC and GIPC (every QP "
        "back-end) per step on paper P's satellite for 2, 4 and 8 polytope vertices; write "
        "DIR/timing.json, DIR/timing.md, DIR/timing.png and DIR/timing_samples.npz. Percentiles, "
        "not means; the machine and its load are recorded. Exit status: 0 done, 2 bad input.",
    )
    parser.add_argument("--out", required=True, metavar="DIR", help="output directory")
    parser.add_argument(
        "--steps", default=None, metavar="N",
        help=f"RMPC states per vertex count (default 40; --quick: 3); OfflineRMPC and GIPC, which cost "
        f"microseconds per step, use {CHEAP_FACTOR} N",
    )
    parser.add_argument("--vertices", nargs="+", default=None, metavar="V",
                        help="polytope vertex counts among 2 4 8 (default all three)")
    parser.add_argument("--problems", nargs="+", default=None, metavar="P",
                        help="problems among RMPC OfflineRMPC GIPC Scale (default the first three; Scale: "
                        "the flexible satellite at 6-20 states, see benchmarks.timing.scale)")
    parser.add_argument("--scale-steps", default=None, metavar="N",
                        help="Scale: closed-loop states per size and vertex count (default 10; --quick: 2)")
    parser.add_argument("--scale-sizes", nargs="+", default=None, metavar="n",
                        help="Scale: state dimensions among 6 10 14 20 (default all; --quick: 6)")
    parser.add_argument("--scale-cvxpy-steps", default=None, metavar="K",
                        help="Scale: states for cvxpy + Clarabel, textbook and delta LMIs, up to 14 states "
                        "(default 2; --quick: 0; 0 leaves them out)")
    parser.add_argument("--quick", action="store_true",
                        help="a small run (3 states, 5 ellipsoids) to check the set-up; used by the tests")
    parser.add_argument("--rebuild-steps", default=None, metavar="K",
                        help="states for the rebuild-the-cvxpy-problem path (default 10; --quick: 2)")
    parser.add_argument("--scs-steps", default=None, metavar="K",
                        help="states for cvxpy + SCS (default 5; --quick: 1; 0 leaves SCS out)")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar even on a terminal")
    parser.set_defaults(func=run_timing_command)
