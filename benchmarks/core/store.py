"""The embedded SQLite store of a sweep: one row per case, committed as soon as it finishes.

Schema (``DIR/sweep.sqlite``, WAL journal so a reader never blocks the writer)::

    runs(run INTEGER PRIMARY KEY, started_at REAL, command TEXT)
    cases(case_id TEXT PRIMARY KEY, position INTEGER, scenario TEXT, status TEXT,
          record TEXT, error TEXT, run INTEGER, finished_at REAL)
    meta(key TEXT PRIMARY KEY, value TEXT)      -- key 'sweep': the sweep's name

``status`` is ``"done"`` (``record`` holds the JSON record) or ``"error"`` (``error`` holds
the one-line error, ``record`` the traceback and scenario). A case id is the primary key, so
a case is stored at most once; ``run`` says which invocation of the sweep finished it.

Examples
--------
>>> import tempfile, os
>>> from benchmarks.core.store import CaseStore
>>> with tempfile.TemporaryDirectory() as tmp:
...     with CaseStore(os.path.join(tmp, "s.sqlite")) as store:
...         run = store.begin_run("example")
...         store.put_done("abc", 0, {"plant": "linear"}, {"metrics": {}}, run)
...         store.finished_ids()
{'abc'}
"""

from __future__ import annotations

import contextlib
import json
import sqlite3
import time
from collections.abc import Iterator
from pathlib import Path
from types import TracebackType
from typing import Any

from benchmarks.core.schema import (
    ANY_DICT,
    NUMBER,
    STRING,
    Check,
    dict_of,
    fields,
    first_problem,
    optional,
)
from toolkit_common.errors import StoreError

__all__ = ["RECORD_SCHEMA", "STORE_NAME", "CaseStore"]

#: File name of the store inside a sweep's output directory.
STORE_NAME = "sweep.sqlite"

_SCHEMA = """
CREATE TABLE IF NOT EXISTS runs (
    run INTEGER PRIMARY KEY AUTOINCREMENT,
    started_at REAL NOT NULL,
    command TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS cases (
    case_id TEXT PRIMARY KEY,
    position INTEGER NOT NULL,
    scenario TEXT NOT NULL,
    status TEXT NOT NULL CHECK (status IN ('done', 'error')),
    record TEXT,
    error TEXT,
    run INTEGER NOT NULL,
    finished_at REAL NOT NULL
);
CREATE TABLE IF NOT EXISTS meta (
    key TEXT PRIMARY KEY,
    value TEXT NOT NULL
);
"""

_COLUMNS = {
    "runs": ("run", "started_at", "command"),
    "cases": ("case_id", "position", "scenario", "status", "record", "error", "run", "finished_at"),
    "meta": ("key", "value"),
}
_NUM = optional(NUMBER)
_PER_AXIS = dict_of(_NUM)

#: A stored record of a finished case: every field the sweep's report reads, with its type.
RECORD_SCHEMA: Check = fields(
    {
        "experiment": STRING,
        "case_id": STRING,
        "label": STRING,
        "controller": STRING,
        "plant": STRING,
        "saturation": STRING,
        "status": STRING,
        "settings": ANY_DICT,
        "metrics": fields(
            {},
            {
                **{
                    k: _PER_AXIS
                    for k in ("sum_abs_err", "final_abs_err", "iae", "settling_time", "overshoot")
                },
                **{
                    k: _NUM
                    for k in (
                        "max_abs_u", "saturated_fraction", "constraint_violation", "solve_time_solves_p50",
                        "solve_time_solves_p95", "solve_time_solves_max", "n_solves", "step_time_p95",
                        "fallback_count", "failure_count",
                    )
                },
            },
        ),
    }
)
_ERROR_RECORD: Check = optional(fields({}, {"traceback": STRING}))

_EXPECTED = "the SQLite store of a sweep"
_REMEDY = "move it away or choose another --out"


def _found(err: sqlite3.Error) -> str:
    """What an SQLite error says about the file, and what to do."""
    text = str(err)
    if "locked" in text:
        return f"a store locked by another process ({text}); wait for the other sweep or choose another --out"
    if "not a database" in text:
        return f"a file that is not an SQLite database ({text}); {_REMEDY}"
    if "malformed" in text:
        return f"a damaged SQLite file ({text}); {_REMEDY}"
    return f"a file SQLite cannot use ({text}); {_REMEDY}"


class CaseStore:
    """Finished cases of a sweep in an SQLite file (created if missing).

    Parameters
    ----------
    path : str or Path
        The database file.
    """

    def __init__(self, path: str | Path, *, timeout: float = 30.0) -> None:
        self.path = Path(path)
        if self.path.is_dir():
            raise StoreError(str(self.path), _EXPECTED, f"a folder; {_REMEDY}")
        try:
            self._db = sqlite3.connect(self.path, timeout=timeout)
        except sqlite3.Error as err:
            raise StoreError(str(self.path), _EXPECTED, _found(err)) from None
        try:
            self._db.execute("PRAGMA journal_mode=WAL")
            self._db.execute("PRAGMA synchronous=NORMAL")
            self._db.executescript(_SCHEMA)
            self._db.commit()
            self._check_schema()
        except sqlite3.Error as err:
            self._db.close()
            raise StoreError(str(self.path), _EXPECTED, _found(err)) from None
        except StoreError:
            self._db.close()
            raise

    def _check_schema(self) -> None:
        """A table of this name made by another program (other columns) is refused."""
        for table, columns in _COLUMNS.items():
            found = tuple(row[1] for row in self._db.execute(f"PRAGMA table_info({table})"))
            if found != columns:
                raise StoreError(
                    str(self.path), _EXPECTED,
                    f"a table {table!r} with the columns {', '.join(found)} (another program's file); "
                    + _REMEDY,
                )

    def sweep_name(self) -> str | None:
        """The name of the sweep this store belongs to (None for a new store or one written before
        stores recorded it)."""
        row = self._db.execute("SELECT value FROM meta WHERE key = 'sweep'").fetchone()
        return None if row is None else str(row[0])

    def claim(self, name: str, case_ids: set[str], *, overwrite: bool = False) -> None:
        """Make this the store of the sweep ``name`` whose cases are ``case_ids``.

        A store of another sweep (its recorded name differs, or it records none and holds no case
        of this sweep) is refused with :class:`StoreError`, unless ``overwrite``: then its cases
        and runs are deleted first.
        """
        owner = self.sweep_name()
        stored = self.finished_ids()
        unrelated = owner is None and bool(stored) and not stored & case_ids
        foreign = (owner is not None and owner != name) or unrelated
        if foreign and not overwrite:
            found = f"the store of the sweep {owner!r}" if owner is not None else (
                f"a store of {len(stored)} cases none of which is in this sweep"
            )
            raise StoreError(
                "--out", f"a new folder or one of the sweep {name!r} (--overwrite replaces it)", found
            )
        if foreign:
            self._db.execute("DELETE FROM cases")
            self._db.execute("DELETE FROM runs")
        self._db.execute("INSERT OR REPLACE INTO meta (key, value) VALUES ('sweep', ?)", (name,))
        self._db.commit()

    def __enter__(self) -> CaseStore:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()

    def close(self) -> None:
        """Close the connection (every write is already committed)."""
        self._db.close()

    def begin_run(self, command: str) -> int:
        """Register an invocation of the sweep; return its run number (1, 2, ...)."""
        with self._sqlite_errors():
            cur = self._db.execute(
                "INSERT INTO runs (started_at, command) VALUES (?, ?)", (time.time(), command)
            )
            self._db.commit()
        return int(cur.lastrowid)

    @contextlib.contextmanager
    def _sqlite_errors(self) -> Iterator[None]:
        """An SQLite error inside (a lock held too long, a damaged page) as a :class:`StoreError`."""
        try:
            yield
        except sqlite3.Error as err:
            raise StoreError(str(self.path), _EXPECTED, _found(err)) from None

    def _put(
        self,
        case_id: str,
        position: int,
        scenario: dict[str, Any],
        status: str,
        record: Any,
        error: str | None,
        run: int,
    ) -> None:
        with self._sqlite_errors():
            self._db.execute(
                "INSERT OR REPLACE INTO cases"
                " (case_id, position, scenario, status, record, error, run, finished_at)"
                " VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
                (
                    case_id,
                    position,
                    json.dumps(scenario, sort_keys=True),
                    status,
                    None if record is None else json.dumps(record, allow_nan=False),
                    error,
                    run,
                    time.time(),
                ),
            )
            self._db.commit()

    def put_done(
        self, case_id: str, position: int, scenario: dict[str, Any], record: dict[str, Any], run: int
    ) -> None:
        """Store a finished case and commit."""
        self._put(case_id, position, scenario, "done", record, None, run)

    def put_error(
        self, case_id: str, position: int, scenario: dict[str, Any], error: str, detail: str, run: int
    ) -> None:
        """Store a case that raised (one-line ``error``, ``detail`` the traceback) and commit."""
        self._put(case_id, position, scenario, "error", {"traceback": detail}, error, run)

    def finished_ids(self, include_errors: bool = True) -> set[str]:
        """Ids of the stored cases (``include_errors=False``: only those that succeeded)."""
        sql = "SELECT case_id FROM cases" + ("" if include_errors else " WHERE status = 'done'")
        return {row[0] for row in self._db.execute(sql)}

    def unusable(self, scenarios: dict[str, dict[str, Any]]) -> dict[str, str]:
        """The stored cases among ``scenarios`` (case id -> the case's scenario as a dict) that
        cannot be trusted, each with why: a column that is not JSON, a row that does not fit
        :data:`RECORD_SCHEMA`, or another case's scenario or record under this case's id.

        A sweep measures these cases again (a new row replaces the old one).
        """
        with self._sqlite_errors():
            raw = list(self._db.execute("SELECT case_id, scenario, status, record, error FROM cases"))
        out = {}
        for cid, scen, status, record, error in raw:
            if cid in scenarios:
                why = _row_problem(cid, scenarios[cid], scen, status, record, error)
                if why is not None:
                    out[cid] = why
        return out

    def rows(self, scenarios: dict[str, dict[str, Any]] | None = None) -> list[dict[str, Any]]:
        """Every stored case in sweep order: ``case_id, position, scenario, status, record,
        error, run, finished_at`` (JSON columns decoded).

        With ``scenarios`` (case id -> scenario dict): only the cases among them that
        :meth:`unusable` does not refuse. Without: every row, and a column that is not JSON is a
        :class:`StoreError`.
        """
        cur = self._db.execute(
            "SELECT case_id, position, scenario, status, record, error, run, finished_at FROM cases"
            " ORDER BY position, case_id"
        )
        out = []
        for cid, pos, scen, status, record, error, run, fin in cur:
            if scenarios is not None and (
                cid not in scenarios or _row_problem(cid, scenarios[cid], scen, status, record, error)
            ):
                continue
            try:
                scenario = json.loads(scen)
                decoded = None if record is None else json.loads(record)
            except (TypeError, ValueError, RecursionError) as err:
                raise StoreError(
                    str(self.path), "cases stored as JSON",
                    f"case {cid!r} holding text that is not JSON ({err}); the store is damaged: move it away "
                    "or choose another --out to run the sweep afresh",
                ) from None
            out.append(
                {
                    "case_id": cid,
                    "position": pos,
                    "scenario": scenario,
                    "status": status,
                    "record": decoded,
                    "error": error,
                    "run": run,
                    "finished_at": fin,
                }
            )
        return out

    def count(self) -> dict[str, int]:
        """Number of stored cases per status."""
        return {
            status: n for status, n in self._db.execute("SELECT status, COUNT(*) FROM cases GROUP BY status")
        }


def _row_problem(
    cid: str, expected: dict[str, Any], scen: Any, status: Any, record: Any, error: Any
) -> str | None:
    """Why the stored row of case ``cid`` cannot be trusted (``None``: it can)."""
    try:
        scenario = json.loads(scen)
        decoded = None if record is None else json.loads(record)
    except (TypeError, ValueError, RecursionError) as err:
        return f"a column that is not JSON ({str(err)[:80]})"
    if scenario != json.loads(json.dumps(expected, sort_keys=True)):
        return "the scenario stored under this id is another case's"
    if status == "done":
        problem = first_problem(decoded, RECORD_SCHEMA, "record")
        if problem is not None:
            return problem
        if decoded["case_id"] != cid:
            return f"the record of another case (record.case_id {decoded['case_id']!r})"
        return None
    if status == "error":
        if not isinstance(error, str):
            return "an error row without its message"
        return first_problem(decoded, _ERROR_RECORD, "record")
    return f"status {status!r}, not 'done' or 'error'"
