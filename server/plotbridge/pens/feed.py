"""A layer's lines on their way to the board with its pen: draw feeds capped to the
pen's speed, pen-down length counted for the odometer as the board acknowledges lines,
and a stop at the first pen-up after the pen is due for re-inking.

`PenFeed.lines()` wraps the runner's (line number, text) stream of the normalized program
(docs/INTERNALS.md) before its wire compaction; `acked(line)` is called with each
acknowledged line. Numpy-free and cheap per line: the streaming path runs it.
"""

from __future__ import annotations

import contextlib
import math
import re
from collections import deque
from collections.abc import AsyncIterator, Callable

from plotbridge.pens.model import Pen
from plotbridge.program.reader import PEN_UP, Command, Tracker

DRAW_WORDS = frozenset({"G1", "G2", "G3", "G01", "G02", "G03"})
FEED = re.compile(r"(?<=\s)F[0-9.]+", re.IGNORECASE)


def move_length(command: Command, x: float, y: float) -> float:
    """Length (mm) of the move `command` from (x, y): a line, or an arc by its I/J centre
    (same start and end: a full circle, as GRBL draws it)."""
    end_x = command.x if command.x is not None else x
    end_y = command.y if command.y is not None else y
    if not command.arc:
        return math.hypot(end_x - x, end_y - y)
    cx, cy = x + (command.i or 0.0), y + (command.j or 0.0)
    radius = math.hypot(x - cx, y - cy)
    start, end = math.atan2(y - cy, x - cx), math.atan2(end_y - cy, end_x - cx)
    clockwise = command.word in ("G2", "G02")
    sweep = (start - end) if clockwise else (end - start)
    sweep %= 2 * math.pi
    if sweep < 1e-9:
        sweep = 2 * math.pi
    return radius * sweep


class PenFeed:
    """One layer's (or one stretch between re-ink pauses') stream with pen `pen`.

    `drawn(pen_id, mm)` is told the pen-down length of acknowledged lines. With a re-ink
    interval, the stream ends after the first `M5` once `odometer_mm` plus what was sent
    reaches the next multiple of the interval: `stopped_at` is then that line and
    `position` where the carriage stands.
    """

    def __init__(self, pen: Pen | None, odometer_mm: float,
                 drawn: Callable[[int, float], None]) -> None:  # fmt: skip
        self.pen = pen
        self._drawn = drawn
        self._pending: deque[tuple[int, float]] = deque()  # (line, mm) sent, not acked
        self.sent_mm = 0.0
        self.stopped_at: int | None = None
        self.position = (0.0, 0.0)
        self._reink_at = math.inf
        if pen is not None and pen.reink_m:
            interval = pen.reink_m * 1000.0
            self._reink_at = (math.floor(odometer_mm / interval + 1e-9) + 1) * interval
        self._odometer_mm = odometer_mm

    @property
    def reink_due(self) -> bool:
        return self._odometer_mm + self.sent_mm >= self._reink_at - 1e-6

    async def lines(self, source: AsyncIterator[tuple[int, str]]
                    ) -> AsyncIterator[tuple[int, str]]:  # fmt: skip
        speed = self.pen.speed if self.pen is not None else None
        at = Tracker()
        async with contextlib.aclosing(source):
            if self.pen is None:  # nothing to change or count: no parsing on the way
                async for item in source:
                    yield item
                return
            async for number, text in source:
                command = Command.parse(text)
                if command.word in DRAW_WORDS:
                    if at.down and number > 0:
                        length = move_length(command, at.x, at.y)
                        self.sent_mm += length
                        self._pending.append((number, length))
                    if speed is not None and command.feed is not None and command.feed > speed:
                        text = FEED.sub(f"F{speed:g}", text)
                at.follow(command)
                yield number, text
                if command.word == PEN_UP and number > 0 and self.reink_due:
                    self.stopped_at, self.position = number, (at.x, at.y)
                    return

    def acked(self, line: int) -> None:
        """The board acknowledged lines up to `line`: their pen-down length is drawn."""
        if self.pen is None:
            return
        mm = 0.0
        while self._pending and self._pending[0][0] <= line:
            mm += self._pending.popleft()[1]
        if mm:
            self._drawn(self.pen.id, mm)
