"""Areas with shapely: fill regions (even-odd and nonzero), clipping, hatch lines."""

from __future__ import annotations

import math

import numpy as np
import shapely.affinity
import shapely.prepared
from shapely.geometry import LineString, MultiLineString, Polygon, box
from shapely.geometry.base import BaseGeometry

from . import geos

MAX_HATCH_LINES = 20_000     # per shape: a finer hatch is refused with a warning


def _winding(rings: list[np.ndarray], pts: np.ndarray) -> np.ndarray:
    """Winding number of each point about the rings (closed point arrays)."""
    w = np.zeros(len(pts), dtype=int)
    px, py = pts[:, 0][:, None], pts[:, 1][:, None]
    for r in rings:
        a, b = r[:-1], r[1:]
        ax, ay, bx, by = a[:, 0][None], a[:, 1][None], b[:, 0][None], b[:, 1][None]
        cross = (bx - ax) * (py - ay) - (px - ax) * (by - ay)
        up = (ay <= py) & (by > py) & (cross > 0)
        down = (ay > py) & (by <= py) & (cross < 0)
        w += up.sum(axis=1) - down.sum(axis=1)
    return w


def region(rings: list[np.ndarray], rule: str) -> BaseGeometry:
    """The area a fill covers: the closed rings under SVG's fill rule."""
    rings = [np.vstack([r, r[:1]]) if not np.array_equal(r[0], r[-1]) else r
             for r in rings if len(r) >= 3]
    if not rings:
        return Polygon()
    if len(rings) == 1:
        poly = Polygon(rings[0])
        if poly.is_valid:
            return poly
    # Split the plane along every ring's edges, then keep the faces the rule fills.
    faces = geos.faces(geos.union([LineString(r) for r in rings]))
    if not faces:
        return Polygon()
    inside = np.array([f.representative_point().coords[0] for f in faces])
    w = _winding(rings, inside)
    keep = (w % 2 == 1) if rule == "evenodd" else (w != 0)
    return geos.union([f for f, k in zip(faces, keep, strict=True) if k])


def clip_lines(lines: list[np.ndarray], area: BaseGeometry) -> list[np.ndarray]:
    """The parts of the polylines inside the area."""
    if area.is_empty:
        return []
    return geos.merged_lines(MultiLineString([ln for ln in lines if len(ln) > 1])
                             .intersection(area))


def rect(x0: float, y0: float, x1: float, y1: float) -> BaseGeometry:
    return box(min(x0, x1), min(y0, y1), max(x0, x1), max(y0, y1))


def inside_rect(lines: list[np.ndarray], r: tuple[float, float, float, float]) -> bool:
    return all(ln[:, 0].min() >= r[0] and ln[:, 1].min() >= r[1] and ln[:, 0].max() <= r[2]
               and ln[:, 1].max() <= r[3] for ln in lines)


def _hatch_once(area: BaseGeometry, spacing: float, angle: float) -> list[np.ndarray]:
    """Parallel lines `spacing` apart at `angle` degrees across the area, each joined to
    the next where the link between them stays inside the area (little pen-up travel)."""
    rot = shapely.affinity.rotate(area, -angle, origin=(0, 0), use_radians=False)
    x0, y0, x1, y1 = rot.bounds
    count = int((y1 - y0) / spacing)
    if count > MAX_HATCH_LINES:
        raise ValueError(f"hatch of {count} lines is too fine (spacing {spacing:g} mm)")
    ys = y0 + spacing / 2 + spacing * np.arange(count + 1)
    ys = ys[ys < y1]
    if not len(ys):
        return []
    scan = MultiLineString([[(x0 - 1, y), (x1 + 1, y)] for y in ys])
    rows: dict[int, list[np.ndarray]] = {}
    for g in geos.parts(scan.intersection(rot)):
        if isinstance(g, LineString) and len(g.coords) > 1:
            c = np.asarray(g.coords)
            k = round((c[0, 1] - ys[0]) / spacing)
            rows.setdefault(k, []).append(c[np.argsort(c[:, 0])] if c[0, 0] > c[-1, 0] else c)
    for k in rows:
        rows[k].sort(key=lambda c: c[0, 0])
    inner = shapely.prepared.prep(rot.buffer(spacing * 1e-3))
    chains: list[np.ndarray] = []
    keys = sorted(rows)
    while keys:
        k = keys[0]
        chain = [rows[k].pop(0)]
        while True:
            if not rows.get(k):
                rows.pop(k, None)
            nxt = rows.get(k + 1)
            if not nxt:
                break
            end = chain[-1][-1]
            pick = min(range(len(nxt)), key=lambda i: min(abs(nxt[i][0, 0] - end[0]),
                                                         abs(nxt[i][-1, 0] - end[0])))
            seg = nxt[pick]
            seg = seg if abs(seg[0, 0] - end[0]) <= abs(seg[-1, 0] - end[0]) else seg[::-1]
            if not inner.covers(LineString([end, seg[0]])):
                break
            nxt.pop(pick)
            chain.append(seg)
            k += 1
        if not rows.get(k):
            rows.pop(k, None)
        chains.append(np.vstack(chain))
        keys = sorted(rows)
    back = []
    for c in chains:
        g = shapely.affinity.rotate(LineString(c), angle, origin=(0, 0), use_radians=False)
        back.append(np.asarray(g.coords))
    return back


def hatch(area: BaseGeometry, spacing: float, angle: float, cross: bool) -> list[np.ndarray]:
    if area.is_empty or spacing <= 0 or not math.isfinite(spacing):
        return []
    lines = _hatch_once(area, spacing, angle)
    if cross:
        lines += _hatch_once(area, spacing, angle + 90.0)
    return lines
