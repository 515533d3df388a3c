"""A job's program read lazily for streaming.

A one-million-line program is about 50 MB of text and several times that as a
list of strings, so it is never read whole: a worker thread reads blocks of
lines one block ahead of the sender (the event loop never touches the disk),
and at most two blocks are held at any time. The only per-line memory kept is
one byte of motion flag (see `resume.motion_flags`), which resume needs.
"""

from __future__ import annotations

import asyncio
import itertools
from collections.abc import AsyncIterator, Sequence
from pathlib import Path
from typing import IO

from plotbridge.resume import motion_flags

BLOCK_LINES = 2048  # lines per read: ~100 KB of G-code


class ProgramReader:
    """(line number, text) of `path` from line `start` on, after `preamble` (numbered 0).

    `lines()` is the async iterator (close it, e.g. with `contextlib.aclosing`,
    when not iterated to the end). `motion` holds a motion flag for every line
    read so far (skipped ones included), so `motion[n - 1]` is known for every
    line that was handed out. `held` is the number of program lines read and
    not yet handed out; `max_held` its peak (at most two blocks).
    """

    def __init__(
        self,
        path: Path,
        start: int = 1,
        preamble: Sequence[str] = (),
        block_lines: int = BLOCK_LINES,
    ) -> None:
        if start < 1 or block_lines < 1:
            raise ValueError("start and block_lines must be at least 1")
        self.path = path
        self.start = start
        self.preamble = list(preamble)
        self.block_lines = block_lines
        self.motion = bytearray()
        self.held = 0
        self.max_held = 0

    async def lines(self) -> AsyncIterator[tuple[int, str]]:
        for text in self.preamble:
            yield 0, text
        file = await asyncio.to_thread(_open, self.path)
        ahead: asyncio.Future[list[str]] | None = None
        try:
            self.motion += await asyncio.to_thread(_skip, file, self.start - 1)
            number = self.start - 1
            ahead = asyncio.ensure_future(self._read(file))
            while True:
                block = await asyncio.shield(ahead)  # cancelled or not, the read completes
                if not block:
                    return
                ahead = asyncio.ensure_future(self._read(file))  # the next, while this one goes
                for text in block:
                    number += 1
                    self.held -= 1
                    yield number, text
        finally:
            if ahead is not None:  # a thread cannot be cancelled: let its read finish
                await asyncio.gather(ahead, return_exceptions=True)
            await asyncio.to_thread(file.close)
            self.held = 0

    async def _read(self, file: IO[str]) -> list[str]:
        block, flags = await asyncio.to_thread(_read_block, file, self.block_lines)
        self.motion += flags
        self.held += len(block)
        self.max_held = max(self.max_held, self.held)
        return block


def _open(path: Path) -> IO[str]:
    # Programs are ASCII; a stray byte becomes U+FFFD, which the link refuses
    # with the line's number instead of the whole job failing to decode.
    return path.open("r", encoding="utf-8", errors="replace")


def _skip(file: IO[str], count: int) -> bytearray:
    """Read past `count` lines, keeping only their motion flags."""
    return motion_flags(itertools.islice(file, count))


def _read_block(file: IO[str], count: int) -> tuple[list[str], bytearray]:
    block = [line.rstrip("\r\n") for line in itertools.islice(file, count)]
    return block, motion_flags(block)
