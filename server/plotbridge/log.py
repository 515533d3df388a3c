"""Console logging: one line per meaningful event, written by a thread of its own.

The event loop never writes to the console itself: a write to a file or pipe blocks
when the disk is saturated (the kernel throttles a writer of dirty pages) or the reader
of the pipe is slow, and the emergency stop must not wait behind a log line. Records go
through a bounded queue to a writer thread; if that backs up, records are dropped and
counted rather than held.
"""

from __future__ import annotations

import atexit
import copy
import logging
import logging.handlers
import queue
import sys
from typing import TextIO

from plotbridge.guard import logs

LEVELS = ("debug", "info", "warning", "error")
QUEUE_RECORDS = 10_000  # records waiting for the writer before new ones are dropped


class _Handoff(logging.handlers.QueueHandler):
    """Hands a record to the writer thread without ever blocking the caller."""

    def __init__(self, records: queue.Queue[logging.LogRecord]) -> None:
        super().__init__(records)
        self.dropped = 0

    def prepare(self, record: logging.LogRecord) -> logging.LogRecord:
        record = copy.copy(record)
        record.msg, record.args = record.getMessage(), None  # the arguments may change later
        return record

    def enqueue(self, record: logging.LogRecord) -> None:
        if self.dropped:
            try:  # say once the writer catches up how much was lost
                self.queue.put_nowait(logging.makeLogRecord({
                    "name": __name__, "levelno": logging.WARNING, "levelname": "WARNING",
                    "msg": f"{self.dropped} log records dropped: the console was not keeping up",
                }))  # fmt: skip
                self.dropped = 0
            except queue.Full:
                pass
        try:
            self.queue.put_nowait(record)
        except queue.Full:
            self.dropped += 1


class _Writer(logging.handlers.QueueListener):
    def enqueue_sentinel(self) -> None:
        self.queue.put(self._sentinel)  # waits for room: at stop, everything queued is written


def handoff(stream: TextIO) -> tuple[logging.Handler, logging.handlers.QueueListener]:
    """A handler that never blocks, and the started thread writing its records to `stream`
    (escaped, repeats rate-limited: guard/logs.py); stop the writer to flush it."""
    console = logging.StreamHandler(stream)
    logs.format_escaped(console, "%(asctime)s %(levelname)-7s %(name)s: %(message)s", "%H:%M:%S")
    records: queue.Queue[logging.LogRecord] = queue.Queue(QUEUE_RECORDS)
    handler = _Handoff(records)
    logs.rate_limit(handler)  # keyed by the message template, so before the handoff merges it
    writer = _Writer(records, console)
    writer.start()
    return handler, writer


def setup(level: str) -> None:
    """Console logging (standard error) through the writer thread."""
    handler, writer = handoff(sys.stderr)
    atexit.register(writer.stop)  # what is queued is written before the process exits
    logging.basicConfig(level=getattr(logging, level.upper(), logging.INFO), handlers=[handler])
