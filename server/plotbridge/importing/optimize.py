"""Stroke optimization: fewer pen lifts and less pen-up travel.

1. drop repeated points, simplify each stroke within the tolerance;
2. order greedily: from where the pen is, go to the nearest free stroke end (either
   end: a stroke may be drawn backwards), found through a grid index; when that end
   is within `merge_distance` the two strokes become one and the pen stays down;
3. improve the order with 2-opt moves (reverse a run of up to TWO_OPT_WINDOW
   strokes) until none helps or a deadline passes.
"""

from __future__ import annotations

import itertools
import math
import time

import numpy as np

from .ops import Stroke
from .simplify import simplify_all

MERGE_DISTANCE = 0.01   # mm: ends this close are joined without lifting the pen
TWO_OPT_WINDOW = 64     # longest run of strokes a 2-opt move reverses


class EndIndex:
    """Grid over stroke ends for nearest-neighbour queries with removal.

    Ends at the same point share one entry (a list of their indices, removed ones
    dropped lazily), so a drawing of many identical strokes costs one distance per
    point, not per stroke: ordering stays near n log n on such degenerate input."""

    def __init__(self, ends: list[tuple[float, float]], cell: float) -> None:
        self.cell = cell
        self.grid: dict[tuple[int, int], dict[tuple[float, float], list[int]]] = {}
        self.ends = ends
        self.removed = bytearray(len(ends))
        self.left: dict[tuple[float, float], int] = {}  # ends not yet removed per point
        for k, end in enumerate(ends):
            self.grid.setdefault(self._key(*end), {}).setdefault(end, []).append(k)
            self.left[end] = self.left.get(end, 0) + 1
        self.count = len(ends)

    def _key(self, x: float, y: float) -> tuple[int, int]:
        return math.floor(x / self.cell), math.floor(y / self.cell)

    def remove(self, k: int) -> None:
        end = self.ends[k]
        self.removed[k] = 1
        self.count -= 1
        self.left[end] -= 1
        if not self.left[end]:
            del self.grid[self._key(*end)][end]

    def _any(self, waiting: list[int]) -> int:
        while self.removed[waiting[-1]]:
            waiting.pop()
        return waiting[-1]

    def nearest(self, x: float, y: float) -> int:
        """Index of the nearest remaining end (the index must not be empty)."""
        cx, cy = self._key(x, y)
        best, best_d = -1, math.inf
        ring = 0
        grid, cell = self.grid, self.cell
        while True:
            for gx in range(cx - ring, cx + ring + 1):
                edge = gx in (cx - ring, cx + ring)
                for gy in (range(cy - ring, cy + ring + 1) if edge else (cy - ring, cy + ring)):
                    for (ex, ey), waiting in grid.get((gx, gy), {}).items():
                        d = (ex - x) ** 2 + (ey - y) ** 2
                        if d < best_d:
                            best, best_d = self._any(waiting), d
            # Every end outside the rings searched is at least ring*cell away.
            if best >= 0 and best_d <= (ring * cell) ** 2:
                return best
            ring += 1


def _clean_all(strokes: list[Stroke]) -> list[np.ndarray]:
    """Each non-empty stroke as an array without repeated points; a single point is
    doubled (a dot: pen down and up at one place)."""
    strokes = [s for s in strokes if s]
    sizes = np.fromiter((len(s) for s in strokes), dtype=np.intp, count=len(strokes))
    flat = np.fromiter(itertools.chain.from_iterable(itertools.chain.from_iterable(strokes)),
                       dtype=float, count=2 * int(sizes.sum()))
    pts = flat.reshape(-1, 2)
    ends = np.cumsum(sizes)
    starts = ends - sizes
    keep = np.ones(len(pts), dtype=bool)
    keep[1:] = np.any(np.abs(np.diff(pts, axis=0)) > 1e-9, axis=1)
    keep[starts] = True
    out = []
    for a, b in zip(starts.tolist(), ends.tolist(), strict=True):
        s = pts[a:b][keep[a:b]]
        out.append(np.vstack([s, s]) if len(s) == 1 else s)
    return out


def order_greedy(strokes: list[np.ndarray], start: tuple[float, float],
                 merge_distance: float) -> list[np.ndarray]:
    n = len(strokes)
    ends = [(float(s[0][0]), float(s[0][1])) for s in strokes] + \
           [(float(s[-1][0]), float(s[-1][1])) for s in strokes]
    pts = np.concatenate(strokes)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
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


def _gains(s: np.ndarray, e: np.ndarray, origin: np.ndarray, lo: int, hi: int,
           window: int) -> np.ndarray:
    """Travel saved by reversing positions i..i+k, for rows i in lo..hi-1 and columns
    k <= window (-inf where i+k is past the end)."""
    n = len(s)
    rows = np.arange(lo, hi)[:, None]
    js = rows + np.arange(window + 1)[None, :]
    valid = js < n
    js = np.minimum(js, n - 1)
    nxt = np.minimum(js + 1, n - 1)
    last = js + 1 >= n
    prev = e[np.maximum(rows[:, 0] - 1, 0)]
    if lo == 0:
        prev[0] = origin
    si = s[rows[:, 0]]
    # Reversing positions i..j turns the edges prev→s[i] and e[j]→s[j+1] into
    # prev→e[j] and s[i]→s[j+1] (no edge after the last position).
    head = np.hypot(si[:, 0] - prev[:, 0], si[:, 1] - prev[:, 1])[:, None]
    ej, sn = e[js], s[nxt]
    old = head + np.where(last, 0.0, np.hypot(sn[..., 0] - ej[..., 0], sn[..., 1] - ej[..., 1]))
    new = np.hypot(ej[..., 0] - prev[:, None, 0], ej[..., 1] - prev[:, None, 1]) + \
        np.where(last, 0.0, np.hypot(sn[..., 0] - si[:, None, 0], sn[..., 1] - si[:, None, 1]))
    return np.where(valid, old - new, -np.inf)


def two_opt(strokes: list[np.ndarray], start: tuple[float, float], deadline: float,
            window: int = TWO_OPT_WINDOW) -> list[np.ndarray]:
    """Reverses runs of up to `window` strokes (and each stroke in them) while that
    shortens the travel, until no run does or the deadline passes. Each pass takes
    positions i in order and makes the best reversal starting at i; the gains of a band
    of rows are computed at once, again from just after each reversal (it changes the
    travel of no row that starts past its end)."""
    n = len(strokes)
    if n < 3:
        return strokes
    order = np.arange(n)
    flipped = np.zeros(n, dtype=bool)
    s = np.array([st[0] for st in strokes], dtype=float)    # start of position k
    e = np.array([st[-1] for st in strokes], dtype=float)   # end of position k
    origin = np.asarray(start, dtype=float)
    band = 16
    improved = True
    while improved and time.monotonic() < deadline:
        improved = False
        i = 0
        while i < n - 1 and time.monotonic() < deadline:
            hi = min(n - 1, i + band)
            gains = _gains(s, e, origin, i, hi, window)
            best = gains.max(axis=1)
            hits = np.flatnonzero(best > 1e-9)
            if not len(hits):
                i = hi
                continue
            i += int(hits[0])
            j = i + int(np.argmax(gains[hits[0]]))
            s[i:j + 1], e[i:j + 1] = e[i:j + 1][::-1].copy(), s[i:j + 1][::-1].copy()
            order[i:j + 1] = order[i:j + 1][::-1].copy()
            flipped[i:j + 1] = ~flipped[i:j + 1][::-1]
            improved = True
            i += 1
    return [strokes[o][::-1] if f else strokes[o] for o, f in zip(order, flipped, strict=True)]


def time_budget(strokes: int) -> float:
    """Seconds the 2-opt pass may take for a drawing of `strokes` strokes."""
    return min(2.0, 0.05 + 1e-4 * strokes)


def optimize_strokes(strokes: list[Stroke], tolerance: float, deadline: float,
                     start: tuple[float, float] = (0.0, 0.0),
                     merge_distance: float = MERGE_DISTANCE) -> list[Stroke]:
    """Strokes reordered, reversed, merged and simplified; the drawn geometry stays
    within `tolerance` of the original."""
    arrays = _clean_all(strokes)
    if not arrays:
        return []
    arrays = simplify_all(arrays, tolerance)
    ordered = two_opt(order_greedy(arrays, start, merge_distance), start, deadline)
    given = join_touching(arrays, merge_distance)
    if travel(given, start) < travel(ordered, start):
        ordered = given     # greedy is a heuristic: never hand back a worse order
    return [list(map(tuple, s.tolist())) for s in ordered]


def join_touching(strokes: list[np.ndarray], merge_distance: float) -> list[np.ndarray]:
    """The strokes in their given order, each joined to the one before where they meet."""
    out = [strokes[0]]
    for s in strokes[1:]:
        if float(np.hypot(*(s[0] - out[-1][-1]))) <= merge_distance:
            out[-1] = np.concatenate([out[-1], s[1:]])
        else:
            out.append(s)
    return out


def travel(strokes, start: tuple[float, float] = (0.0, 0.0)) -> float:
    """Pen-up travel from `start` through the strokes (point sequences) in order."""
    total = 0.0
    x, y = start
    for s in strokes:
        total += math.hypot(float(s[0][0]) - x, float(s[0][1]) - y)
        x, y = float(s[-1][0]), float(s[-1][1])
    return total
