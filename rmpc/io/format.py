"""The controller file: one UTF-8 JSON document with a versioned envelope and a checksum.

A file written by ``ctrl.save(path)`` holds one JSON object::

    {"format": "rmpc-controller", "version": 1, "kind": "RMPC",
     "toolkit_version": "0.1.0", "design": {...}, "sha256": "..."}

``design`` is the controller's design (:mod:`rmpc.io.design`; per class, its ``_design``
method), numbers written by Python's ``repr`` of a float (which reads back to the same bits) and
the non-finite ones as the strings ``"inf"``, ``"-inf"`` and ``"nan"`` (strict JSON has none).
``sha256`` is the hexadecimal SHA-256 of the *canonical* text of the other five fields (keys
sorted, no spaces, UTF-8), so a changed byte anywhere in them is found on reading. The file is
written to a temporary file in the same folder and moved over ``path`` with :func:`os.replace`:
an interrupted save leaves the old file (or none), never half of one.

:data:`VERSION` is the one this toolkit writes; it reads every version up to it. A file of a
newer version is refused (written by a newer toolkit), never guessed at. ``docs/save_load.rst``
states the fields and the versioning policy.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from importlib import metadata
from pathlib import Path
from typing import Any

from toolkit_common.errors import ArgumentTypeError, ControllerFileError
from toolkit_common.validation import is_integer

__all__ = ["FORMAT", "VERSION", "ControllerFile", "canonical", "checksum", "read_file", "write_file"]

#: The ``format`` field of every controller file.
FORMAT = "rmpc-controller"
#: The version this toolkit writes (and the newest it reads).
VERSION = 1
#: The fields the checksum covers, besides ``sha256`` itself.
_FIELDS = ("format", "version", "kind", "toolkit_version", "design")


def canonical(payload: dict[str, Any]) -> bytes:
    """The canonical UTF-8 text of ``payload``: keys sorted, no spaces, no NaN literals."""
    return json.dumps(payload, sort_keys=True, separators=(",", ":"), ensure_ascii=False,
                      allow_nan=False).encode("utf-8")


def checksum(payload: dict[str, Any]) -> str:
    """The hexadecimal SHA-256 of :func:`canonical` of the checked fields of ``payload``."""
    return hashlib.sha256(canonical({key: payload[key] for key in _FIELDS})).hexdigest()


def _toolkit_version() -> str:
    try:
        return metadata.version("rmpc-satellite")
    except metadata.PackageNotFoundError:  # a source tree run without an install
        return "unknown"


class ControllerFile:
    """A read (and checked) controller file: its ``kind``, ``design`` and envelope.

    Attributes
    ----------
    path : Path
    kind : str
        The controller's class name (:data:`rmpc.io.registry.KINDS`).
    version : int
        The file's format version.
    toolkit_version : str
        The version of the toolkit that wrote it.
    design : dict
        The design, as JSON values.
    """

    def __init__(self, path: Path, kind: str, version: int, toolkit_version: str, design: dict[str, Any]):
        self.path, self.kind, self.version = path, kind, version
        self.toolkit_version, self.design = toolkit_version, design

    def __repr__(self) -> str:
        return f"ControllerFile({str(self.path)!r}, kind={self.kind!r}, version={self.version})"


def _path(path: Any) -> Path:
    if not isinstance(path, str | os.PathLike):
        raise ArgumentTypeError("path", "a file path (str or os.PathLike)", type(path).__name__)
    return Path(path)


def write_file(path: Any, kind: str, design: dict[str, Any]) -> Path:
    """Write the controller file of ``kind`` with ``design`` (JSON values) to ``path``, atomically.

    Raises
    ------
    ControllerFileError
        When ``path`` is a folder, its folder does not exist, or the file cannot be written.
    """
    target = _path(path)
    folder = target.parent if str(target.parent) else Path(".")
    if target.is_dir():
        raise ControllerFileError(str(target), "a file path to write the controller to", "a directory")
    if not folder.is_dir():
        found = "a file" if folder.exists() else "no such folder"
        raise ControllerFileError(str(target), f"a path in an existing folder ({folder})", found)
    payload: dict[str, Any] = {
        "format": FORMAT, "version": VERSION, "kind": kind, "toolkit_version": _toolkit_version(),
        "design": design,
    }
    try:
        payload["sha256"] = checksum(payload)
    except ValueError as err:  # a NaN or inf the design encoder did not turn into a string
        raise ControllerFileError(str(target), "a design of finite numbers or their string forms",
                                  str(err)) from None
    text = json.dumps(payload, sort_keys=True, ensure_ascii=False, allow_nan=False) + "\n"
    # the file keeps the mode of the one it replaces (a new one: rw-r--r--, not mkstemp's rw-------)
    mode = target.stat().st_mode & 0o777 if target.exists() else 0o644
    handle, temp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=folder)
    try:
        os.chmod(temp, mode)
        with os.fdopen(handle, "w", encoding="utf-8") as stream:
            stream.write(text)
            stream.flush()
            os.fsync(stream.fileno())
        os.replace(temp, target)
    except BaseException as err:
        Path(temp).unlink(missing_ok=True)
        if isinstance(err, OSError):
            found = f"{type(err).__name__}: {err}"
            raise ControllerFileError(str(target), "a writable file", found) from None
        raise
    return target


def read_file(path: Any) -> ControllerFile:
    """Read and check a controller file: its envelope, version and checksum.

    Raises
    ------
    ControllerFileError
        Naming the file and what is wrong: missing, a directory, not UTF-8 or not JSON (a
        truncated file says so), not a controller file (``format``), a newer ``version``, a
        checksum that does not match (a damaged file).
    """
    source = _path(path)
    name = str(source)
    if source.is_dir():
        raise ControllerFileError(name, "a controller file", "a directory")
    try:
        raw = source.read_bytes()
    except FileNotFoundError:
        raise ControllerFileError(name, "an existing controller file", "no such file") from None
    except OSError as err:
        found = f"{type(err).__name__}: {err}"
        raise ControllerFileError(name, "a readable controller file", found) from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as err:
        found = f"bytes that are not UTF-8 ({err})"
        raise ControllerFileError(name, "a UTF-8 JSON controller file", found) from None
    if not text.strip():
        raise ControllerFileError(name, "a JSON controller file", "an empty file")
    try:
        payload = json.loads(text, parse_constant=_no_constant)
    except json.JSONDecodeError as err:
        if err.pos >= len(text.rstrip()) or err.msg.startswith("Unterminated string"):
            found = f"a JSON document that ends early at character {err.pos} (a truncated file)"
        else:
            found = f"text that is not JSON ({err.msg} at line {err.lineno}, column {err.colno})"
        raise ControllerFileError(name, "a JSON controller file", found) from None
    except ValueError as err:
        raise ControllerFileError(name, "a JSON controller file", str(err)) from None
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        fmt = payload.get("format") if isinstance(payload, dict) else None
        found = f"format {fmt!r}" if fmt is not None else f"a JSON {type(payload).__name__} without 'format'"
        raise ControllerFileError(name, f"a controller file (format {FORMAT!r})",
                                  f"{found}: not a controller file")
    version = payload.get("version")
    if not is_integer(version) or version < 1:
        raise ControllerFileError(name, "a format version (an integer >= 1)", repr(version))
    if version > VERSION:
        writer = payload.get("toolkit_version", "unknown")
        raise ControllerFileError(
            name, f"format version {VERSION} or older (what this toolkit reads)",
            f"version {version}, written by toolkit {writer}: load it with a newer toolkit",
        )
    missing = [key for key in (*_FIELDS, "sha256") if key not in payload]
    if missing:
        raise ControllerFileError(name, "every field of a controller file", f"missing {', '.join(missing)}")
    if payload["sha256"] != checksum(payload):
        raise ControllerFileError(
            name, "a file whose sha256 matches its content",
            "a checksum that does not match: the file is damaged (or was edited by hand)",
        )
    kind, design = payload["kind"], payload["design"]
    if not isinstance(kind, str) or not isinstance(design, dict):
        raise ControllerFileError(name, "a kind (str) and a design (object)",
                                  f"{type(kind).__name__} and {type(design).__name__}")
    return ControllerFile(source, kind, version, str(payload["toolkit_version"]), design)


def _no_constant(token: str) -> Any:
    raise ValueError(f"the non-JSON constant {token} (non-finite numbers are written as strings)")
