"""Markers (SVG 1.1, 11.6): `marker-start`, `marker-mid` and `marker-end` (and the
`marker` shorthand) of paths, lines, polylines and polygons draw the marker's content
at the first, every inner and the last vertex: turned by `orient` (an angle, `auto`:
the bisector of the directions in and out of the vertex, `auto-start-reverse`: turned
back at the start), scaled by the stroke width (`markerUnits="strokeWidth"`, the
default) or not (`userSpaceOnUse`), the viewBox mapped into `markerWidth` x
`markerHeight` (3 x 3) with `refX`/`refY` on the vertex, clipped to that box unless
`overflow` is visible. The content takes its style from the marker, not from the shape.
"""

from __future__ import annotations

import math
from xml.etree.ElementTree import Element

import numpy as np
from shapely.geometry import Polygon

from . import curves, pathdata
from .curves import Affine, compose
from .svgstyle import cascade, length, local, numbers, url_id

MARKED = frozenset({"path", "line", "polyline", "polygon"})
_ANGLE_UNITS = {"": 1.0, "deg": 1.0, "rad": 180 / math.pi, "grad": 0.9, "turn": 360.0}


def _angle(text: str) -> float:
    t = text.strip().lower()
    for unit in ("deg", "grad", "rad", "turn"):
        if t.endswith(unit):
            return float(t[:-len(unit)]) * _ANGLE_UNITS[unit]
    return float(t)


def _shape_vertices(elem: Element, tag: str, ctx) -> list[tuple[float, float, float]]:
    g = elem.get
    if tag == "path":
        return pathdata.vertices(pathdata.parse(g("d") or ""))
    if tag == "line":
        pts = np.array([[length(g("x1"), ctx.vw), length(g("y1"), ctx.vh)],
                        [length(g("x2"), ctx.vw), length(g("y2"), ctx.vh)]])
    else:
        vals, _ = pathdata.numbers(g("points"))
        if len(vals) < 2:
            return []
        pts = np.array(vals[: len(vals) // 2 * 2], dtype=float).reshape(-1, 2)
    sub = pathdata.Subpath((float(pts[0, 0]), float(pts[0, 1])))
    if tag == "polygon":
        pts = np.vstack([pts, pts[:1]])
        sub.closed = True
    if len(pts) > 1:
        sub.segments.append(("L", pts))
    return pathdata.vertices(pathdata.PathData([sub]))


class MarkerMixin:
    """The markers half of SvgReader (svg.py)."""

    def _markers(self, elem: Element, tag: str, ctx) -> None:
        style = ctx.style
        ids = [url_id(style.get(f"marker-{pos}")) for pos in ("start", "mid", "end")]
        if not any(ids):
            return
        vertices = _shape_vertices(elem, tag, ctx)
        if not vertices:
            return
        try:
            width = length(style.get("stroke-width"), math.hypot(ctx.vw, ctx.vh) / math.sqrt(2),
                           default=1.0)
        except ValueError:
            width = 1.0
        last = len(vertices) - 1
        for k, (x, y, angle) in enumerate(vertices):
            ident = ids[0] if k == 0 else ids[2] if k == last else ids[1]
            if ident is None:
                continue
            marker = self.ids.get(ident)
            if marker is None or local(marker.tag) != "marker":
                self._warn_once(elem, tag, f"marker '#{ident}' not found; not drawn")
                continue
            if ident in ctx.uses:
                self._warn_once(elem, tag, f"marker '#{ident}' draws itself; not drawn again")
                continue
            self._marker(marker, ident, ctx, x, y, angle, width, k == 0)

    def _marker(self, mk: Element, ident: str, ctx, x: float, y: float, angle: float,
                width: float, start: bool) -> None:
        orient = (mk.get("orient") or "0").strip()
        if orient == "auto":
            degrees = math.degrees(angle)
        elif orient == "auto-start-reverse":
            degrees = math.degrees(angle) + (180.0 if start else 0.0)
        else:
            try:
                degrees = _angle(orient)
            except ValueError:
                degrees = 0.0
        scale = width if (mk.get("markerUnits") or "strokeWidth") == "strokeWidth" else 1.0
        mw = length(mk.get("markerWidth") or "3", ctx.vw)
        mh = length(mk.get("markerHeight") or "3", ctx.vh)
        if mw <= 0 or mh <= 0:
            return
        a = math.radians(degrees)
        c, s = math.cos(a), math.sin(a)
        m: Affine = compose(ctx.m, (1.0, 0.0, 0.0, 1.0, x, y))
        m = compose(m, (c * scale, s * scale, -s * scale, c * scale, 0.0, 0.0))
        vb = numbers(mk.get("viewBox"))
        if len(vb) == 4 and vb[2] > 0 and vb[3] > 0:
            inner = curves.viewbox_transform(vb, 0.0, 0.0, mw, mh, mk.get("preserveAspectRatio"))
            vw, vh = vb[2], vb[3]
        else:
            inner = curves.IDENTITY
            vw, vh = mw, mh
        ref = curves.apply(inner, np.array([[length(mk.get("refX"), vw),
                                             length(mk.get("refY"), vh)]]))[0]
        m = compose(m, (1.0, 0.0, 0.0, 1.0, -float(ref[0]), -float(ref[1])))
        style, own = cascade(mk, "marker", self.root_style, self.sheet)
        sub = ctx.__class__(m=compose(m, inner), style=style, opacity=ctx.opacity,
                            clip=ctx.clip, clip_box=ctx.clip_box, chain=ctx.chain,
                            layer=ctx.layer, vw=vw, vh=vh, uses=ctx.uses | {ident},
                            depth=ctx.depth + 1)
        overflow = (own.get("overflow") or "hidden").strip()
        if overflow not in ("visible", "auto"):
            box = curves.apply(m, np.array([[0.0, 0.0], [mw, 0.0], [mw, mh], [0.0, mh]]))
            sub = self._intersect(sub, Polygon(box))
            if sub.clip.is_empty:
                return
        for child in mk:
            self.element(child, sub)
