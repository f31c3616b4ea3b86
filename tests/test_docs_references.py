"""The documentation points only at files of this repository, and not at the project's history.

A reader has the repository, not the specification, the source material of the reference papers
or the tracker the toolkit was built from. Every page under ``docs/`` (``docs/tutorial`` too) is
checked for

- file paths (``tests/foo.py``, ``benchmarks/x.toml``, ``../shared/notes.md``, ``docs/examples/y.py``)
  that do not exist in the repository;
- the word ``SPEC`` (the specification the toolkit was written from);
- ``issue <number>`` (a tracker reference);
- the project's history (``the previous default``, ``before the budget existed``);
- file names of the papers' source notes (``paper-W-....md``, ``papers-S-V-....md``) and the
  word "seed" used for them (``the seed``, ``seed 8(c)``, ``seed section 6``, ``seed's``), while
  a random seed (``seed=1``, ``--seed 0``, ``random seed 7``) is fine.

Only ``docs/changelog.rst`` may tell history; it is checked for file paths only.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
PAGES = sorted(
    page for page in DOCS.rglob("*.rst") if not {"_build", "_generated"} & set(page.relative_to(DOCS).parts)
)

# A path: optional ``../`` or ``./`` prefixes, then segments of word characters, dots and dashes
# joined by ``/``, ending in a file extension; or a directory of the repository's top level
# followed by a segment. Module names (``lmi.kothare``) and URLs are not paths.
_EXTENSIONS = "py|toml|md|rst|txt|json|csv|cfg|ini|yaml|yml|png|svg|npz|npy|sh|lock|sqlite|db"
_PATH = re.compile(
    rf"(?<![\w/:.@-])((?:\.\.?/)*(?:[\w.-]+/)*[\w.-]+\.(?:{_EXTENSIONS}))(?![\w/-])"
)
_TOP_DIRS = ("benchmarks", "dev", "docs", "lmi", "models", "rmpc", "tests", "toolkit_common")
_DIR = re.compile(rf"(?<![\w/:.@-])((?:{'|'.join(_TOP_DIRS)})/[\w.-]+(?:/[\w.-]+)*)/?(?![\w-])")
_URL = re.compile(r"\b(?:https?|ftp)://\S+")

# The output folders the pages' commands write to (``--out results/mrp``, ``damaged/sweep.sqlite``
# in an error message): the user's, not the repository's.
_OUTPUT_ROOTS = frozenset({"results", "timing", "t", "out", "OUT", "DIR", "damaged"})
# What the documentation build writes: the HTML and the figures drawn at build time.
_BUILD_OUTPUTS = ("_generated/", "_build/", "docs/_generated/", "docs/_build/")

_FORBIDDEN = [
    (re.compile(r"\bSPEC\b"), "the specification (SPEC)"),
    (re.compile(r"\b[Ii]ssues? #?\d+"), "an issue number"),
    (re.compile(r"\bpapers?-[\w-]+\.md\b"), "a file name of a paper's source notes"),
    (re.compile(r"\b[Ss]eeds?/"), "the papers' source-notes folder"),
    (re.compile(r"\b[Tt]he seed\b|\bseed's\b|\b[Ss]eed section \d+|\b[Ss]eed \d+(?:\.\d+|\([a-z]\))"),
     "the papers' source notes (the seed)"),
    (re.compile(r"\b(?:previous|old|former) default\b|\bbefore the [\w ]{1,30} existed\b"),
     "the project's history"),
]


def _references(text: str) -> list[str]:
    text = _URL.sub(" ", text)
    found = [m.group(1) for m in _PATH.finditer(text)]
    found += [m.group(1) for m in _DIR.finditer(text)]
    return found


def _resolves(ref: str, page: Path) -> bool:
    """Whether ``ref`` names a file or directory of the repository (from its root, or the page's folder)."""
    candidates = [ROOT / ref, page.parent / ref]
    for candidate in candidates:
        try:
            resolved = candidate.resolve()
        except OSError:
            continue
        if resolved.exists() and resolved.is_relative_to(ROOT):
            return True
    return False


def dangling_paths(page: Path) -> list[str]:
    """The paths a page names that are not in the repository.

    Only names with a ``/`` are paths here (a bare ``results.md`` is an output file's name);
    absolute paths are never matched (they are the user's, e.g. ``/tmp/timing_b``), and names
    under the commands' output folders (:data:`_OUTPUT_ROOTS`) are the user's too.
    """
    text = page.read_text(encoding="utf-8")
    bad = []
    for ref in _references(text):
        if "/" not in ref or ref.split("/")[0] in _OUTPUT_ROOTS or (ref + "/").startswith(_BUILD_OUTPUTS):
            continue
        if not _resolves(ref, page):
            bad.append(ref)
    return sorted(set(bad))


def forbidden_words(page: Path) -> list[str]:
    """``what: line`` for each pointer at the specification, the tracker or the papers' notes."""
    if page.name == "changelog.rst":
        return []
    hits = []
    for number, line in enumerate(page.read_text(encoding="utf-8").splitlines(), start=1):
        for pattern, what in _FORBIDDEN:
            if pattern.search(line):
                hits.append(f"{what}: {page.name}:{number}: {line.strip()}")
    return hits


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.relative_to(DOCS).as_posix())
def test_every_file_a_page_names_is_in_the_repository(page: Path) -> None:
    assert dangling_paths(page) == []


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.relative_to(DOCS).as_posix())
def test_no_page_points_at_the_specification_the_tracker_or_the_source_notes(page: Path) -> None:
    assert forbidden_words(page) == []


def test_the_checks_see_what_they_must(tmp_path: Path) -> None:
    """On a page written for the purpose each kind of pointer is found, and a random seed is not."""
    page = tmp_path / "page.rst"
    page.write_text(
        "See ``tests/no_such_test.py`` and ../shared/notes.md, but also ``tests/test_docs.py``.\n"
        "As SPEC section 3 says; fixed in issue 12; values from ``paper-W-wheel-faults.md``.\n"
        "As the seed prescribes (seed 8(c)). Random draws use ``seed=1`` and a random seed 7.\n"
        "The previous default, before the budget existed.\n",
        encoding="utf-8",
    )
    # A page outside docs/ resolves relative paths against its own folder, so only the
    # repository-rooted ones are judged here.
    assert dangling_paths(page) == ["../shared/notes.md", "tests/no_such_test.py"]
    words = forbidden_words(page)
    assert [w.split(":")[0] for w in words] == [
        "the specification (SPEC)", "an issue number", "a file name of a paper's source notes",
        "the papers' source notes (the seed)", "the project's history",
    ]
