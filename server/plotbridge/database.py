"""The server's SQLite file (`DATA_DIR/plotbridge.db`): one way to open it, shared by
the tables that keep their own connection (jobs, pens, the webhook outbox)."""

from __future__ import annotations

import sqlite3
from pathlib import Path


def connect(path: Path, schema: str) -> sqlite3.Connection:
    """A connection usable from a writer thread, in autocommit, with `schema` applied.
    WAL journaling with synchronous=FULL: every commit reaches the disk (the WAL is
    fsynced) before it returns, so a job the server has acknowledged survives a kill -9
    and a power cut (a Raspberry Pi's usual way to stop); NORMAL would lose the last
    commits on a power cut. The cost is one fsync per commit, on the writer thread."""
    db = sqlite3.connect(path, check_same_thread=False, isolation_level=None)
    db.execute("PRAGMA journal_mode=WAL")
    db.execute("PRAGMA synchronous=FULL")
    db.execute(schema)
    return db
