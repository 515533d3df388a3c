"""The preview body: strokes and travel moves, decimated to what a phone can draw."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .simplify import simplify_all, simplify_mask

MAX_POINTS = 200_000
BASE_TOLERANCE = 0.1   # mm: below what a preview on any screen shows
_BATCH = 1 << 16       # raw points simplified at a time


class PreviewBuilder:
    """Collects pen-down polylines and pen-up travel as they are written; strokes are
    simplified in batches, harder only when the total would exceed `max_points`."""

    def __init__(self, max_points: int = MAX_POINTS) -> None:
        self.max_points = max_points
        self.tolerance = BASE_TOLERANCE
        self.strokes: list[np.ndarray] = []
        self.colour: str | None = None   # of the strokes drawn from now on (their layer's)
        self.colours: list[str | None] = []
        # Program lines of each stroke: its pen-down line and its pen-up line, so the
        # web preview maps progress onto strokes exactly, whatever lies between them
        # (M0 between layers, dwells, travel).
        self.lines: list[tuple[int, int]] = []
        self._pen_lines = (0, 0)   # (pen-down line, pen-up line) of the current stroke
        self.travel: list[tuple[float, float, float, float]] = []
        self.points = 0
        self._raw: list[tuple[float, float]] = []
        # Raw pieces waiting for the next batch: (points, continues into the next piece,
        # colour, program lines).
        self._pending: list[tuple[list[tuple[float, float]], bool, str | None,
                                  tuple[int, int]]] = []
        self._pending_points = 0
        self._open: np.ndarray | None = None   # simplified start of a stroke still going
        self._travel_from: tuple[float, float] | None = None
        self._travel_to = (0.0, 0.0)

    def draw(self, x0: float, y0: float, x: float, y: float) -> None:
        if self._travel_from is not None:
            self._flush_travel()
        raw = self._raw
        if not raw:
            raw.append((x0, y0))
        raw.append((x, y))
        if len(raw) >= _BATCH:
            self._queue(continues=True)
            self._raw = [raw[-1]]

    def draw_many(self, x0: float, y0: float, pts: list[tuple[float, float]]) -> None:
        """`draw` along a polyline from (x0, y0) through `pts`."""
        if self._travel_from is not None:
            self._flush_travel()
        raw = self._raw
        if not raw:
            raw.append((x0, y0))
        while pts:
            room = _BATCH - len(raw)
            raw.extend(pts[:room])
            pts = pts[room:]
            if len(raw) >= _BATCH:
                self._queue(continues=True)
                self._raw = raw = [raw[-1]]

    def move(self, x0: float, y0: float, x: float, y: float) -> None:
        """A pen-up move; consecutive ones are shown as one travel line."""
        self.end_stroke()
        if self._travel_from is None:
            self._travel_from = (x0, y0)
        self._travel_to = (x, y)

    def _flush_travel(self) -> None:
        assert self._travel_from is not None
        self.travel.append((*self._travel_from, *self._travel_to))
        self._travel_from = None
        self.points += 2

    def pen_down(self, line: int) -> None:
        """The pen goes down at program line `line`: a new stroke starts."""
        self.end_stroke()
        self._pen_lines = (line, line)

    def pen_up(self, line: int) -> None:
        """The pen goes up at program line `line`: the stroke's last line."""
        self._pen_lines = (self._pen_lines[0], line)

    def end_stroke(self) -> None:
        if self._raw:
            self._queue(continues=False)
            self._raw = []

    def _queue(self, continues: bool) -> None:
        self._pending.append((self._raw, continues, self.colour, self._pen_lines))
        self._pending_points += len(self._raw)
        if self._pending_points >= _BATCH:
            self._simplify_pending()

    def _simplify_pending(self) -> None:
        if not self._pending:
            return
        sizes = [len(p[0]) for p in self._pending]
        pts = np.array([q for p in self._pending for q in p[0]], dtype=float)
        ends = np.cumsum(sizes)
        fixed = np.unique(np.concatenate([ends - np.array(sizes), ends - 1]))
        keep = simplify_mask(pts, self.tolerance, fixed)
        for (_, continues, colour, lines), lo, hi in zip(self._pending, ends - np.array(sizes),
                                                         ends, strict=True):
            piece = pts[lo:hi][keep[lo:hi]]
            if self._open is not None:
                piece = np.concatenate([self._open, piece[1:]])
                self._open = None
            if continues:
                self._open = piece
            else:
                self.strokes.append(piece)
                self.colours.append(colour)
                self.lines.append(lines)
                self.points += len(piece)
        self._pending, self._pending_points = [], 0
        self._fit()

    def _fit(self) -> None:
        while self.points > self.max_points and self.tolerance < 50:
            self.tolerance *= 2
            self.strokes = simplify_all(self.strokes, self.tolerance)
            self.points = sum(len(s) for s in self.strokes) + 2 * len(self.travel)
        if self.points > self.max_points:
            # Only travel can still be too much: keep an even sample of it.
            room = max(self.max_points - (self.points - 2 * len(self.travel)), 0) // 2
            step = max(1, -(-len(self.travel) // max(room, 1)))
            self.travel = self.travel[::step][:room]
            self.points = sum(len(s) for s in self.strokes) + 2 * len(self.travel)

    def finish(self, bounds: dict[str, float]) -> dict:
        self.end_stroke()
        if self._travel_from is not None:
            self._flush_travel()
        self._simplify_pending()
        self._fit()
        return {
            "strokes": [np.round(s, 3).tolist() for s in self.strokes],
            "colours": self.colours,
            "lines": [list(span) for span in self.lines],
            "travel": [[[round(a, 3), round(b, 3)], [round(c, 3), round(d, 3)]]
                       for a, b, c, d in self.travel],
            "bounds": bounds,
        }

    def write(self, path: Path, bounds: dict[str, float]) -> None:
        # json.dumps uses the C encoder; json.dump to a file would not.
        path.write_text(json.dumps(self.finish(bounds), separators=(",", ":")), encoding="utf-8")
