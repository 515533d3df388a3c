"""Where a program can continue, and how to get there (pure logic, blocking file reads).

An interrupted job continues where the board's last report (or the position it ran
out at) shows the pen stopped (`locate`); a finished one from a point the user picks:
a stroke vertex, a line or a layer, with an overlap back along the stroke (`pick`).
`layer_runs` says which program lines a job plots when it skips layers.
"""

from __future__ import annotations

import contextlib
import itertools
import json
import math
import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from plotbridge.jobs.model import Layer

from plotbridge.program.reader import PEN_DOWN, PEN_UP, Command, read_program, state_before

LOCATE_TOLERANCE = 0.05  # mm: four 80 steps/mm steps; a reported position is step-exact
RUN_OUT_LINES = 256  # lines past the last report's acked count a dead server's board may run
# A report's position may lie a few moves before its `Ln:`: stock GRBL names the block its
# segment preparer works on, up to its 6-segment buffer ahead of the steps (ours names
# the executing block, read before the position).
LOOK_BACK_MOVES = 8
LOOK_BACK_LINES = 4 * LOOK_BACK_MOVES  # (pen lifts and other lines between them)
Point = tuple[float, float]


@dataclass(frozen=True)
class Mark:
    """What the last status report told about an active job: the executing line lies in
    `first..last` (first: the board's reported `Ln:` where it numbers lines, else the
    conservative acked-minus-queued bound; last: acked, or `Ln:` if beyond), and
    the carriage was at `x`, `y` (machine mm). `ran_to`: where the board stood once it
    had run out of moves after the server died (its first Idle report on reconnect)."""

    first: int
    last: int
    x: float
    y: float
    ran_to: Point | None = None

    def save(self, path: Path) -> None:
        """Written through the page cache, no fsync: it survives the server's death
        (a kill -9), which is what it is for, at the cost of a few µs (blocking)."""
        tmp = path.with_suffix(".tmp")
        extra = list(self.ran_to) if self.ran_to is not None else []
        tmp.write_text(json.dumps([self.first, self.last, self.x, self.y, *extra]))
        os.replace(tmp, path)

    @classmethod
    def ran_out(cls, path: Path, point: Point) -> None:
        """Add where the board ran out to the mark kept in `path`, if any (blocking)."""
        mark = cls.load(path)
        if mark is not None:
            cls(mark.first, mark.last, mark.x, mark.y, point).save(path)

    @classmethod
    def load(cls, path: Path) -> Mark | None:
        try:
            first, last, x, y, *ran_to = json.loads(path.read_text())
            end = (float(ran_to[0]), float(ran_to[1])) if len(ran_to) == 2 else None
            return cls(int(first), int(last), float(x), float(y), end)
        except (OSError, ValueError, TypeError):
            return None


@dataclass(frozen=True)
class ResumePoint:
    """Continue with program line `line`; when `at` is set, from that point on the
    line's move (the pen goes down there if the line draws)."""

    line: int
    at: Point | None = None


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


def executing_line(reported: int, conservative: int | None, floor: int) -> int | None:
    """The first line not known to be executed when the board reports (`Ln:`) that it
    executes line `reported`: that line (the report's position lies on its move, or on
    stock GRBL a few moves before it: `locate` looks back).
    A number before `floor` (from before this stream) tells nothing: `conservative`."""
    return reported if reported >= floor else conservative


# ---- the geometry of one move ----------------------------------------------------------


@dataclass(frozen=True)
class Move:
    """Program line `line` moving from `start` to `end`; an arc has its `centre` and turns
    clockwise (G2) or not (G3); `down`: the pen draws it."""

    line: int
    command: Command
    start: Point
    end: Point
    down: bool
    stroke: int = 0
    centre: Point | None = None

    @property
    def clockwise(self) -> bool:
        return self.command.word in ("G2", "G02")

    def _sweep(self) -> tuple[float, float, float]:
        """Radius, start angle, signed sweep (a full circle when start and end meet)."""
        assert self.centre is not None
        cx, cy = self.centre
        radius = math.hypot(self.start[0] - cx, self.start[1] - cy)
        a0 = math.atan2(self.start[1] - cy, self.start[0] - cx)
        a1 = math.atan2(self.end[1] - cy, self.end[0] - cx)
        sweep = a1 - a0
        if self.clockwise:
            sweep = sweep if sweep < 0 else sweep - 2 * math.pi
        else:
            sweep = sweep if sweep > 0 else sweep + 2 * math.pi
        return radius, a0, sweep

    @property
    def length(self) -> float:
        if self.centre is None:
            return math.dist(self.start, self.end)
        radius, _, sweep = self._sweep()
        return radius * abs(sweep)

    def at(self, t: float) -> Point:
        """The point a fraction `t` (0..1) along the move."""
        if self.centre is None:
            return (self.start[0] + t * (self.end[0] - self.start[0]),
                    self.start[1] + t * (self.end[1] - self.start[1]))  # fmt: skip
        radius, a0, sweep = self._sweep()
        angle = a0 + t * sweep
        return (self.centre[0] + radius * math.cos(angle),
                self.centre[1] + radius * math.sin(angle))  # fmt: skip

    def nearest(self, p: Point) -> tuple[float, float]:
        """(distance from `p` to the move, the fraction along it of the nearest point)."""
        if self.centre is None:
            dx, dy = self.end[0] - self.start[0], self.end[1] - self.start[1]
            length2 = dx * dx + dy * dy
            along = (p[0] - self.start[0]) * dx + (p[1] - self.start[1]) * dy
            t = 0.0 if length2 == 0 else max(0.0, min(1.0, along / length2))
            return math.dist(p, self.at(t)), t
        radius, a0, sweep = self._sweep()
        angle = math.atan2(p[1] - self.centre[1], p[0] - self.centre[0])
        turned = (angle - a0) % (2 * math.pi) if sweep > 0 else (a0 - angle) % (2 * math.pi)
        if radius > 0 and turned <= abs(sweep):
            t = turned / abs(sweep)
            return abs(math.dist(p, self.centre) - radius), t
        to_start, to_end = math.dist(p, self.start), math.dist(p, self.end)
        return (to_start, 0.0) if to_start <= to_end else (to_end, 1.0)

    def rest_from(self, p: Point) -> str:
        """G-code for the rest of this move from `p` on it: the same end, an arc's centre
        offsets from `p` (so it continues on the arc, not as a chord)."""
        c = self.command
        feed = f" F{c.feed:g}" if c.feed is not None else ""
        if self.centre is None:
            return f"{c.word} X{self.end[0]:.4f} Y{self.end[1]:.4f}{feed}"
        i, j = self.centre[0] - p[0], self.centre[1] - p[1]
        return f"{c.word} X{self.end[0]:.4f} Y{self.end[1]:.4f} I{i:.4f} J{j:.4f}{feed}"


def moves(program: Path, start: int = 1) -> Iterator[Move]:
    """Every move of the program from line `start` on, with where it starts (blocking)."""
    state = state_before(program, start)
    here, down, stroke = (state.x, state.y), state.pen_down, 0
    for number, text in read_program(program, start):
        command = Command.parse(text)
        if command.word == PEN_DOWN:
            down, stroke = True, stroke + 1
        elif command.word == PEN_UP:
            down = False
        if not command.moves:
            continue
        end = (command.x if command.x is not None else here[0],
               command.y if command.y is not None else here[1])  # fmt: skip
        centre = ((here[0] + (command.i or 0.0), here[1] + (command.j or 0.0))
                  if command.arc else None)  # fmt: skip
        yield Move(number, command, here, end, down, stroke, centre)
        here = end


# ---- an interrupted job: where the pen stopped ---------------------------------------


def locate(program: Path, mark: Mark, tolerance: float = LOCATE_TOLERANCE) -> ResumePoint:
    """The earliest move of the mark's line window that passes through the mark's
    position, else the latest of the `LOOK_BACK_MOVES` moves before the window that does,
    and that position (on an arc too); with `ran_to`, the earliest move from there on
    that passes through where the board ran out. No match falls back to the mark's
    point, else to the conservative first line."""
    point = (mark.x, mark.y)
    start = max(1, mark.first - LOOK_BACK_LINES)
    with contextlib.closing(moves(program, start)) as walk:
        window = list(itertools.takewhile(
            lambda move: move.line <= mark.last + RUN_OUT_LINES, walk))  # fmt: skip
    on = [i for i, move in enumerate(window)
          if move.line <= mark.last and move.nearest(point)[0] <= tolerance]  # fmt: skip
    behind = sum(move.line < mark.first for move in window)
    found = next((i for i in on if i >= behind), None)
    if found is None:
        found = max((i for i in on if behind - LOOK_BACK_MOVES <= i), default=None)
        if found is None:
            return ResumePoint(mark.first)
    move, rest = window[found], window[found + 1:]
    if mark.ran_to is None:
        return ResumePoint(_past_end(move, rest[0] if rest else None, point).line, point)
    distance, t = move.nearest(mark.ran_to)
    if distance <= tolerance and t >= move.nearest(point)[1]:
        return ResumePoint(move.line, mark.ran_to)
    after = next((m for m in rest if m.nearest(mark.ran_to)[0] <= tolerance), None)
    return ResumePoint(after.line, mark.ran_to) if after else ResumePoint(move.line, point)


def _past_end(found: Move, after: Move | None, point: Point) -> Move:
    """A point within the tolerance of `found`'s end but past it (the pen stopped a step
    into the next line) lies on the move after it when that one passes closer: resuming
    on `found` would go back to its end and draw that bit twice."""
    distance, t = found.nearest(point)
    if t < 1.0 or distance == 0.0:
        return found
    return after if after is not None and after.nearest(point)[0] < distance else found


# ---- a point the user picks ----------------------------------------------------------


class PickError(ValueError):
    """A resume point that names nothing in the program (the message says what)."""


def pick(program: Path, layers: list[Layer], lines_total: int,
         where: dict[str, Any], overlap: float = 0.0) -> ResumePoint:  # fmt: skip
    """Where to resume from `where`: {"x", "y"} (the nearest point on any pen-down move,
    along a segment or an arc, not only at its ends), {"line"}
    (its start) or {"layer"} (1-based; its first line), then `overlap` mm back along
    the stroke that point lies on (split mid-move, never past the stroke's start)."""
    if "layer" in where:
        layer = int(where["layer"])
        if not 1 <= layer <= max(len(layers), 1):
            raise PickError(f"layer {layer}: the job has {max(len(layers), 1)} layer(s)")
        return ResumePoint(1 if layer == 1 else layers[layer - 1].first_line)
    if "line" in where:
        line = int(where["line"])
        if not 1 <= line <= lines_total:
            raise PickError(f"line {line}: the program has lines 1 to {lines_total}")
        return _back(program, ResumePoint(line), overlap)
    target = (float(where["x"]), float(where["y"]))
    best: tuple[float, ResumePoint] | None = None
    with contextlib.closing(moves(program)) as walk:
        for move in walk:
            if not move.down:
                continue
            distance, t = move.nearest(target)
            if best is None or distance < best[0]:
                best = (distance, ResumePoint(move.line, move.at(t)))
    if best is None:
        raise PickError("the job draws nothing: there is no stroke to resume from")
    return _back(program, best[1], overlap)


def _back(program: Path, point: ResumePoint, overlap: float) -> ResumePoint:
    """`overlap` mm back along the pen-down path from `point` (same stroke only)."""
    if overlap <= 0:
        return point
    stroke: list[Move] = []
    with contextlib.closing(moves(program)) as walk:
        for move in walk:
            if move.line > point.line:
                break
            if not move.down or (stroke and move.stroke != stroke[-1].stroke):
                stroke = []
            if move.down:
                stroke.append(move)
    if not stroke:
        return point
    if stroke[-1].line == point.line:  # the part of the point's own move before it
        last = stroke.pop()
        at = point.at if point.at is not None else last.start
        done = last.nearest(at)[1] * last.length
        if overlap <= done:
            return ResumePoint(last.line, last.at((done - overlap) / last.length))
        overlap -= done
    for move in reversed(stroke):
        if overlap <= move.length:
            return ResumePoint(move.line, move.at(1 - overlap / move.length))
        overlap -= move.length
    first = stroke[0] if stroke else None
    return ResumePoint(first.line, first.start) if first is not None else point


def resume_preamble(program: Path, point: ResumePoint) -> tuple[int, list[str]]:
    """The line to stream from and the G-code before it that puts the machine in the
    state in which the resume point is: pen up, millimetres, absolute, at the point
    (the line's start, or where on the line's move it lies), then the pen as it was;
    a point inside an arc adds the rest of that arc (its centre kept) and streams on
    from the next line. Every G1/G2/G3 carries its own F. Blocking."""
    state = state_before(program, point.line)
    x, y = point.at if point.at is not None else (state.x, state.y)
    out = [PEN_UP, "G21", "G90", f"G0 X{x:.4f} Y{y:.4f}"]
    if state.pen_down:
        out.append(PEN_DOWN)
    if point.at is not None:
        with contextlib.closing(moves(program, point.line)) as walk:
            move = next(walk, None)
        if move is not None and move.line == point.line and move.centre is not None:
            return point.line + 1, [*out, move.rest_from(point.at)]
    return point.line, out


# ---- layers a job plots ------------------------------------------------------------


def layer_bounds(layers: list[Layer]) -> list[tuple[int, int | None]]:
    """(first line, the next layer's `M0` or None) of every layer; the first starts at 1."""
    starts = [1] + [layer.first_line for layer in layers[1:]]
    stops: list[int | None] = [layer.first_line - 1 for layer in layers[1:]]
    return list(zip(starts, [*stops, None], strict=True))


def first_line(layers: list[Layer], plot: list[int] | None) -> int:
    """The line a job that plots layers `plot` (1-based; None: all) starts with."""
    if not layers or not plot:
        return 1
    return layer_bounds(layers)[min(plot) - 1][0]


def layer_runs(layers: list[Layer], plot: list[int] | None,
               line: int) -> list[tuple[int, int | None, int]]:  # fmt: skip
    """What to stream from `line` on: (first line, the line to stop before or None, layer
    index) for the rest of `line`'s layer, then each later layer in `plot` (None: all);
    a pen change comes between two runs."""
    if not layers:
        return [(line, None, 0)]
    bounds = layer_bounds(layers)
    here = max(k for k, (start, _) in enumerate(bounds) if k == 0 or start - 1 <= line)
    runs = [(max(line, bounds[here][0]), bounds[here][1], here)]
    runs += [(start, stop, k) for k, (start, stop) in enumerate(bounds)
             if k > here and (plot is None or k + 1 in plot)]  # fmt: skip
    return runs
