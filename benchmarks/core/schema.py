"""One validating schema for what a run reads back from disk: stored cases and their records.

A run that resumes (``rmpc bench methods``, a sweep) trusts nothing it reads: every stored case
goes through a schema built from the checks below, which gives the first thing that is wrong
(``"record.gamma: expected a finite number or null, found str 'abc'"``) or ``None``. A case that
fails is measured again, and the run says so.

A check is a callable ``check(value, where) -> str | None``; :func:`fields`, :func:`list_of`,
:func:`dict_of` and :func:`optional` build bigger checks from smaller ones.

Examples
--------
>>> from benchmarks.core.schema import NUMBER, STRING, fields, first_problem, optional
>>> case = fields({"name": STRING, "gamma": optional(NUMBER)})
>>> first_problem({"name": "a", "gamma": 0.5}, case, "case") is None
True
>>> first_problem({"name": "a", "gamma": "abc"}, case, "case")
"case.gamma: expected a finite number or null, found str 'abc'"
>>> first_problem({"gamma": 1.0}, case, "case")
'case: expected the key name, found none'
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

__all__ = [
    "BOOL",
    "INTEGER",
    "NUMBER",
    "STRING",
    "Check",
    "dict_of",
    "equal_to",
    "fields",
    "first_problem",
    "list_of",
    "one_of",
    "optional",
    "read_json_file",
]

Check = Callable[[Any, str], "str | None"]
"""``check(value, where)``: ``None`` when ``value`` fits, else one line saying what is wrong."""


def _found(value: Any) -> str:
    if value is None:
        return "null"
    text = repr(value)
    return f"{type(value).__name__} {text if len(text) <= 40 else text[:37] + '...'}"


def _at(where: str) -> str:
    return where or "the top level"


def _simple(expected: str, ok: Callable[[Any], bool]) -> Check:
    def check(value: Any, where: str) -> str | None:
        return None if ok(value) else f"{_at(where)}: expected {expected}, found {_found(value)}"

    check.expected = expected  # type: ignore[attr-defined]
    return check


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


NUMBER: Check = _simple("a finite number", _is_number)
INTEGER: Check = _simple("an integer", lambda v: isinstance(v, int) and not isinstance(v, bool))
STRING: Check = _simple("a string", lambda v: isinstance(v, str))
BOOL: Check = _simple("true or false", lambda v: isinstance(v, bool))


def _expected(check: Check) -> str:
    return str(getattr(check, "expected", "a valid value"))


def optional(check: Check) -> Check:
    """``check`` or ``null``."""

    def inner(value: Any, where: str) -> str | None:
        if value is None:
            return None
        problem = check(value, where)
        if problem is not None and problem.startswith(f"{_at(where)}: expected {_expected(check)},"):
            return f"{_at(where)}: expected {_expected(check)} or null, found {_found(value)}"
        return problem  # a problem inside the value says where it is

    inner.expected = f"{_expected(check)} or null"  # type: ignore[attr-defined]
    return inner


def equal_to(expected: Any, what: str) -> Check:
    """Exactly ``expected`` (``what`` names it in the message)."""

    def check(value: Any, where: str) -> str | None:
        return None if value == expected else f"{_at(where)}: expected {what}, found {_found(value)}"

    check.expected = what  # type: ignore[attr-defined]
    return check


def one_of(choices: tuple[str, ...]) -> Check:
    """One of the strings ``choices``."""
    return _simple("one of " + ", ".join(choices), lambda v: isinstance(v, str) and v in choices)


def list_of(item: Check, *, min_len: int = 0) -> Check:
    """A list (at least ``min_len`` long) whose every item passes ``item``."""

    def check(value: Any, where: str) -> str | None:
        if not isinstance(value, list):
            return f"{_at(where)}: expected a list, found {_found(value)}"
        if len(value) < min_len:
            return f"{_at(where)}: expected a list of at least {min_len} items, found {len(value)}"
        for i, v in enumerate(value):
            problem = item(v, f"{where}[{i}]")
            if problem is not None:
                return problem
        return None

    check.expected = "a list"  # type: ignore[attr-defined]
    return check


def dict_of(value_check: Check) -> Check:
    """An object whose every value passes ``value_check`` (keys are strings in JSON)."""

    def check(value: Any, where: str) -> str | None:
        if not isinstance(value, dict):
            return f"{_at(where)}: expected an object, found {_found(value)}"
        for k, v in value.items():
            problem = value_check(v, f"{where}.{k}")
            if problem is not None:
                return problem
        return None

    check.expected = "an object"  # type: ignore[attr-defined]
    return check


ANY_DICT: Check = dict_of(lambda v, w: None)


def fields(required: Mapping[str, Check], optional_fields: Mapping[str, Check] | None = None) -> Check:
    """An object with every key of ``required`` and, where present, the keys of ``optional_fields``,
    each passing its check (other keys are allowed: a reader ignores what it does not use)."""
    extra = dict(optional_fields or {})

    def check(value: Any, where: str) -> str | None:
        if not isinstance(value, dict):
            return f"{_at(where)}: expected an object, found {_found(value)}"
        missing = [k for k in required if k not in value]
        if missing:
            keys = ("the keys " if len(missing) > 1 else "the key ") + ", ".join(missing)
            return f"{_at(where)}: expected {keys}, found none"
        for k, sub in (*required.items(), *((k, c) for k, c in extra.items() if k in value)):
            problem = sub(value[k], f"{where}.{k}" if where else k)
            if problem is not None:
                return problem
        return None

    check.expected = "an object"  # type: ignore[attr-defined]
    return check


def first_problem(value: Any, check: Check, where: str = "") -> str | None:
    """The first thing in ``value`` that ``check`` refuses, or ``None``."""
    return check(value, where)


def _refuse_constant(name: str) -> Any:
    raise ValueError(f"{name} is not strict JSON")


def read_json_file(path: Path) -> tuple[Any, str | None]:
    """The strict JSON in ``path`` and ``None``, or ``None`` and why it cannot be read.

    A folder, a file that cannot be read, text that is not JSON (truncated, ``NaN``, not UTF-8):
    each gives ``(None, reason)``, never an exception.
    """
    if path.is_dir():
        return None, "a folder, not a file"
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        return None, f"unreadable ({type(err).__name__}: {err})"
    try:
        return json.loads(text, parse_constant=_refuse_constant), None
    except (ValueError, RecursionError) as err:
        return None, f"not JSON ({err})"
