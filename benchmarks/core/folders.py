"""Whether an output folder can be written, tried before a command spends its time."""

from __future__ import annotations

import os
import tempfile

__all__ = ["not_writable"]


def not_writable(path: str | os.PathLike[str]) -> str | None:
    """Why no file can be made in ``path`` or, if it does not exist, in the folder above it that does.

    Tried with a temporary file (removed at once), so it holds for the superuser and on read-only
    mounts, where the permission bits say nothing. ``None`` when a file can be made there.

    Examples
    --------
    >>> import tempfile
    >>> not_writable(tempfile.gettempdir()) is None
    True
    """
    folder = os.path.abspath(path)
    while not os.path.exists(folder):
        folder = os.path.dirname(folder)
    if not os.path.isdir(folder):
        return f"{folder!r} above it is a file"
    try:
        handle, name = tempfile.mkstemp(dir=folder, prefix=".rmpc-write-test-")
    except OSError as err:
        if folder == os.path.abspath(path):
            return f"not writable: {err.strerror or err}"
        return f"it does not exist and {folder!r} above it is not writable: {err.strerror or err}"
    os.close(handle)
    os.unlink(name)
    return None
