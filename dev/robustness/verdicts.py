"""The verdicts of the probe and how an outcome is classified."""

from __future__ import annotations

import traceback
from dataclasses import dataclass, field
from types import TracebackType

VERDICTS = ("clear", "unclear", "crash", "silent", "hang")
"""Every verdict, from the best to the worst for a user (``hang`` last)."""

TOOLKIT_PACKAGES = ("models", "lmi", "rmpc", "benchmarks", "toolkit_common")
"""Packages whose frames count as "the toolkit raised it on purpose"."""


@dataclass
class Outcome:
    """What one probe did.

    Attributes
    ----------
    verdict : str
        One of :data:`VERDICTS`.
    detail : str
        The exception's type and message, the CLI's stderr, or why the verdict was given.
    elapsed : float
        Seconds from the call to its answer (the time limit for a hang).
    """

    verdict: str
    detail: str
    elapsed: float
    extra: dict[str, object] = field(default_factory=dict)


def raised_by_toolkit(tb: TracebackType | None) -> bool:
    """Whether the innermost frame of ``tb`` is in one of the toolkit's packages."""
    frames = traceback.extract_tb(tb)
    if not frames:
        return False
    filename = frames[-1].filename.replace("\\", "/")
    return (
        any(f"/{package}/" in filename for package in TOOLKIT_PACKAGES)
        and "/site-packages/numpy" not in filename
    )


def classify_exception(error: BaseException, names: tuple[str, ...], found: tuple[str, ...] = ()) -> str:
    """The verdict for an API probe that raised ``error``; ``names`` are words the message should contain.

    ``clear`` needs a ``ValueError`` or ``TypeError`` raised by the toolkit's own code (not by numpy,
    scipy or the standard library passing through) whose message contains one of ``names``
    (compared without case) and, when ``found`` is given, one of ``found`` (what the user gave:
    "nan", "complex", "none"). A toolkit ``ValueError``/``TypeError`` without those words is
    ``unclear``; anything else (``MemoryError``, ``RecursionError``, ``IndexError``, a library's
    error) is a ``crash``.
    """
    if not isinstance(error, ValueError | TypeError):
        return "crash"
    if not raised_by_toolkit(error.__traceback__):
        return "crash"
    message = str(error).lower()
    named = not names or any(name.lower() in message for name in names)
    described = not found or any(word.lower() in message for word in found)
    return "clear" if named and described else "unclear"


def classify_cli(returncode: int | None, stderr: str, names: tuple[str, ...], *, expect_exit: int = 2) -> str:
    """The verdict for a CLI probe: exit ``expect_exit``, no traceback, one line naming one of ``names``.

    ``returncode`` None means the command did not finish in time (``hang``). Exit 0 where an error
    was expected is ``silent``. A traceback, or an exit status other than 0 and ``expect_exit``,
    is a ``crash``. The right exit status with a message that is several lines long or misses every
    word of ``names`` is ``unclear``.
    """
    if returncode is None:
        return "hang"
    if "Traceback (most recent call last)" in stderr:
        return "crash"
    if returncode == 0:
        return "silent"
    if returncode != expect_exit:
        return "crash"
    lines = [line for line in stderr.strip().splitlines() if line.strip()]
    usage = [line for line in lines if not line.startswith("usage:") and not line.startswith("  ")]
    message = "\n".join(usage).lower()
    if not usage or len(usage) > 1:
        return "unclear"
    if names and not any(name.lower() in message for name in names):
        return "unclear"
    return "clear"
