"""Progress over the cases of a run, on standard error.

On a terminal a live bar (``rich``); otherwise (a log file, a pipe, a batch job) one plain line
per finished case, ``title: n/total label (elapsed s)``, so a run that is not watched on a terminal
still says how far it has come.
"""

from __future__ import annotations

import sys
import time
from types import TracebackType
from typing import Any, TextIO

__all__ = ["CaseProgress"]


class CaseProgress:
    """Progress over a number of cases: ``with CaseProgress(n, "paper") as bar: bar.advance(...)``.

    Parameters
    ----------
    total : int
        Number of cases to run.
    description : str
        Shown before the bar (or at the start of each plain line).
    enabled : bool, optional
        ``None`` (default): a bar when standard error is a terminal, else one plain line per
        finished case. ``True``: the bar. ``False``: nothing at all.
    stream : text stream, optional
        Where the plain lines go (default: ``sys.stderr`` at the time of the call).

    Examples
    --------
    >>> import io
    >>> buf = io.StringIO()
    >>> with CaseProgress(2, "demo", stream=buf) as bar:
    ...     bar.advance("case a")
    ...     bar.advance("case b", ok=False)
    >>> [line.split(" (")[0] for line in buf.getvalue().splitlines()]
    ['demo: 1/2 case a', 'demo: 2/2 case b failed']
    """

    def __init__(
        self, total: int, description: str, enabled: bool | None = None, stream: TextIO | None = None
    ) -> None:
        from rich.console import Console

        self._console = Console(stderr=True)
        self.enabled = self._console.is_terminal if enabled is None else enabled
        # Plain lines: the default asked for on something that is not a terminal.
        self.plain = enabled is None and not self.enabled
        self.total = total
        self.description = description
        self.failed = 0
        self.done = 0
        self._stream = stream
        self._start = time.perf_counter()
        self._progress: Any = None
        self._task: Any = None

    def __enter__(self) -> CaseProgress:
        self._start = time.perf_counter()
        if self.enabled:
            from rich.progress import (
                BarColumn,
                MofNCompleteColumn,
                Progress,
                TextColumn,
                TimeElapsedColumn,
                TimeRemainingColumn,
            )

            self._progress = Progress(
                TextColumn("[bold]{task.description}"),
                BarColumn(),
                MofNCompleteColumn(),
                TextColumn("{task.fields[last]}"),
                TimeElapsedColumn(),
                TimeRemainingColumn(),
                console=self._console,
            )
            self._progress.start()
            self._task = self._progress.add_task(self.description, total=self.total, last="")
        return self

    def advance(self, label: str, ok: bool = True) -> None:
        """One case finished (``ok=False``: it failed)."""
        self.done += 1
        if not ok:
            self.failed += 1
        if self._progress is not None:
            mark = "" if ok else " [red](failed)[/red]"
            self._progress.update(self._task, advance=1, last=f"{label}{mark}")
        elif self.plain:
            stream = self._stream if self._stream is not None else sys.stderr
            elapsed = time.perf_counter() - self._start
            mark = "" if ok else " failed"
            stream.write(f"{self.description}: {self.done}/{self.total} {label}{mark} ({elapsed:.0f} s)\n")
            stream.flush()

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        if self._progress is not None:
            self._progress.stop()
