"""The benchmark suite "faults": paper W's scenarios S1-S4 as experiments W1-W4, and three studies.

W1-W4 run paper W's adaptive backstepping compensator (``ABFTC``) and the robust MPC family
(``RMPC``, ``CRMPC``, ``GIPC``, on the wheel-effectiveness polytope) on the nonlinear
four-wheel satellite with the scenario's faults; W4 runs twice per controller, with the plant's
inertia at 1.2 J and at 0.8 J (the controllers keep J). W5-W7 run on S1 (whose recovery time is
paper W's one number).

====  ========================================================================================
W1    S1: wheel 2 stuck at 0.05 N m for 8 < t < 37 s, from [40, -21, -80] deg, 60 s
W2    S2: wheel 1 sinusoidal 30-80 s, wheel 4 stuck 90-120 s, from [23, 24, 73] deg, 150 s
W3    S3: wheel 4 out throughout, wheel 1 sinusoidal 30-80 s, wheel 2 stuck 90-120 s, 150 s
W4    S4: wheel 4 out, wheel 1 stuck 30-60 s, wheel 2 sinusoidal 70-100 s, wheel noise, J x1.2 / x0.8
W5    S1, ABFTC: adaptation gain Gamma x wheel limits on/off x freeze off/on (sweep ``faults_gamma``)
W6    S1, ABFTC: wheel friction and angle noise, apart and together (paper W's hardware, approximate)
W7    S1: the plant's wheel axes tilted 5 deg (an error in D), the controllers on the nominal D
====  ========================================================================================

:func:`fault_cases` lists the cases (settings from :mod:`benchmarks.families.wheel.defaults`);
:func:`run_faults` runs them in parallel and writes ``results.json``, ``results.md``,
``results.csv``, ``run.json``, the figures (``figures/W*.png``) and the trajectories
(``traces/*.npz``).
"""

from __future__ import annotations

import math
import re
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
from benchmarks.families.wheel import defaults
from benchmarks.reports.citations import citation_line
from benchmarks.reports.measurement import records_reason, run_durations, withhold
from benchmarks.reports.sections import failed_cases, rows_table, run_lines, settings_section, statuses

__all__ = ["CONTROLLERS", "EXPERIMENTS", "fault_cases", "run_faults"]

#: Experiment -> (paper W's scenario, what it shows).
EXPERIMENTS: dict[str, tuple[str, str]] = {
    "W1": ("S1", "Wheel 2 stuck at 0.05 N m for 8 < t < 37 s, before the attitude has converged."),
    "W2": ("S2", "Wheel 1 sinusoidal (0.03 sin 0.2t) 30-80 s, then wheel 4 stuck at 0.03 N m 90-120 s."),
    "W3": (
        "S3",
        "Wheel 4 out throughout; wheel 1 sinusoidal 30-80 s and wheel 2 stuck 90-120 s: two wheels "
        "lost at once, outside paper W's condition (17).",
    ),
    "W4": (
        "S4",
        "Wheel 4 out; wheel 1 stuck 30-60 s, wheel 2 sinusoidal 70-100 s; wheel-level noise; the "
        "plant's inertia 1.2 J and 0.8 J while the controllers keep J.",
    ),
    "W5": (
        "S1",
        "The adaptation-gain study: ABFTC with Gamma_0 = Gamma_j = Gamma I3 (paper W's value is lost "
        "with its appendix; 0.1 I3 elsewhere in this suite is assumed), with the wheels' torque and "
        "momentum limits in the plant and without them, with the freeze option (the estimates held "
        "while a command or a momentum is at its wheel's limit) off and on.",
    ),
    "W6": (
        "S1",
        "Paper W's hardware effects, approximated: ABFTC with wheel bearing friction, with 0.2 deg "
        "angle noise, and with both (the friction values are assumed).",
    ),
    "W7": (
        "S1",
        "An error in the distribution matrix D: every wheel axis of the plant tilted by 5 deg in a "
        "seeded direction; every controller keeps the nominal D.",
    ),
}

#: The controllers every experiment runs.
CONTROLLERS: tuple[str, ...] = ("ABFTC", "RMPC", "CRMPC", "GIPC")

#: The fraction of each duration (and fault window) kept by ``--short``.
SHORT_TIME_SCALE = 0.1


def _w5_cases(time_scale: float) -> list[SuiteCase]:
    short = time_scale < 1.0
    gammas = defaults.W5_GAMMAS_SHORT if short else defaults.W5_GAMMAS
    cases = []
    for freeze in (False,) if short else (False, True):
        for limits in (True, False):
            for gamma in gammas:
                data: dict[str, Any] = {
                    "family": "wheel",
                    "controller": "ABFTC",
                    "scenario": "S1",
                    "time_scale": time_scale,
                    "wheel_limits": limits,
                    "settings": {"gamma_g": gamma, "gamma_theta": gamma, "freeze": freeze},
                }
                tag = f"G{gamma:g}_{'limits' if limits else 'nolimits'}" + ("_freeze" if freeze else "")
                cases.append(SuiteCase("W5", Scenario.from_dict(data), tag))
    return cases


#: W6's variants: tag -> the plant fields it changes.
_FRICTION = {"viscous_friction": defaults.VISCOUS_FRICTION, "coulomb_friction": defaults.COULOMB_FRICTION}
W6_VARIANTS: dict[str, dict[str, float]] = {
    "nominal": {},
    "friction": _FRICTION,
    "noise": {"angle_noise": defaults.ANGLE_NOISE_DEG},
    "friction_noise": {**_FRICTION, "angle_noise": defaults.ANGLE_NOISE_DEG},
}


def _w6_cases(time_scale: float) -> list[SuiteCase]:
    base = {"family": "wheel", "controller": "ABFTC", "scenario": "S1", "time_scale": time_scale}
    return [SuiteCase("W6", Scenario.from_dict({**base, **v}), tag) for tag, v in W6_VARIANTS.items()]


def _w7_cases(time_scale: float) -> list[SuiteCase]:
    cases = []
    for ctrl in CONTROLLERS:
        data = {
            "family": "wheel",
            "controller": ctrl,
            "scenario": "S1",
            "time_scale": time_scale,
            "d_misalignment": defaults.D_TILT_DEG,
        }
        cases.append(SuiteCase("W7", Scenario.from_dict(data), ctrl))
    return cases


def fault_cases(time_scale: float = 1.0, experiments: Sequence[str] | None = None) -> list[SuiteCase]:
    """The cases of W1-W7 (run lengths and fault windows multiplied by ``time_scale``).

    W5 runs every gain of :data:`~benchmarks.families.wheel.defaults.W5_GAMMAS` with the limits
    on and off and the freeze off and on; a time scale below 1 (``--short``) keeps two gains and
    the freeze off.

    Examples
    --------
    >>> cases = fault_cases()
    >>> len(cases), sorted({c.experiment for c in cases})
    (52, ['W1', 'W2', 'W3', 'W4', 'W5', 'W6', 'W7'])
    >>> len(fault_cases(0.1, ["W5"]))
    4
    """
    check_time_scale(time_scale)
    chosen = chosen_experiments(EXPERIMENTS, experiments)
    cases = []
    extra = {"W5": _w5_cases, "W6": _w6_cases, "W7": _w7_cases}
    for exp in chosen:
        if exp in extra:
            cases += extra[exp](time_scale)
            continue
        scenario = EXPERIMENTS[exp][0]
        scales = (1.2, 0.8) if scenario == "S4" else (None,)
        for ctrl in CONTROLLERS:
            for scale in scales:
                data: dict[str, Any] = {
                    "family": "wheel",
                    "controller": ctrl,
                    "scenario": scenario,
                    "time_scale": time_scale,
                }
                tag = ctrl
                if scale is not None:
                    data["inertia_scale"] = scale
                    tag = f"{ctrl}_J{scale:g}"
                cases.append(SuiteCase(exp, Scenario.from_dict(data), tag))
    return cases


def _cost(case: SuiteCase) -> float:
    weight = {"RMPC": 4.0, "CRMPC": 6.0}.get(case.scenario.controller, 1.0)
    return weight * (60.0 if case.scenario.scenario == "S1" else 150.0)


def run_faults(
    out: str | Path,
    workers: int | None = None,
    scheduler: str | None = None,
    time_scale: float = 1.0,
    experiments: Sequence[str] | None = None,
    progress: bool | None = None,
) -> SuiteOutcome:
    """Run W1-W4 and write every output file into ``out`` (created if needed).

    Parameters
    ----------
    out : str or Path
        Output directory.
    workers : int, optional
        Worker processes (default: one per CPU; 0 runs in-process).
    scheduler : str, optional
        A Dask scheduler address instead of local workers.
    time_scale : float
        Factor on every run length and fault window (``--short`` uses ``SHORT_TIME_SCALE``).
    experiments : sequence of str, optional
        A subset of ``W1`` .. ``W4``.
    progress : bool, optional
        Force the progress bar on or off (default: on when stderr is a terminal).
    """
    cases = fault_cases(time_scale, experiments)
    outcome, runs = run_suite_cases(cases, out, "rmpc bench faults", workers, scheduler, progress, _cost)
    with staged_reports(Path(out)) as stage:  # every report file, or none of them, is new
        files = _write(stage, cases, runs, outcome, workers, scheduler, time_scale)
    outcome.files = published_paths(files, stage, Path(out))
    return outcome


# -- the report ------------------------------------------------------------------------
def _deg(value: float | None) -> str:
    return "-" if value is None else f"{math.degrees(value):.2f}"


def _recovery_text(events: list[dict[str, Any]]) -> str:
    parts = []
    for ev in events:
        rec = ev["recovery_time"]
        when = "not recovered" if rec is None else f"{rec:.1f} s"
        parts.append(f"{ev['event']} w{ev['wheel']} {ev['kind']} @{ev['t_event']:g}s: {when}")
    return "; ".join(parts) or "-"


def _peaks_text(windows: list[dict[str, Any]]) -> str:
    parts = []
    for w in windows:
        peaks = [v for v in w["peak"].values() if v is not None]
        if peaks:
            parts.append(f"[{w['t_start']:g}, {w['t_end']:g}): {math.degrees(max(peaks)):.1f}")
    return "; ".join(parts) or "-"


def case_row(rec: dict[str, Any]) -> dict[str, Any]:
    """The table row of one record (strings and numbers, for Markdown and CSV)."""
    m, f = rec["metrics"], rec["metrics"]["faults"]
    final = max(v for v in f["final_abs_err"].values())
    mom = f.get("momentum_limit_events", {})
    return {
        "controller": rec["controller"],
        "saturation": rec["saturation"],
        "plant J": f"x{rec['settings']['inertia_scale_used']:g}",
        "final max |e| (deg)": _deg(final),
        "recovery (2 deg) per fault event": _recovery_text(f["recovery_time"]),
        "peak |e| per fault window (deg)": _peaks_text(f["peak_abs_err"]["fault_windows"]),
        "max |u| cmd / applied (N m)": f"{f['max_abs_u_cmd']:.3f} / {f['max_abs_u']:.3f}",
        "wheels clipped (time)": f"{100 * f['sat_fraction']['any']:.1f} %",
        "max |h| (N m s)": f"{max(f['max_abs_h']):.3f}",
        "momentum-limit samples": str(mom.get("samples", "-")),
        "step p50 / p95 (ms)": f"{1e3 * m['step_time_p50']:.2f} / {1e3 * m['step_time_p95']:.2f}",
        "statuses": statuses(m["status_counts"]),
    }


def _find(records: list[dict], exp: str, ctrl: str) -> list[dict]:
    return [r for r in records if r["experiment"] == exp and r["controller"] == ctrl]


def paper_w_results(records: list[dict[str, Any]]) -> list[str]:
    """Paper W's reported results R1-R4 and its abstract's claim on D, next to what this run measured.

    The verdicts are computed by :mod:`benchmarks.suites.faults_claims` from the records.
    """
    from benchmarks.suites.faults_claims import assess_d_error, assess_hardware, assess_r1, claims_markdown

    reason = _smoke(records)
    lines = ["## Paper W's reported results and what this toolkit measures", ""]
    lines += claims_markdown(withhold([assess_r1(records), *assess_hardware(records)], reason))
    r4 = [r for exp in ("W2", "W3", "W4") for r in _find(records, exp, "ABFTC")]
    if r4:
        cmd = max(r["metrics"]["faults"]["max_abs_u_cmd"] for r in r4)
        h = max(max(r["metrics"]["faults"]["max_abs_h"]) for r in r4)
        final = max(max(r["metrics"]["faults"]["final_abs_err"].values()) for r in r4)
        clipped = max(r["metrics"]["faults"]["sat_fraction"]["any"] for r in r4)
        lines.append(
            f"- **R4** (S2-S4 torques within 0.123 N m, momenta within 0.625 N m s, stable through every "
            f"fault, ending at eta_d): ABFTC commands up to {cmd:.3f} N m (the plant clips at "
            f"{defaults.U_MAX:g}; wheels clipped up to {100 * clipped:.1f} % of the time), momenta up to "
            f"{h:.3f} N m s, final error up to {math.degrees(final):.2f} deg."
        )
    else:
        lines.append("- **R4**: W2-W4 were not run.")
    lines += claims_markdown(withhold([assess_d_error(records)], reason))
    lines.append("")
    return lines


def _smoke(records: list[dict[str, Any]]) -> str | None:
    """Why this run measures none of paper W's claims (a smoke run), read from the records; else None."""
    return records_reason(records, "recovery after a fault or a steady state (the fault windows shrink too)")


def _recovery_cell(rec: dict[str, Any] | None) -> str:
    from benchmarks.suites.faults_claims import onset_recovery

    if rec is None:
        return "-"
    rt = onset_recovery(rec)
    if rt is not None:
        return f"{rt:.1f} s"
    return "diverged" if rec["metrics"]["faults"]["status_counts"].get("diverged") else "not recovered"


def w5_section(records: list[dict[str, Any]]) -> list[str]:
    """W5's table (recovery after the onset per Gamma, limits and freeze) and what it says about R1."""
    from benchmarks.suites.faults_claims import assess_r1

    recs = [r for r in records if r["experiment"] == "W5"]
    if not recs:
        return []
    cols = sorted(
        {(r["settings"]["limits_in_plant"], r["settings"]["settings"]["freeze"]) for r in recs}, reverse=True
    )
    gammas = sorted({r["settings"]["settings"]["gamma_g"] for r in recs})

    def pick(g: float, col: tuple[bool, bool]) -> dict[str, Any] | None:
        for r in recs:
            s = r["settings"]
            if (s["settings"]["gamma_g"], s["limits_in_plant"], s["settings"]["freeze"]) == (g, *col):
                return r
        return None

    rows = []
    for g in gammas:
        row = {"Gamma_0 = Gamma_j": f"{g:g} I3"}
        for col in cols:
            name = ("limits on" if col[0] else "no limits") + (", freeze on" if col[1] else ", freeze off")
            row[name] = _recovery_cell(pick(g, col))
        rows.append(row)
    reason = _smoke(records)
    r1 = withhold([assess_r1(records)], reason)[0]
    lines = [
        "### W5: recovery after the onset (2 deg) per adaptation gain",
        "",
        "Gamma is assumed: paper W printed its adaptation gains in an appendix that is lost, and every "
        "other ABFTC run of this suite uses 0.1 I3.",
        "",
        rows_table(rows),
        "",
        f"Measured: {r1.evidence}.",
    ]
    if reason is not None:
        lines.append(f"No measurement of the gap to paper W's R1: {reason}.")
    elif r1.why:
        lines.append(f"The gap to paper W's R1: {r1.why}.")
    return [*lines, ""]


def null_drift_section(records: list[dict[str, Any]]) -> list[str]:
    """The null-space momentum that grows after the faults, flagged per case with its numbers."""
    from benchmarks.suites.faults_claims import DRIFT_LIMIT, assess_null_drift

    rows = assess_null_drift(records)
    if not rows:
        return []
    flagged = [r for r in rows if r[3]]
    lines = [
        "## Wheel momentum in the null space of D after the faults",
        "",
        "Four wheels on three axes leave one direction of wheel momentum (the null space of D) that the "
        "body does not feel; no controller here manages it. Drift: growth of that momentum from the "
        f"last fault event to the end of the run; flagged above {DRIFT_LIMIT:g} N m s.",
        "",
    ]
    if flagged:
        lines.append(
            "Flagged: "
            + "; ".join(
                f"{name}: drift {d:+.3f} N m s, largest final |h_j| {h:.3f} N m s"
                for name, d, h, _ in flagged
            )
            + "."
        )
    else:
        lines.append(f"No case drifts by more than {DRIFT_LIMIT:g} N m s.")
    worst = max(rows, key=lambda r: r[1])
    lines += ["", f"Largest drift of the run: {worst[0]}, {worst[1]:+.3f} N m s.", ""]
    return lines


def inconsistencies(records: list[dict[str, Any]]) -> list[str]:
    """The inconsistencies of paper W, with this run's numbers where it has them."""
    lines = ["## Inconsistencies in paper W (reported, not hidden)", ""]
    w1 = _find(records, "W1", "ABFTC")
    cmd = (
        f" This run: ABFTC's largest command in W1 is {w1[0]['metrics']['faults']['max_abs_u_cmd']:.3f} N m."
        if w1
        else ""
    )
    lines.append(
        "- The printed gains ask for far more than the wheels give: at t = 0 S1 commands "
        "nu(0) = [-0.262, 1.616, 0.640, 1.151] N m, 13x the 0.123 N m limit; the suite "
        "clips in the plant and reports the clipped time." + cmd
    )
    rank_lines = []
    for exp in ("W3", "W4"):
        for rec in _find(records, exp, "ABFTC")[:1]:
            windows = rec["metrics"]["faults"]["rank_deficient_windows"]
            peaks = rec["metrics"]["faults"]["peak_abs_err"]["rank_deficient_windows"]
            for w, p in zip(windows, peaks, strict=False):
                peak = max(v for v in p["peak"].values() if v is not None) if p["peak"] else None
                where = f"{exp} [{w[0]:g}, {w[1]:g}) rank {w[2]} (wheels {w[3]} lost)"
                rank_lines.append(f"{where}, ABFTC peak {_deg(peak)} deg")
    lines.append(
        "- S3 and S4 leave paper W's own condition (17): two wheels are lost at once and the healthy "
        "ones no longer span three axes. Rank-deficient windows: "
        + ("; ".join(rank_lines) if rank_lines else "none in this run")
        + "."
    )
    altered = [
        f"{r['label']}: {r['metrics']['faults']['momentum_limit_events']['fault_altered']} samples"
        for r in records
        if r["metrics"]["faults"].get("momentum_limit_events", {}).get("fault_altered")
    ]
    lines.append(
        "- Stuck faults outlast the wheel: stuck at 0.05 N m from rest a wheel reaches its 0.625 N m s "
        "limit in 12.5 s, inside S1's 29 s window; the fault's output is then altered by the "
        "momentum limit: " + ("; ".join(altered) if altered else "not in this run") + "."
    )
    lines.append(
        "- S1's stuck torque is 0.05 N m in paper W's paragraph and 0.03 N m in its fault list "
        "(0.05 here). Misprints in eqs. (4), (6), (13), (37), (42). The abstract claims robustness "
        "to inertia and distribution errors, but the proof covers them only through G: S4 and W7 lie "
        "outside it."
    )
    lines.append(
        "- S4's disturbance, read as a body torque, would need about 6.4 N m s of z momentum over 150 s "
        "against 0.99 N m s available: the suite applies it at wheel level, before the faults and limits."
    )
    lines.append("")
    return lines


def _case_limits(records: Sequence[dict]) -> tuple[float, float]:
    """The largest wheel torque (N m) and momentum (N m s) limits of the plants of ``records`` (NaN where
    no plant applies one)."""
    def largest(key: str) -> float:
        values = [max(r["settings"][key]) for r in records if r["settings"].get(key)]
        return float(max(values, default=math.nan))

    return largest("wheel_torque_max"), largest("wheel_momentum_max")


def _write(
    out: Path,
    cases: list[SuiteCase],
    runs: list[tuple[SuiteCase, dict, dict]],
    outcome: SuiteOutcome,
    workers: int | None,
    scheduler: str | None,
    time_scale: float,
) -> list[Path]:
    from benchmarks.families.wheel.family import case_faults
    from benchmarks.reports.fault_figures import plot_fault_case_group

    files: list[Path] = write_traces(out, runs)
    groups: dict[tuple[str, float], list[tuple[SuiteCase, dict, dict]]] = {}
    for case, rec, trace in runs:
        groups.setdefault((case.experiment, rec["settings"]["inertia_scale_used"]), []).append(
            (case, rec, trace)
        )
    figures: dict[str, list[Path]] = {}
    for (exp, scale), items in groups.items():
        if exp == "W5":  # 24 runs of one controller: the report's table summarises them
            continue
        windows = [(f.t_on, f.t_off) for f in case_faults(items[0][0].scenario)]
        name = exp if len({k[1] for k in groups if k[0] == exp}) == 1 else f"{exp}_J{scale:g}"
        path = plot_fault_case_group(
            [(rec, trace) for _, rec, trace in items],
            windows,
            out / "figures" / f"{name}.png",
            f"{name}: paper W's {EXPERIMENTS[exp][0]}",
            *_case_limits([rec for _, rec, _ in items]),
        )
        figures.setdefault(exp, []).append(path)
        files.append(path)

    records = outcome.records
    write_records(out, records)
    rows = [{"experiment": r["experiment"], **case_row(r)} for r in records]
    csv_path = write_rows_csv(out / "results.csv", rows)
    if csv_path is not None:
        files.append(csv_path)
    run_info = write_run_info(
        out, "rmpc bench faults", outcome, len(cases), workers, scheduler, ("time_scale", time_scale)
    )
    (out / "results.md").write_text(_markdown(records, outcome, figures, run_info, out), encoding="utf-8")
    files += [out / n for n in ("results.json", "run.json", "results.md")]
    return files


_FAULT = re.compile(r"WheelFault\(wheel=(\d+), kind='(\w+)', t_on=([^,]+), t_off=([^,]+), value=([^)]+)\)")


def _fault_words(text: str) -> str:
    """A record's fault (``settings.faults_used``, the fault's repr) in words, with its window."""
    m = _FAULT.fullmatch(text)
    if m is None:
        return text
    wheel, kind, t_on, t_off, value = m.groups()
    end = "the end" if t_off in ("inf", "math.inf") else f"{float(t_off):g} s"
    size = "" if kind == "out" else f" ({value})"
    return f"wheel {wheel} {kind}{size} from t = {float(t_on):g} s to {end}"


def run_text(text: str, records: list[dict[str, Any]]) -> str:
    """An experiment's description for the report: paper W's scenario as :data:`EXPERIMENTS`
    words it for a full run; for a run at a time scale below 1 (whose times differ from paper
    W's), that the scenario is scaled; then the faults, run lengths and time scale of ``records``."""
    scales = sorted({float(r["settings"].get("time_scale", 1.0)) for r in records})
    scaled = any(t < 1.0 for t in scales)
    out = text
    if scaled:
        out = f"Paper W's scenario with its times scaled by {' / '.join(f'{t:g}' for t in scales)}."
    faults = list(dict.fromkeys(f for r in records for f in r["settings"].get("faults_used", [])))
    spans = sorted({round(d, 9) for d in run_durations(records)})
    if faults:
        out += " Faults in this run: " + "; ".join(_fault_words(f) for f in faults) + "."
    if spans:
        out += f" Runs of {' / '.join(f'{d:g}' for d in spans)} s."
    return out


def _markdown(
    records: list[dict],
    outcome: SuiteOutcome,
    figures: dict[str, list[Path]],
    info: dict[str, Any],
    out: Path,
) -> str:
    smoke = " (a smoke run: durations and fault windows shortened, no measurement)"
    scale = f"time scale {info['time_scale']:g}" + (smoke if info["time_scale"] < 1 else "")
    lines = [
        "# Benchmark suite `faults`: paper W's scenarios S1-S4 (W1-W4)",
        "",
        citation_line("W"), "",
        *run_lines(info, scale, versions_in_run_json=True),
        "",
        "Nonlinear four-wheel satellite (records: `plant` = \"wheel\"), RK4 at 5 ms inside the 40 ms hold; "
        "every wheel's torque "
        f"({defaults.U_MAX:g} N m) and momentum limits act in the plant. Recovery: time from a fault "
        f"event until every angle stays within {defaults.RECOVERY_DEG:g} deg until the next event. "
        "`step` times are the controller's wall time per 40 ms period.",
        "",
    ]
    for exp, (scenario, text) in EXPERIMENTS.items():
        recs = [r for r in records if r["experiment"] == exp]
        if not recs and exp not in figures:
            continue
        lines += [f"## {exp} (paper W's {scenario})", "", run_text(text, recs), ""]
        if recs:
            lines += [rows_table([case_row(r) for r in recs]), ""]
        for path in figures.get(exp, []):
            lines += [f"![{path.stem}]({path.relative_to(out).as_posix()})", ""]
        if exp == "W5":
            lines += w5_section(records)
    lines += paper_w_results(records)
    lines += null_drift_section(records)
    lines += inconsistencies(records)
    lines += failed_cases(outcome.failures)
    intro = (
        "Every value paper W leaves out is the toolkit's choice "
        "(`benchmarks/families/wheel/defaults.py`; each is a scenario field or controller setting)."
    )
    rationale = None if _smoke(records) else defaults.rationale()
    lines += settings_section(intro, defaults.settings_rows(), rationale)
    return "\n".join(lines)
