"""Time left of a running job, and how far along a stretch of it is, from the import's
timeline."""

from __future__ import annotations

from bisect import bisect_left
from collections.abc import Sequence

Timeline = Sequence[Sequence[float]]
"""(line, seconds elapsed when it ends) samples, lines rising (docs/INTERNALS.md)."""


def _line(sample: Sequence[float]) -> int:
    return int(sample[0])


def elapsed(timeline: Timeline, line: int) -> float:
    """Seconds from the start until program line `line` ends, interpolating the samples
    (0 without a timeline)."""
    if not timeline:
        return 0.0
    k = bisect_left(timeline, line, key=_line)  # per status report: no copy of the samples
    if k < len(timeline) and _line(timeline[k]) == line:
        return float(timeline[k][1])
    if k == 0:
        l1, t1 = timeline[0]
        return float(t1) * max(line, 0) / l1 if l1 > 0 else 0.0
    if k >= len(timeline):
        return float(timeline[-1][1])
    (l0, t0), (l1, t1) = timeline[k - 1], timeline[k]
    return t0 + (t1 - t0) * (line - l0) / (l1 - l0)


def eta(timeline: Timeline, estimate_s: float, lines_done: int) -> float:
    """Seconds left when `lines_done` lines are acknowledged."""
    if not timeline:
        return max(estimate_s, 0.0)
    return max(estimate_s - elapsed(timeline, lines_done), 0.0)


def share_done(timeline: Timeline, first: int, last: int, lines_done: int) -> float:
    """How much of program lines `first`..`last` is done when `lines_done` lines are
    acknowledged: the share of their estimated time (of their lines without a timeline
    or when they take no time), 0..1."""
    if lines_done < first:
        return 0.0
    if lines_done >= last:
        return 1.0
    start, end = elapsed(timeline, first - 1), elapsed(timeline, last)
    if end > start:
        return min(max((elapsed(timeline, lines_done) - start) / (end - start), 0.0), 1.0)
    return (lines_done - first + 1) / (last - first + 1)
