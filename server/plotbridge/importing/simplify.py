"""Polyline simplification (Ramer-Douglas-Peucker, distance to the segment), done by
native/simplify.c: one pass per recursion level over a million preview points is too
slow in Python or array operations.
"""

from __future__ import annotations

import ctypes

import numpy as np

from ..native import array, function


def simplify(points: np.ndarray, tolerance: float) -> np.ndarray:
    """The subset of `points` (n x 2) that keeps every dropped point within `tolerance`
    of the simplified line; ends are always kept."""
    if len(points) < 3 or tolerance <= 0:
        return points
    return points[simplify_mask(points, tolerance, np.array([0, len(points) - 1]))]


def simplify_all(polylines: list[np.ndarray], tolerance: float) -> list[np.ndarray]:
    """`simplify` over many polylines in one pass."""
    if not polylines or tolerance <= 0:
        return polylines
    sizes = np.array([len(p) for p in polylines])
    ends = np.cumsum(sizes)
    starts = ends - sizes
    pts = np.concatenate(polylines)
    keep = simplify_mask(pts, tolerance, np.concatenate([starts, ends - 1]))
    return kept_pieces(pts, keep, starts, ends)


def kept_pieces(points: np.ndarray, keep: np.ndarray, starts: np.ndarray,
                ends: np.ndarray) -> list[np.ndarray]:
    """points[a:b][keep[a:b]] for each piece [a, b) of starts and ends, taken at once (a
    file of short strokes has thousands of pieces): views of one array of the kept
    points."""
    kept = np.compress(keep, points, axis=0)    # 10 times what points[keep] costs
    at = np.concatenate([[0], np.cumsum(keep, dtype=np.intp)])
    return [kept[a:b] for a, b in zip(at[starts].tolist(), at[ends].tolist(), strict=True)]


def simplify_mask(points: np.ndarray, tolerance: float, fixed: np.ndarray) -> np.ndarray:
    """Which points (n x 2) to keep; `fixed` are indices always kept (repeats allowed),
    which must include the first and the last (several polylines laid end to end are
    simplified at once by fixing the ends of each)."""
    keep = np.zeros(len(points), dtype=np.uint8)
    keep[fixed] = 1
    xy = np.ascontiguousarray(points, dtype=np.float64)
    if _native()(len(points), xy, tolerance * tolerance, keep):
        raise MemoryError("simplify: out of memory")
    return keep.view(bool)


def _native():
    return function("simplify", "simplify_mask",
                    [ctypes.c_long, array(np.float64, 2), ctypes.c_double, array(np.uint8)],
                    ctypes.c_int)
