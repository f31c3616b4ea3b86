"""``rmpc timing --out DIR``: the solver timing report.

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
  and the smallest recomputed LMI margin. ``F`` is never compared: it is not unique at the optimum.
- **OfflineRMPC** (Wan & Kothare 2003): the per-step lookup, with and without interpolation, at
  the states of its own closed loop; its design time; ``gamma_1`` (the outermost ellipsoid,
  designed at ``x0``) against the online reference ``gamma(x0)``.
- **GIPC** (velocity-form MPC): the per-step QP (``update`` + ``solve``) of each QP
  back-end on the QPs of one closed loop (with experiment E4's step disturbance half-way), the
  objective against a high-accuracy reference (cvxpy + Clarabel at 1e-10) and the KKT residual.

The 4-vertex polytope is 4 of the box's 8 corners: ``Ixx = Iyy`` scaled together by ``1 +- s``
(the satellite stays axisymmetric, as paper P's is) and ``Izz`` by ``1 +- s`` independently.

Times are wall-clock per step and reported as percentiles (p50, p95, max), never means, with
the machine, its load average at the start and at the end, and the package versions. Writes
``DIR/timing.json`` (the API contract), ``DIR/timing.md``, ``DIR/timing.png`` and the raw
per-step times ``DIR/timing_samples.npz``.

The work is split by problem: :mod:`benchmarks.timing.config` (the options),
:mod:`benchmarks.timing.common` (the problem, its polytopes, record helpers), the sections in
:mod:`benchmarks.timing.rmpc`, :mod:`benchmarks.timing.offline`, :mod:`benchmarks.timing.gipc`
and :mod:`benchmarks.timing.scale`, and :mod:`benchmarks.timing.markdown` (``timing.md``); this
module runs them and writes the files.
"""

from __future__ import annotations

import argparse
import json
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.baseline import Baseline, load_baseline
from benchmarks.core.folders import not_writable
from benchmarks.core.jsonable import json_safe
from benchmarks.core.machine import machine_info, package_versions
from benchmarks.timing.common import Q1, SPREAD, U_MAX, R, polytope
from benchmarks.timing.config import CHEAP_FACTOR, PROBLEMS, VERTEX_COUNTS, TimingConfig, config_from_args
from benchmarks.timing.markdown import format_markdown
from toolkit_common.errors import InvalidArgumentError

# The solvers, models and controllers are imported where they are used, so that registering the
# sub-command (add_timing_parser) costs the ``rmpc`` command line nothing at start-up.

__all__ = [
    "PROBLEMS",
    "VERTEX_COUNTS",
    "TimingConfig",
    "add_timing_parser",
    "config_from_args",
    "format_markdown",
    "polytope",
    "run_timing",
    "run_timing_command",
    "write_report",
]


# -- the run --------------------------------------------------------------------------------------
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
    from benchmarks.timing.gipc import time_gipc
    from benchmarks.timing.offline import time_offline
    from benchmarks.timing.rmpc import time_rmpc
    from models import PAPER_P_SAMPLE_TIME, RigidSatellite

    start = time.perf_counter()
    machine = machine_info()
    machine["load_average_start"] = machine.pop("load_average")
    units = (cfg.steps * len(cfg.vertices) if "RMPC" in cfg.problems else 0) + (
        len(cfg.vertices) if "OfflineRMPC" in cfg.problems else 0) + (1 if "GIPC" in cfg.problems else 0) + (
        2 * len(cfg.scale_sizes) if "Scale" in cfg.problems else 0) + (
        len(cfg.vertices) if "Breakdown" in cfg.problems else 0) + (
        len(cfg.vertices) if "C" in cfg.problems else 0)
    records: list[dict[str, Any]] = []
    samples: dict[str, np.ndarray] = {}
    ratios, references = [], []
    gipc_ref = None
    c_runs: list[dict[str, Any]] = []
    with CaseProgress(units, "rmpc timing", enabled=cfg.progress) as bar:
        for count in cfg.vertices:
            poly = polytope(count)
            gamma_x0 = None
            rmpc_states = None
            if "RMPC" in cfg.problems:
                res = time_rmpc(poly, cfg, bar)
                records += res["records"]
                samples.update(res["samples"])
                ratios.append(res["ratio"])
                references.append(res["reference"])
                gamma_x0 = res["gamma_x0"]
                rmpc_states = res["states"]
            if "OfflineRMPC" in cfg.problems:
                res = time_offline(poly, cfg, gamma_x0)
                records += res["records"]
                samples.update(res["samples"])
                bar.advance(f"OfflineRMPC {count} vertices")
            if "C" in cfg.problems:
                from benchmarks.timing.c_exports import time_c

                res = time_c(poly, cfg, rmpc_states, bar)
                records += res["records"]
                samples.update(res["samples"])
                c_runs.append(res)
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
        breakdowns = []
        if "Breakdown" in cfg.problems:
            from benchmarks.timing.breakdown import breakdown

            for count in cfg.vertices:
                breakdowns.append(breakdown(count, cfg.steps))
                bar.advance(f"Breakdown {count} vertices")
    end_load = machine_info()["load_average"]
    machine["load_average_end"] = end_load
    report = {
        "machine": machine,
        "versions": package_versions(),
        "records": records,
        "rebuild_over_fast": ratios,
        "reference": {"RMPC": references, "GIPC": gipc_ref},
        "breakdown": breakdowns,
        "c": _c_summary(records, c_runs),
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
    return {"report": json_safe(report), "samples": samples}


def _c_summary(records: list[dict[str, Any]], runs: list[dict[str, Any]]) -> dict[str, Any] | None:
    """The C section's compiler, CVXPYgen's outcomes and the targets (``None``: not asked for)."""
    if not runs:
        return None
    from benchmarks.timing.c_exports import judge_targets

    attempts = {r["cvxpygen"]["vertices"]: r["cvxpygen"] for r in runs if r["cvxpygen"] is not None}
    return {"compiler": runs[0]["compiler"], "note": runs[0]["note"], "cvxpygen": list(attempts.values()),
            "targets": judge_targets(records, attempts) if runs[0]["compiler"] else []}


# -- the files ------------------------------------------------------------------------------------
def write_report(result: dict[str, Any], out: Path, baseline: Baseline | None = None) -> list[Path]:
    """Write ``timing.json``, ``timing.md``, ``timing.png`` and ``timing_samples.npz`` into ``out``.

    With ``baseline`` (an earlier report, :func:`benchmarks.baseline.load_baseline`) the report
    gains ``baseline`` (:func:`benchmarks.timing.versus.timing_comparison`) and ``timing.md``
    its section.
    """
    from benchmarks.timing.plots import plot_distributions

    out.mkdir(parents=True, exist_ok=True)
    report = result["report"]
    if baseline is not None:
        from benchmarks.timing.versus import timing_comparison

        report["baseline"] = timing_comparison(report, baseline)
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
    problem = not_writable(cfg.out)  # fail before minutes of measuring, not after
    if problem is not None:
        raise InvalidArgumentError("--out", "a folder that can be written", f"{str(cfg.out)!r} ({problem})")
    baseline = None if cfg.baseline is None else load_baseline(cfg.baseline, "timing")
    cfg.out.mkdir(parents=True, exist_ok=True)
    result = run_timing(cfg)
    write_report(result, cfg.out, baseline)
    report = result["report"]
    print(f"rmpc timing: {len(report['records'])} records in {report['wall_time_s']:.1f} s; "
          f"report in {cfg.out}/timing.md")
    if report["c"] is not None and report["c"]["note"]:
        print(f"  C section: {report['c']['note']}")
    if report.get("baseline") is not None:
        cmp = report["baseline"]
        mean = cmp["p50_ratio_geomean"]
        print(f"  against {cmp['baseline']}: {cmp['counts']['both']} cases in both"
              + ("" if mean is None else f", p50 new/old geometric mean {mean:.3f}")
              + ("" if cmp["same_machine"] else " (measured on another machine, or unknown)"))
    for q in report["rebuild_over_fast"]:
        ratio = q["rebuild_over_fast"]
        print(f"  {q['vertices']} vertices: rebuild-per-step / fast path (p50) = {ratio:.1f}x")
    for r in report["records"]:
        if r["problem"] == "C" and r["backend"] == "c-export" and r["formulation"] == "delta_shared":
            print(f"  C export, {r['vertices']} vertices: p50 {1e3 * r['cpu_p50_s']:.2f} ms thread CPU "
                  f"({1e3 * r['p50_s']:.2f} ms wall), {r['status_counts']}")
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
                        help="problems among RMPC OfflineRMPC GIPC Scale Breakdown C (default the first "
                        "three; Scale: the flexible satellite at 6-20 states, see benchmarks.timing.scale; "
                        "Breakdown: the ipm's time per kernel and iteration on paper P and the floor of its "
                        "arithmetic, see benchmarks.timing.breakdown; C: the exported C controllers (on-line "
                        "RMPC, off-line lookup) against the Python ipm, Clarabel and CVXPYgen, their object "
                        "code and static memory, each target met or not, see benchmarks.timing.c_exports)")
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
    parser.add_argument("--baseline", default=None, metavar="OLD_DIR",
                        help="an earlier report's output directory: timing.md and timing.json put its "
                        "per-case times (p50, p95, solver p50, iterations) next to this run's, with "
                        "new/old, and flag a baseline measured on another machine")
    parser.set_defaults(func=run_timing_command)
