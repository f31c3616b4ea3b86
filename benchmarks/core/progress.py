"""A progress bar (rich) on standard error, silent when standard error is not a terminal."""

from __future__ import annotations

from types import TracebackType
from typing import Any

__all__ = ["CaseProgress"]


class CaseProgress:
    """Progress over a number of cases: ``with CaseProgress(n, "paper") as bar: bar.advance(...)``.

    Parameters
    ----------
    total : int
        Number of cases to run.
    description : str
        Shown before the bar.
    enabled : bool, optional
        Force the bar on or off; by default it is shown only when standard error is a terminal,
        so logs and pipes stay clean.
    """

    def __init__(self, total: int, description: str, enabled: bool | None = None) -> None:
        from rich.console import Console

        self._console = Console(stderr=True)
        self.enabled = self._console.is_terminal if enabled is None else enabled
        self.total = total
        self.description = description
        self.failed = 0
        self._progress: Any = None
        self._task: Any = None

    def __enter__(self) -> CaseProgress:
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
        if not ok:
            self.failed += 1
        if self._progress is not None:
            mark = "" if ok else " [red](failed)[/red]"
            self._progress.update(self._task, advance=1, last=f"{label}{mark}")

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        if self._progress is not None:
            self._progress.stop()
