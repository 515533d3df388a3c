"""Where an interrupted program can safely continue, and how to get there (pure logic)."""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path

from plotbridge.program.reader import PEN_DOWN, PEN_UP, Command, read_program, state_before

LOCATE_TOLERANCE = 0.05  # mm: four 80 steps/mm steps; a reported position is step-exact


@dataclass(frozen=True)
class Mark:
    """What the last status report told about an active job: the executing line lies in
    `first..last` (first: the conservative acked-minus-queued bound, last: acked), and
    the carriage was at `x`, `y` (machine mm)."""

    first: int
    last: int
    x: float
    y: float

    def save(self, path: Path) -> None:
        """Written through the page cache, no fsync: it survives the server's death
        (a kill -9), which is what it is for, at the cost of a few µs (blocking)."""
        tmp = path.with_suffix(".tmp")
        tmp.write_text(json.dumps([self.first, self.last, self.x, self.y]))
        os.replace(tmp, path)

    @classmethod
    def load(cls, path: Path) -> Mark | None:
        try:
            first, last, x, y = json.loads(path.read_text())
            return cls(int(first), int(last), float(x), float(y))
        except (OSError, ValueError, TypeError):
            return None


@dataclass(frozen=True)
class ResumePoint:
    """Continue with program line `line`; when `at` is set, from that point on the
    line's straight move (the pen goes down there if the line draws)."""

    line: int
    at: tuple[float, float] | None = None


def first_unexecuted_line(motion: bytes, acked: int, queued_blocks: int, floor: int = 1) -> int:
    """The first line not known to be executed.

    `acked` lines had been acknowledged when the board last reported
    `queued_blocks` planner blocks still waiting (the block in motion included).
    Every move queues at least one block, so walking back over that many move
    lines never skips motion; the cost is redrawing at most one status interval.
    """
    line = acked + 1
    remaining = max(queued_blocks, 0)
    while remaining > 0 and line > floor:
        line -= 1
        if line - 1 < len(motion) and motion[line - 1]:
            remaining -= 1
    return max(line, floor)


def _distance(p: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
    dx, dy = b[0] - a[0], b[1] - a[1]
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 == 0 else max(0.0, min(1.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy)
                                          / length2))  # fmt: skip
    return math.hypot(p[0] - (a[0] + t * dx), p[1] - (a[1] + t * dy))


def locate(program: Path, mark: Mark, tolerance: float = LOCATE_TOLERANCE) -> ResumePoint:
    """The earliest line in the mark's range whose straight move passes through the
    mark's position, and that position. An arc met first is resumed from its start
    (redrawn: never skipped); no match falls back to the conservative first line."""
    state = state_before(program, mark.first)
    here = (state.x, state.y)
    point = (mark.x, mark.y)
    for number, text in read_program(program, mark.first):
        if number > mark.last:
            break
        command = Command.parse(text)
        if not command.moves:
            continue
        if command.arc:
            return ResumePoint(number)
        end = (command.x if command.x is not None else here[0],
               command.y if command.y is not None else here[1])  # fmt: skip
        if _distance(point, here, end) <= tolerance:
            return ResumePoint(number, point)
        here = end
    return ResumePoint(mark.first)


def resume_preamble(program: Path, point: ResumePoint) -> list[str]:
    """G-code that puts the machine in the state in which the resume point is: pen
    up, millimetres, absolute, at the point (the line's start, or where on the line
    the pen stopped), then the pen as it was. Every G1/G2/G3 of the program carries
    its own F, so the resumed line draws at its own speed. Blocking."""
    state = state_before(program, point.line)
    x, y = point.at if point.at is not None else (state.x, state.y)
    out = [PEN_UP, "G21", "G90", f"G0 X{x:.4f} Y{y:.4f}"]
    if state.pen_down:
        out.append(PEN_DOWN)
    return out
