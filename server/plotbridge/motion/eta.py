"""Time left of a running job from the import's timeline."""

from __future__ import annotations

from bisect import bisect_left
from collections.abc import Sequence


def eta(timeline: Sequence[Sequence[float]], estimate_s: float, lines_done: int) -> float:
    """Seconds left when `lines_done` lines are acknowledged, interpolating the
    (line, seconds elapsed when it ends) samples."""
    if not timeline:
        return max(estimate_s, 0.0)
    lines = [int(s[0]) for s in timeline]
    k = bisect_left(lines, lines_done)
    if k < len(lines) and lines[k] == lines_done:
        elapsed = float(timeline[k][1])
    elif k == 0:
        l1, t1 = timeline[0]
        elapsed = float(t1) * lines_done / l1 if l1 > 0 else 0.0
    elif k >= len(lines):
        elapsed = float(timeline[-1][1])
    else:
        (l0, t0), (l1, t1) = timeline[k - 1], timeline[k]
        elapsed = t0 + (t1 - t0) * (lines_done - l0) / (l1 - l0)
    return max(estimate_s - elapsed, 0.0)
