"""The preview body: strokes and travel moves, decimated to what a phone can draw."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..native.previewjson import strokes_json
from .simplify import kept_pieces, simplify_all, simplify_mask

MAX_POINTS = 200_000
BASE_TOLERANCE = 0.1   # mm: below what a preview on any screen shows
_BATCH = 1 << 16       # raw points simplified at a time


def _joined(parts: list[list[tuple[float, float]] | np.ndarray]) -> np.ndarray:
    """The points of lists and arrays of points, in order, as one n x 2 array."""
    arrays: list[np.ndarray] = []
    run: list[tuple[float, float]] = []
    for p in parts:
        if isinstance(p, list):
            run.extend(p)
        else:
            if run:
                arrays.append(np.array(run, dtype=float))
                run = []
            arrays.append(p)
    if run or not arrays:
        arrays.append(np.array(run, dtype=float).reshape(-1, 2))
    return arrays[0] if len(arrays) == 1 else np.concatenate(arrays)


class PreviewBuilder:
    """Collects pen-down polylines and pen-up travel as they are written; strokes are
    simplified in batches, harder only when the total would exceed `max_points`."""

    def __init__(self, max_points: int = MAX_POINTS) -> None:
        self.fills: list[list[tuple[float, float]]] = []   # SVG filled shapes' outlines
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
        # The raw points of the stroke being drawn, in parts: lists of points drawn one
        # at a time and n x 2 arrays drawn in bulk; _raw_n counts them.
        self._raw: list[list[tuple[float, float]] | np.ndarray] = []
        self._raw_n = 0
        # Raw pieces waiting for the next batch: (parts as in _raw, points, continues into
        # the next piece, colour, program lines).
        self._pending: list[tuple[list, int, bool, str | None, tuple[int, int]]] = []
        self._pending_points = 0
        self._open: np.ndarray | None = None   # simplified start of a stroke still going
        self._travel_from: tuple[float, float] | None = None
        self._travel_to = (0.0, 0.0)

    def draw(self, x0: float, y0: float, x: float, y: float) -> None:
        if self._travel_from is not None:
            self._flush_travel()
        if not self._raw_n:
            self._raw.append([(x0, y0)])
            self._raw_n = 1
        part = self._raw[-1]
        if isinstance(part, np.ndarray):
            part = []
            self._raw.append(part)
        part.append((x, y))
        self._raw_n += 1
        if self._raw_n >= _BATCH:
            self._restart_raw((x, y))

    def draw_path(self, pts: np.ndarray) -> None:
        """`draw` along the polyline `pts` (n x 2) from its first point, where the pen
        is."""
        if self._travel_from is not None:
            self._flush_travel()
        if self._raw_n:
            pts = pts[1:]
        while len(pts):
            room = _BATCH - self._raw_n
            self._raw.append(pts[:room])
            self._raw_n += len(pts[:room])
            pts = pts[room:]
            if self._raw_n >= _BATCH:
                last = self._raw[-1][-1]
                self._restart_raw((float(last[0]), float(last[1])))

    def _restart_raw(self, last: tuple[float, float]) -> None:
        """A full batch of raw points goes to be simplified; the stroke goes on from its
        last point."""
        self._queue(continues=True)
        self._raw = [[last]]
        self._raw_n = 1

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
        if self._raw_n:
            self._queue(continues=False)
            self._raw = []
            self._raw_n = 0

    def _queue(self, continues: bool) -> None:
        self._pending.append((self._raw, self._raw_n, continues, self.colour,
                              self._pen_lines))
        self._pending_points += self._raw_n
        if self._pending_points >= _BATCH:
            self._simplify_pending()

    def _simplify_pending(self) -> None:
        if not self._pending:
            return
        sizes = [p[1] for p in self._pending]
        pts = _joined([part for p in self._pending for part in p[0]])
        ends = np.cumsum(sizes)
        starts = ends - np.array(sizes)
        keep = simplify_mask(pts, self.tolerance, np.concatenate([starts, ends - 1]))
        pieces = kept_pieces(pts, keep, starts, ends)
        for (_, _, continues, colour, lines), piece in zip(self._pending, pieces, strict=True):
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

    def _settle(self) -> None:
        """Everything drawn so far simplified and within the budget."""
        self.end_stroke()
        if self._travel_from is not None:
            self._flush_travel()
        self._simplify_pending()
        self._fit()

    def _rest(self, bounds: dict[str, float]) -> dict:
        """The body after its strokes."""
        body = {
            "colours": self.colours,
            "lines": [list(span) for span in self.lines],
            "travel": [[[round(a, 3), round(b, 3)], [round(c, 3), round(d, 3)]]
                       for a, b, c, d in self.travel],
            "bounds": bounds,
        }
        if self.fills:
            body["fills"] = [[[round(x, 3), round(y, 3)] for x, y in ring]
                             for ring in self.fills]
        return body

    def finish(self, bounds: dict[str, float]) -> dict:
        self._settle()
        return {"strokes": [np.round(s, 3).tolist() for s in self.strokes], **self._rest(bounds)}

    def write(self, path: Path, bounds: dict[str, float]) -> None:
        """preview.json: json.dumps(self.finish(bounds)) without spaces, the strokes
        (up to max_points numbers written by Python one at a time) by
        native/previewjson.c."""
        self._settle()
        strokes = strokes_json(self.strokes)
        if strokes is None:
            text = json.dumps(self.finish(bounds), separators=(",", ":"))
        else:
            # json.dumps uses the C encoder; json.dump to a file would not.
            rest = json.dumps(self._rest(bounds), separators=(",", ":"))
            text = f'{{"strokes":{strokes},{rest[1:]}'
        path.write_text(text, encoding="utf-8")
