"""The public LMI benchmark (:mod:`dev.public_lmi`): its records and its report.

No timing is asserted (times live in the benchmark's output); what is checked is what the
records claim: both solvers' answers on control2 against SDPLIB's published optimum, and the
table and files the command writes.
"""

from __future__ import annotations

import json

import pytest

from dev.public_lmi import PUBLISHED_OPTIMA, format_public, load_case, main, run_public
from toolkit_common.errors import InvalidArgumentError


@pytest.fixture(scope="module")
def records():
    return run_public(["control2"], repeats=2)


def test_both_solvers_solve_control2_to_the_published_optimum(records):
    """One record per solver; both "optimal", objectives within 1e-6 of SDPLIB's 8.3 (measured:
    8.9e-10 for the IPM, 5.8e-8 for Clarabel at its default tolerances), the repeats agree."""
    assert [r["solver"] for r in records] == ["BlockLMISolver", "cvxpy + Clarabel"]
    for rec in records:
        assert rec["case"] == "control2" and rec["variables"] == 66 and rec["block_orders"] == [20, 10]
        assert rec["status"] == "optimal" and rec["repeats_agree"] and rec["repeats"] == 2
        assert rec["rel_error"] == pytest.approx(abs(rec["objective"] / PUBLISHED_OPTIMA["control2"] - 1.0))
        assert rec["rel_error"] <= 1e-6
        assert rec["iterations"] > 0 and 0.0 < rec["solve_time_s"] <= rec["total_time_s"]


def test_the_table_has_a_row_per_record(records):
    text = format_public(records)
    rows = [line for line in text.splitlines() if line.startswith("| control2 |")]
    assert len(rows) == 2
    assert "| BlockLMISolver | optimal |" in rows[0] and "| cvxpy + Clarabel | optimal |" in rows[1]


def test_the_command_writes_the_table_and_the_records(tmp_path, capsys):
    assert main(["--cases", "control2", "--repeats", "1", "--out", str(tmp_path / "out")]) == 0
    printed = capsys.readouterr().out
    md = (tmp_path / "out" / "results.md").read_text()
    assert md == printed and "| control2 | 66 | 20, 10 | BlockLMISolver | optimal |" in md
    saved = json.loads((tmp_path / "out" / "results.json").read_text())
    assert [r["solver"] for r in saved] == ["BlockLMISolver", "cvxpy + Clarabel"]


def test_bad_arguments_name_the_argument():
    with pytest.raises(InvalidArgumentError, match="case"):
        load_case("control9")
    with pytest.raises(InvalidArgumentError, match="repeats"):
        run_public(["control2"], repeats=0)
