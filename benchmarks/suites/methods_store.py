"""The stored cases of ``rmpc bench methods`` (``DIR/cases/<problem>__<method>.json``): schema, read, write.

A stored case is ``{"settings": ..., "record": ..., "extra": ...}``. :func:`load_case` hands it
back only when it passes :data:`CASE_SCHEMA` (the type of every field the report reads) and is
the case asked for (its problem, method, suite settings and record version); otherwise it says
why, and the suite measures the case again. :func:`store_case` writes through a temporary file
in the same folder and never leaves it behind.

Examples
--------
>>> import tempfile
>>> from pathlib import Path
>>> with tempfile.TemporaryDirectory() as tmp:
...     path = case_path(Path(tmp), "kothare_ex1", "kothare")
...     _ = path.parent.mkdir()
...     _ = path.write_text('{"settings": {"seed": 0}}')
...     load_case(path, {"seed": 0}, "kothare_ex1", "kothare", 1)
(None, 'the top level: expected the key record, found none')
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from pathlib import Path
from typing import Any

from benchmarks.core.jsonable import json_safe
from benchmarks.core.schema import (
    ANY_DICT,
    BOOL,
    INTEGER,
    NUMBER,
    STRING,
    Check,
    dict_of,
    fields,
    first_problem,
    list_of,
    optional,
    read_json_file,
)

__all__ = ["CASE_SCHEMA", "RECORD_SCHEMA", "case_path", "load_case", "store_case"]

_NUM = optional(NUMBER)
_COUNTS = dict_of(INTEGER)

_REGION: Check = fields(
    {
        "t": list_of(NUMBER, min_len=1),
        "limits": list_of(STRING),
        "ended_by": _COUNTS,
        "geo_mean_t": NUMBER,
        "min_t": NUMBER,
        "t_x0": _NUM,
        "capped": BOOL,
        "directions": INTEGER,
        "status_counts": _COUNTS,
    }
)

_RECORD_SETTINGS: Check = fields(
    {
        "options": ANY_DICT,
        "n_states": INTEGER,
        "n_inputs": INTEGER,
        "n_vertices": INTEGER,
        "dt": NUMBER,
        "u_max": NUMBER,
        "input_constraint": STRING,
        "x0": list_of(NUMBER, min_len=1),
        "suite": ANY_DICT,
        "record_version": INTEGER,
    }
)

#: Every field of a record that the report reads, with its type.
RECORD_SCHEMA: Check = fields(
    {
        "problem": STRING,
        "method": STRING,
        "status": STRING,
        "gamma": _NUM,
        "iterations": optional(INTEGER),
        "solve_time_p50": _NUM,
        "solve_time_p95": _NUM,
        "cvxpy_time_p50": _NUM,
        "region": optional(_REGION),
        "closed_loop_cost": _NUM,
        "closed_loop_cost_switching": _NUM,
        "status_counts": _COUNTS,
        "skip_reason": optional(STRING),
        "comparable": BOOL,
        "notes": list_of(STRING),
        "settings": _RECORD_SETTINGS,
    },
    {
        "cvxpy_ratio": _NUM,
        "ipm_time_same_states_p50": _NUM,
        "slack": dict_of(_NUM),
        "x0_solve_time": _NUM,
        "closed_loop_steps": INTEGER,
        "closed_loop_max_abs_u": _NUM,
        "closed_loop_final_norm": _NUM,
        "solves": INTEGER,
        "case_time_s": _NUM,
    },
)

_POINTS = optional(list_of(list_of(_NUM, min_len=1)))

#: A stored case: the suite settings it was measured with, the record and the figures' data.
CASE_SCHEMA: Check = fields(
    {"settings": ANY_DICT, "record": RECORD_SCHEMA},
    {"extra": fields({}, {"region_points": _POINTS, "trajectory": _POINTS})},
)


def case_path(out: Path, problem: str, method: str) -> Path:
    """Where the case ``problem`` x ``method`` of a run in ``out`` is stored."""
    return out / "cases" / f"{problem}__{method}.json"


def load_case(
    path: Path, settings: dict[str, Any], problem: str, method: str, record_version: int
) -> tuple[dict[str, Any] | None, str | None]:
    """The stored case at ``path`` and ``None``, or ``None`` and why it is not used.

    Parameters
    ----------
    path : Path
        The case file.
    settings : dict
        The run's suite settings (:meth:`MethodsSettings.as_dict`).
    problem, method : str
        The case asked for.
    record_version : int
        The record layout this build writes.

    Returns
    -------
    stored : dict or None
        The case (``settings``, ``record``, ``extra``), when it fits the schema and is this case
        measured with these settings.
    reason : str or None
        Why it is not used (``None`` also when there is no file: nothing to say).
    """
    if not path.exists() and not path.is_symlink():
        return None, None
    stored, reason = read_json_file(path)
    if reason is not None:
        return None, reason
    problem_found = first_problem(stored, CASE_SCHEMA)
    if problem_found is not None:
        return None, problem_found
    rec = stored["record"]
    for key, want in (("problem", problem), ("method", method)):
        if rec[key] != want:
            return None, f"the record of another case (record.{key} {rec[key]!r}, not {want!r})"
    if rec["settings"]["record_version"] != record_version:
        return None, f"record version {rec['settings']['record_version']}, this build writes {record_version}"
    wanted = json_safe(settings)
    if stored["settings"] != wanted or rec["settings"]["suite"] != wanted:
        return None, "measured with other suite settings"
    stored.setdefault("extra", {})
    return stored, None


def store_case(
    path: Path, settings: dict[str, Any], rec: dict[str, Any], extra: dict[str, Any]
) -> str | None:
    """Write the case to ``path`` (the old file or the new one, never half of one); ``None`` when
    it is stored, else why not (a folder in its place, a read-only ``cases/``): the run goes on."""
    payload = json.dumps(json_safe({"settings": settings, "record": rec, "extra": extra}), allow_nan=False)
    tmp: str | None = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        if path.is_dir():
            return f"{path} is a folder"
        fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=".tmp", dir=path.parent)
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(payload + "\n")
        os.replace(tmp, path)  # atomic: an interrupt leaves the old file or the new one
        tmp = None
    except OSError as err:
        return f"{path}: {type(err).__name__}: {err.strerror or err}"
    finally:
        if tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
    return None
