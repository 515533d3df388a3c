"""Polyline simplification (Ramer-Douglas-Peucker with distance to the segment)."""

from __future__ import annotations

import numpy as np


def simplify(points: np.ndarray, tolerance: float) -> np.ndarray:
    """The subset of `points` (n x 2) that keeps every dropped point within `tolerance`
    of the simplified line; ends are always kept."""
    n = len(points)
    if n < 3 or tolerance <= 0:
        return points
    keep = np.zeros(n, dtype=bool)
    keep[0] = keep[-1] = True
    stack = [(0, n - 1)]
    tol2 = tolerance * tolerance
    while stack:
        a, b = stack.pop()
        if b - a < 2:
            continue
        p = points[a]
        d = points[b] - p
        rel = points[a + 1:b] - p
        dd = float(d @ d)
        if dd == 0.0:
            dist2 = np.einsum("ij,ij->i", rel, rel)
        else:
            t = np.clip(rel @ d / dd, 0.0, 1.0)
            off = rel - t[:, None] * d
            dist2 = np.einsum("ij,ij->i", off, off)
        k = int(np.argmax(dist2))
        if dist2[k] > tol2:
            m = a + 1 + k
            keep[m] = True
            stack.append((a, m))
            stack.append((m, b))
    return points[keep]
