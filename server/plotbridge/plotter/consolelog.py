"""A plotter's console lines, published together: one `log` event per short interval.

A `$$` is answered with some 35 lines; sent one message each to every page, a few
clients repeating it cost the loop tens of thousands of sends a second. Lines
are gathered for LOG_INTERVAL and published as one event (`lines`), at most
LOG_LINES of them; beyond that a line says how many were left out.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any

LOG_INTERVAL = 0.05  # s a console line may wait for the ones after it
LOG_LINES = 256  # per event; more in one interval are counted, not sent


class ConsoleLog:
    def __init__(self, plotter: str, publish: Callable[[dict[str, Any]], None]) -> None:
        self.plotter = plotter
        self.publish = publish
        self.pending: list[dict[str, str]] = []
        self.left_out = 0
        self._timer: asyncio.TimerHandle | None = None

    def add(self, direction: str, line: str) -> None:
        if len(self.pending) >= LOG_LINES:
            self.left_out += 1
        else:
            self.pending.append({"direction": direction, "line": line})
        if self._timer is None:
            self._timer = asyncio.get_running_loop().call_later(LOG_INTERVAL, self.flush)

    def flush(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        if self.left_out:
            self.pending.append({"direction": "rx", "line": f"({self.left_out} console lines "
                                 "not shown: they came faster than pages are sent them)"})
            self.left_out = 0
        if self.pending:
            lines, self.pending = self.pending, []
            self.publish({"type": "log", "plotter": self.plotter, "lines": lines})
