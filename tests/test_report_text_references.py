"""The modules that write the reports cite papers, never the notes the toolkit was written from.

A reader of ``results.md`` or of the API reference built from the docstrings has the report and
the repository, not the specification (``SPEC``, ``API.md``) or the papers' source notes (once
called "the seed": ``seed 6``, ``seed section 8``, ``(seed 8(c))``, ``the seed's choice``). Every
module of the packages (``models``, ``rmpc``, ``lmi``, ``toolkit_common`` and ``benchmarks``, whose
settings tables, notes and headings become report text) and of the development tools (``dev``) is
scanned as source text (strings, comments and docstrings alike), but for the few whose "seed" is
a random seed in words the patterns cannot tell apart. A random seed is fine: ``seed=``,
``--seed``, ``random seed 0``, ``seeds``, ``seeded``. Nothing is run.

A string that ends up in a benchmark record keeps its wording (changing it would change the
records); :data:`RECORD_STRINGS` lists those, and the scan passes over their lines only.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

#: Modules whose only matches are random seeds in words ("with seed 0", "(seed {seed})").
RANDOM_SEED_MODULES = {
    "dev/generic_stress.py",
    "dev/stress.py",
}

#: The scanned modules: every module of the packages but :data:`RANDOM_SEED_MODULES`.
MODULES = sorted(
    path
    for package in ("models", "rmpc", "lmi", "toolkit_common", "benchmarks", "dev")
    for path in (ROOT / package).rglob("*.py")
    if path.relative_to(ROOT).as_posix() not in RANDOM_SEED_MODULES
)

#: Strings that end up in benchmark records, by module: left as they are (the records must not
#: change); a line holding one is not scanned.
RECORD_STRINGS: dict[str, tuple[str, ...]] = {
    # the ``notes`` of scenario S3, written into every S3 record
    "models/wheels/scenarios.py": ("paper W's condition (17) fails (seed 6.7)",),
}

#: (pattern, what it points at) for every reference a reader cannot follow.
FORBIDDEN: list[tuple[re.Pattern[str], str]] = [
    (re.compile(r"\bSPEC\b"), "the specification (SPEC)"),
    (re.compile(r"\b[Ss]eed sections? \d"), "a section of the papers' source notes"),
    (re.compile(r"(?<!random )(?<!-)\b[Ss]eed \d"), "a numbered part of the papers' source notes"),
    (re.compile(r"(?<!\w)\(seed(?=[ :])"), "a parenthesised reference to the papers' source notes"),
    (re.compile(r"\b[Tt]he seed\b(?!ed)|\b[Ss]eed's\b"), "the papers' source notes (the seed)"),
    (re.compile(r"\bpapers?-[\w-]+\.md\b"), "a file name of a paper's source notes"),
    (re.compile(r"\b(?:SPEC|API|STYLE)\.md\b"), "a file of the specification"),
]


def offences(text: str, allowed: tuple[str, ...] = ()) -> list[str]:
    """``line N: <match> (<what>)`` for every forbidden reference in ``text``.

    A line holding one of the ``allowed`` strings is passed over.
    """
    found = []
    for number, line in enumerate(text.splitlines(), start=1):
        if any(a in line for a in allowed):
            continue
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
        # the modules whose docstrings the API reference shows
        "models/flexible/polytope.py",
        "models/mrp/spinning_disk.py",
        "models/wheels/satellite.py",
        "models/wheels/scenarios.py",
        "models/wheels/noise.py",
        "models/attitude/euler_inverse.py",
        "models/rigid/satellite.py",
        "rmpc/laws/wheel/adaptive_backstepping.py",
        "rmpc/laws/flexible/mtsmc.py",
        "rmpc/mpc/scheduled.py",
        "rmpc/sim/integrators.py",
        "lmi/scaling.py",
        "benchmarks/timing/suite.py",
        "benchmarks/cli.py",
    ):
        assert expected in names
    assert len(names) > 100  # the packages, not a handful


def test_the_record_strings_are_still_there() -> None:
    """An exception that no longer matches a line would hide nothing and should go."""
    for module, strings in RECORD_STRINGS.items():
        text = (ROOT / module).read_text(encoding="utf-8")
        for s in strings:
            assert s in text, f"{module}: {s!r} is gone; drop it from RECORD_STRINGS"


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
        ("def _check_seed(seed: Any) -> int | None:", False),
        ("the solver timing report (SPEC 2.1, 2.3, 2.4 and 5; API.md)", True),
        ("the timing report of API.md", True),
    ],
)
def test_the_patterns(text: str, bad: bool) -> None:
    assert bool(offences(text)) is bad


@pytest.mark.parametrize("path", MODULES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_no_reference_a_reader_cannot_follow(path: Path) -> None:
    module = path.relative_to(ROOT).as_posix()
    found = offences(path.read_text(encoding="utf-8"), RECORD_STRINGS.get(module, ()))
    assert not found, f"{path.relative_to(ROOT)}: " + "; ".join(found)
