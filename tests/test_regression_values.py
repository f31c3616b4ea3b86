"""The regression values (``tests/regression``): the files agree with their margins, every value is
checked by a test and every check names a stored value, and ``check`` and the regeneration do
what they say."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import pytest
import regression
from regression import RECORD_ENV, check, load, suites, thresholds
from regression.regenerate import regenerate_entry

TESTS = Path(__file__).resolve().parent
ROOT = TESTS.parent
#: ``check("suite", "name", ...)`` as the tests write it.
CALL = re.compile(r"""\bcheck\(\s*"([^"]+)",\s*"([^"]+)",""")


def _calls() -> dict[tuple[str, str], list[str]]:
    """Every ``check`` call in the test files: (suite, name) -> the files that make it."""
    found: dict[tuple[str, str], list[str]] = {}
    for path in sorted(TESTS.glob("test_*.py")):
        if path.name == Path(__file__).name:  # this file's calls test ``check`` itself
            continue
        for suite, name in CALL.findall(path.read_text()):
            found.setdefault((suite, name), []).append(f"tests/{path.name}")
    return found


def test_there_are_regression_suites_with_values():
    assert {"crmpc", "gipc", "mras", "rmpc_satellite", "sim_simulate"} <= set(suites())
    assert sum(len(load(s)["values"]) for s in suites()) >= 30


@pytest.mark.parametrize("suite", suites())
def test_each_value_states_what_it_is_its_margin_and_why(suite):
    doc = load(suite)
    assert doc["suite"] == suite and doc["about"]
    assert doc["tests"] and all((ROOT / f).is_file() for f in doc["tests"])
    for name, entry in doc["values"].items():
        assert entry["what"] and entry["unit"] and entry["reason"], name
        assert ("upper_margin" in entry) == ("upper" in entry), name
        assert ("lower_margin" in entry) == ("lower" in entry), name
        lower, upper = thresholds(entry)
        assert math.isfinite(lower) or math.isfinite(upper), f"{name}: no threshold"
        # the thresholds sit their margins away from the measurement, on its two sides
        if "upper" in entry:
            assert entry["upper_margin"] > 0 and entry["upper"] == pytest.approx(
                entry["measured"] + entry["upper_margin"], rel=1e-5), name
        if "lower" in entry:
            assert entry["lower_margin"] > 0 and entry["lower"] == pytest.approx(
                entry["measured"] - entry["lower_margin"], rel=1e-5), name
        assert lower < entry["measured"] < upper, name


def test_every_value_is_checked_by_its_suites_tests_and_every_check_is_stored():
    calls = _calls()
    for suite in suites():
        doc = load(suite)
        for name in doc["values"]:
            files = calls.get((suite, name), [])
            assert files, f"{suite}.{name} is checked by no test"
            assert set(files) <= set(doc["tests"]), (suite, name, files)
    for suite, name in calls:
        assert suite in suites() and name in load(suite)["values"], f"unknown value {suite}.{name}"


# -- check and the record mode ------------------------------------------------------------------
def test_check_passes_inside_and_fails_outside_with_the_regeneration_command(monkeypatch):
    monkeypatch.delenv(RECORD_ENV, raising=False)
    entry = load("mras")["values"]["example_5_2_settling_time_0.05_s"]  # bounded on both sides
    check("mras", "example_5_2_settling_time_0.05_s", entry["measured"])
    check("mras", "example_5_2_settling_time_0.05_s", entry["upper"])  # inclusive
    for outside in (entry["upper"] + 0.01, entry["lower"] - 0.01):
        with pytest.raises(AssertionError, match=r"python -m tests\.regression\.regenerate mras"):
            check("mras", "example_5_2_settling_time_0.05_s", outside)
    with pytest.raises(KeyError):
        check("mras", "no_such_value", 1.0)


def test_record_mode_appends_the_value_and_asserts_nothing(monkeypatch, tmp_path):
    record = tmp_path / "record.jsonl"
    monkeypatch.setenv(RECORD_ENV, str(record))
    check("gipc", "e4_settled_s", 1e9)  # far outside: recorded, not asserted
    check("gipc", "e4_settled_s", 20.0)
    lines = [json.loads(line) for line in record.read_text().splitlines()]
    assert lines == [{"suite": "gipc", "name": "e4_settled_s", "value": 1e9},
                     {"suite": "gipc", "name": "e4_settled_s", "value": 20.0}]


def test_an_unknown_suite_is_refused():
    with pytest.raises(FileNotFoundError, match="no regression file"):
        regression.load("no_such_suite")


# -- regeneration ---------------------------------------------------------------------------------
def test_regeneration_moves_the_thresholds_with_the_worst_measurement():
    upper = {"what": "w", "unit": "s", "measured": 10.0, "upper_margin": 2.0, "upper": 12.0, "reason": "r"}
    new = regenerate_entry(upper, [11.0, 13.5, 12.0])  # the largest counts for an upper bound
    assert new["measured"] == 13.5 and new["upper"] == 15.5 and new["upper_margin"] == 2.0
    assert upper["measured"] == 10.0  # the entry itself is left alone
    lower = {"measured": 5.0, "lower_margin": 1.0, "lower": 4.0}
    assert regenerate_entry(lower, [6.0, 4.5]) == {"measured": 4.5, "lower_margin": 1.0, "lower": 3.5}
    both = {"measured": 5.0, "lower_margin": 1.0, "lower": 4.0, "upper_margin": 0.5, "upper": 5.5}
    new = regenerate_entry(both, [6.0, 6.0])
    assert (new["lower"], new["measured"], new["upper"]) == (5.0, 6.0, 6.5)
    with pytest.raises(ValueError, match="measured differently"):
        regenerate_entry(both, [6.0, 6.1])
    with pytest.raises(ValueError, match="not measured"):
        regenerate_entry(upper, [])


def test_keep_thresholds_recomputes_the_margins_instead():
    entry = {"measured": 19.0, "upper_margin": 1.0, "upper": 20.0, "lower_margin": 1.0, "lower": 18.0}
    new = regenerate_entry(entry, [19.25], keep_thresholds=True)
    assert new == {"measured": 19.25, "upper_margin": 0.75, "upper": 20.0,
                   "lower_margin": 1.25, "lower": 18.0}
