"""The benchmark suite "paper": experiments E1-E6 of paper P.

All experiments regulate paper P's satellite to zero attitude from its initial attitude.

====  =====================================================================  ================
E1    no input constraint, linear model: RMPC vs GIPC                        linear
E2    saturation by a limiter vs the controller's constraint                 linear
E3    E2 on the nonlinear satellite (figure: overlaid on E2)                 nonlinear
E4    0.5 N m step disturbance from t = 10 s: RMPC, GIPC, CRMPC              nonlinear
E5    E4 with +-70 % inertia uncertainty (true inertia 1.7 x nominal)        nonlinear
E6    initial attitude x 1.3: RMPC and GIPC                                  linear, nonlinear
====  =====================================================================  ================

:func:`paper_cases` lists the cases (settings from :mod:`benchmarks.families.rigid.defaults`);
:func:`run_paper` runs them in parallel and writes ``results.json``, ``results.md``,
``results.csv``, ``results.tex``, ``results_table.json``, ``run.json``, the figures
(``figures/*.png``) and the trajectories (``traces/*.npz``).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.core.publish import published_paths, staged_reports
from benchmarks.core.scenario import Scenario
from benchmarks.core.suite import (
    SuiteCase,
    SuiteOutcome,
    chosen_experiments,
    run_suite_cases,
    write_records,
    write_run_info,
    write_traces,
)
from benchmarks.families.rigid import defaults
from benchmarks.reports.citations import citation_line
from benchmarks.reports.measurement import run_durations, smoke_reason
from benchmarks.reports.sections import failed_cases, run_lines, settings_section
from benchmarks.reports.tables import (
    SUMMARY_COLUMNS,
    drop_empty_columns,
    metric_table,
    select_columns,
    to_markdown,
    write_tables,
)
from models import PAPER_P_INERTIA
from toolkit_common.errors import ConfigError

__all__ = ["EXPERIMENTS", "PaperCase", "PaperOutcome", "experiment_text", "paper_cases", "run_paper"]

#: Experiment name -> what it shows.
EXPERIMENTS: dict[str, str] = {
    "E1": "No input constraint, linear model: RMPC vs GIPC step responses and torques.",
    "E2": "Saturation handled two ways on the linear model: a limiter clipping the controller output to "
    "+-u_max, versus the constraint inside the controller (RMPC ||u||_2 <= u_max; GIPC |u| <= u_max, "
    "|du| <= du_max). Paper P's metric: sum_k |e(k)| per axis.",
    "E3": "E2 on the nonlinear satellite; the figure overlays the linear responses of E2 (dashed).",
    "E4": "Input disturbance: a step torque on the nonlinear satellite: RMPC, GIPC, CRMPC.",
    "E5": "Inertia uncertainty raised to +-70 % (true inertia at the heavy corner) with the E4 disturbance.",
    "E6": "Initial attitude raised by 30 %: linear vs nonlinear satellite, RMPC and GIPC.",
}


#: One run of the suite: the experiment it belongs to and its scenario.
PaperCase = SuiteCase
#: What :func:`run_paper` did: records, failures, files, wall time, interruption.
PaperOutcome = SuiteOutcome


def _values(records: Sequence[dict], key: str) -> list[Any]:
    """The distinct values of ``settings[key]`` in ``records``, in order of appearance."""
    out: list[Any] = []
    for rec in records:
        value = rec.get("settings", {}).get(key)
        if value is not None and value not in out:
            out.append(value)
    return out


def _seconds(values: Sequence[Any]) -> str:
    return " / ".join(f"{float(v):g}" for v in values) + " s"


def experiment_text(exp: str, records: Sequence[dict]) -> str:
    """What ``exp`` shows (:data:`EXPERIMENTS`), then the run length and, for a disturbed experiment,
    the step's size, axes and start, all read from ``records`` (the experiment's records)."""
    text = EXPERIMENTS[exp]
    durations = _values(records, "duration")
    if durations:
        text += f" Runs of {_seconds(durations)}."
    disturbed = [r for r in records if r.get("settings", {}).get("disturbance")]
    if disturbed:
        sizes = " / ".join(f"{float(v):g}" for v in _values(disturbed, "disturbance"))
        axes = " / ".join(", ".join(a) for a in _values(disturbed, "disturbance_axes"))
        start = _values(disturbed, "disturbance_start")
        text += f" The step: {sizes} N m" + (f" on {axes}" if axes else "")
        text += (f" from t = {_seconds(start)}" if start else "") + "."
    return text


def paper_cases(duration_scale: float = 1.0, experiments: Sequence[str] | None = None) -> list[PaperCase]:
    """The cases of E1-E6, durations (and the disturbance time) multiplied by ``duration_scale``.

    Examples
    --------
    >>> cases = paper_cases()
    >>> len(cases), sorted({c.experiment for c in cases})
    (21, ['E1', 'E2', 'E3', 'E4', 'E5', 'E6'])
    """
    if not duration_scale > 0:
        raise ConfigError("--duration-scale", "a number > 0", repr(duration_scale))
    chosen = chosen_experiments(EXPERIMENTS, experiments)
    base = {
        "duration": defaults.DURATION * duration_scale,
        "disturbance_start": defaults.DISTURBANCE_START * duration_scale,
    }
    disturbed = {
        **base,
        "plant": "nonlinear",
        "saturation": "constraint",
        "disturbance": defaults.DISTURBANCE_MAGNITUDE,
        "disturbance_axes": list(defaults.DISTURBANCE_AXES),
    }
    heavy = [defaults.E5_TRUE_INERTIA_FACTOR * j for j in PAPER_P_INERTIA]
    spec: list[tuple[str, dict[str, Any]]] = []
    for ctrl in ("RMPC", "GIPC"):
        spec.append(("E1", {**base, "controller": ctrl, "plant": "linear", "saturation": "none"}))
    for exp, plant in (("E2", "linear"), ("E3", "nonlinear")):
        for sat in ("limiter", "constraint"):
            for ctrl in ("RMPC", "GIPC"):
                spec.append((exp, {**base, "controller": ctrl, "plant": plant, "saturation": sat}))
    for ctrl in ("RMPC", "GIPC", "CRMPC"):
        spec.append(("E4", {**disturbed, "controller": ctrl}))
    e5 = {**disturbed, "spread": defaults.E5_SPREAD, "true_inertia": heavy}
    for ctrl in ("RMPC", "GIPC", "CRMPC"):
        spec.append(("E5", {**e5, "controller": ctrl}))
    # Paper P's "GIPC's torques saturate" needs GIPC without its own constraint, behind the limiter.
    spec.append(("E5", {**e5, "controller": "GIPC", "saturation": "limiter"}))
    for plant in ("linear", "nonlinear"):
        for ctrl in ("RMPC", "GIPC"):
            spec.append(
                (
                    "E6",
                    {
                        **base,
                        "controller": ctrl,
                        "plant": plant,
                        "saturation": "constraint",
                        "ic_scale": defaults.E6_IC_SCALE,
                    },
                )
            )
    return [PaperCase(exp, Scenario.from_dict(d)) for exp, d in spec if exp in chosen]


def _cost(case: PaperCase) -> float:
    """A rough relative cost, to start the long cases first (the LMI solves dominate)."""
    sc = case.scenario
    weight = {"RMPC": 3.0, "CRMPC": 3.0, "OfflineRMPC": 1.0}.get(sc.controller, 0.5)
    if sc.disturbance and sc.controller == "RMPC":
        weight *= 4.0
    return weight * sc.duration


def run_paper(
    out: str | Path,
    workers: int | None = None,
    scheduler: str | None = None,
    duration_scale: float = 1.0,
    experiments: Sequence[str] | None = None,
    progress: bool | None = None,
) -> PaperOutcome:
    """Run E1-E6 and write every output file into ``out`` (created if needed).

    Parameters
    ----------
    out : str or Path
        Output directory.
    workers : int, optional
        Worker processes (default: one per CPU; 0 runs in-process).
    scheduler : str, optional
        A Dask scheduler address instead of local workers.
    duration_scale : float
        Factor on every duration and on the disturbance time (``--short`` uses 0.075).
    experiments : sequence of str, optional
        A subset of ``E1`` .. ``E6``.
    progress : bool, optional
        Force the progress bar on or off (default: on when stderr is a terminal).
    """
    cases = paper_cases(duration_scale, experiments)
    outcome, runs = run_suite_cases(cases, out, "rmpc bench paper", workers, scheduler, progress, _cost)
    out = Path(out)
    with staged_reports(out) as stage:  # every report file, or none of them, is new
        files = _write(stage, cases, runs, outcome, workers, scheduler, duration_scale)
    outcome.files = published_paths(files, stage, out)
    return outcome


def _write(
    out: Path,
    cases: list[PaperCase],
    runs: list[tuple[PaperCase, dict, dict]],
    outcome: PaperOutcome,
    workers: int | None,
    scheduler: str | None,
    duration_scale: float,
) -> list[Path]:
    from benchmarks.reports.figures import plot_gamma, plot_responses

    files: list[Path] = write_traces(out, runs)
    groups: dict[str, list[tuple[dict, dict]]] = {}
    for case, rec, trace in runs:
        groups.setdefault(case.experiment, []).append((rec, trace))
    figures: dict[str, list[Path]] = {}
    for exp, items in groups.items():
        recs = [rec for rec, _ in items]
        title = f"{exp}: {experiment_text(exp, recs)}"
        path = plot_responses(items, out / "figures" / f"{exp}.png", title, _u_max(recs))
        figures.setdefault(exp, []).append(path)
    if "E2" in groups and "E3" in groups:
        path = plot_responses(
            groups["E2"] + groups["E3"],
            out / "figures" / "E3_linear_vs_nonlinear.png",
            "E2 (linear, dashed) vs E3 (nonlinear, solid)",
            _u_max([rec for rec, _ in groups["E2"]]),
        )
        figures.setdefault("E3", []).append(path)
    gamma = plot_gamma(groups, out / "figures" / "gamma.png")
    files += [p for ps in figures.values() for p in ps] + ([gamma] if gamma else [])

    records = outcome.records
    write_records(out, records)
    header, rows = metric_table(records)
    files += write_tables(out, header, rows, "Benchmark suite paper: E1-E6")
    run_info = write_run_info(
        out, "rmpc bench paper", outcome, len(cases), workers, scheduler, ("duration_scale", duration_scale)
    )
    md = _markdown(records, outcome, figures, gamma, run_info, out, duration_scale)
    (out / "results.md").write_text(md, encoding="utf-8")
    files += [out / n for n in ("results.json", "run.json", "results.md")]
    return files


def _u_max(records: Sequence[dict]) -> float:
    """The torque limit the records ran with (the defaults' when they do not say)."""
    values = _values(records, "u_max")
    return float(values[0]) if values else defaults.U_MAX


def _tables(recs: Sequence[dict]) -> list[str]:
    """A compact summary table, then the full table without its empty columns (and why they are)."""
    header, rows = metric_table(recs, lead=("controller", "plant", "saturation"))
    lead = ["controller", "plant", "saturation"]
    short_h, short_rows = select_columns(header, rows, [*lead, *SUMMARY_COLUMNS])
    full_h, full_rows, dropped = drop_empty_columns(header, rows)
    lines = [to_markdown(short_h, short_rows), "", "All metrics:", "", to_markdown(full_h, full_rows), ""]
    if dropped:
        why = {"max settling (s)": "no run settled within its run length"}
        listed = "; ".join(f"{d} ({why.get(d, 'not measured in any run')})" for d in dropped)
        lines += [f"Columns left out, empty in every run: {listed}.", ""]
    return lines


def _settings_rows(records: Sequence[dict]) -> list[tuple[str, str, str]]:
    """The defaults' settings rows, with the run length and the disturbance start of this run's
    records in place of the full runs' values."""
    rows = []
    durations = _values(records, "duration")
    disturbed = [r for r in records if r.get("settings", {}).get("disturbance")]
    starts = _values(disturbed, "disturbance_start")
    sizes = _values(disturbed, "disturbance")
    for name, value, source in defaults.settings_rows():
        if name == "duration per run (s)" and durations:
            value = " / ".join(f"{float(d):g}" for d in durations)
        elif name == "disturbance (E4, E5)" and starts and sizes:
            value = " / ".join(f"{float(m):g}" for m in sizes) + f" N m step from t = {_seconds(starts)}"
        rows.append((name, value, source))
    return rows


def inconsistencies(inertia: np.ndarray) -> list[str]:
    """Paper P's values that no physical satellite has, checked on ``inertia`` (the suite's).

    The principal moments of inertia of a rigid body obey the triangle inequality, each at most
    the sum of the other two (equality for a flat plate). Paper P's decoded values break it; the
    suite runs them as printed and says so here.
    """
    moments = np.sort(np.linalg.eigvalsh(np.asarray(inertia, dtype=float)))
    excess = moments[2] - (moments[0] + moments[1])
    lines = ["## Inconsistencies in paper P (reported, not hidden)", ""]
    if excess > 0:
        listed = ", ".join(f"{j:.4f}" for j in moments)
        share = excess / (moments[0] + moments[1])
        lines.append(
            f"- The principal inertias {listed} kg m^2 break the triangle inequality of a rigid body: "
            f"the largest exceeds the sum of the other two by {excess:.4f} kg m^2 ({share:.0%}), so no "
            "rigid satellite has them. The suite runs them as decoded; the attitude dynamics "
            "J w' = -w x (J w) + u + d hold for any positive definite J, so the control results "
            "stand as results about this model."
        )
    else:
        lines.append("- None found in the values this suite uses.")
    return [*lines, ""]


def _markdown(
    records: list[dict],
    outcome: PaperOutcome,
    figures: dict[str, list[Path]],
    gamma: Path | None,
    info: dict[str, Any],
    out: Path,
    duration_scale: float = 1.0,
) -> str:
    from benchmarks.families.rigid.defaults import rationale
    from benchmarks.reports.measurement import withhold
    from benchmarks.suites.paper_claims import assess_claims, claims_markdown

    reason = smoke_reason(
        duration_scale, run_durations(records), "settling, rejection of the disturbance or steady behaviour"
    )
    lines = ["# Benchmark suite `paper`: experiments E1-E6 of paper P", "", citation_line("P"), ""]
    lines += [
        *run_lines(
            info,
            f"duration scale {info['duration_scale']:g}"
            + (" (a smoke run: run lengths shortened, no measurement)" if reason else ""),
            versions_in_run_json=True,
        ),
        "",
        "Errors are the attitude angles (rad); `sum|e|` is paper P's `sum_k |e(k)|` over all samples; "
        "settling and overshoot are the worst axis (`-`: not settled within the run); `per-solve` times are "
        "the optimiser time of the steps that solved (paper P's algorithm: RMPC and CRMPC re-solve at every "
        "sample, `resolve_threshold = 1`), `step p95` the wall time of a controller "
        "step over all steps; results.json also has the per-step `solve_time_p50/p95/max` over all steps.",
        "",
    ]
    for exp, text in EXPERIMENTS.items():
        recs = [r for r in records if r["experiment"] == exp]
        if not recs and exp not in figures:
            continue
        lines += [f"## {exp}", "", experiment_text(exp, recs) if recs else text, ""]
        if recs:
            lines += _tables(recs)
        for path in figures.get(exp, []):
            lines += [f"![{path.stem}]({path.relative_to(out).as_posix()})", ""]
    lines += claims_markdown(withhold(assess_claims(records), reason))
    if gamma is not None:
        lines += [
            "## gamma(k)",
            "",
            "The robust MPC's cost bound at the steps that solved (log axis).",
            "",
            f"![gamma]({gamma.relative_to(out).as_posix()})",
            "",
        ]
    lines += inconsistencies(np.diag(PAPER_P_INERTIA))
    lines += failed_cases(outcome.failures)
    intro = (
        "Every value paper P leaves out is the toolkit's choice "
        "(`benchmarks/families/rigid/defaults.py`; each is a scenario field or controller setting)."
    )
    lines += settings_section(intro, _settings_rows(records), None if reason else rationale())
    return "\n".join(lines)
