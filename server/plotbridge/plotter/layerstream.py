"""One stretch of a job's program streamed to the board: the lines from a start line up to
a stop line (not sent), after a preamble, through the pen's feed and the wire compaction;
then the wait until the board stands."""

from __future__ import annotations

import asyncio
import contextlib
import time
from collections.abc import AsyncIterator, Callable
from pathlib import Path

from plotbridge.pens import PenFeed
from plotbridge.plotter.link import Link
from plotbridge.program import wire
from plotbridge.program.reader import ProgramReader


async def until(lines: AsyncIterator[tuple[int, str]],
                stop: int | None) -> AsyncIterator[tuple[int, str]]:  # fmt: skip
    """The lines before program line `stop` (all with None); the preamble (0) passes."""
    async with contextlib.aclosing(lines):
        async for number, text in lines:
            if stop is not None and number >= stop:
                return
            yield number, text


class LayerStream:
    def __init__(self, link: Link) -> None:
        self.link = link
        self.resets = link.resets  # the link's count when the job began (`begin`)

    def begin(self) -> None:
        """A job begins: a soft reset from now on (its stop, its cancel) ends it, even one
        that comes before its first stream does."""
        self.resets = self.link.resets

    async def run(self, program: Path, line: int, stop: int | None, preamble: list[str],
                  feed: PenFeed, on_ack: Callable[[int], None],
                  motion: Callable[[bytearray], None]) -> str:  # fmt: skip
        """Stream lines `line`..`stop` - 1 after `preamble`; `motion` is handed the reader's
        motion flags (filled as it reads); the board's state once it stands: Idle, Alarm
        or Disconnected. Raises StreamAborted as `Link.stream` does."""
        reader = ProgramReader(program, line, preamble)
        motion(reader.motion)
        since = time.time()
        async with contextlib.aclosing(until(reader.lines(), stop)) as lines:
            await self.link.stream(wire.compact_async(feed.lines(lines), self.link.settings,
                                                      self.link.facts.line_numbers),
                                   on_ack, self.resets)  # fmt: skip
        return await self.standing(since)

    async def standing(self, since: float) -> str:
        """After the last ok: wait until the board is Idle (a report made after `since`),
        or in Alarm, or gone."""
        while True:
            status = self.link.status
            state = status.state if status.connected else "Disconnected"
            if state in ("Alarm", "Disconnected"):
                return state
            if state == "Idle" and status.updated_at > since:
                return state
            await asyncio.sleep(0.05)
