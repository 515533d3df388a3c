"""The one reader of the normalized program (docs/INTERNALS.md): what streams, resumes,
tests and benchmarks use to read `program.gcode`.

`Command.parse` reads one line; `read_program` the file (blocking); `state_before`
where the machine is before a line (for a resume); `ProgramReader` streams it.

A job's program is read lazily for streaming.

A one-million-line program is about 50 MB of text and several times that as a
list of strings, so it is never read whole: a worker thread reads blocks of
lines one block ahead of the sender (the event loop never touches the disk),
and at most two blocks are held at any time. The only per-line memory kept is
one byte of motion flag (see `motion_flags`), which resume needs.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
from collections.abc import AsyncIterator, Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO

BLOCK_LINES = 2048  # lines per read: ~100 KB of G-code
MOTION_WORDS = frozenset({"G0", "G1", "G2", "G3", "G00", "G01", "G02", "G03"})
PEN_DOWN, PEN_UP = "M3", "M5"


@dataclass(frozen=True)
class Command:
    """One line of the program: its first word and the words after it by letter."""

    word: str
    x: float | None = None
    y: float | None = None
    i: float | None = None
    j: float | None = None
    feed: float | None = None
    p: float | None = None

    @classmethod
    def parse(cls, text: str) -> Command:
        words = text.split()
        if not words:
            return cls("")
        values: dict[str, float] = {}
        for word in words[1:]:
            key = word[0].lower()
            if key in "xyijfp" and len(word) > 1:
                values["feed" if key == "f" else key] = float(word[1:])
        return cls(words[0].upper(), **values)

    @property
    def moves(self) -> bool:
        """A move: it queues at least one planner block."""
        return self.word in MOTION_WORDS

    @property
    def arc(self) -> bool:
        return self.word in ("G2", "G3", "G02", "G03")


def motion_flags(lines: Iterable[str]) -> bytearray:
    """One flag per program line: 1 when the line queues a planner block (a move)."""
    flags = bytearray()
    for line in lines:
        word = line.split(maxsplit=1)[0].upper() if line.strip() else ""
        flags.append(1 if word in MOTION_WORDS else 0)
    return flags


def read_program(path: Path, start: int = 1) -> Iterator[tuple[int, str]]:
    """(line number, text) of every line from `start` on (blocking; for threads, tests)."""
    with _open(path) as file:
        for number, text in enumerate(file, 1):
            if number >= start:
                yield number, text.rstrip("\r\n")


def drawn_strokes(lines: Iterable[str]) -> list[list[tuple[float, float]]]:
    """Pen-down polylines through the end points of the moves (arcs by their ends)."""
    strokes: list[list[tuple[float, float]]] = []
    x = y = 0.0
    down = False
    for line in lines:
        command = Command.parse(line)
        if command.word == PEN_DOWN:
            down = True
            strokes.append([(x, y)])
        elif command.word == PEN_UP:
            down = False
        elif command.moves:
            x = command.x if command.x is not None else x
            y = command.y if command.y is not None else y
            if down:
                strokes[-1].append((x, y))
    return [stroke for stroke in strokes if len(stroke) > 1]


@dataclass(frozen=True)
class MachineState:
    """Where the program leaves the machine: position (mm) and pen."""

    x: float = 0.0
    y: float = 0.0
    pen_down: bool = False


@dataclass
class Tracker:
    """Follows the program line by line: where the carriage goes and whether the pen is down."""

    x: float = 0.0
    y: float = 0.0
    down: bool = False

    def follow(self, command: Command) -> None:
        if command.moves:
            self.x = command.x if command.x is not None else self.x
            self.y = command.y if command.y is not None else self.y
        elif command.word == PEN_DOWN:
            self.down = True
        elif command.word == PEN_UP:
            self.down = False


def state_before(path: Path, line: int) -> MachineState:
    """The state in which program line `line` (1-based) starts (blocking)."""
    tracker = Tracker()
    with contextlib.closing(read_program(path)) as lines:
        for number, text in lines:
            if number >= line:
                break
            tracker.follow(Command.parse(text))
    return MachineState(tracker.x, tracker.y, tracker.down)


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
