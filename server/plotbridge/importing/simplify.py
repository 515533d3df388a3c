"""Polyline simplification (Ramer-Douglas-Peucker, distance to the segment).

All intervals of one recursion level are split at once with array operations, so the
cost is a few passes over the points rather than one Python step per kept point.
"""

from __future__ import annotations

import numpy as np


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
    keep = simplify_mask(pts, tolerance, np.unique(np.concatenate([starts, ends - 1])))
    return [pts[a:b][keep[a:b]] for a, b in zip(starts, ends, strict=True)]


def simplify_mask(points: np.ndarray, tolerance: float, fixed: np.ndarray) -> np.ndarray:
    """Which points to keep; `fixed` are indices always kept, which must include the
    first and the last (several polylines laid end to end are simplified at once by
    fixing the ends of each)."""
    n = len(points)
    keep = np.zeros(n, dtype=bool)
    keep[fixed] = True
    active = np.flatnonzero(~keep)
    tol2 = tolerance * tolerance
    xs, ys = np.ascontiguousarray(points[:, 0]), np.ascontiguousarray(points[:, 1])
    while active.size:
        kept = np.flatnonzero(keep)
        pos = np.cumsum(keep)[active]    # kept points before each active one
        a, b = kept[pos - 1], kept[pos]
        ax, ay = xs[a], ys[a]
        dx, dy = xs[b] - ax, ys[b] - ay
        rx, ry = xs[active] - ax, ys[active] - ay
        dd = dx * dx + dy * dy
        t = (rx * dx + ry * dy) / np.where(dd > 0, dd, 1.0)
        np.clip(t, 0.0, 1.0, out=t)
        ox, oy = rx - t * dx, ry - t * dy
        dist2 = ox * ox + oy * oy
        starts = np.flatnonzero(np.r_[True, pos[1:] != pos[:-1]])
        gmax = np.maximum.reduceat(dist2, starts)
        sizes = np.diff(np.r_[starts, active.size])
        group = np.repeat(np.arange(starts.size), sizes)
        split = gmax > tol2
        # The farthest point of each interval that must be split becomes a kept point.
        cand = np.flatnonzero((dist2 == gmax[group]) & split[group])
        if not cand.size:
            break
        first = cand[np.r_[True, group[cand][1:] != group[cand][:-1]]]
        keep[active[first]] = True
        still = split[group]
        still[first] = False
        active = active[still]
    return keep
