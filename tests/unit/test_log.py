"""Console logging (plotbridge/log.py): the caller never waits for the console."""

from __future__ import annotations

import io
import logging
import threading
import time

from plotbridge import log
from plotbridge.guard import logs


class StuckConsole(io.StringIO):
    """A console whose writes wait until released (a saturated disk, an unread pipe)."""

    def __init__(self) -> None:
        super().__init__()
        self.release = threading.Event()

    def write(self, text: str) -> int:
        self.release.wait(10)
        return super().write(text)


def logger_to(handler: logging.Handler, name: str) -> logging.Logger:
    logger = logging.getLogger(name)
    logger.propagate = False
    logger.setLevel(logging.INFO)
    logger.addHandler(handler)
    return logger


def test_a_stuck_console_never_blocks_the_caller():
    console = StuckConsole()
    handler, writer = log.handoff(console)
    logger = logger_to(handler, "test_log.stuck")
    try:
        began = time.monotonic()
        for n in range(50):
            logger.info("record %d of %s", n, "evil\nFORGED" if n == 0 else "x")
        assert time.monotonic() - began < 5.0  # the console holds each write for 10 s
    finally:
        console.release.set()
        writer.stop()
        logger.removeHandler(handler)
    lines = console.getvalue().splitlines()
    assert lines[0].endswith("test_log.stuck: record 0 of evil\\nFORGED")  # escaped
    assert len(lines) == logs.PER_WINDOW  # repeats of one template are limited


def test_records_the_console_cannot_take_are_dropped_and_counted(monkeypatch):
    monkeypatch.setattr(log, "QUEUE_RECORDS", 3)
    console = StuckConsole()
    handler, writer = log.handoff(console)
    logger = logger_to(handler, "test_log.full")
    try:
        for n in range(10):
            logger.warning(f"distinct record {n}")  # ten templates: none rate-limited
        console.release.set()
        deadline = time.monotonic() + 30
        while not handler.queue.empty() and time.monotonic() < deadline:  # the writer catches up
            time.sleep(0.01)
        logger.warning("after the jam")
    finally:
        console.release.set()
        writer.stop()
        logger.removeHandler(handler)
    text = console.getvalue()
    assert "distinct record 0" in text and "distinct record 9" not in text
    assert "log records dropped: the console was not keeping up" in text
    assert text.rstrip().endswith("after the jam")
