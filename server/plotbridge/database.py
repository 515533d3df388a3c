"""The server's SQLite file (`DATA_DIR/plotbridge.db`): one way to open it, shared by
the tables that keep their own connection (jobs, pens, the webhook outbox)."""

from __future__ import annotations

import sqlite3
from pathlib import Path


def connect(path: Path, schema: str) -> sqlite3.Connection:
    """A connection usable from a writer thread, in autocommit, with WAL journaling and
    no fsync per commit (WAL: a kill -9 loses nothing committed), and `schema` applied."""
    db = sqlite3.connect(path, check_same_thread=False, isolation_level=None)
    db.execute("PRAGMA journal_mode=WAL")
    db.execute("PRAGMA synchronous=NORMAL")
    db.execute(schema)
    return db
