"""What the suites share: the experiment and time-scale checks and the pieces of results.md."""

from __future__ import annotations

import pytest

from benchmarks.core.suite import check_time_scale, chosen_experiments
from benchmarks.reports.sections import dash, failed_cases, rows_table, run_lines, settings_section, statuses
from benchmarks.suites.faults import fault_cases
from benchmarks.suites.flexible import flexible_cases
from benchmarks.suites.mrp import mrp_cases
from benchmarks.suites.paper import paper_cases
from toolkit_common.errors import ConfigError


@pytest.mark.parametrize(
    ("cases", "known"),
    [(paper_cases, "E1, E2"), (fault_cases, "W1, W2"), (mrp_cases, "M1, M2"), (flexible_cases, "F1, F2")],
)
def test_every_suite_names_an_unknown_experiment_and_the_known_ones(cases, known):
    with pytest.raises(ConfigError, match=rf"--experiments: expected names among {known}.*'X9'"):
        cases(1.0, ["X9"])


@pytest.mark.parametrize("cases", [fault_cases, mrp_cases, flexible_cases])
@pytest.mark.parametrize("scale", [0.0, -0.5, 1.5])
def test_the_time_scaled_suites_refuse_a_factor_outside_0_1(cases, scale):
    with pytest.raises(ConfigError, match=r"time_scale: expected a factor in \(0, 1\]"):
        cases(scale)


def test_the_checks_return_what_they_accept():
    assert chosen_experiments({"A": "a", "B": "b"}, None) == ["A", "B"]
    assert chosen_experiments(("A", "B"), ["B", "A"]) == ["B", "A"]
    assert check_time_scale(1.0) == 1.0 and check_time_scale(0.02) == 0.02


def test_run_lines():
    info = {"wall_time_s": 12.34, "executor": "2 worker processes", "done": 3, "cases": 4, "failed": 1,
            "interrupted": True, "machine": {"platform": "P", "cpu_count": 2, "load_average": [1.0]}}
    run, machine = run_lines(info, "time scale 0.1 (smoke)")
    assert run == ("Wall time 12.3 s on 2 worker processes; time scale 0.1 (smoke); 3 of 4 cases done, "
                   "1 failed (interrupted).")
    assert machine == "Machine: P, 2 CPUs, load average [1.0] at the end."
    info["interrupted"] = False
    run, machine = run_lines(info, "duration scale 1", versions_in_run_json=True)
    assert run.endswith("1 failed.") and machine.endswith("at the end; package versions in `run.json`.")


def test_failures_settings_and_tables():
    assert failed_cases([]) == []
    assert failed_cases([{"key": "E1_RMPC", "error": "ValueError: x"}]) == [
        "## Failed cases", "", "- E1_RMPC: ValueError: x", ""
    ]
    lines = settings_section("Intro.", [("dt", 0.01, "assumed")], "Because.")
    assert lines[:4] == ["## Settings", "", "Intro.", ""]
    assert lines[-4:] == ["Why these values:", "", "Because.", ""]
    assert lines[4].splitlines()[2] == "| dt | 0.01 | assumed |"
    assert rows_table([{"a": "1", "b|c": None}]).splitlines()[0] == "| a | b\\|c |"
    assert dash(None) == "-" and dash(2.0, ".1f") == "2.0"
    assert statuses({}) == "" and statuses({"b": 1, "a": 2}) == "a 2, b 1"
