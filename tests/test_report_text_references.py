"""The modules that write the reports cite papers, never the notes the toolkit was written from.

A reader of ``results.md`` has the report and the repository, not the specification (``SPEC``)
or the papers' source notes (once called "the seed": ``seed 6``, ``seed section 8``,
``(seed 8(c))``, ``the seed's choice``). The report-writing modules (every module of
``benchmarks/suites`` and ``benchmarks/families``, whose settings tables, notes and headings
become report text) and the modules whose docstrings the brief names are scanned as source text
(strings, comments and docstrings alike). A random seed is fine: ``seed=``, ``--seed``,
``random seed 0``, ``seeds``, ``seeded``. Nothing is run.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

#: The scanned modules: the report writers and the models/controllers they describe.
MODULES = sorted(
    {
        *(ROOT / "benchmarks" / "suites").glob("*.py"),
        *(ROOT / "benchmarks" / "families").rglob("*.py"),
        *(ROOT / "rmpc" / "laws" / "mrp").glob("*.py"),
        ROOT / "rmpc" / "mpc" / "gipc.py",
        ROOT / "models" / "flexible" / "satellite.py",
    }
)

#: (pattern, what it points at) for every reference a reader cannot follow.
FORBIDDEN: list[tuple[re.Pattern[str], str]] = [
    (re.compile(r"\bSPEC\b"), "the specification (SPEC)"),
    (re.compile(r"\b[Ss]eed sections? \d"), "a section of the papers' source notes"),
    (re.compile(r"(?<!random )(?<!-)\b[Ss]eed \d"), "a numbered part of the papers' source notes"),
    (re.compile(r"\(seed(?=[ :])"), "a parenthesised reference to the papers' source notes"),
    (re.compile(r"\b[Tt]he seed\b(?!ed)|\b[Ss]eed's\b"), "the papers' source notes (the seed)"),
    (re.compile(r"\bpapers?-[\w-]+\.md\b"), "a file name of a paper's source notes"),
]


def offences(text: str) -> list[str]:
    """``line N: <match> (<what>)`` for every forbidden reference in ``text``."""
    found = []
    for number, line in enumerate(text.splitlines(), start=1):
        for pattern, what in FORBIDDEN:
            found += [f"line {number}: {m.group(0)!r} ({what})" for m in pattern.finditer(line)]
    return found


def test_the_scan_covers_the_report_writers() -> None:
    names = {p.relative_to(ROOT).as_posix() for p in MODULES}
    for expected in (
        "benchmarks/suites/flexible_report.py",
        "benchmarks/suites/paper_claims.py",
        "benchmarks/families/flexible/defaults.py",
        "benchmarks/families/mrp/defaults.py",
        "benchmarks/families/wheel/defaults.py",
    ):
        assert expected in names


@pytest.mark.parametrize(
    ("text", "bad"),
    [
        ('"assumed (seed 5)"', True),
        ('"toolkit (seed 9)"', True),
        ("seed section 8's record fields", True),
        ("(seed 8(c))", True),
        ("- Seed 7.8: CI falls", True),
        ("the seed's choice", True),
        ("initial error's box (SPEC 1, covering polytope)", True),
        ("Seed ``papers-S-V-flexible.md`` sections 4.4", True),
        ("noise of variance 0.0052, every 40 ms, random seed 0", False),
        ("rng = np.random.default_rng(seed=3)", False),
        ("np.random.default_rng(seed); scenario.disturbance(seed, n)", False),
        ("Sample time (s) (seed: 0.01).", True),
        ("rmpc bench faults --seed 4", False),
        ("seeded directions; the seeds of the sweep", False),
        ("spec = load_sweep(config)", False),
    ],
)
def test_the_patterns(text: str, bad: bool) -> None:
    assert bool(offences(text)) is bad


@pytest.mark.parametrize("path", MODULES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_no_reference_a_reader_cannot_follow(path: Path) -> None:
    found = offences(path.read_text(encoding="utf-8"))
    assert not found, f"{path.relative_to(ROOT)}: " + "; ".join(found)
