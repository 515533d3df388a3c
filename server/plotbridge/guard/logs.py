"""Log hygiene: user text escaped, repeated messages rate-limited.

A file name with a newline must not forge a log line, a NUL must not reach the
journal, and an attacker must not be able to fill the disk with one message.
"""

from __future__ import annotations

import logging
import time

WINDOW = 10.0  # s
PER_WINDOW = 20  # records of one (logger, message template) per window


def escape(text: str) -> str:
    """Control characters as escapes ('\\n', '\\x00'); printable text unchanged."""
    if text.isprintable():
        return text
    return "".join(ch if ch.isprintable() else ch.encode("unicode_escape").decode() for ch in text)


class EscapingFormatter(logging.Formatter):
    def formatMessage(self, record: logging.LogRecord) -> str:
        record.message = escape(record.message)
        return super().formatMessage(record)


class RateLimit(logging.Filter):
    """At most PER_WINDOW records per message template and WINDOW; the next record
    after a suppressed burst says how many were left out."""

    def __init__(self) -> None:
        super().__init__()
        self.windows: dict[tuple[str, object], list[float | int]] = {}

    def filter(self, record: logging.LogRecord) -> bool:
        key = (record.name, record.msg)
        now = time.monotonic()
        window = self.windows.get(key)
        if window is None or now - window[0] > WINDOW:
            suppressed = int(window[2]) if window else 0
            self.windows[key] = [now, 1, 0]
            if len(self.windows) > 1000:
                self.windows = {key: self.windows[key]}
            if suppressed:
                record.msg = f"{record.msg} ({suppressed} similar messages suppressed)"
            return True
        window[1] += 1
        if window[1] > PER_WINDOW:
            window[2] += 1
            return False
        return True


def format_escaped(handler: logging.Handler, fmt: str, datefmt: str) -> None:
    handler.setFormatter(EscapingFormatter(fmt, datefmt))


def rate_limit(handler: logging.Handler) -> None:
    handler.addFilter(RateLimit())
