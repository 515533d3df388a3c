"""The preview body: strokes and travel moves, decimated to what a phone can draw."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .simplify import simplify

MAX_POINTS = 200_000
BASE_TOLERANCE = 0.1   # mm: below what a preview on any screen shows
_CHUNK = 4096          # raw points simplified at a time inside one long stroke


class PreviewBuilder:
    """Collects pen-down polylines and pen-up travel as they are written; strokes are
    simplified as they end, harder only when the total would exceed `max_points`."""

    def __init__(self, max_points: int = MAX_POINTS) -> None:
        self.max_points = max_points
        self.tolerance = BASE_TOLERANCE
        self.strokes: list[np.ndarray] = []
        self.travel: list[tuple[float, float, float, float]] = []
        self.points = 0
        self._raw: list[tuple[float, float]] = []
        self._done: list[np.ndarray] = []
        self._travel_from: tuple[float, float] | None = None
        self._travel_to = (0.0, 0.0)

    def draw(self, x0: float, y0: float, x: float, y: float) -> None:
        if self._travel_from is not None:
            self._flush_travel()
        raw = self._raw
        if not raw:
            raw.append((x0, y0))
        raw.append((x, y))
        if len(raw) >= _CHUNK:
            part = simplify(np.array(raw), self.tolerance)
            self._done.append(part[:-1])
            self._raw = [raw[-1]]

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

    def end_stroke(self) -> None:
        if not self._raw:
            return
        parts = [*self._done, simplify(np.array(self._raw), self.tolerance)]
        stroke = np.concatenate(parts) if len(parts) > 1 else parts[0]
        if len(parts) > 1:
            stroke = simplify(stroke, self.tolerance)
        self._raw, self._done = [], []
        self.strokes.append(stroke)
        self.points += len(stroke)
        self._fit()

    def _fit(self) -> None:
        while self.points > self.max_points and self.tolerance < 50:
            self.tolerance *= 2
            self.strokes = [simplify(s, self.tolerance) for s in self.strokes]
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
        self._fit()
        return {
            "strokes": [np.round(s, 3).tolist() for s in self.strokes],
            "travel": [[[round(a, 3), round(b, 3)], [round(c, 3), round(d, 3)]]
                       for a, b, c, d in self.travel],
            "bounds": bounds,
        }

    def write(self, path: Path, bounds: dict[str, float]) -> None:
        with path.open("w", encoding="utf-8") as f:
            json.dump(self.finish(bounds), f, separators=(",", ":"))
