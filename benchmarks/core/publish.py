"""A run's reports written together or not at all.

A suite writes ``results.json``, ``results.md``, ``results.csv``, ``run.json`` and its figures in
one go; if the writer fails half-way, a reader must not find a new ``results.json`` next to the
``results.md`` of the previous run. :func:`staged_reports` hands the writer a staging folder inside
the output folder; when the writer returns, every file it wrote replaces its namesake in the
output folder (a rename each, on the same file system), and when it raises, the staging folder is
removed and the output folder is left exactly as it was. Should a rename fail part-way (a folder
in a report's place), the files already moved are put back first.

A run killed while it publishes (SIGKILL, a power cut) leaves its hidden staging folder behind
(``.staging-<pid>-...``); the next run into the same output folder removes the ones whose process
is gone, and says so on the standard error (:func:`remove_stale_stages`). They are never read as
results: the reports are the files in the output folder itself, and :mod:`benchmarks.compare`
refuses a staging folder given as a run.

Examples
--------
>>> import tempfile
>>> from pathlib import Path
>>> with tempfile.TemporaryDirectory() as tmp:
...     out = Path(tmp)
...     _ = (out / "results.json").write_text("old")
...     try:
...         with staged_reports(out) as stage:
...             _ = (stage / "results.json").write_text("new")
...             raise RuntimeError("the writer failed")
...     except RuntimeError:
...         pass
...     (out / "results.json").read_text(), sorted(p.name for p in out.iterdir())
('old', ['results.json'])
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import sys
import tempfile
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path

from toolkit_common.errors import InvalidArgumentError

__all__ = ["STAGING_PREFIX", "published_paths", "remove_stale_stages", "staged_reports"]

STAGING_PREFIX = ".staging-"
"""The name's start of a staging folder (hidden): ``.staging-<pid>-<random>`` (``-old-`` for the
previous reports while they are replaced)."""
_PREFIX = STAGING_PREFIX
_OWNER = re.compile(r"^\.staging-(?:old-)?(\d+)-")


def _process_alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    return True


def remove_stale_stages(out: Path, notice: Callable[[str], None] | None = None) -> list[str]:
    """Remove the staging folders in ``out`` left by runs that were killed while they published.

    A staging folder whose process (the pid in its name) is gone, or whose name carries no pid
    (made before the pid was part of it), is removed; one of a run still going is left alone.
    ``notice`` (default: a line on the standard error) is told which were removed.

    Returns
    -------
    list of str
        The names of the folders removed.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     _ = (Path(tmp) / ".staging-999999999-x1").mkdir()
    ...     _ = (Path(tmp) / "results.json").write_text("{}")
    ...     removed = remove_stale_stages(Path(tmp), notice=lambda line: None)
    ...     removed, sorted(p.name for p in Path(tmp).iterdir())
    (['.staging-999999999-x1'], ['results.json'])
    """
    removed: list[str] = []
    try:
        entries = sorted(Path(out).iterdir())
    except OSError:
        return removed
    for entry in entries:
        if not entry.name.startswith(STAGING_PREFIX) or entry.is_symlink() or not entry.is_dir():
            continue
        owner = _OWNER.match(entry.name)
        if owner is not None and _process_alive(int(owner.group(1))):
            continue
        shutil.rmtree(entry, ignore_errors=True)
        if not entry.exists():
            removed.append(entry.name)
    if removed:
        line = (f"rmpc: removed {len(removed)} unfinished report folder(s) in {out} left by a run that "
                f"was killed while writing its reports: {', '.join(removed)}")
        if notice is None:
            print(line, file=sys.stderr, flush=True)
        else:
            notice(line)
    return removed


@contextlib.contextmanager
def staged_reports(out: Path, notice: Callable[[str], None] | None = None) -> Iterator[Path]:
    """A staging folder inside ``out`` whose files replace those of ``out`` when the block ends.

    Staging folders left in ``out`` by a killed run are removed first (:func:`remove_stale_stages`,
    which tells ``notice``).

    Raises
    ------
    InvalidArgumentError
        (``--out``) A report's place in ``out`` holds a folder; nothing of ``out`` is changed.
    """
    out = Path(out)
    remove_stale_stages(out, notice)
    stage = Path(tempfile.mkdtemp(prefix=f"{_PREFIX}{os.getpid()}-", dir=out))
    try:
        yield stage
        _publish(stage, out)
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def published_paths(paths: Sequence[Path], stage: Path, out: Path) -> list[Path]:
    """``paths`` written in ``stage`` as they are named once published in ``out`` (others as they are)."""
    moved = []
    for path in paths:
        try:
            moved.append(Path(out) / Path(path).relative_to(stage))
        except ValueError:
            moved.append(Path(path))
    return moved


def _publish(stage: Path, out: Path) -> None:
    files = sorted(p for p in stage.rglob("*") if not p.is_dir())
    targets = [(f, out / f.relative_to(stage)) for f in files]
    for _, target in targets:
        if target.is_dir():
            raise InvalidArgumentError(
                "--out",
                f"a folder where {target.name} can be written",
                f"a folder at {target}; nothing was written",
            )
    backup = Path(tempfile.mkdtemp(prefix=f"{_PREFIX}old-{os.getpid()}-", dir=out))
    done: list[tuple[Path, Path | None]] = []  # (target, its previous file moved to backup)
    try:
        for k, (new, target) in enumerate(targets):
            target.parent.mkdir(parents=True, exist_ok=True)
            old: Path | None = None
            if target.exists() or target.is_symlink():
                old = backup / str(k)
                os.replace(target, old)
            done.append((target, old))
            os.replace(new, target)
    except OSError as err:
        for target, old in reversed(done):
            with contextlib.suppress(OSError):
                if old is not None:
                    os.replace(old, target)
                else:
                    target.unlink()
        raise InvalidArgumentError(
            "--out",
            "a folder where the reports can be written",
            f"{type(err).__name__}: {err}; nothing was changed",
        ) from None
    finally:
        shutil.rmtree(backup, ignore_errors=True)
