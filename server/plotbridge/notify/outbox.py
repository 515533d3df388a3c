"""Webhook events not yet delivered, kept in the server's SQLite file so that a restart
or a crash loses none of them.

One row per event and URL, numbered in the order the events were queued (`seq`). A
row is written when its event is queued and removed once the receiver took it,
refused it for good, or the bounded queue dropped it; the rows left at start-up are
the queues to deliver first. The table is additive to the jobs' schema (created if
missing), like the pens'.

The sqlite3 work is blocking, so it runs on one writer thread: `add`, `remove` and
`forget` never wait (they run inside the event hub's publish), `open` and `close` are
awaited. One thread keeps the writes in the order they were asked for: a row is
always inserted before it is removed. Limits: a kill within the few milliseconds
between queueing an event and its row reaching the file loses that event; a kill
between a receiver's 2xx and the row's removal posts it once more after the restart,
with the same `id` (receivers recognise repeats by it anyway, see delivery.py).
"""

from __future__ import annotations

import asyncio
import logging
import sqlite3
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from plotbridge.database import connect

log = logging.getLogger("plotbridge.notify")

SCHEMA = """
CREATE TABLE IF NOT EXISTS webhook_outbox (
    seq INTEGER PRIMARY KEY,
    url TEXT NOT NULL,
    event TEXT NOT NULL,
    body BLOB NOT NULL
)
"""


@dataclass(frozen=True)
class Pending:
    """One event waiting for one URL: its row number, name and encoded body."""

    seq: int
    event: str
    body: bytes


class Outbox:
    def __init__(self, path: Path) -> None:
        self.path = path
        self._db: sqlite3.Connection | None = None
        self._writer = ThreadPoolExecutor(1, thread_name_prefix="plotbridge-webhooks")
        self._next_seq = 1
        self._closed = False

    async def open(self) -> dict[str, list[Pending]]:
        """Opens the table; the events still waiting, per URL, oldest first."""
        rows = await asyncio.wrap_future(self._writer.submit(self._open))
        waiting: dict[str, list[Pending]] = {}
        for seq, url, event, body in rows:
            waiting.setdefault(url, []).append(Pending(seq, event, bytes(body)))
        self._next_seq = (rows[-1][0] + 1) if rows else 1
        return waiting

    async def close(self) -> None:
        """Waits for the writes asked for so far, then closes the file."""
        if self._closed:
            return
        self._closed = True
        await asyncio.wrap_future(self._writer.submit(self._close))
        self._writer.shutdown(wait=False)

    # ---- from the event loop: never wait ------------------------------------------------

    def add(self, url: str, event: str, body: bytes) -> Pending:
        pending = Pending(self._next_seq, event, body)
        self._next_seq += 1
        self._submit(self._write, "INSERT INTO webhook_outbox (seq, url, event, body) "
                     "VALUES (?, ?, ?, ?)", (pending.seq, url, event, body))  # fmt: skip
        return pending

    def remove(self, pending: Pending) -> None:
        self._submit(self._write, "DELETE FROM webhook_outbox WHERE seq = ?", (pending.seq,))

    def forget(self, url: str) -> None:
        """Every event still waiting for `url` (no longer a webhook)."""
        self._submit(self._write, "DELETE FROM webhook_outbox WHERE url = ?", (url,))

    def _submit(self, work: Callable[..., None], *args: Any) -> None:
        try:
            self._writer.submit(work, *args).add_done_callback(self._failed)
        except RuntimeError:  # closed: the server is stopping, the row stays as it was
            log.warning("webhook events: a write after closing %s was not done", self.path)

    def _failed(self, done: Future[None]) -> None:
        if (exc := done.exception()) is not None:
            log.error("webhook events could not be kept in %s (%s: %s): a restart would "
                      "lose them", self.path, type(exc).__name__, exc)  # fmt: skip

    # ---- on the writer thread -----------------------------------------------------------

    def _open(self) -> list[tuple[int, str, str, bytes]]:
        self._db = connect(self.path, SCHEMA)
        return self._db.execute(
            "SELECT seq, url, event, body FROM webhook_outbox ORDER BY seq").fetchall()

    def _write(self, sql: str, args: tuple[Any, ...]) -> None:
        if self._db is None:
            raise RuntimeError("the outbox is not open")
        self._db.execute(sql, args)

    def _close(self) -> None:
        if self._db is not None:
            self._db.close()
            self._db = None
