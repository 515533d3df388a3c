"""Built-in calibration patterns, drawn in millimetres from the origin."""

from __future__ import annotations

import math

from .font import text_strokes
from .models import ImportFailed
from .ops import Stroke

PATTERNS: dict[str, str] = {
    "square": "100 mm square with both diagonals: checks scale and squareness",
    "target": "concentric circles 10-100 mm across: checks backlash and roundness",
    "radial": "16 lines from the centre through all eight octants: checks direction handling",
    "text": "a line of single-stroke text: checks fine detail and pen lifts",
}


def _circle(cx: float, cy: float, r: float, tolerance: float = 0.01) -> Stroke:
    n = max(16, math.ceil(math.pi / math.acos(1 - tolerance / r)))
    return [(cx + r * math.cos(2 * math.pi * k / n), cy + r * math.sin(2 * math.pi * k / n))
            for k in range(n + 1)]


def pattern_strokes(name: str) -> list[Stroke]:
    if name == "square":
        return [[(0, 0), (100, 0), (100, 100), (0, 100), (0, 0)],
                [(0, 0), (100, 100)], [(100, 0), (0, 100)]]
    if name == "target":
        return [_circle(50, 50, r) for r in range(5, 51, 5)] + [
            [(45, 50), (55, 50)], [(50, 45), (50, 55)]]
    if name == "radial":
        # 16 directions: both sides of each octant boundary, every octant visited.
        return [[(50.0, 50.0), (50 + 50 * math.cos(a), 50 + 50 * math.sin(a))]
                for a in (math.pi / 8 * k + math.pi / 16 for k in range(16))]
    if name == "text":
        return text_strokes("PLOTBRIDGE 0123456789", 0.0, 0.0, 5.0)
    raise ImportFailed.one(422, f"unknown pattern '{name}': one of {', '.join(PATTERNS)}")
