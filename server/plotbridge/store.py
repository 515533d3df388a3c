"""SQLite job store (WAL): one row per job, the job object kept as JSON.

Blocking by design (sqlite3); the job manager calls it from one worker thread so
the event loop never waits on the disk.
"""

from __future__ import annotations

import json
import sqlite3
import threading
from pathlib import Path
from typing import Any

SCHEMA = """
CREATE TABLE IF NOT EXISTS jobs (
    id TEXT PRIMARY KEY,
    position INTEGER NOT NULL,
    data TEXT NOT NULL
)
"""


class JobStore:
    def __init__(self, path: Path) -> None:
        self.path = path
        self._lock = threading.Lock()
        self._db = sqlite3.connect(path, check_same_thread=False, isolation_level=None)
        self._db.execute("PRAGMA journal_mode=WAL")
        self._db.execute("PRAGMA synchronous=NORMAL")
        self._db.execute(SCHEMA)

    def close(self) -> None:
        with self._lock:
            self._db.close()

    def load_all(self) -> list[dict[str, Any]]:
        """Every job, in queue order."""
        with self._lock:
            rows = self._db.execute("SELECT data FROM jobs ORDER BY position, id").fetchall()
        return [json.loads(row[0]) for row in rows]

    def save(self, job: dict[str, Any], position: int) -> None:
        with self._lock:
            self._db.execute(
                "INSERT INTO jobs (id, position, data) VALUES (?, ?, ?) "
                "ON CONFLICT(id) DO UPDATE SET position = excluded.position, data = excluded.data",
                (job["id"], position, json.dumps(job)),
            )

    def set_order(self, ids: list[str]) -> None:
        """Rewrite every job's position from its index in `ids` (one transaction)."""
        with self._lock:
            self._db.execute("BEGIN")
            try:
                self._db.executemany(
                    "UPDATE jobs SET position = ? WHERE id = ?",
                    [(index, job_id) for index, job_id in enumerate(ids)],
                )
                self._db.execute("COMMIT")
            except BaseException:
                self._db.execute("ROLLBACK")
                raise

    def delete(self, job_id: str) -> None:
        with self._lock:
            self._db.execute("DELETE FROM jobs WHERE id = ?", (job_id,))

    def journal_mode(self) -> str:
        with self._lock:
            return self._db.execute("PRAGMA journal_mode").fetchone()[0]
