"""The pytest plugin of the mutation check, loaded in its child processes (``-p benchmarks.mutation.plugin``).

Two jobs, chosen by option:

``--mutation-trace OUT.json --mutation-targets FILE...``
    The map run: a line tracer (:func:`sys.settrace`, every thread) records which lines of the
    target files each test runs. Lines run while a fixture is set up are kept for that fixture
    and given to every test that uses it, so a module-scoped fixture that solves a problem once
    counts for all the tests that read its result. Writes, per test, its outcome, its duration
    and its lines; the lines run outside any test (imports) are recorded too.
``--mutation-select IDS.json``
    A mutant's run: only the listed tests run, in the listed order (fastest first, so that with
    ``-x`` a caught mutant stops early). ``--mutation-root DIR`` makes the run fail with a usage
    error if a module of a target package was imported from anywhere but ``DIR`` (the copy that
    holds the mutant), so a mutant can never be tested against the working files by mistake.

This module imports nothing of the toolkit.
"""

from __future__ import annotations

import json
import sys
import threading
import time
from collections.abc import Generator
from pathlib import Path
from typing import Any

import pytest

__all__ = ["LineTracer"]


class LineTracer:
    """Records the lines run in a set of files, into the context (test or fixture) that is current.

    Parameters
    ----------
    files : collection of str
        Absolute paths of the files to trace (as code objects name them).
    """

    def __init__(self, files: Any) -> None:
        self.files = {str(f): i for i, f in enumerate(files)}
        self.hits: set[tuple[int, int]] = set()
        self._stack: list[set[tuple[int, int]]] = []

    def _global(self, frame: Any, event: str, arg: Any) -> Any:
        index = self.files.get(frame.f_code.co_filename)
        if index is None:
            return None
        self.hits.add((index, frame.f_lineno))
        return _bound(self.hits, index)  # the frame's own tracer, which knows its file

    def start(self) -> None:
        """Trace this thread and every thread started from now on."""
        threading.settrace(self._global)
        sys.settrace(self._global)

    def stop(self) -> None:
        """Stop tracing (threads already running keep their tracer until they return)."""
        sys.settrace(None)
        threading.settrace(None)  # type: ignore[arg-type]

    def push(self) -> None:
        """Enter a new context: the lines recorded so far go to the enclosing one."""
        self._stack.append(set(self.hits))
        self.hits.clear()

    def pop(self) -> set[tuple[int, int]]:
        """Leave the current context and return its lines; the enclosing context resumes."""
        lines = set(self.hits)
        self.hits.clear()
        self.hits.update(self._stack.pop())
        return lines


def _bound(hits: set[tuple[int, int]], index: int) -> Any:
    add = hits.add

    def local(frame: Any, event: str, arg: Any) -> Any:
        if event == "line":
            add((index, frame.f_lineno))
        return local

    return local


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("mutation", "mutation check (benchmarks.mutation)")
    group.addoption("--mutation-trace", default=None, help="write the per-test line map to this JSON file")
    group.addoption("--mutation-targets", default=None, help="JSON file: the absolute paths to trace")
    group.addoption("--mutation-select", default=None, help="JSON file: the node ids to run, in order")
    group.addoption("--mutation-root", default=None, help="the target packages must be imported from here")
    group.addoption("--mutation-packages", default="", help="comma-separated top-level packages to check")


class _TracePlugin:
    def __init__(self, out: Path, files: list[str]) -> None:
        self.out = out
        self.files = files
        self.tracer = LineTracer(files)
        self.fixture_lines: dict[int, set[tuple[int, int]]] = {}
        self.tests: list[dict[str, Any]] = []
        self.outside: set[tuple[int, int]] = set()
        self._current: dict[str, Any] | None = None
        self.tracer.start()

    @pytest.hookimpl(hookwrapper=True)
    def pytest_fixture_setup(self, fixturedef: Any, request: Any) -> Generator[None, None, None]:
        self.tracer.push()
        try:
            yield
        finally:
            self.fixture_lines.setdefault(id(fixturedef), set()).update(self.tracer.pop())

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_protocol(self, item: pytest.Item, nextitem: Any) -> Generator[None, None, None]:
        self.tracer.push()
        self._current = {"nodeid": item.nodeid, "passed": True, "ran": False, "duration": 0.0}
        try:
            yield
        finally:
            lines = self.tracer.pop()
            info = getattr(item, "_fixtureinfo", None)
            for name in getattr(item, "fixturenames", ()):
                for fixturedef in (info.name2fixturedefs.get(name, ()) if info is not None else ()):
                    lines |= self.fixture_lines.get(id(fixturedef), set())
            record = self._current
            record["passed"] = record["passed"] and record.pop("ran")
            record["lines"] = sorted(lines)
            self.tests.append(record)
            self._current = None

    def pytest_runtest_logreport(self, report: pytest.TestReport) -> None:
        if self._current is None:
            return
        self._current["duration"] += report.duration
        if report.when == "call":
            self._current["ran"] = True
        if report.outcome != "passed":
            self._current["passed"] = False

    def pytest_sessionfinish(self, session: pytest.Session) -> None:
        self.tracer.stop()
        self.outside |= self.tracer.hits
        data = {
            "files": self.files,
            "tests": self.tests,
            "outside": sorted(self.outside),
            "finished": time.time(),
        }
        self.out.write_text(json.dumps(data), encoding="utf-8")


class _SelectPlugin:
    def __init__(self, order: list[str]) -> None:
        self.rank = {nodeid: i for i, nodeid in enumerate(order)}

    def pytest_collection_modifyitems(self, config: pytest.Config, items: list[pytest.Item]) -> None:
        keep = [item for item in items if item.nodeid in self.rank]
        drop = [item for item in items if item.nodeid not in self.rank]
        keep.sort(key=lambda item: self.rank[item.nodeid])
        if drop:
            config.hook.pytest_deselected(items=drop)
        items[:] = keep


class _RootGuard:
    def __init__(self, root: Path, packages: list[str]) -> None:
        self.root = root.resolve()
        self.packages = packages

    def pytest_collection_finish(self, session: pytest.Session) -> None:
        for name, module in list(sys.modules.items()):
            if name.split(".")[0] not in self.packages:
                continue
            file = getattr(module, "__file__", None)
            if file is not None and not Path(file).resolve().is_relative_to(self.root):
                raise pytest.UsageError(f"mutation check: {name} was imported from {file}, "
                                        f"not from {self.root}")


def pytest_configure(config: pytest.Config) -> None:
    trace = config.getoption("--mutation-trace")
    if trace:
        files = json.loads(Path(config.getoption("--mutation-targets")).read_text(encoding="utf-8"))
        config.pluginmanager.register(_TracePlugin(Path(trace), files), "mutation-trace")
    select = config.getoption("--mutation-select")
    if select:
        order = json.loads(Path(select).read_text(encoding="utf-8"))
        config.pluginmanager.register(_SelectPlugin(order), "mutation-select")
    root = config.getoption("--mutation-root")
    packages = [p for p in config.getoption("--mutation-packages").split(",") if p]
    if root and packages:
        config.pluginmanager.register(_RootGuard(Path(root), packages), "mutation-root")
