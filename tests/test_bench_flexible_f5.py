"""Experiment F5 of the flexible suite: paper S's baselines on F1's V-slew, and the report's
computed sentences (each checked against the records it is computed from, and flipped with them)."""

from __future__ import annotations

import json
import re

import pytest
from figure_checks import assert_readable, capture

import benchmarks.reports.flexible_figures as flexible_figures
import benchmarks.suites.flexible as flexible_suite
from benchmarks.cli import main
from benchmarks.suites.flexible_f5 import F5_BASELINES, f5_lines, f5_verdicts
from benchmarks.suites.flexible_report import case_row

NAMES = ["PD", "PD-DOB", "ASMC", "NPD", "APD", "ZVD-PD"]


def test_f5_cases_are_the_six_baselines_on_f1s_slew():
    cases = flexible_suite.flexible_cases(experiments=["F1", "F5"])
    f1 = [c.scenario for c in cases if c.experiment == "F1"]
    f5 = {c.tag: c.scenario for c in cases if c.experiment == "F5"}
    assert list(f5) == [tag for tag, _ in F5_BASELINES] == NAMES
    assert [s.controller for s in f5.values()] == ["PD", "PD", "ASMC", "NPD", "APD", "ZVD-PD"]
    assert [s.settings.get("disturbance_observer", None) for s in f5.values()][:2] == [False, True]
    for s in f5.values():  # F1's slew, period, limit and length
        ref = f1[0]
        assert (s.experiment, s.angle_deg, s.dt, s.saturation, s.u_max, s.duration, s.avc) == (
            ref.experiment, ref.angle_deg, ref.dt, ref.saturation, ref.u_max, ref.duration, False
        )


def _rec(name, t_s, peak, energy):
    m = {"t_s": t_s, "eta_peak": [peak, 0.0], "modal_energy_residual": energy}
    return {"experiment": "F5", "settings": {"controller_name": name}, "metrics": m}


def test_f5_verdicts_follow_the_numbers():
    recs = [_rec("PD", None, 0.10, 3e-5), _rec("NPD", 98.0, 0.10, 2e-5), _rec("ZVD-PD", 120.0, 0.04, 4e-5)]
    v = f5_verdicts(recs)
    assert (v["fastest"], v["unsettled"], v["least_peak"], v["least_residual"]) == (
        ["NPD"], ["PD"], ["ZVD-PD"], ["NPD"]
    )
    flipped = [_rec("PD", 90.0, 0.03, 1e-6), _rec("NPD", 98.0, 0.10, 2e-5), _rec("ZVD-PD", None, 0.04, 4e-5)]
    v = f5_verdicts(flipped)
    assert (v["fastest"], v["unsettled"], v["least_peak"], v["least_residual"]) == (
        ["PD"], ["ZVD-PD"], ["PD"], ["PD"]
    )
    text = "\n".join(f5_lines(flipped, lambda r: {"closed loop": r["settings"]["controller_name"]}))
    assert "Settles fastest (t_s, 1 deg): PD at 90 s (in order: PD 90 s; NPD 98 s)" in text
    assert "not settled within the run: ZVD-PD." in text
    assert "peak |eta_1|): PD at 0.03 (largest: NPD at 0.1)" in text
    none = [_rec("PD", None, 0.1, 1e-5), _rec("NPD", None, 0.1, 2e-5)]
    text = "\n".join(f5_lines(none, lambda r: {}))
    assert "None of paper S's baselines settles within the run" in text
    assert "peak |eta_1|): PD and NPD at 0.1" in text  # a tie names both


def test_bench_flexible_short_runs_f5_and_its_sentences_match_the_numbers(tmp_path, capsys, monkeypatch):
    built = capture(monkeypatch, flexible_figures, "flexible_group_figure")
    out = tmp_path / "flex"
    status = main(["bench", "flexible", "--out", str(out), "--short", "--workers", "0", "--experiments",
                   "F1,F5", "--no-progress"])
    assert status == 0, capsys.readouterr().out
    records = json.loads((out / "results.json").read_text())
    f5 = [r for r in records if r["experiment"] == "F5"]
    assert sorted(r["settings"]["controller_name"] for r in f5) == sorted(NAMES)
    assert {r["settings"]["duration_used"] for r in f5} == {
        r["settings"]["duration_used"] for r in records if r["experiment"] == "F1"
    }
    md = (out / "results.md").read_text()
    section = md[md.index("## F5"):md.index("## Paper V's reported results")]
    for r in f5:  # every F5 row in the F5 table
        assert "| " + " | ".join(case_row(r).values()) + " |" in section
    for name in ("MTSMC", "CSMC"):  # F1's reference rows on the same slew
        (ref,) = [r for r in records if r["experiment"] == "F1" and r["settings"]["controller_name"] == name]
        assert "| " + " | ".join(case_row(ref).values()) + " |" in section
    # the sentences, recomputed here from results.json
    peak = min(r["metrics"]["eta_peak"][0] for r in f5)
    least = [r["settings"]["controller_name"] for r in f5 if r["metrics"]["eta_peak"][0] == peak]
    assert f"peak |eta_1|): {' and '.join(least)} at {peak:.3g} (largest" in section
    energy = min(r["metrics"]["modal_energy_residual"] for r in f5)
    quiet = [r["settings"]["controller_name"] for r in f5 if r["metrics"]["modal_energy_residual"] == energy]
    tail = f"the last 10 s (here the whole run: runs of {f5[0]['settings']['duration_used']:g} s)"
    assert f"modal energy over {tail}: {' and '.join(quiet)} at {energy:.3g}" in section
    settled = sorted((r["metrics"]["t_s"], r["settings"]["controller_name"]) for r in f5
                     if r["metrics"]["t_s"] is not None)
    if settled:
        assert re.search(rf"Settles fastest \(t_s, 1 deg\): {re.escape(settled[0][1])} at ", section)
    else:
        assert "None of paper S's baselines settles within the run" in section
    # the figure: six runs, readable, the whole title
    ((items, title), fig) = next(b for b in built if b[0][1].startswith("F5"))
    assert title == f"F5: {flexible_suite.EXPERIMENTS['F5']}"
    assert_readable(fig, [name for name, _, _ in items])
    assert len(items) == 6


@pytest.mark.parametrize(("observer", "name"), [(True, "PD-DOB"), (False, "PD")])
def test_pd_with_the_observer_is_named_in_the_record(observer, name):
    from benchmarks.core.runner import run_scenario
    from benchmarks.core.scenario import Scenario

    data = {"family": "flexible", "controller": "PD", "settings": {"disturbance_observer": observer}}
    rec = run_scenario(Scenario.from_dict({**data, "duration": 0.05}))
    assert rec["settings"]["controller_name"] == name and rec["controller"] == "PD"
    assert rec["label"].startswith(name + " ")
