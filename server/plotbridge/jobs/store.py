"""SQLite job store (WAL): one row per job, the job kept as JSON, in queue order.

`JobStore` is blocking by design (sqlite3). The queue writes through `writer`,
one worker thread, so the event loop never waits on the disk; jobs are
snapshotted on the loop before they go to it.

Schema versions (`PRAGMA user_version`):
- 0: one server, one plotter; a job does not name its plotter.
- 1: several plotters; a job that has run names its `plotter`. Migrating 0 -> 1
  gives every job that ran (or was interrupted) the first plotter's name, so it
  resumes where it was.
"""

from __future__ import annotations

import json
import logging
import threading
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Any

from plotbridge.database import connect
from plotbridge.jobs.model import Job

log = logging.getLogger("plotbridge.jobs.store")

SCHEMA_VERSION = 1
SCHEMA = """
CREATE TABLE IF NOT EXISTS jobs (
    id TEXT PRIMARY KEY,
    position INTEGER NOT NULL,
    data TEXT NOT NULL
)
"""


class JobStore:
    def __init__(self, path: Path, first_plotter: str) -> None:
        self.path = path
        self._lock = threading.Lock()
        self._db = connect(path, SCHEMA)
        self._migrate(first_plotter)
        self._writer = ThreadPoolExecutor(1, thread_name_prefix="plotbridge-db")

    @property
    def version(self) -> int:
        with self._lock:
            return int(self._db.execute("PRAGMA user_version").fetchone()[0])

    def _migrate(self, first_plotter: str) -> None:
        version = self.version
        if version > SCHEMA_VERSION:
            raise RuntimeError(f"{self.path} was written by a newer plotbridge "
                               f"(schema {version}, this one knows {SCHEMA_VERSION})")
        if version == 0:
            with self._lock:
                self._db.execute("BEGIN")
                try:
                    rows = self._db.execute("SELECT id, data FROM jobs").fetchall()
                    for job_id, data in rows:
                        job = json.loads(data)
                        if job.get("state") != "queued" and not job.get("plotter"):
                            job["plotter"] = first_plotter
                        self._db.execute("UPDATE jobs SET data = ? WHERE id = ?",
                                         (json.dumps(job), job_id))
                    self._db.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
                    self._db.execute("COMMIT")
                except BaseException:
                    self._db.execute("ROLLBACK")
                    raise
            if rows:
                log.info("store migrated to schema %d: %d jobs", SCHEMA_VERSION, len(rows))

    def close(self) -> None:
        self._writer.shutdown(wait=True)
        with self._lock:
            self._db.close()

    def load_all(self) -> list[Job]:
        """Every job, in queue order (blocking; at start-up)."""
        with self._lock:
            rows = self._db.execute("SELECT data FROM jobs ORDER BY position, id").fetchall()
        return [Job.model_validate(json.loads(row[0])) for row in rows]

    # ---- writes: from the event loop, done by the writer thread -------------------

    def save(self, job: Job, position: int) -> Future[None]:
        return self._writer.submit(self.write, job.record(), position)

    def set_order(self, ids: list[str]) -> Future[None]:
        return self._writer.submit(self.write_order, ids)

    def delete(self, job_id: str) -> Future[None]:
        return self._writer.submit(self.write_delete, job_id)

    # ---- blocking writes ------------------------------------------------------------

    def write(self, record: dict[str, Any], position: int) -> None:
        with self._lock:
            self._db.execute(
                "INSERT INTO jobs (id, position, data) VALUES (?, ?, ?) "
                "ON CONFLICT(id) DO UPDATE SET position = excluded.position, data = excluded.data",
                (record["id"], position, json.dumps(record)),
            )

    def write_order(self, ids: list[str]) -> None:
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

    def write_delete(self, job_id: str) -> None:
        with self._lock:
            self._db.execute("DELETE FROM jobs WHERE id = ?", (job_id,))

    def journal_mode(self) -> str:
        with self._lock:
            return self._db.execute("PRAGMA journal_mode").fetchone()[0]
