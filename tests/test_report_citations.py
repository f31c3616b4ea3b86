"""The reports cite the papers they reproduce under their title, from one place.

:mod:`benchmarks.reports.citations` holds what is known of each reference paper (and names what
is not); each suite's ``results.md`` carries the citation of its papers on the line under its
title. The suites are run here with their case runner replaced by one that runs nothing (every
case "not run"), so the whole report writer runs in a second; what the cases measure is tested
with the suites.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import pytest

import benchmarks.suites.faults as faults_suite
import benchmarks.suites.flexible as flexible_suite
import benchmarks.suites.mrp as mrp_suite
import benchmarks.suites.paper as paper_suite
from benchmarks.core.suite import SuiteOutcome
from benchmarks.reports.citations import REFERENCES, Reference, citation, citation_line
from toolkit_common.errors import InvalidArgumentError


def test_paper_p_is_cited_with_what_is_known() -> None:
    text = citation("P")
    for part in ("Fatemeh Pirouzmand", "Nematollah Ghahramani", "Mohammadreza Arvan",
                 "Design of a robust predictive controller using linear matrix inequalities for a "
                 "satellite attitude control system",
                 "English rendering", "Tabriz Journal of Electrical Engineering", "Vol. 44, No. 4",
                 "2014", "in Persian"):
        assert part in text, part
    assert "not known" not in text  # everything a citation needs is known of paper P
    assert "journal paper" not in text


def test_the_papers_known_only_in_part_say_what_is_unknown() -> None:
    text = citation("S")
    assert "Mohammad Fathi and Hossein Bolandi" in text
    title = "Survey on flexible satellite: dynamic analysis, challenges and attitude control strategies"
    assert f'"{title}"' in text
    assert text.endswith("venue and year not known).")
    for key in ("W", "M", "V"):
        ref = REFERENCES[key]
        assert ref.unknown == ("authors", "title", "venue", "year")
        assert citation(key).endswith("; authors, title, venue and year not known).")
        assert ref.subject in citation(key)  # what the paper is about stands in for its title
    assert "no English metadata" in citation("M")
    # no year is given for S, W, M or V: none is printed
    for key in ("S", "W", "M", "V"):
        assert not any(ch.isdigit() for ch in citation(key)), citation(key)


def test_a_reference_is_frozen_and_the_table_read_only() -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        REFERENCES["P"].year = "2015"  # type: ignore[misc]
    with pytest.raises(TypeError):
        REFERENCES["X"] = REFERENCES["P"]  # type: ignore[index]


def test_bad_arguments_are_refused() -> None:
    with pytest.raises(InvalidArgumentError, match="key: expected one of M, P, S, V, W, but found 'Q'"):
        citation("Q")
    with pytest.raises(InvalidArgumentError, match="keys: expected at least one paper's key, but found none"):
        citation_line()
    with pytest.raises(InvalidArgumentError, match=r"affiliations: expected one per author .*found 1"):
        Reference(key="X", subject="s", language="l", authors=("A", "B"), affiliations=("a",))
    with pytest.raises(InvalidArgumentError, match="title_note: expected no note without a title"):
        Reference(key="X", subject="s", language="l", title_note="English rendering")


def _nothing_run(cases: Any, out: Any, *args: Any, **kwargs: Any) -> tuple[SuiteOutcome, list]:
    """A case runner that runs nothing: every case is reported as not run."""
    Path(out).mkdir(parents=True, exist_ok=True)
    failures = [{"key": case.key, "error": "not run"} for case in cases]
    return SuiteOutcome(failures=failures, executor="none"), []


@pytest.mark.parametrize(
    ("module", "run", "keys"),
    [
        (paper_suite, "run_paper", ("P",)),
        (faults_suite, "run_faults", ("W",)),
        (mrp_suite, "run_mrp", ("M",)),
        (flexible_suite, "run_flexible", ("V", "S")),
    ],
    ids=["paper", "faults", "mrp", "flexible"],
)
def test_each_report_cites_its_papers_under_its_title(
    module: Any, run: str, keys: tuple[str, ...], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(module, "run_suite_cases", _nothing_run)
    getattr(module, run)(tmp_path, workers=0, progress=False)
    lines = (tmp_path / "results.md").read_text(encoding="utf-8").splitlines()
    assert lines[0].startswith("# Benchmark suite ")
    assert lines[1:4] == ["", citation_line(*keys), ""]
    text = "\n".join(lines)
    assert "not run" in text  # the cases' failures are reported: the writer ran to its end
    assert "journal paper" not in text
