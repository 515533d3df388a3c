"""Stroke optimization: fewer pen lifts and less pen-up travel.

1. drop repeated points, simplify each stroke within the tolerance;
2. order greedily: from where the pen is, go to the nearest free stroke end (either
   end: a stroke may be drawn backwards), found through a grid index; when that end
   is within `merge_distance` the two strokes become one and the pen stays down;
3. improve the order with 2-opt moves (reverse a run of strokes) until a deadline.
"""

from __future__ import annotations

import math
import time

import numpy as np

from .ops import Stroke
from .simplify import simplify

MERGE_DISTANCE = 0.01   # mm: ends this close are joined without lifting the pen


class EndIndex:
    """Grid over stroke ends for nearest-neighbour queries with removal."""

    def __init__(self, ends: list[tuple[float, float]], cell: float) -> None:
        self.cell = cell
        self.grid: dict[tuple[int, int], set[int]] = {}
        self.ends = ends
        for k, (x, y) in enumerate(ends):
            self.grid.setdefault(self._key(x, y), set()).add(k)
        self.count = len(ends)

    def _key(self, x: float, y: float) -> tuple[int, int]:
        return math.floor(x / self.cell), math.floor(y / self.cell)

    def remove(self, k: int) -> None:
        x, y = self.ends[k]
        cell = self.grid[self._key(x, y)]
        cell.discard(k)
        self.count -= 1

    def nearest(self, x: float, y: float) -> int:
        """Index of the nearest remaining end (the index must not be empty)."""
        cx, cy = self._key(x, y)
        best, best_d = -1, math.inf
        ring = 0
        grid, ends, cell = self.grid, self.ends, self.cell
        while True:
            for gx in range(cx - ring, cx + ring + 1):
                edge = gx in (cx - ring, cx + ring)
                for gy in (range(cy - ring, cy + ring + 1) if edge else (cy - ring, cy + ring)):
                    for k in grid.get((gx, gy), ()):
                        ex, ey = ends[k]
                        d = (ex - x) ** 2 + (ey - y) ** 2
                        if d < best_d:
                            best, best_d = k, d
            # Every end outside the rings searched is at least ring*cell away.
            if best >= 0 and best_d <= (ring * cell) ** 2:
                return best
            ring += 1


def _clean(stroke: Stroke, tolerance: float) -> np.ndarray | None:
    a = np.asarray(stroke, dtype=float)
    if len(a) > 1:
        keep = np.ones(len(a), dtype=bool)
        keep[1:] = np.any(np.abs(np.diff(a, axis=0)) > 1e-9, axis=1)
        a = a[keep]
    if len(a) == 1:
        a = np.vstack([a, a])       # a dot: pen down and up at one place
    return simplify(a, tolerance) if tolerance > 0 else a


def order_greedy(strokes: list[np.ndarray], start: tuple[float, float],
                 merge_distance: float) -> list[np.ndarray]:
    n = len(strokes)
    ends = [(float(s[0][0]), float(s[0][1])) for s in strokes] + \
           [(float(s[-1][0]), float(s[-1][1])) for s in strokes]
    lo = np.min([s.min(axis=0) for s in strokes], axis=0)
    hi = np.max([s.max(axis=0) for s in strokes], axis=0)
    area = float(np.prod(np.maximum(hi - lo, 1.0)))
    index = EndIndex(ends, max(math.sqrt(area / max(n, 1)), 0.5))
    out: list[np.ndarray] = []
    x, y = start
    current: list[np.ndarray] | None = None
    for _ in range(n):
        k = index.nearest(x, y)
        s = k % n
        index.remove(s)
        index.remove(s + n)
        stroke = strokes[s] if k < n else strokes[s][::-1]
        ex, ey = ends[k]
        if current is not None and (ex - x) ** 2 + (ey - y) ** 2 <= merge_distance ** 2:
            current.append(stroke[1:])
        else:
            if current is not None:
                out.append(np.concatenate(current))
            current = [stroke]
        x, y = float(stroke[-1][0]), float(stroke[-1][1])
    if current is not None:
        out.append(np.concatenate(current))
    return out


def two_opt(strokes: list[np.ndarray], start: tuple[float, float],
            deadline: float) -> list[np.ndarray]:
    """Reverses runs of strokes (and each stroke in them) while that shortens travel."""
    n = len(strokes)
    if n < 3:
        return strokes
    order = list(range(n))
    rev = [False] * n
    heads = np.array([s[0] for s in strokes])
    tails = np.array([s[-1] for s in strokes])

    def ends_of() -> tuple[np.ndarray, np.ndarray]:
        o = np.array(order)
        r = np.array(rev)
        s = np.where(r[:, None], tails[o], heads[o])
        e = np.where(r[:, None], heads[o], tails[o])
        return s, e

    improved = True
    while improved and time.monotonic() < deadline:
        improved = False
        s, e = ends_of()
        prev_end = np.vstack([np.asarray(start, dtype=float)[None, :], e[:-1]])
        for i in range(n - 1):
            if time.monotonic() >= deadline:
                break
            # Reverse positions i..j: edge into i becomes prev_end[i] -> e[j], edge out of j
            # becomes s[i] -> s[j+1] (nothing after the last stroke).
            js = np.arange(i + 1, n)
            old = np.hypot(*(s[i] - prev_end[i])) + np.where(
                js + 1 < n, np.hypot(*(s[np.minimum(js + 1, n - 1)] - e[js]).T), 0.0)
            new = np.hypot(*(e[js] - prev_end[i]).T) + np.where(
                js + 1 < n, np.hypot(*(s[np.minimum(js + 1, n - 1)] - s[i]).T), 0.0)
            gain = old - new
            k = int(np.argmax(gain))
            if gain[k] > 1e-9:
                j = int(js[k])
                order[i:j + 1] = order[i:j + 1][::-1]
                rev[i:j + 1] = [not r for r in rev[i:j + 1][::-1]]
                s, e = ends_of()
                prev_end = np.vstack([np.asarray(start, dtype=float)[None, :], e[:-1]])
                improved = True
    return [strokes[o][::-1] if r else strokes[o] for o, r in zip(order, rev, strict=True)]


def optimize_strokes(strokes: list[Stroke], tolerance: float, deadline: float,
                     start: tuple[float, float] = (0.0, 0.0),
                     merge_distance: float = MERGE_DISTANCE) -> list[Stroke]:
    """Strokes reordered, reversed, merged and simplified; the drawn geometry stays
    within `tolerance` of the original."""
    arrays = [a for s in strokes if s and (a := _clean(s, tolerance)) is not None]
    if not arrays:
        return []
    ordered = two_opt(order_greedy(arrays, start, merge_distance), start, deadline)
    given = join_touching(arrays, merge_distance)
    if _travel(given, start) < _travel(ordered, start):
        ordered = given     # greedy is a heuristic: never hand back a worse order
    return [[(float(x), float(y)) for x, y in s] for s in ordered]


def join_touching(strokes: list[np.ndarray], merge_distance: float) -> list[np.ndarray]:
    """The strokes in their given order, each joined to the one before where they meet."""
    out = [strokes[0]]
    for s in strokes[1:]:
        if float(np.hypot(*(s[0] - out[-1][-1]))) <= merge_distance:
            out[-1] = np.concatenate([out[-1], s[1:]])
        else:
            out.append(s)
    return out


def _travel(strokes: list[np.ndarray], start: tuple[float, float]) -> float:
    pos = np.asarray(start, dtype=float)
    total = 0.0
    for s in strokes:
        total += float(np.hypot(*(s[0] - pos)))
        pos = s[-1]
    return total
