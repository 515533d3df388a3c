"""The pen tables (SQLite, in the server's database file beside the jobs).

One row per pen: its settings as JSON and its odometer in millimetres. `PenStore` is
blocking (sqlite3); the library calls it through its one writer thread, so the event
loop never waits on the disk. The table is additive to the jobs' schema (created if
missing), so the jobs' `user_version` does not change.
"""

from __future__ import annotations

import json
import threading
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Any

from plotbridge.database import connect
from plotbridge.pens.model import Pen

SCHEMA = """
CREATE TABLE IF NOT EXISTS pens (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    name TEXT NOT NULL UNIQUE COLLATE NOCASE,
    data TEXT NOT NULL,
    odometer_mm REAL NOT NULL DEFAULT 0
)
"""


class PenStore:
    def __init__(self, path: Path) -> None:
        self._lock = threading.Lock()
        self._db = connect(path, SCHEMA)
        self._writer = ThreadPoolExecutor(1, thread_name_prefix="plotbridge-pens")

    def close(self) -> None:
        self._writer.shutdown(wait=True)
        with self._lock:
            self._db.close()

    def load_all(self) -> list[tuple[Pen, float]]:
        """Every pen with its odometer in mm, by id (blocking; at start-up)."""
        with self._lock:
            rows = self._db.execute("SELECT id, data, odometer_mm FROM pens ORDER BY id").fetchall()
        return [(Pen(id=pen_id, **json.loads(data)), float(mm)) for pen_id, data, mm in rows]

    def submit(self, fn: Any, *args: Any) -> Future[Any]:
        """Run one of the blocking writes below on the writer thread."""
        return self._writer.submit(fn, *args)

    # ---- blocking writes (on the writer thread) -------------------------------------

    def insert(self, name: str, data: dict[str, Any]) -> int:
        with self._lock:
            cursor = self._db.execute("INSERT INTO pens (name, data) VALUES (?, ?)",
                                      (name, json.dumps(data)))  # fmt: skip
            return int(cursor.lastrowid or 0)

    def update(self, pen_id: int, name: str, data: dict[str, Any]) -> None:
        with self._lock:
            self._db.execute("UPDATE pens SET name = ?, data = ? WHERE id = ?",
                             (name, json.dumps(data), pen_id))  # fmt: skip

    def delete(self, pen_id: int) -> None:
        with self._lock:
            self._db.execute("DELETE FROM pens WHERE id = ?", (pen_id,))

    def set_odometers(self, odometers: dict[int, float]) -> None:
        """Every given pen's odometer (mm) in one transaction."""
        with self._lock:
            self._db.execute("BEGIN")
            try:
                rows = [(mm, pen_id) for pen_id, mm in odometers.items()]
                self._db.executemany("UPDATE pens SET odometer_mm = ? WHERE id = ?", rows)
                self._db.execute("COMMIT")
            except BaseException:
                self._db.execute("ROLLBACK")
                raise
