"""Polyline simplification (Ramer-Douglas-Peucker, distance to the segment).

All intervals of one recursion level are split at once with array operations, so the
cost is a few passes over the points rather than one Python step per kept point.
"""

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
    active = np.arange(1, n - 1)
    tol2 = tolerance * tolerance
    while active.size:
        kept = np.flatnonzero(keep)
        pos = np.searchsorted(kept, active)
        a, b = kept[pos - 1], kept[pos]
        p = points[a]
        d = points[b] - p
        rel = points[active] - p
        dd = np.einsum("ij,ij->i", d, d)
        t = np.einsum("ij,ij->i", rel, d) / np.where(dd > 0, dd, 1.0)
        np.clip(t, 0.0, 1.0, out=t)
        off = rel - t[:, None] * d
        dist2 = np.einsum("ij,ij->i", off, off)
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
    return points[keep]
