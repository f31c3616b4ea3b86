"""The embedded SQLite store of a sweep: one row per case, committed as soon as it finishes.

Schema (``DIR/sweep.sqlite``, WAL journal so a reader never blocks the writer)::

    runs(run INTEGER PRIMARY KEY, started_at REAL, command TEXT)
    cases(case_id TEXT PRIMARY KEY, position INTEGER, scenario TEXT, status TEXT,
          record TEXT, error TEXT, run INTEGER, finished_at REAL)

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

import json
import sqlite3
import time
from pathlib import Path
from types import TracebackType
from typing import Any

__all__ = ["STORE_NAME", "CaseStore"]

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
"""


class CaseStore:
    """Finished cases of a sweep in an SQLite file (created if missing).

    Parameters
    ----------
    path : str or Path
        The database file.
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self._db = sqlite3.connect(self.path, timeout=30.0)
        self._db.execute("PRAGMA journal_mode=WAL")
        self._db.execute("PRAGMA synchronous=NORMAL")
        self._db.executescript(_SCHEMA)
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
        cur = self._db.execute("INSERT INTO runs (started_at, command) VALUES (?, ?)", (time.time(), command))
        self._db.commit()
        return int(cur.lastrowid)

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

    def rows(self) -> list[dict[str, Any]]:
        """Every stored case in sweep order: ``case_id, position, scenario, status, record,
        error, run, finished_at`` (JSON columns decoded)."""
        cur = self._db.execute(
            "SELECT case_id, position, scenario, status, record, error, run, finished_at FROM cases"
            " ORDER BY position, case_id"
        )
        out = []
        for cid, pos, scen, status, record, error, run, fin in cur:
            out.append(
                {
                    "case_id": cid,
                    "position": pos,
                    "scenario": json.loads(scen),
                    "status": status,
                    "record": None if record is None else json.loads(record),
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
