"""The benchmark suite "mrp": paper M's scenarios M1-M3 on the MRP satellite.

Every experiment runs paper M's three backstepping controllers (``BS``, ``MAB``, ``TFAB``) and
the robust MPC (``RMPC``, ``CRMPC``, on the error attitude, with the covering polytope of the
kinematics over the 57.8 deg initial error) on the same truth plant, from the same initial
state, with the same control period (0.05 s; the plant is integrated by RK4 at 0.01 s).

====  =====================================================================================
M1    nominal: constant target, no disturbance
M2    the spinning disk inside the bus
M3    the disk, the true inertia 1.3 J0 and 0.7 J0 (two runs per controller), 1 N m per axis
====  =====================================================================================

:func:`mrp_cases` lists the cases; :func:`run_mrp` runs them in parallel and writes
``results.json``, ``results.md``, ``results.csv``, ``run.json``, the figures
(``figures/M*.png``) and the trajectories (``traces/*.npz``).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from benchmarks.core.publish import published_paths, staged_reports
from benchmarks.core.scenario import Scenario
from benchmarks.core.suite import (
    SuiteCase,
    SuiteOutcome,
    check_time_scale,
    chosen_experiments,
    run_suite_cases,
    write_records,
    write_rows_csv,
    write_run_info,
    write_traces,
)
from benchmarks.families.mrp import defaults
from benchmarks.reports.citations import citation_line
from benchmarks.reports.measurement import records_reason, withhold
from benchmarks.reports.sections import dash, failed_cases, rows_table, run_lines, settings_section, statuses

__all__ = ["CONTROLLERS", "EXPERIMENTS", "mrp_cases", "run_mrp"]

#: Experiment -> what it shows.
EXPERIMENTS: dict[str, str] = {
    "M1": "Nominal: constant target fixed in the orbital frame, no disturbance; 57.8 deg initial error.",
    "M2": "The spinning disk inside the bus (a state-dependent disturbance torque).",
    "M3": "M2 with the true inertia 1.3 J0 and 0.7 J0 (the controllers keep J0) and a 1 N m per-axis limit.",
}

#: The controllers every experiment runs.
CONTROLLERS: tuple[str, ...] = ("BS", "MAB", "TFAB", "RMPC", "CRMPC")

#: Control period of every controller in the suite (s) and the plant's RK4 step.
CONTROL_PERIOD = 0.05
PLANT_STEP = 0.01

#: The fraction of each run length kept by ``--short``.
SHORT_TIME_SCALE = 0.05

def mrp_cases(time_scale: float = 1.0, experiments: Sequence[str] | None = None) -> list[SuiteCase]:
    """The cases of M1-M3 (run lengths multiplied by ``time_scale``).

    Examples
    --------
    >>> cases = mrp_cases()
    >>> len(cases), sorted({c.experiment for c in cases})
    (20, ['M1', 'M2', 'M3'])
    """
    check_time_scale(time_scale)
    chosen = chosen_experiments(EXPERIMENTS, experiments)
    cases = []
    for exp in chosen:
        scales = (1.3, 0.7) if exp == "M3" else (None,)
        for ctrl in CONTROLLERS:
            for scale in scales:
                data: dict[str, Any] = {
                    "family": "mrp",
                    "controller": ctrl,
                    "scenario": exp,
                    "dt": CONTROL_PERIOD,
                    "plant_step": PLANT_STEP,
                    "time_scale": time_scale,
                }
                tag = ctrl
                if scale is not None:
                    data["inertia_scale"] = scale
                    data["saturation"] = "constraint" if ctrl in ("RMPC", "CRMPC") else "limiter"
                    tag = f"{ctrl}_J{scale:g}"
                cases.append(SuiteCase(exp, Scenario.from_dict(data), tag))
    return cases


def _cost(case: SuiteCase) -> float:
    return {"RMPC": 10.0, "CRMPC": 12.0}.get(case.scenario.controller, 1.0)


def run_mrp(
    out: str | Path,
    workers: int | None = None,
    scheduler: str | None = None,
    time_scale: float = 1.0,
    experiments: Sequence[str] | None = None,
    progress: bool | None = None,
) -> SuiteOutcome:
    """Run M1-M3 and write every output file into ``out`` (created if needed).

    Parameters are those of :func:`benchmarks.suites.faults.run_faults`.
    """
    cases = mrp_cases(time_scale, experiments)
    outcome, runs = run_suite_cases(cases, out, "rmpc bench mrp", workers, scheduler, progress, _cost)
    with staged_reports(Path(out)) as stage:  # every report file, or none of them, is new
        files = _write(stage, cases, runs, outcome, workers, scheduler, time_scale)
    outcome.files = published_paths(files, stage, Path(out))
    return outcome


def case_row(rec: dict[str, Any]) -> dict[str, str]:
    """The table row of one record."""
    m = rec["metrics"]
    solve = m.get("solve_time_solves_p50")
    return {
        "controller": rec["controller"],
        "saturation": rec["saturation"],
        "plant J": f"x{rec['settings']['inertia_scale_used']:g}",
        "max / RMS error on the window (deg)": (
            f"{dash(m['err_angle_ss_max_deg'])} / {dash(m['err_angle_rms_deg'])}"
        ),
        "final error (deg)": dash(m["err_angle_final_deg"]),
        "max |u| (N m)": f"{m['max_abs_u']:.3f}",
        "max |Td est - Td| (N m)": dash(m.get("td_est_err_max"), ".2e"),
        "torque variation (N m/s) / over the disk's": (
            f"{dash(m.get('chatter_tv_rate'), '.3g')} / {dash(m.get('chatter_ratio'), '.3g')}"
        ),
        "step p50 / p95 (ms)": f"{1e3 * m['step_time_p50']:.2f} / {1e3 * m['step_time_p95']:.2f}",
        "LMI solve p50 (ms)": "-" if solve is None else f"{1e3 * solve:.1f}",
        "statuses": statuses(m["status_counts"]),
    }


def _find(records: list[dict], exp: str, ctrl: str, scale: float = 1.0) -> dict | None:
    for r in records:
        if (r["experiment"], r["controller"]) == (exp, ctrl) and r["settings"]["inertia_scale_used"] == scale:
            return r
    return None


def _smoke(records: list[dict[str, Any]]) -> str | None:
    """Why this run measures none of paper M's claims (a smoke run), read from the records; else None."""
    return records_reason(records, "a steady window after the transient")


def paper_m_comparison(records: list[dict[str, Any]]) -> list[str]:
    """Paper M's reported outcomes with this run's verdicts (:mod:`benchmarks.suites.mrp_claims`)."""
    from benchmarks.suites.mrp_claims import assess_paper_m, paper_m_claims_markdown

    lines = [
        "## Paper M's reported results and what this toolkit measures",
        "",
        "Paper M reports figures and words only; each outcome is tested on this run's records "
        "(`benchmarks/suites/mrp_claims.py` holds the thresholds).",
        "",
    ]

    def err(exp: str, ctrl: str, scale: float = 1.0) -> float | None:
        rec = _find(records, exp, ctrl, scale)
        return None if rec is None else rec["metrics"]["err_angle_ss_max_deg"]

    lines += paper_m_claims_markdown(withhold(assess_paper_m(records), _smoke(records)))
    robust = [
        f"{c} {dash(err('M2', c))} deg" for c in ("RMPC", "CRMPC") if _find(records, "M2", c) is not None
    ]
    if robust:
        lines.append(
            "- The robust MPC on the same plant (to be measured, not asserted: RMPC, state feedback, "
            "might keep a persistent error like BS, CRMPC reject the disk like MAB). M2 max error on the "
            "window: "
            + ", ".join(robust)
            + "."
        )
    lines += [
        "",
        "Inconsistencies of paper M, as `models.mrp.scenarios.PAPER_M_NOTES` states them:",
        "",
    ]
    from models.mrp.scenarios import PAPER_M_NOTES

    lines += [f"- {note}" for note in PAPER_M_NOTES]
    lines.append("")
    return lines


def _write(
    out: Path,
    cases: list[SuiteCase],
    runs: list[tuple[SuiteCase, dict, dict]],
    outcome: SuiteOutcome,
    workers: int | None,
    scheduler: str | None,
    time_scale: float,
) -> list[Path]:
    from benchmarks.reports.mrp_figures import plot_mrp_group

    files: list[Path] = write_traces(out, runs)
    groups: dict[tuple[str, float], list[tuple[dict, dict]]] = {}
    for case, rec, trace in runs:
        groups.setdefault((case.experiment, rec["settings"]["inertia_scale_used"]), []).append((rec, trace))
    figures: dict[str, list[Path]] = {}
    for (exp, scale), items in groups.items():
        name = exp if exp != "M3" else f"M3_J{scale:g}"
        path = plot_mrp_group(items, out / "figures" / f"{name}.png", f"{name}: {EXPERIMENTS[exp]}")
        figures.setdefault(exp, []).append(path)
        files.append(path)
    records = outcome.records
    write_records(out, records)
    rows = [{"experiment": r["experiment"], **case_row(r)} for r in records]
    csv_path = write_rows_csv(out / "results.csv", rows)
    if csv_path is not None:
        files.append(csv_path)
    info = write_run_info(
        out, "rmpc bench mrp", outcome, len(cases), workers, scheduler, ("time_scale", time_scale)
    )
    scale = f"time scale {time_scale:g}" + (" (a smoke run, no measurement)" if time_scale < 1 else "")
    lines = [
        "# Benchmark suite `mrp`: paper M's scenarios M1-M3",
        "",
        citation_line("M"), "",
        *run_lines(info, scale),
        "",
        f"Every controller at a {CONTROL_PERIOD:g} s period on the same truth plant "
        f"(RK4 at {PLANT_STEP:g} s, "
        'records: `plant` = "mrp"); errors are the error angle 4 atan|se| (deg) on the steady window '
        "(the run's second half).",
        "",
    ]
    for exp, text in EXPERIMENTS.items():
        recs = [r for r in records if r["experiment"] == exp]
        if not recs:
            continue
        lines += [f"## {exp}", "", text, ""]
        lines += [rows_table([case_row(r) for r in recs]), ""]
        for path in figures.get(exp, []):
            lines += [f"![{path.stem}]({path.relative_to(out).as_posix()})", ""]
    lines += paper_m_comparison(records)
    lines += failed_cases(outcome.failures)
    intro = "Every value paper M leaves out is the toolkit's choice (`benchmarks/families/mrp/defaults.py`)."
    rationale = None if _smoke(records) else defaults.rationale()
    lines += settings_section(intro, defaults.settings_rows(), rationale)
    (out / "results.md").write_text("\n".join(lines), encoding="utf-8")
    files += [out / n for n in ("results.json", "run.json", "results.md")]
    return files
