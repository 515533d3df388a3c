"""Clip paths and masks as areas (shapely, page millimetres) that clip what they apply to.

A `<clipPath>`'s area is the union of its children's (shapes under `clip-rule`, text as
its single-stroke glyphs widened to a tenth of the font size, `<use>` of either), each
cut by its own `clip-path`, the whole cut by the clipPath's own `clip-path`. A `<mask>`
is made binary: its children are painted in order, and where one's luminance times its
opacity is at least one half (a gradient counts as visible) the mask shows what it
masks, where less it hides it; its fill and its stroke (widened to its stroke-width)
both paint. The mask's region (`x`, `y`, `width`, `height`: by default 10 % around the
element's bounding box) bounds it. A masked or clipped element is then drawn where the
area is, as a clip path draws it; one masked away entirely is not drawn.
"""

from __future__ import annotations

from dataclasses import replace
from xml.etree.ElementTree import Element

import numpy as np
from shapely.geometry import MultiLineString, Polygon
from shapely.geometry.base import BaseGeometry

from . import curves, fill, geos
from .curves import Affine, compose
from .svgstyle import ROOT_STYLE, cascade, href, length, local, opacity, paint, url_id

SHAPES = frozenset({"path", "rect", "circle", "ellipse", "line", "polyline", "polygon"})
GLYPH_WIDTH = 0.1      # text in a clip path: its strokes this share of the font size wide


def _bbox_units(bbox: tuple[float, float, float, float]) -> Affine:
    x0, y0, x1, y1 = bbox
    return (x1 - x0, 0.0, 0.0, y1 - y0, x0, y0)


def luminance(colour: str) -> float:
    r, g, b = (int(colour[k:k + 2], 16) / 255 for k in (1, 3, 5))
    return 0.2125 * r + 0.7154 * g + 0.0721 * b


class ClipMixin:
    """The clipping half of SvgReader (svg.py), which holds ids, sheet, errors and the
    geometry and text methods used here."""

    def _intersect(self, ctx, area: BaseGeometry):
        if ctx.clip is None:
            return replace(ctx, clip=area, clip_box=None)
        return replace(ctx, clip=ctx.clip.intersection(area), clip_box=None)

    # ---- clip-path -----------------------------------------------------------------

    def _clipped(self, ctx, clip_id: str, elem: Element, tag: str):
        area = self._clip_area(clip_id, ctx, elem, tag, frozenset())
        return ctx if area is None else self._intersect(ctx, area)

    def _clip_area(self, clip_id: str, ctx, elem: Element, tag: str,
                   seen: frozenset) -> BaseGeometry | None:
        """The area of clip path `clip_id` applied to `elem` (whose user space is
        ctx.m), None when there is no such clip path (a warning)."""
        cp = self.ids.get(clip_id)
        if cp is None or local(cp.tag) != "clipPath" or clip_id in seen:
            self.errors.warn(None, f"{self._where(elem, tag)}: clip-path '#{clip_id}' "
                                   f"{'refers to itself' if clip_id in seen else 'not found'};"
                                   " drawn unclipped")
            return None
        seen = seen | {clip_id}
        _, cown = cascade(cp, "clipPath", ROOT_STYLE, self.sheet)
        m = ctx.m
        if cp.get("clipPathUnits") == "objectBoundingBox":
            bbox = self._bbox(elem, tag, ctx)
            if bbox is None:
                return Polygon()
            m = compose(m, _bbox_units(bbox))
        m = compose(m, self._transform(cp, "clipPath", cown))
        key = (clip_id, m)
        area = self._clip_cache.get(key)
        if area is None:
            area = self._children_area(cp, m, ctx, seen)
            own = url_id(cown.get("clip-path"))
            if own is not None:
                outer = self._clip_area(own, replace(ctx, m=ctx.m), cp, "clipPath", seen)
                if outer is not None:
                    area = area.intersection(outer)
            self._clip_cache[key] = area
        return area

    def _children_area(self, cp: Element, m: Affine, ctx, seen: frozenset) -> BaseGeometry:
        parts = []
        for child in cp:
            ctag = local(child.tag)
            cm = m
            if ctag == "use":
                target = self.ids.get(href(child) or "")
                if target is None:
                    continue
                _, uown = cascade(child, "use", ROOT_STYLE, self.sheet)
                cm = compose(cm, self._transform(child, "use", uown))
                cm = compose(cm, (1.0, 0.0, 0.0, 1.0, length(child.get("x"), ctx.vw),
                                  length(child.get("y"), ctx.vh)))
                child, ctag = target, local(target.tag)
            if ctag not in SHAPES and ctag != "text":
                continue
            cstyle, cown = cascade(child, ctag, ROOT_STYLE, self.sheet)
            if (cown.get("display", "").strip() == "none"
                    or cstyle.get("visibility", "visible").strip() in ("hidden", "collapse")):
                continue
            cm = compose(cm, self._transform(child, ctag, cown))
            sub = replace(ctx, m=cm, style=cstyle, clip=None, clip_box=None)
            if ctag == "text":
                region = self._text_area(child, sub)
            else:
                rings = [curves.apply(cm, p) for p, _ in self._geometry(child, ctag, sub)]
                region = fill.region(rings, cstyle.get("clip-rule", "nonzero"))
            inner = url_id(cown.get("clip-path"))
            if inner is not None:
                area = self._clip_area(inner, sub, child, ctag, seen)
                if area is not None:
                    region = region.intersection(area)
            parts.append(region)
        return geos.union(parts) if parts else Polygon()

    def _text_area(self, elem: Element, ctx) -> BaseGeometry:
        """Text in a clip path: its glyph strokes, widened."""
        lines = self._captured(lambda: self._text(elem, ctx))
        if not lines:
            return Polygon()
        size = length(ctx.style.get("font-size"), 16.0, default=16.0)
        width = size * curves.scale_of(ctx.m) * GLYPH_WIDTH
        return MultiLineString(lines).buffer(width / 2)

    def _captured(self, draw) -> list[np.ndarray]:
        """What `draw` emits, kept instead of drawn."""
        outer, self._capture = self._capture, []
        try:
            draw()
            return self._capture
        finally:
            self._capture = outer

    def _bbox(self, elem: Element, tag: str, ctx) -> tuple | None:
        """The bounding box of an element's geometry in its user space."""
        pts = self._bbox_points(elem, tag, ctx, curves.IDENTITY, 0)
        if not pts:
            return None
        allp = np.vstack(pts)
        return (*allp.min(axis=0), *allp.max(axis=0))

    def _bbox_points(self, elem: Element, tag: str | None, ctx, m: Affine,
                     depth: int) -> list[np.ndarray]:
        if tag in SHAPES:
            return [curves.apply(m, p) for p, _ in self._geometry(elem, tag, ctx)]
        if tag not in ("g", "a") or depth > 32:
            return []
        out = []
        for child in elem:
            ctag = local(child.tag)
            if ctag in SHAPES or ctag in ("g", "a"):
                _, cown = cascade(child, ctag, ctx.style, self.sheet)
                cm = compose(m, self._transform(child, ctag, cown))
                out += self._bbox_points(child, ctag, ctx, cm, depth + 1)
        return out

    # ---- mask ----------------------------------------------------------------------

    def _masked(self, ctx, mask_id: str, elem: Element, tag: str):
        mk = self.ids.get(mask_id)
        if mk is None or local(mk.tag) != "mask":
            self.errors.warn(None, f"{self._where(elem, tag)}: mask '#{mask_id}' not found; "
                                   "drawn unmasked")
            return ctx
        bbox = self._bbox(elem, tag, ctx)
        if mk.get("maskUnits") == "userSpaceOnUse":
            region = [length(mk.get(k), ref, default=d) for k, ref, d in (
                ("x", ctx.vw, -0.1 * ctx.vw), ("y", ctx.vh, -0.1 * ctx.vh),
                ("width", ctx.vw, 1.2 * ctx.vw), ("height", ctx.vh, 1.2 * ctx.vh))]
        elif bbox is None:
            return replace(ctx, clip=Polygon())
        else:
            region = [length(mk.get(k), 1.0, default=d) for k, d in (
                ("x", -0.1), ("y", -0.1), ("width", 1.2), ("height", 1.2))]
            bx0, by0, bx1, by1 = bbox
            region = [bx0 + region[0] * (bx1 - bx0), by0 + region[1] * (by1 - by0),
                      region[2] * (bx1 - bx0), region[3] * (by1 - by0)]
        x, y, w, h = region
        if not (w > 0 and h > 0):              # no region: nothing shows
            return replace(ctx, clip=Polygon())
        box = Polygon(curves.apply(ctx.m, np.array([[x, y], [x + w, y], [x + w, y + h],
                                                    [x, y + h]])))
        m = ctx.m
        if mk.get("maskContentUnits") == "objectBoundingBox":
            if bbox is None:
                return replace(ctx, clip=Polygon())
            m = compose(m, _bbox_units(bbox))
        mstyle, _ = cascade(mk, "mask", ROOT_STYLE, self.sheet)
        area = self._paint_area(mk, m, replace(ctx, style=mstyle, clip=None, clip_box=None),
                                Polygon(), 0)
        return self._intersect(ctx, area.intersection(box))

    def _paint_area(self, node: Element, m: Affine, ctx, area: BaseGeometry,
                    depth: int) -> BaseGeometry:
        """The area where the mask's children paint visibly, in painting order."""
        for child in node:
            ctag = local(child.tag)
            if (ctag not in SHAPES and ctag not in ("g", "use")) or depth > 32:
                continue
            cstyle, cown = cascade(child, ctag, ctx.style, self.sheet)
            if cown.get("display", "").strip() == "none":
                continue
            cm = compose(m, self._transform(child, ctag, cown))
            op = opacity(cown.get("opacity"))
            if ctag == "use":
                target = self.ids.get(href(child) or "")
                if target is None or local(target.tag) not in SHAPES | {"g"}:
                    continue
                cm = compose(cm, (1.0, 0.0, 0.0, 1.0, length(child.get("x"), ctx.vw),
                                  length(child.get("y"), ctx.vh)))
                holder = Element("g")
                holder.append(target)
                area = self._paint_area(holder, cm, replace(ctx, style=cstyle), area,
                                        depth + 1)
                continue
            if ctag == "g":
                area = self._paint_area(child, cm, replace(ctx, style=cstyle), area, depth + 1)
                continue
            area = self._paint_shape(child, ctag, replace(ctx, m=cm, style=cstyle), op, area)
        return area

    def _paint_shape(self, elem: Element, tag: str, ctx, op: float,
                     area: BaseGeometry) -> BaseGeometry:
        """The mask's area after a shape paints it: its fill, then its stroke."""
        style = ctx.style
        geo = self._geometry(elem, tag, ctx)
        rings = [curves.apply(ctx.m, p) for p, _ in geo]
        for key in ("fill", "stroke"):
            p = paint(style, key)
            if p is None or style.get("visibility", "visible").strip() != "visible":
                continue
            value = 1.0 if style.get(key, "").strip().startswith("url(") else luminance(p[0])
            value *= p[1] * opacity(style.get(f"{key}-opacity")) * op
            shape = (fill.region(rings, style.get("fill-rule", "nonzero")) if key == "fill"
                     else self._stroke_area(rings, geo, style, ctx.m, ctx))
            area = area.union(shape) if value >= 0.5 else area.difference(shape)
        return area

    def _stroke_area(self, rings: list[np.ndarray], geo: list, style: dict, m: Affine,
                     ctx) -> BaseGeometry:
        try:
            width = length(style.get("stroke-width"), ctx.vw, default=1.0)
        except ValueError:
            width = 1.0
        lines = [r if not closed else np.vstack([r, r[:1]])
                 for r, (_, closed) in zip(rings, geo, strict=True) if len(r) > 1]
        if not lines or width <= 0:
            return Polygon()
        return MultiLineString(lines).buffer(width * curves.scale_of(m) / 2)
