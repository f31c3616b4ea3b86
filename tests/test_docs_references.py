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

The reference papers are cited where they are used: a page that names paper P, S, W, M or V cites
it at its first use (outside headings) or before, by a cross-reference to the paper's entry on the
references page (``:ref:`paper-p```, the entries of ``docs/citing.rst``) or, for the papers whose
authors are known, by an author's name; the README cites paper P by its authors at its first
mention. No page, the README or a module (whose text becomes the reports and the API reference)
calls paper P "a 2014 journal paper".
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


# -- citations of the reference papers ---------------------------------------------------------

#: What cites each paper besides a cross-reference to its entry: an author's name, where known.
AUTHORS = {"P": "Pirouzmand", "S": "Fathi", "W": None, "M": None, "V": None}
#: Where the papers are listed (it cites them all) and the history (which may quote old wording).
CITATION_EXEMPT = frozenset({"citing.rst", "changelog.rst"})

# "paper P", "Paper V's", "papers S and V", "papers W, M, S and V"
_NAMED = re.compile(r"\b[Pp]apers?\s+((?:[PSWMV](?:'s)?(?:,\s+|\s+and\s+|/))*[PSWMV])(?![\w-])")
_UNDERLINE = re.compile(r"""^([=\-~^"'`#*+])\1+\s*$""")


def _paragraphs(text: str) -> list[str]:
    """The blocks of ``text`` between blank lines, with the section titles (and their lines) left out."""
    paragraphs = []
    for block in re.split(r"\n[ \t]*\n", text):
        lines = block.splitlines()
        if lines and _UNDERLINE.match(lines[0]):  # an overline
            lines = lines[1:]
        if len(lines) >= 2 and _UNDERLINE.match(lines[1]) and len(lines[1].strip()) >= len(lines[0].strip()):
            lines = lines[2:]
        if lines:
            paragraphs.append("\n".join(lines))
    return paragraphs


def _cites(text: str, key: str) -> bool:
    ref = re.compile(rf":ref:`(?:[^`]*<)?paper-{key.lower()}>?`")
    author = AUTHORS[key]
    return bool(ref.search(text)) or (author is not None and author in text)


def uncited_papers(text: str) -> list[str]:
    """``paper <key>: <paragraph's start>`` for each paper named before it is cited.

    The citation must stand in the paragraph of the paper's first mention (headings are not
    paragraphs) or before it.
    """
    bad, seen = [], set()
    done = ""
    for block in _paragraphs(text):
        done += block + "\n\n"
        for m in _NAMED.finditer(block):
            for key in re.findall(r"[PSWMV]", m.group(1)):
                if key in seen:
                    continue
                seen.add(key)
                if not _cites(done, key):
                    bad.append(f"paper {key}: {' '.join(block.split())[:100]}")
    return bad


def _citing_pages() -> list[Path]:
    return [p for p in PAGES if p.relative_to(DOCS).as_posix() not in CITATION_EXEMPT]


@pytest.mark.parametrize("page", _citing_pages(), ids=lambda p: p.relative_to(DOCS).as_posix())
def test_a_page_cites_each_paper_at_its_first_use(page: Path) -> None:
    assert uncited_papers(page.read_text(encoding="utf-8")) == []


def test_the_readme_cites_paper_p_at_its_first_mention() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert "paper P" in readme
    assert [b for b in uncited_papers(readme) if b.startswith("paper P")] == []


def test_every_paper_has_its_entry_on_the_references_page() -> None:
    """The targets of the cross-references: an entry per paper, with its authors where known."""
    citing = (DOCS / "citing.rst").read_text(encoding="utf-8")
    for key, author in AUTHORS.items():
        entry = citing.split(f".. _paper-{key.lower()}:\n", 1)
        assert len(entry) == 2, f"docs/citing.rst has no entry for paper {key}"
        body = entry[1].split("\n.. _", 1)[0]
        if author is None:
            assert "authors, title, venue and year are not known" in body, key
        else:
            assert author in body, key


def _texts_for_readers() -> list[Path]:
    modules = [p for package in _TOP_DIRS if package not in ("docs", "tests")
               for p in (ROOT / package).rglob("*.py")]
    return [*PAGES, ROOT / "README.md", *modules]


def test_paper_p_is_not_called_a_2014_journal_paper() -> None:
    bad = [p.relative_to(ROOT).as_posix() for p in _texts_for_readers()
           if re.search(r"2014\s+journal\s+paper", p.read_text(encoding="utf-8"))]
    assert bad == []


def test_the_citation_check_sees_what_it_must() -> None:
    cited = "Paper P (Pirouzmand, Ghahramani and Arvan) and paper W (:ref:`what is known <paper-w>`).\n"
    assert uncited_papers(cited) == []
    assert uncited_papers("Title of paper S\n================\n\nPaper S (:ref:`paper-s`) says.\n") == []
    # a mention in a heading does not count as the first use, a citation there does not count
    assert uncited_papers("Paper M\n=======\n\nPaper M's model.\n") == ["paper M: Paper M's model."]
    assert uncited_papers("=======\nPaper M\n=======\nPaper M's model.\n") == ["paper M: Paper M's model."]
    # cited later than its first paragraph: too late
    late = "The satellite of paper P.\n\nLater: Pirouzmand, Ghahramani and Arvan.\n"
    assert uncited_papers(late) == ["paper P: The satellite of paper P."]
    # each paper of a list is checked; an author known of S does not cite V
    assert uncited_papers("Papers S and V (Fathi and Bolandi).\n") == [
        "paper V: Papers S and V (Fathi and Bolandi)."
    ]
    assert uncited_papers("The papers W, M and V's laws; see :ref:`paper-w`.\n") == [
        "paper M: The papers W, M and V's laws; see :ref:`paper-w`.",
        "paper V: The papers W, M and V's laws; see :ref:`paper-w`.",
    ]
    # the reference to another paper's entry does not cite this one; code names are not papers
    assert uncited_papers("Paper V (:ref:`paper-s`).\n") == ["paper V: Paper V (:ref:`paper-s`)."]
    assert uncited_papers("``RigidSatellite.paper_p()`` and ``PAPER_P_INERTIA``.\n") == []
