"""A record says what ran: ``settings.duration_used`` is the time simulated, whole samples of ``dt``.

``simulate`` runs ``round(duration / dt)`` samples, so a ``duration`` that is not a whole number of
samples runs a little shorter or longer than asked; the record kept only the value asked for (the
rigid family wrote nothing else, the other families copied it into ``duration_used``). Now
``duration`` keeps what was asked for (it names the case) and ``duration_used`` is ``n_steps dt``.
"""

from __future__ import annotations

import json

import pytest

from benchmarks.cli import main
from benchmarks.core.runner import simulate_scenario
from benchmarks.core.scenario import Scenario
from dev.robustness.cli_cases import TINY_SWEEP

# family: (scenario, duration asked for, dt, samples that run = round(duration / dt))
CASES = {
    "rigid": ({"controller": "LQR", "saturation": "limiter", "plant": "linear", "duration": 0.2049}, 0.2049,
              0.01, 20),
    "wheel": ({"family": "wheel", "controller": "ABFTC", "saturation": "limiter", "fault_kind": "none",
               "duration": 0.13}, 0.13, 0.04, 3),
    "mrp": ({"family": "mrp", "controller": "BS", "duration": 0.0351}, 0.0351, 0.01, 4),
    "flexible": ({"family": "flexible", "controller": "MTSMC", "duration": 0.0349}, 0.0349, 0.01, 3),
}


@pytest.mark.parametrize(("data", "asked", "dt", "samples"), CASES.values(), ids=list(CASES))
def test_the_record_gives_the_time_that_ran_next_to_the_duration_asked_for(data, asked, dt, samples):
    record, trace = simulate_scenario(Scenario.from_dict(data), keep_trace=True)
    settings = record["settings"]
    assert settings["duration"] == asked and settings["dt"] == dt
    assert settings["duration_used"] == samples * dt != asked
    if "t" in trace:  # the trajectory ends there
        assert trace["t"][-1] == settings["duration_used"] and len(trace["t"]) == samples + 1


def test_a_family_that_picks_the_length_records_it():
    """No ``duration``: paper M's M2 (100 s) at time scale 0.0005 is 0.05 s, 5 samples of 0.01 s."""
    scenario = Scenario.from_dict({"family": "mrp", "controller": "BS", "time_scale": 0.0005})
    record, _ = simulate_scenario(scenario)
    assert record["settings"]["duration"] is None
    assert record["settings"]["duration_used"] == 5 * 0.01


def test_a_sweep_record_says_what_ran(tmp_path):
    config = tmp_path / "sweep.toml"
    config.write_text(TINY_SWEEP.replace("duration = 0.2", "duration = 0.2049"))
    out = tmp_path / "out"
    assert main(["bench", "sweep", "--config", str(config), "--out", str(out), "--workers", "0",
                 "--no-progress"]) == 0
    (record,) = json.loads((out / "results.json").read_text())
    assert record["settings"]["duration"] == 0.2049
    assert record["settings"]["duration_used"] == 20 * 0.01
