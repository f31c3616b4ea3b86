"""A copy of the project in a temporary folder, where mutants are written and tests run.

The working files are never written: :class:`Sandbox` copies the project (without ``.git``,
virtual environments and caches), each mutant is written into the copy and the copy's file is
restored after the mutant's run, whatever happens (the run finishing, timing out, or the whole
check being interrupted). The child processes import the packages from the copy (it comes first
on ``PYTHONPATH``; the plugin's ``--mutation-root`` check fails a run that imported them from
anywhere else), write no byte-code (``PYTHONDONTWRITEBYTECODE``: a restored file never meets a
stale compiled mutant) and keep numba's cache inside the copy (a mutant of a module with compiled
functions gets a cache of its own, so its kernels are compiled from its own source).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import subprocess
import tempfile
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

from benchmarks.mutation.operators import Mutant, apply_mutant

__all__ = ["ChildResult", "Sandbox", "run_child"]

#: Folders and files never copied into the sandbox.
_SKIP = frozenset({".git", ".venv", "venv", "__pycache__", ".pytest_cache", ".ruff_cache", ".mypy_cache",
                   ".hypothesis", "_build", "node_modules"})
#: Where this toolkit's own packages live (for the plugin, when the project checked is another one).
_TOOLKIT_ROOT = Path(__file__).resolve().parents[2]


@dataclass(frozen=True)
class ChildResult:
    """How a child process ended: its exit code (``None`` if it was killed at the timeout)."""

    returncode: int | None
    output: str
    seconds: float


def run_child(cmd: Sequence[str], cwd: Path, env: dict[str, str], timeout: float | None) -> ChildResult:
    """Run ``cmd`` in a process group of its own, killed on timeout (reported) or interrupt (re-raised)."""
    start = time.perf_counter()
    proc = subprocess.Popen(list(cmd), cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            start_new_session=True, text=True, errors="replace")
    try:
        out, _ = proc.communicate(timeout=timeout)
        return ChildResult(proc.returncode, out, time.perf_counter() - start)
    except subprocess.TimeoutExpired:
        _kill_group(proc)
        out, _ = proc.communicate()
        return ChildResult(None, out, time.perf_counter() - start)
    except BaseException:
        _kill_group(proc)
        proc.communicate()
        raise


def _kill_group(proc: subprocess.Popen[str]) -> None:
    with contextlib.suppress(ProcessLookupError):
        os.killpg(proc.pid, signal.SIGKILL)


class Sandbox:
    """A temporary copy of the project at ``root``; use as a context manager (removed on exit).

    Parameters
    ----------
    root : Path
        The project to copy.
    exclude : sequence of Path
        Folders inside ``root`` not to copy (the output folder of the check, for instance).
    keep : bool
        Leave the copy on disk at exit (its path is in :attr:`path`).
    """

    def __init__(self, root: Path, exclude: Sequence[Path] = (), keep: bool = False) -> None:
        self.root = root.resolve()
        self.exclude = {p.resolve() for p in exclude}
        self.keep = keep
        self.path = Path(tempfile.mkdtemp(prefix="mutation-"))
        self.tree = self.path / "tree"
        self.numba_cache = self.path / "numba-cache"

    def __enter__(self) -> Sandbox:
        def ignore(folder: str, names: list[str]) -> set[str]:
            skip = {n for n in names if n in _SKIP or n.endswith(".egg-info")}
            skip |= {n for n in names if (Path(folder) / n).resolve() in self.exclude}
            return skip

        shutil.copytree(self.root, self.tree, ignore=ignore, symlinks=True)
        return self

    def __exit__(self, *exc: object) -> None:
        if not self.keep:
            shutil.rmtree(self.path, ignore_errors=True)

    def env(self, numba_cache: Path | None = None) -> dict[str, str]:
        """The environment of a child process: the copy first on the import path."""
        env = dict(os.environ)
        path = [str(self.tree), env.get("PYTHONPATH", ""), str(_TOOLKIT_ROOT)]
        env["PYTHONPATH"] = os.pathsep.join(p for p in path if p)
        env["PYTHONDONTWRITEBYTECODE"] = "1"
        env["NUMBA_CACHE_DIR"] = str(numba_cache or self.numba_cache)
        env.setdefault("MPLBACKEND", "Agg")
        return env

    @contextlib.contextmanager
    def mutated(self, mutant: Mutant) -> Iterator[dict[str, str]]:
        """Write ``mutant`` into the copy for the duration of the block; yields the child environment."""
        target = self.tree / mutant.path
        original = target.read_bytes()
        private = None
        try:
            target.write_text(apply_mutant(original.decode(), mutant), encoding="utf-8")
            if mutant.scope == "compiled" or b"numba" in original:
                private = Path(tempfile.mkdtemp(prefix="numba-", dir=self.path))
            yield self.env(private)
        finally:
            target.write_bytes(original)
            if private is not None:
                shutil.rmtree(private, ignore_errors=True)

    def pytest_command(self, python: str, args: Sequence[str]) -> list[str]:
        """``python -m pytest`` with the plugin loaded and no cache written."""
        return [python, "-m", "pytest", "-p", "benchmarks.mutation.plugin", "-p", "no:cacheprovider",
                f"--rootdir={self.tree}", *args]

