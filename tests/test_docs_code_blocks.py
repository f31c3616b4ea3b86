"""Every ``code-block:: python`` in the docs runs, or says why it does not.

The blocks of a page run in the order they appear, in one namespace, as a reader would type
them. Three reST comments, invisible in the built pages, go with a block:

``.. snippet-setup:``
    right before the block, an indented body of code that defines what the block takes from
    the surrounding text (``plant``, ``Q``, ``x0``); it runs just before the block.
``.. snippet-check:``
    right after the block, an indented body of assertions on what the block or its comments
    claim (``# 15, 115.11``); it runs just after the block.
``.. not-runnable: reason``
    right before the block: the block is not run (only compiled), and the reason must be given.

A block whose last lines are a comment ``# SomeError: message`` shows an error: it must raise
that exception with that message (whitespace aside). A marker that is not next to a python code
block, or a ``not-runnable`` without a reason, fails.
"""

from __future__ import annotations

import re
import textwrap
from dataclasses import dataclass
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parent.parent / "docs"

_BLOCK = re.compile(r"^(\s*)\.\. (?:code-block|code|sourcecode)::\s*python3?\s*$")
_MARKER = re.compile(r"^(\s*)\.\. (not-runnable|snippet-setup|snippet-check):(.*)$")
_ERROR = re.compile(r"^#\s*(\w+(?:Error|Exception|Warning)):\s*(.*)$")


@dataclass
class Block:
    """One python code block of a page and the markers that go with it."""

    page: str
    line: int
    code: str
    setup: str = ""
    check: str = ""
    reason: str | None = None


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip())


def _body(lines: list[str], i: int) -> tuple[str, int]:
    """The indented body under line ``i`` (dedented) and the index of the first line after it."""
    j = i + 1
    while j < len(lines) and (not lines[j].strip() or _indent(lines[j]) > _indent(lines[i])):
        j += 1
    return textwrap.dedent("\n".join(lines[i + 1 : j])).strip("\n"), j


def _next_item(lines: list[str], j: int) -> int:
    while j < len(lines) and not lines[j].strip():
        j += 1
    return j


def parse(page: str, text: str) -> tuple[list[Block], list[str]]:
    """The python code blocks of a page with their markers, and the misplaced markers.

    Parameters
    ----------
    page : str
        The page's name, for messages.
    text : str
        The page's reST source.

    Returns
    -------
    blocks : list of Block
        In the order of the page.
    errors : list of str
        One line per marker that is not next to a python code block of its indentation, or a
        ``not-runnable`` without a reason.
    """
    lines = text.splitlines()
    blocks: list[Block] = []
    errors: list[str] = []
    pending: tuple[str, str] | None = None  # (kind, text) of a marker waiting for its block
    after_block = -1  # index of the first item after the last block's body
    i = 0
    while i < len(lines):
        marker, block = _MARKER.match(lines[i]), _BLOCK.match(lines[i])
        if marker is None and block is None:
            i += 1
            continue
        body, j = _body(lines, i)
        where = f"{page}:{i + 1}"
        if marker is not None:
            kind, head = marker.group(2), marker.group(3).strip()
            if kind == "snippet-check":
                if i != after_block or _indent(lines[i]) != _indent(lines[blocks[-1].line - 1]):
                    errors.append(f"{where}: snippet-check does not follow a python code block")
                else:
                    blocks[-1].check = body
            else:
                nxt = _next_item(lines, j)
                target = _BLOCK.match(lines[nxt]) if nxt < len(lines) else None
                if target is None or _indent(lines[nxt]) != _indent(lines[i]):
                    errors.append(f"{where}: {kind} is not followed by a python code block")
                elif kind == "not-runnable" and not " ".join([head, body]).strip():
                    errors.append(f"{where}: not-runnable gives no reason")
                else:
                    pending = (kind, " ".join([head, body]).strip() if kind == "not-runnable" else body)
            i = j
            continue
        code_lines = body.splitlines()
        while code_lines and code_lines[0].lstrip().startswith(":"):  # the directive's options
            code_lines.pop(0)
        found = Block(page, i + 1, textwrap.dedent("\n".join(code_lines)).strip("\n"))
        if pending is not None:
            kind, content = pending
            if kind == "not-runnable":
                found.reason = content
            else:
                found.setup = content
            pending = None
        blocks.append(found)
        after_block = _next_item(lines, j)
        i = j
    return blocks, errors


def _pages() -> dict[str, str]:
    return {page.name: page.read_text(encoding="utf-8") for page in sorted(DOCS.glob("*.rst"))}


def _expected_error(code: str) -> tuple[str, str] | None:
    """``(name, message)`` if the block ends with a ``# SomeError: message`` comment."""
    tail: list[str] = []
    for line in reversed(code.splitlines()):
        if not line.lstrip().startswith("#"):
            break
        tail.insert(0, line.strip())
    for k, line in enumerate(tail):
        match = _ERROR.match(line)
        if match:
            rest = [part.lstrip("#").strip() for part in tail[k + 1 :]]
            return match.group(1), " ".join([match.group(2), *rest]).strip()
    return None


def _run(block: Block, namespace: dict[str, object]) -> None:
    where = f"docs/{block.page}:{block.line}"
    if block.setup:
        exec(compile(block.setup, f"{where} (snippet-setup)", "exec"), namespace)
    expected = _expected_error(block.code)
    code = compile(block.code, where, "exec")
    if expected is None:
        exec(code, namespace)
    else:
        name, message = expected
        with pytest.raises(Exception) as raised:  # the type is checked by name below
            exec(code, namespace)
        assert type(raised.value).__name__ == name, f"{where}: raised {raised.value!r}, documented {name}"
        assert " ".join(str(raised.value).split()) == " ".join(message.split()), (
            f"{where}: the message differs from the documented one:\n{raised.value}\n---\n{message}"
        )
    if block.check:
        exec(compile(block.check, f"{where} (snippet-check)", "exec"), namespace)


_PAGES = {name: parse(name, text) for name, text in _pages().items()}
_RUNNABLE = sorted(name for name, (blocks, _) in _PAGES.items() if any(b.reason is None for b in blocks))


def test_markers_sit_next_to_python_code_blocks() -> None:
    errors = [error for _, page_errors in _PAGES.values() for error in page_errors]
    assert not errors, "\n".join(errors)
    assert sum(len(blocks) for blocks, _ in _PAGES.values()) > 0, "no python code block found"
    for blocks, _ in _PAGES.values():
        for block in blocks:
            if block.reason is not None:  # not run, but still python
                compile(block.code, f"docs/{block.page}:{block.line}", "exec")


@pytest.mark.parametrize("page", _RUNNABLE)
def test_python_code_blocks_run(page: str) -> None:
    namespace: dict[str, object] = {"__name__": "__docs__"}
    blocks = _PAGES[page][0]
    for block in blocks:
        if block.reason is None:
            _run(block, namespace)


def test_the_parser_attaches_markers_and_finds_misplaced_ones() -> None:
    text = textwrap.dedent(
        """
        .. snippet-setup:
           a = 1

        .. code-block:: python

           b = a + 1

        .. snippet-check:
           assert b == 2

        .. not-runnable: needs a flight computer

        .. code-block:: python

           fly()

        .. not-runnable:

        .. code-block:: python

           land()

        .. snippet-setup:
           c = 1

        Some text.

        .. code-block:: python

           c
        """
    )
    blocks, errors = parse("page.rst", text)
    assert [(b.code, b.setup, b.check, b.reason) for b in blocks] == [
        ("b = a + 1", "a = 1", "assert b == 2", None),
        ("fly()", "", "", "needs a flight computer"),
        ("land()", "", "", None),
        ("c", "", "", None),
    ]
    assert errors == [
        "page.rst:18: not-runnable gives no reason",
        "page.rst:24: snippet-setup is not followed by a python code block",
    ]


def test_a_documented_error_must_be_raised_with_its_message() -> None:
    ok = Block("page.rst", 1, 'raise ValueError("x: bad")\n# ValueError: x:\n#   bad')
    _run(ok, {})
    wrong_message = Block("page.rst", 1, 'raise ValueError("x: worse")\n# ValueError: x: bad')
    with pytest.raises(AssertionError, match="message differs"):
        _run(wrong_message, {})
    no_error = Block("page.rst", 1, "y = 1\n# ValueError: x: bad")
    with pytest.raises(pytest.fail.Exception):
        _run(no_error, {})
