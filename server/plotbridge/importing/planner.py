"""Plot time estimate: a simulation of the firmware's motion planner.

The model is our firmware's (firmware/src/planner.c, segment.c, arc.c), which is
GRBL's: every move is a block with a trapezoidal speed profile; the speed through
the corner between two blocks is limited by the junction deviation; each axis is
held to its own maximum rate and acceleration; arcs are cut into chords by the arc
tolerance. The planner only sees the blocks in its buffer
(`profile.planner_blocks`): while block k executes, the buffer holds k .. k+N-1 and
the last of them must be able to stop, so long chains of short moves run slower
than an unlimited look-ahead would allow. New blocks enter as old ones finish,
because the sender keeps the buffer full, but a line cannot arrive faster than the
serial line carries it (`profile.baud`), so dense short moves can starve the planner.
M3/M5 wait for motion to stop, then hold for the pen settle time; G4 likewise.
"""

from __future__ import annotations

import math
from collections import deque

from .models import MachineProfile
from .ops import arc_sweep

_STRAIGHT = 1e30
ARC_MAX_SEGMENTS = 20000
RX_LINES = 4    # lines of a plot that wait in the 128-byte receive buffer, about


class Timeline:
    """(line, seconds elapsed when it ends) samples, thinned to at most `limit`."""

    def __init__(self, limit: int = 2000) -> None:
        self.limit = limit
        self.samples: list[tuple[int, float]] = []
        self.stride = 1
        self._next = 0

    def record(self, line: int, t: float) -> None:
        if line < self._next:
            return
        self.samples.append((line, t))
        self._next = line + self.stride
        if len(self.samples) >= self.limit:
            self.samples = self.samples[1::2]
            self.stride *= 2

    def finish(self, line: int, t: float) -> list[tuple[int, float]]:
        """The samples, ending with (line, t), times rounded to milliseconds."""
        samples = [(n, round(x, 3)) for n, x in self.samples if n < line]
        if len(samples) >= self.limit:
            samples.pop()
        samples.append((line, round(t, 3)))
        return samples


def trapezoid_time(v0: float, v1: float, vn: float, a: float, length: float) -> float:
    """Seconds to cover `length` mm starting at v0, ending at v1 (mm/s), cruising at no
    more than vn with acceleration a. Assumes v0, v1 <= vn and that v1 is reachable."""
    da = (vn * vn - v0 * v0) / (2 * a)
    dd = (vn * vn - v1 * v1) / (2 * a)
    if da + dd <= length:
        return (vn - v0) / a + (vn - v1) / a + (length - da - dd) / vn
    vp = math.sqrt(max((2 * a * length + v0 * v0 + v1 * v1) / 2, 0.0))
    return max(vp - v0, 0.0) / a + max(vp - v1, 0.0) / a


class Planner:
    """Feed it moves in order; `time` is the estimate so far once `flush` is called."""

    def __init__(self, profile: MachineProfile, start: tuple[float, float] = (0.0, 0.0)):
        self.p = profile
        self.rapid = (profile.max_rate[0] / 60.0, profile.max_rate[1] / 60.0)
        self.accel = profile.accel
        self.junction = profile.junction_deviation
        self.depth = max(2, profile.planner_blocks)
        self.x, self.y = start
        self.time = 0.0
        self.timeline = Timeline()
        # pending blocks: [length, accel, nominal², max entry², line, arrival time,
        # 2·accel·length (the change of squared speed the block allows)]
        self.pending: list[list] = []
        # The serial line: a line arrives `bytes · 10 / baud` after the one before it,
        # and not before the planner and the receive buffer have room for it.
        self.byte_time = 10.0 / profile.baud if profile.baud else 0.0
        self.arrival = 0.0
        # The firmware needs plan_block_s to parse and plan each block.
        self.block_s = profile.plan_block_s
        self.ready = 0.0
        self.ends: deque[float] = deque(maxlen=self.depth + RX_LINES)
        self.v2 = 0.0           # squared speed at the end of the last finished block
        self.prev_u: tuple[float, float] | None = None
        self.prev_nom2 = 0.0

    def receive(self, nbytes: int) -> None:
        """The next program line, `nbytes` long with its newline, is sent."""
        if self.byte_time:
            ends = self.ends
            start = self.arrival
            if len(ends) == ends.maxlen and ends[0] > start:
                start = ends[0]
            self.arrival = start + nbytes * self.byte_time

    def move(self, line: int, x: float, y: float, feed: float | None) -> None:
        """A straight move to (x, y); feed in mm/min, None for a rapid."""
        dx, dy = x - self.x, y - self.y
        length = math.hypot(dx, dy)
        if length < 1e-9:
            return
        self.x, self.y = x, y
        ux, uy = dx / length, dy / length
        # Each axis holds to its own maximum rate and acceleration (inline, with
        # comparisons rather than min/max calls: this runs once per block).
        ax, ay = abs(ux), abs(uy)
        if ax > 1e-12:
            vmax, acc = self.rapid[0] / ax, self.accel[0] / ax
            if ay > 1e-12:
                v = self.rapid[1] / ay
                if v < vmax:
                    vmax = v
                a = self.accel[1] / ay
                if a < acc:
                    acc = a
        else:
            vmax, acc = self.rapid[1] / ay, self.accel[1] / ay
        vn = vmax if feed is None or feed / 60.0 > vmax else feed / 60.0
        nom2 = vn * vn
        prev = self.prev_u
        if prev is None:
            entry2 = 0.0
        else:
            cos_t = -(prev[0] * ux + prev[1] * uy)
            if cos_t > 0.999999:
                entry2 = 0.0
            else:
                if cos_t < -0.999999:
                    j2 = _STRAIGHT
                else:
                    # The firmware takes the acceleration of the block entered, along
                    # its own direction (GRBL 1.1 uses the junction vector instead).
                    s = math.sqrt(0.5 * (1.0 - cos_t))
                    j2 = acc * self.junction * s / (1.0 - s)
                entry2 = j2
                if nom2 < entry2:
                    entry2 = nom2
                if self.prev_nom2 < entry2:
                    entry2 = self.prev_nom2
        self.prev_u = (ux, uy)
        self.prev_nom2 = nom2
        pending = self.pending
        ready = self.arrival
        if self.ready > ready:
            ready = self.ready
        if self.ends and len(pending) >= self.depth - 1 and self.ends[-1] > ready:
            ready = self.ends[-1]     # the planner is full: wait for a slot
        self.ready = ready = ready + self.block_s
        pending.append([length, acc, nom2, entry2, line, ready, 2 * acc * length])
        if len(pending) >= self.depth:
            self._finish_first()

    def arc(self, line: int, x: float, y: float, i: float, j: float, feed: float,
            cw: bool) -> None:
        """An arc cut into chords the way the firmware does it: the fewest equal angles
        whose chords stay within the arc tolerance, the radius blended from start to end."""
        sx, sy = self.x, self.y
        cx, cy, r0, sweep = arc_sweep(sx, sy, x, y, i, j, cw)
        r1 = math.hypot(x - cx, y - cy)
        r = max(r0, r1)
        tol = self.p.arc_tolerance
        max_angle = math.pi if tol >= r else 2 * math.acos(1 - tol / r)
        n = min(max(math.ceil(abs(sweep) / max_angle), 1), ARC_MAX_SEGMENTS)
        a0 = math.atan2(sy - cy, sx - cx)
        for k in range(1, n):
            f = k / n
            a = a0 + sweep * f
            rk = r0 + (r1 - r0) * f
            self.move(line, cx + rk * math.cos(a), cy + rk * math.sin(a), feed)
        self.move(line, x, y, feed)

    def stop(self, line: int, seconds: float) -> None:
        """Wait for motion to end, then hold still for `seconds`."""
        self.flush()
        self.time = max(self.time, self.arrival) + seconds
        self.ready = self.time     # the firmware reads the next line only now
        self.timeline.record(line, self.time)

    def flush(self) -> None:
        while self.pending:
            self._finish_first()
        self.prev_u = None
        self.v2 = 0.0

    def _exit_limit(self, horizon: float) -> tuple[float, bool]:
        """Highest squared exit speed of the first pending block that the blocks in the
        buffer by `horizon` allow (every later block must be able to slow down to its
        own entry limit, and the last one to a stop), and whether a block not yet in
        the buffer cut the window short."""
        pending = self.pending
        exit2 = _STRAIGHT
        s = 0.0
        for k in range(1, len(pending)):
            if s >= exit2:
                return exit2, False
            blk = pending[k]
            if blk[5] > horizon:
                return min(exit2, s), True
            limit = blk[3] + s
            if limit < exit2:
                exit2 = limit
            s += blk[6]
        return min(exit2, s), False

    def _finish_first(self) -> None:
        length, acc, nom2, _, line, ready, dv2 = self.pending[0]
        if ready > self.time:
            self.time = ready        # the machine waited for this block, standing still
            self.v2 = 0.0
        start = self.time
        v0, vn = math.sqrt(self.v2), math.sqrt(nom2)
        reach = self.v2 + dv2
        # Blocks that reach the buffer while this one runs still raise its exit speed
        # (the firmware replans the running block): widen the window to its end.
        exit2, cut = self._exit_limit(start)
        bound = reach if reach < nom2 else nom2
        if bound <= exit2:
            exit2 = bound
            cut = False     # no wider window can raise the exit speed
        took = trapezoid_time(v0, math.sqrt(exit2), vn, acc, length)
        if cut:
            wider = min(self._exit_limit(start + took)[0], reach, nom2)
            if wider > exit2:
                took_wider = trapezoid_time(v0, math.sqrt(wider), vn, acc, length)
                exit2 = min(self._exit_limit(start + took_wider)[0], reach, nom2)
                took = trapezoid_time(v0, math.sqrt(exit2), vn, acc, length)
        self.time += took + self.p.block_gap_s
        self.v2 = exit2
        del self.pending[0]
        self.ends.append(self.time)
        self.timeline.record(line, self.time)
