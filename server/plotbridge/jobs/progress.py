"""How far a job is, from where the pen is: the program line the board executes and the
carriage's position on that line's move (docs/INTERNALS.md, "Progress from the pen").

`Measure.of(program)` reads the program once (blocking, run in a thread) and keeps, per
line, where its move starts, whether the pen draws it and the pen-down length up to its
end. `follow(job, measure, plan, line, at)` then sets the job's `lines_done`, `drawn_mm`,
`progress` (share of the plan's time), `eta_s`, `done_point`, `summary` and each layer's
share: nothing after the pen's point counts as done.
"""

from __future__ import annotations

import math
from array import array
from bisect import bisect_left
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from plotbridge.motion.eta import elapsed
from plotbridge.program.reader import PEN_DOWN, PEN_UP, Command, read_program

if TYPE_CHECKING:
    from plotbridge.jobs.model import Job, Layer

Point = tuple[float, float]
SYNC_WORDS = frozenset({PEN_DOWN, PEN_UP, "M0", "M1", "G4"})
RAPID_MM_MIN = 5000.0  # a G0's speed for the split of a stretch's time among its lines


@dataclass
class Measure:
    """Per program line n (1-based): `x[n]`, `y[n]` where its move starts (`x[n + 1]` where
    it ends), `down[n]` whether the pen draws it, `mm[n]` pen-down mm up to its end;
    `arcs[n]` an arc's (centre x, centre y, clockwise)."""

    x: array = field(default_factory=lambda: array("d", [0.0, 0.0]))
    y: array = field(default_factory=lambda: array("d", [0.0, 0.0]))
    down: bytearray = field(default_factory=lambda: bytearray(1))
    mm: array = field(default_factory=lambda: array("d", [0.0]))
    arcs: dict[int, tuple[float, float, bool]] = field(default_factory=dict)
    syncs: array = field(default_factory=lambda: array("l"))
    """Lines the board answers only once the moves before them are done (pen, pause,
    dwell), and the last line."""
    secs: array = field(default_factory=lambda: array("d", [0.0]))
    """Seconds up to the end of each line at its feed, without acceleration (`Plan` scales
    them between two `syncs` to the estimate's time)."""

    @classmethod
    def of(cls, program: Path) -> Measure:
        """The program's measure (blocking: reads the file once)."""
        m = cls()
        x = y = total = seconds = 0.0
        pen, feed = False, RAPID_MM_MIN
        for number, text in read_program(program):
            command = Command.parse(text)
            length = 0.0
            if command.word in SYNC_WORDS:
                m.syncs.append(number)
            if command.word == PEN_DOWN:
                pen = True
            elif command.word == PEN_UP:
                pen = False
            elif command.moves:
                ex = command.x if command.x is not None else x
                ey = command.y if command.y is not None else y
                if command.arc:
                    cx, cy = x + (command.i or 0.0), y + (command.j or 0.0)
                    clockwise = command.word in ("G2", "G02")
                    m.arcs[number] = (cx, cy, clockwise)
                    length = _arc_length((x, y), (ex, ey), (cx, cy), clockwise)
                else:
                    length = math.hypot(ex - x, ey - y)
                x, y = ex, ey
            rapid = command.word in ("G0", "G00")
            if command.feed and not rapid:
                feed = command.feed
            drawn = pen and command.moves and not rapid
            total += length if drawn else 0.0
            seconds += length * 60.0 / (RAPID_MM_MIN if rapid else feed)
            m.secs.append(seconds)
            m.down.append(drawn)
            m.mm.append(total)
            m.x.append(x)
            m.y.append(y)
        if not m.syncs or m.syncs[-1] != m.lines:
            m.syncs.append(m.lines)
        return m

    @property
    def lines(self) -> int:
        return len(self.mm) - 1

    def along(self, line: int, at: Point | None) -> float:
        """How far (0..1) along program line `line`'s move the point `at` lies (0 with no
        point or no move)."""
        if at is None or not 1 <= line <= self.lines:
            return 0.0
        start, end = (self.x[line], self.y[line]), (self.x[line + 1], self.y[line + 1])
        arc = self.arcs.get(line)
        if arc is not None:
            return _arc_along(start, end, arc, at)
        dx, dy = end[0] - start[0], end[1] - start[1]
        length2 = dx * dx + dy * dy
        if length2 == 0:
            return 0.0
        return min(max(((at[0] - start[0]) * dx + (at[1] - start[1]) * dy) / length2, 0.0), 1.0)

    def drawn_mm(self, line: int, t: float) -> float:
        """Pen-down mm drawn once the pen is a fraction `t` along line `line`."""
        line = min(max(line, 1), self.lines + 1)
        before = self.mm[line - 1]
        if line <= self.lines and self.down[line]:
            return before + t * (self.mm[line] - before)
        return before


def _arc_sweep(start: Point, end: Point, centre: Point, clockwise: bool) -> tuple[float, float]:
    a0 = math.atan2(start[1] - centre[1], start[0] - centre[0])
    a1 = math.atan2(end[1] - centre[1], end[0] - centre[0])
    sweep = (a0 - a1) if clockwise else (a1 - a0)
    sweep %= 2 * math.pi
    return a0, sweep if sweep > 1e-9 else 2 * math.pi


def _arc_length(start: Point, end: Point, centre: Point, clockwise: bool) -> float:
    return math.dist(start, centre) * _arc_sweep(start, end, centre, clockwise)[1]


def _arc_along(start: Point, end: Point, arc: tuple[float, float, bool], at: Point) -> float:
    centre, clockwise = (arc[0], arc[1]), arc[2]
    a0, sweep = _arc_sweep(start, end, centre, clockwise)
    angle = math.atan2(at[1] - centre[1], at[0] - centre[0])
    turned = ((a0 - angle) if clockwise else (angle - a0)) % (2 * math.pi)
    return min(turned / sweep, 1.0)


@dataclass(frozen=True)
class Plan:
    """The plan's time per line. The import's timeline holds when the board *accepts*
    each line; a line the board answers only once the moves before it are done (pen up
    or down, a pause, a dwell: `Measure.syncs`) is accepted when those have been executed.
    Between two such lines the stretch's time is split among its lines by their length
    at their feed (`Measure.secs`). Without a measure: the timeline as it is."""

    timeline: Sequence[Sequence[float]]
    estimate_s: float
    measure: Measure | None = None

    def ends(self, line: int) -> float:
        """Seconds from the start until program line `line` has been executed."""
        if line <= 0 or not self.timeline:
            return 0.0
        m = self.measure
        if m is None or not m.syncs:
            return elapsed(self.timeline, line)
        line = min(line, m.lines)
        k = bisect_left(m.syncs, line)
        after = m.syncs[min(k, len(m.syncs) - 1)]
        before = m.syncs[k - 1] if k > 0 else 0
        t0, t1 = elapsed(self.timeline, before), elapsed(self.timeline, after)
        span = m.secs[after] - m.secs[before]
        share = (m.secs[line] - m.secs[before]) / span if span > 0 else 1.0
        return t0 + min(max(share, 0.0), 1.0) * (t1 - t0)

    @property
    def total(self) -> float:
        """The plan's seconds: the timeline's end, else the estimate."""
        return float(self.timeline[-1][1]) if self.timeline else self.estimate_s

    def at(self, line: int, t: float) -> float:
        """Seconds of the plan done with the pen a fraction `t` along line `line`."""
        before = self.ends(line - 1)
        return before + t * (self.ends(line) - before)


def plan_of(job: Job, measure: Measure | None) -> Plan:
    return Plan(job.timeline, job.estimate_s, measure)


def follow(job: Job, measure: Measure | None, plan: Plan, line: int, at: Point | None,
           state: str | None = None) -> None:  # fmt: skip
    """The job's progress with the pen at `at` on program line `line` (`at` None: at the
    line's start); `line` past the last line: all done."""
    line = max(line, 1)
    t = measure.along(line, at) if measure is not None else 0.0
    finished = line > job.lines_total
    job.lines_done = job.lines_total if finished else line - 1
    job.drawn_mm = round(measure.drawn_mm(line, t), 2) if measure is not None else 0.0
    total = plan.total
    seconds = total if finished else plan.at(line, t)
    job.progress = round(min(seconds / total, 1.0), 4) if total > 0 else (
        round(job.lines_done / max(job.lines_total, 1), 4))  # fmt: skip
    job.eta_s = round(max(total - seconds, 0.0), 1)
    index = layer_of(job.layers, line)
    if finished:
        job.done_point = None
    else:
        px, py = at if at is not None else ((measure.x[line], measure.y[line])
                                            if measure is not None else (0.0, 0.0))  # fmt: skip
        layer = job.layers[index] if index is not None else None
        job.done_point = {"line": line, "x": round(px, 3), "y": round(py, 3),
                          "layer": index + 1 if index is not None else None,
                          "layer_name": layer.label if layer else None}  # fmt: skip
    for layer in job.layers:
        _follow_layer(layer, measure, plan, line, t, finished)
    job.summary = summary(job, state or job.state)


def _follow_layer(layer: Layer, measure: Measure | None, plan: Plan, line: int, t: float,
                  finished: bool) -> None:  # fmt: skip
    first, last = layer.first_line, layer.last_line
    if finished or line > last:
        share, done, drawn_line, drawn_t = 1.0, layer.lines_total, last + 1, 0.0
    elif line < first:
        share, done, drawn_line, drawn_t = 0.0, 0, first, 0.0
    else:
        start, end = plan.ends(first - 1), plan.ends(last)
        now = plan.at(line, t)
        share = ((now - start) / (end - start) if end > start
                 else (line - first) / (last - first + 1))  # fmt: skip
        done, drawn_line, drawn_t = line - first, line, t
    layer.progress = round(min(max(share, 0.0), 1.0), 4)
    layer.lines_done = done
    if measure is not None:
        layer.drawn_mm = round(measure.drawn_mm(drawn_line, drawn_t) - measure.mm[first - 1], 2)
    layer.eta_s = round(max(plan.ends(last) - plan.at(line, t), 0.0), 1) if not finished \
        and line <= last else 0.0  # fmt: skip


def layer_of(layers: list[Layer], line: int) -> int | None:
    """The 0-based index of the layer holding program line `line` (its `M0` belongs to the
    layer before), or None without layers."""
    found = None
    for index, layer in enumerate(layers):
        if layer.first_line <= line:
            found = index
    return found


VERBS = {
    "running": "drawing", "paused": "held", "pen_change": "waiting for a pen",
    "stopped": "stopped", "interrupted": "interrupted", "failed": "failed",
    "cancelled": "cancelled",
}  # fmt: skip


def summary(job: Job, state: str) -> str:
    """One sentence on where the job is: "stopped in layer 2 'outline' at X 198.5 Y 97.5,
    58 % drawn"."""
    percent = f"{job.progress * 100:.0f} % drawn"
    if state == "done":
        return f"done, {job.drawn_mm / 1000:.2f} m drawn"
    if state in ("queued", "waiting") or job.done_point is None:
        return state
    point = job.done_point
    where = f"at X {point['x']:.1f} Y {point['y']:.1f}"
    if point.get("layer") is not None and len(job.layers) > 1:
        where = f"in layer {point['layer']} '{point['layer_name']}' {where}"
    return f"{VERBS.get(state, state)} {where}, {percent}"
