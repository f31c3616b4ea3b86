"""A run's reports written together or not at all.

A suite writes ``results.json``, ``results.md``, ``results.csv``, ``run.json`` and its figures in
one go; if the writer fails half-way, a reader must not find a new ``results.json`` next to the
``results.md`` of the previous run. :func:`staged_reports` hands the writer a staging folder inside
the output folder; when the writer returns, every file it wrote replaces its namesake in the
output folder (a rename each, on the same file system), and when it raises, the staging folder is
removed and the output folder is left exactly as it was. Should a rename fail part-way (a folder
in a report's place), the files already moved are put back first.

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
import shutil
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path

from toolkit_common.errors import InvalidArgumentError

__all__ = ["published_paths", "staged_reports"]

_PREFIX = ".staging-"


@contextlib.contextmanager
def staged_reports(out: Path) -> Iterator[Path]:
    """A staging folder inside ``out`` whose files replace those of ``out`` when the block ends.

    Raises
    ------
    InvalidArgumentError
        (``--out``) A report's place in ``out`` holds a folder; nothing of ``out`` is changed.
    """
    out = Path(out)
    stage = Path(tempfile.mkdtemp(prefix=_PREFIX, dir=out))
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
    backup = Path(tempfile.mkdtemp(prefix=_PREFIX + "old-", dir=out))
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
