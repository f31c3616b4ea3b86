"""A probe: one input tried through the API or the command line, and what a good answer is."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

Expect = Literal["error", "either"]
"""``"error"``: the input must be refused; ``"either"``: an edge input that may be accepted (with a
finite answer) or refused clearly."""


@dataclass(frozen=True)
class Probe:
    """One bad or edge input.

    Attributes
    ----------
    id : str
        ``"<target>.<argument>:<value>"`` for the API, ``"cli:<what>"`` for the command line.
    group : {"api", "cli"}
        Through which door the input goes.
    names : tuple of str
        Words a clear message contains (the argument's or option's name, the file); one is enough.
    found : tuple of str
        Words that describe what the user gave (``"nan"``, ``"complex"``, ``"none"``); when given,
        a clear message also contains one of them.
    call : callable, optional
        API probes: the call (no arguments), run in a child process.
    argv : sequence of str, optional
        CLI probes: the arguments after ``rmpc``; ``{tmp}`` is replaced by a scratch folder.
    setup : callable, optional
        CLI probes: ``setup(tmp)`` prepares files in the scratch folder before the command runs.
    expect : {"error", "either"}
        What a good answer is.
    kind : str
        The class the input belongs to (``"nan"``, ``"shape"``, ``"size"``, ``"store"``...), for the tables.
    """

    id: str
    group: Literal["api", "cli"]
    names: tuple[str, ...]
    found: tuple[str, ...] = ()
    call: Callable[[], Any] | None = None
    argv: Sequence[str] = field(default_factory=tuple)
    setup: Callable[[str], None] | None = None
    expect: Expect = "error"
    kind: str = "value"
