"""The benchmark suite "flexible": paper V's study on the flexible satellite (F1-F4, F6) and paper
S's baselines (F5).

Every run uses the published 4-mode plant with the PZT channel (:class:`models.FlexibleSatellite`,
the published 4-mode set), the 2 N m per-axis hub-torque limit and the hub disturbance the toolkit
assumes for paper V (its values were lost); the
plant is integrated by DOP853 between samples.

====  =====================================================================================
F1    the V-slew (160 deg): {MTSMC, CSMC (tanh)} x {AVC off, on}, paper V's 2x2 study
F2    the boundary layer: MTSMC and CSMC (tanh) at each eps of F2_EPSILONS, CSMC (sign)
F3    steady error at the target under 0.05 N m per axis: MTSMC with k_I in F3_INTEGRAL_GAINS,
      CSMC
F4    a 10 deg slew where the linear model holds: OfflineRMPC and RMPC on the 14-state model
      over the 8-vertex polytope (inertia, modal frequencies, damping) against MTSMC and the
      LQR reference, RMPC with a bound on the modal coordinates; the V-slew by MTSMC handing
      over to OfflineRMPC inside 20 deg
F5    paper S's baselines on the V-slew (:mod:`benchmarks.suites.flexible_f5`): PD, PD-DOB,
      ASMC, nonlinear PD, adaptive-gain PD, ZVD-shaped PD
F6    the regime label: MTSMC on the V-slew at a high gain (alpha_f = F6_ALPHA_F), whose bandwidth
      is past Lambda_1/2, against F1's MTSMC (rigid-like)
====  =====================================================================================

:func:`flexible_cases` lists the cases; :func:`run_flexible` runs them in parallel and writes
``results.json``, ``results.md``, ``results.csv``, ``run.json``, the figures (``figures/F*.png``)
and the trajectories (``traces/*.npz``). The words of ``results.md`` are
:mod:`benchmarks.suites.flexible_report`'s (its public names are importable from here too).
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
from benchmarks.families.flexible import defaults
from benchmarks.suites.flexible_f5 import F5_BASELINES
from benchmarks.suites.flexible_report import (
    REACH_GAMMAS,
    case_row,
    inconsistencies,
    paper_v_comparison,
    results_markdown,
)

__all__ = [
    "EXPERIMENTS",
    "F4_MODAL_BOUND",
    "F6_ALPHA_F",
    "HANDOVER_DEG",
    "MODAL_BOUND_POLYTOPE",
    "REACH_GAMMAS",
    "SHORT_TIME_SCALE",
    "case_row",
    "flexible_cases",
    "inconsistencies",
    "paper_v_comparison",
    "run_flexible",
]

#: Experiment -> what it shows.
EXPERIMENTS: dict[str, str] = {
    "F1": "Paper V's 2x2 study on the 160 deg V-slew: {MTSMC, CSMC (tanh)} x {AVC off, on}, equal gains.",
    "F2": "The boundary layer eps of the tanh switching term: MTSMC and CSMC (tanh) per eps, CSMC (sign).",
    "F3": "Steady error at the target under a constant 0.05 N m per axis: MTSMC with and "
    "without the integral term, CSMC.",
    "F4": "A 10 deg slew where the linear model holds: OfflineRMPC and RMPC on the 14-state model "
    "over the 8-vertex polytope (0.5 s period, per-axis peak bound) against MTSMC and the LQR "
    "reference; RMPC with |eta_i| <= 0.02 on the 8-vertex polytope, and with and without it on the "
    "2-vertex polytope; and the 160 deg "
    "V-slew by MTSMC handing over to OfflineRMPC (0.01 s) inside 20 deg.",
    "F5": "Paper S's baselines head to head on F1's V-slew with F1's metrics: PD, PD with the disturbance "
    "observer, adaptive SMC, nonlinear (saturated) PD, adaptive-gain PD and PD behind a ZVD shaper on "
    "mode 1.",
    "F6": "Paper S's regime label: MTSMC on the V-slew with alpha_f = 0.8 1/s (bandwidth 0.4 rad/s, past "
    "Lambda_1/2), against F1's MTSMC (0.05 rad/s, rigid-like).",
}

#: The fraction of each run length kept by ``--short``.
SHORT_TIME_SCALE = 0.02

#: F4's bound on every modal coordinate (kg^1/2 m) for the RMPC case with the output constraint
#: (without it, RMPC's peak ``|eta_1|`` on the 10 deg slew is about 0.066 on this polytope).
F4_MODAL_BOUND = 0.02
#: The polytope of F4's second modal-bound pair (RMPC with and without the bound), next to the
#: pair on the default 8-vertex 'groups' polytope (F4's RMPC case and its bounded twin): the
#: 2-vertex torque-effectiveness polytope, whose re-solves cost a tenth as much.
MODAL_BOUND_POLYTOPE = "effectiveness"
#: F4's hand-over on the V-slew: MTSMC until the rotation error is below this angle (deg), then
#: OfflineRMPC (assumed: inside about 20 deg, where the linear model is taken to hold).
HANDOVER_DEG = 20.0
#: F6's MTSMC surface gain (1/s): bandwidth alpha_f/2 = 0.4 rad/s, past Lambda_1/2 = 0.384 rad/s
#: (paper S's hardest regime); on the V-slew it saturates about a quarter of the samples.
F6_ALPHA_F = 0.8

def _case(exp: str, tag: str, data: dict[str, Any]) -> SuiteCase:
    return SuiteCase(exp, Scenario.from_dict({"family": "flexible", **data}), tag)


def flexible_cases(time_scale: float = 1.0, experiments: Sequence[str] | None = None) -> list[SuiteCase]:
    """The cases of F1-F6 (run lengths multiplied by ``time_scale``).

    Examples
    --------
    >>> cases = flexible_cases()
    >>> len(cases), sorted({c.experiment for c in cases})
    (33, ['F1', 'F2', 'F3', 'F4', 'F5', 'F6'])
    """
    from models.flexible.scenario import F2_EPSILONS, F3_INTEGRAL_GAINS

    check_time_scale(time_scale)
    chosen = chosen_experiments(EXPERIMENTS, experiments)
    cases: list[SuiteCase] = []
    base = {"time_scale": time_scale}
    for exp in chosen:
        if exp == "F6":
            data = {**base, "controller": "MTSMC", "settings": {"alpha_f": F6_ALPHA_F}}
            cases.append(_case(exp, f"MTSMC_alpha{F6_ALPHA_F:g}", data))
            continue
        if exp == "F1":
            for ctrl in ("MTSMC", "CSMC"):
                for avc in (False, True):
                    tag = ctrl + ("_AVC" if avc else "")
                    cases.append(_case(exp, tag, {**base, "controller": ctrl, "avc": avc}))
        elif exp == "F2":
            for eps in F2_EPSILONS:
                for ctrl in ("MTSMC", "CSMC"):
                    cases.append(
                        _case(exp, f"{ctrl}_eps{eps:g}", {**base, "controller": ctrl, "epsilon": eps})
                    )
            cases.append(_case(exp, "CSMC_sign", {**base, "controller": "CSMC", "switch": "sign"}))
        elif exp == "F3":
            for k_i in F3_INTEGRAL_GAINS:
                data = {**base, "controller": "MTSMC", "experiment": "steady", "integral_gain": k_i}
                cases.append(_case(exp, f"MTSMC_kI{k_i:g}", data))
            cases.append(_case(exp, "CSMC", {**base, "controller": "CSMC", "experiment": "steady"}))
        elif exp == "F5":
            for tag, data in F5_BASELINES:
                cases.append(_case(exp, tag, {**base, **data}))
        else:
            for ctrl in ("MTSMC", "LQR", "OfflineRMPC", "RMPC"):
                cases.append(_case(exp, ctrl, {**base, "controller": ctrl, "experiment": "small"}))
            data = {**base, "controller": "RMPC", "experiment": "small", "modal_bound": F4_MODAL_BOUND}
            cases.append(_case(exp, "RMPC_modal_bound", data))
            for bound in (None, F4_MODAL_BOUND):
                data = {**base, "controller": "RMPC", "experiment": "small", "modal_bound": bound}
                data["settings"] = {"polytope": MODAL_BOUND_POLYTOPE}
                tag = "RMPC_effectiveness" + ("" if bound is None else "_modal_bound")
                cases.append(_case(exp, tag, data))
            data = {
                **base,
                "controller": "OfflineRMPC",
                "dt": defaults.SMC_PERIOD,
                "handover_deg": HANDOVER_DEG,
            }
            cases.append(_case(exp, "MTSMC_OfflineRMPC_vslew", data))
    return cases


def _cost(case: SuiteCase) -> float:
    sc = case.scenario
    if sc.controller == "RMPC":
        if sc.settings["polytope"] != "groups":
            return 10.0
        return 100.0 if sc.modal_bound is None else 150.0
    if sc.controller == "OfflineRMPC":
        return 100.0 if sc.handover_deg is None else 150.0
    return {"vslew": 15.0, "steady": 25.0, "small": 10.0}[sc.experiment] * (1.5 if sc.avc else 1.0)


def run_flexible(
    out: str | Path,
    workers: int | None = None,
    scheduler: str | None = None,
    time_scale: float = 1.0,
    experiments: Sequence[str] | None = None,
    progress: bool | None = None,
) -> SuiteOutcome:
    """Run F1-F5 and write every output file into ``out`` (created if needed).

    Parameters are those of :func:`benchmarks.suites.faults.run_faults`.
    """
    cases = flexible_cases(time_scale, experiments)
    outcome, runs = run_suite_cases(cases, out, "rmpc bench flexible", workers, scheduler, progress, _cost)
    with staged_reports(Path(out)) as stage:  # every report file, or none of them, is new
        files = _write(stage, cases, runs, outcome, workers, scheduler, time_scale)
    outcome.files = published_paths(files, stage, Path(out))
    return outcome


def _write(
    out: Path,
    cases: list[SuiteCase],
    runs: list[tuple[SuiteCase, dict, dict]],
    outcome: SuiteOutcome,
    workers: int | None,
    scheduler: str | None,
    time_scale: float,
) -> list[Path]:
    from benchmarks.reports.flexible_figures import plot_flexible_group

    files: list[Path] = write_traces(out, runs)
    groups: dict[str, list[tuple[str, dict, dict]]] = {}
    for case, rec, trace in runs:
        groups.setdefault(case.experiment, []).append((case.tag, rec, trace))
    figures: dict[str, Path] = {}
    for exp in EXPERIMENTS:
        if exp in groups:
            items = sorted(groups[exp], key=lambda item: item[0])
            path = plot_flexible_group(items, out / "figures" / f"{exp}.png", f"{exp}: {EXPERIMENTS[exp]}")
            figures[exp] = path
            files.append(path)
    records = sorted(outcome.records, key=lambda r: (r["experiment"], r["label"]))
    write_records(out, records)
    rows = [{"experiment": r["experiment"], **case_row(r)} for r in records]
    csv_path = write_rows_csv(out / "results.csv", rows)
    if csv_path is not None:
        files.append(csv_path)
    info = write_run_info(
        out, "rmpc bench flexible", outcome, len(cases), workers, scheduler, ("time_scale", time_scale)
    )
    text = results_markdown(
        records, info, EXPERIMENTS, figures, out, outcome.failures, ("groups", MODAL_BOUND_POLYTOPE)
    )
    (out / "results.md").write_text(text, encoding="utf-8")
    files += [out / n for n in ("results.json", "run.json", "results.md")]
    return files
