"""SVG as a browser renders it, as pen-down polylines in millimetres, by layer.

The document is parsed safely (svgxml.py), then walked here: styles cascade and
inherit (svgstyle.py), `<use>` places its target (symbols with their viewBox), nested
viewports and `clip-path` clip (shapely), `<switch>` draws its first matching child,
`<mask>`, `<defs>` and other non-rendered content is never drawn, text is set in a
single-stroke font (svgtext.py), and fills are outlined or hatched on request
(fill.py). Shapes that would not be visible are skipped. An element that cannot be
read is skipped with a warning naming it. SVG's Y axis points down the page, the
plotter's away from the operator: the page is flipped so the drawing reads the same.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, replace
from pathlib import Path
from xml.etree.ElementTree import Element

import numpy as np
from shapely.geometry import Polygon
from shapely.geometry.base import BaseGeometry

from . import curves, fill, geos, pathdata, svgtext
from .curves import Affine, compose, viewbox_transform
from .fillplan import FillPlan, named_colour
from .models import ErrorLog, ImportFailed, ImportOptions
from .ops import Layer
from .svgclip import ClipMixin
from .svgmarkers import MARKED, MarkerMixin
from .svgstyle import (
    ROOT_STYLE,
    Stylesheet,
    cascade,
    href,
    length,
    local,
    numbers,
    opacity,
    paint,
    url_id,
)
from .svgxml import parse_svg_xml

PX_MM = 25.4 / 96.0
INKSCAPE = "{http://www.inkscape.org/namespaces/inkscape}"
NOT_RENDERED = frozenset({
    "defs", "symbol", "clipPath", "mask", "marker", "pattern", "linearGradient",
    "radialGradient", "style", "title", "desc", "metadata", "script", "filter",
    "foreignObject", "font", "font-face", "cursor", "view", "animate", "set",
    "animateTransform", "animateMotion", "image", "namedview",
})
SHAPES = frozenset({"path", "rect", "circle", "ellipse", "line", "polyline", "polygon"})
EDGE_MM = 0.01           # the page clip keeps what lies on the page's edge or this near it
MAX_FILL_POINTS = 50_000   # outlines of filled shapes kept for the preview
MAX_ELEMENTS = 500_000   # elements drawn, counting each <use> copy: bounds clone bombs
MAX_DEPTH = 64
LANGUAGES = ("en",)


@dataclass(frozen=True)
class Ctx:
    m: Affine                          # user units -> page millimetres, y down
    style: dict
    opacity: float = 1.0
    clip: BaseGeometry | None = None   # page millimetres
    clip_box: tuple[float, float, float, float] | None = None   # when clip is that box
    chain: tuple[str, ...] = ()        # ids and labels of enclosing groups
    layer: str | None = None           # enclosing Inkscape layer
    vw: float = 100.0                  # viewport size in user units (for %)
    vh: float = 100.0
    uses: frozenset = frozenset()      # ids of the <use> targets being drawn
    depth: int = 0


def _where(elem: Element, tag: str) -> str:
    ident = elem.get("id")
    return f"<{tag} id=\"{ident}\">" if ident else f"<{tag}>"


def _area(p: np.ndarray) -> float:
    """Zero when the points lie on one line (a ring through them encloses nothing), else
    the summed areas of the triangles they fan into from the first."""
    if len(p) < 3:
        return 0.0
    d = p[1:] - p[0]
    return float(np.abs(d[:-1, 0] * d[1:, 1] - d[:-1, 1] * d[1:, 0]).sum()) / 2


def _unless_percent(value: str | None, vb: list[float]) -> str | None:
    """The root's width or height, None for a percentage when there is no viewBox."""
    if value is not None and value.strip().endswith("%") and not vb:
        return None
    return value


class SvgReader(ClipMixin, MarkerMixin):
    _where = staticmethod(_where)

    def __init__(self, root: Element, options: ImportOptions, errors: ErrorLog) -> None:
        self.root = root
        self.options = options
        self.errors = errors
        self.sheet = Stylesheet(root)
        self.ids: dict[str, Element] = {}
        for el in root.iter():
            ident = el.get("id")
            if ident is not None and ident not in self.ids:
                self.ids[ident] = el
        self.fills = FillPlan(options)
        self.tol_mm = max(min(options.tolerance, 0.05) / 2, 0.005)
        self.layers: dict[str, Layer] = {}
        self.found_names: set[str] = set()
        self.invisible = 0
        self.filled_only = 0
        self.count = 0
        self.substitutions: list[dict] = []
        self.page: tuple[float, float] | None = None
        self._clip_cache: dict[tuple, BaseGeometry] = {}
        self._page_clip: list[tuple[Layer, int, list[np.ndarray]]] = []
        self._warned: set[tuple[int, str]] = set()
        self._capture: list[np.ndarray] | None = None    # ClipMixin._captured
        self.fill_points = 0
        self.root_style = ROOT_STYLE

    # ---- entry ---------------------------------------------------------------------

    def read(self) -> list[Layer]:
        root = self.root
        if local(root.tag) != "svg":
            raise ImportFailed.one(422, f"not SVG: the root element is <{root.tag}>")
        style, own = cascade(root, "svg", ROOT_STYLE, self.sheet)
        self.root_style = style
        vb = numbers(root.get("viewBox"))
        if len(vb) != 4 or vb[2] <= 0 or vb[3] <= 0:
            vb = []
        try:
            # A percentage of the viewBox (the size a browser gives the image), or with
            # no viewBox an unknown size: the drawing's own extent, as with none given.
            w = length(_unless_percent(root.get("width"), vb), vb[2] if vb else 0.0,
                       default=-1.0)
            h = length(_unless_percent(root.get("height"), vb), vb[3] if vb else 0.0,
                       default=-1.0)
        except ValueError as e:
            raise ImportFailed.one(422, f"<svg>: width or height: {e}") from None
        if w < 0:
            w = vb[2] if vb else -1.0
        if h < 0:
            h = vb[3] if vb else -1.0
        if w == 0 or h == 0:
            raise ImportFailed.one(422, "<svg>: width or height is zero: nothing is shown")
        m: Affine = (PX_MM, 0.0, 0.0, PX_MM, 0.0, 0.0)
        vw, vh = (vb[2], vb[3]) if vb else (w if w > 0 else 100.0, h if h > 0 else 100.0)
        if vb and w > 0 and h > 0:
            m = compose(m, viewbox_transform(vb, 0.0, 0.0, w, h,
                                             root.get("preserveAspectRatio")))
        elif vb:
            m = compose(m, (1.0, 0.0, 0.0, 1.0, -vb[0], -vb[1]))
            w, h = vb[2], vb[3]
        ctx = Ctx(m=m, style=style, vw=vw, vh=vh)
        if w > 0 and h > 0:
            self.page = (w * PX_MM, h * PX_MM)
            if self.options.clip_to_page:
                # what lies within EDGE_MM of the page is kept as it is
                b = (-EDGE_MM, -EDGE_MM, w * PX_MM + EDGE_MM, h * PX_MM + EDGE_MM)
                ctx = replace(ctx, clip=fill.rect(0.0, 0.0, w * PX_MM, h * PX_MM), clip_box=b)
        ctx = replace(ctx, m=compose(ctx.m, self._transform(root, "svg", own)))
        ctx = replace(ctx, opacity=opacity(own.get("opacity")))
        with np.errstate(all="ignore"):     # huge or degenerate geometry: skipped, not warned
            self.children(root, ctx)
            self._clip_to_page()
        return self.result()

    def result(self) -> list[Layer]:
        layers = [lay for lay in self.layers.values() if lay.strokes]
        if not layers:
            return []
        if self.page is not None:
            top = self.page[1]
        else:
            top = max(y for lay in layers for s in lay.strokes for _, y in s)
        for lay in layers:
            lay.strokes = [[(x, top - y) for x, y in s] for s in lay.strokes]
            lay.fills = [[(x, top - y) for x, y in s] for s in lay.fills]
        return layers

    # ---- walking -------------------------------------------------------------------

    def children(self, elem: Element, ctx: Ctx) -> None:
        for child in elem:
            self.element(child, ctx)

    def element(self, elem: Element, ctx: Ctx) -> None:
        tag = local(elem.tag)
        if tag is None or tag in NOT_RENDERED:
            return
        if (elem.get(f"{INKSCAPE}groupmode") == "layer"
                and elem.get("style", "").replace(" ", "").find("display:none") >= 0):
            return
        self.count += 1
        if self.count > MAX_ELEMENTS:
            raise ImportFailed.one(422, f"SVG refused: more than {MAX_ELEMENTS} elements to "
                                        "draw (counting every <use> copy)")
        if ctx.depth > MAX_DEPTH:
            self.errors.warn(None, f"{_where(elem, tag)} skipped: nested more than "
                                   f"{MAX_DEPTH} levels deep")
            return
        try:
            self._element(elem, tag, ctx)
        except (ImportFailed, MemoryError):  # a MemoryError names the worker's limit
            raise
        except RecursionError:
            self.errors.warn(None, f"{_where(elem, tag)} skipped: nested too deeply")
        except (ValueError, TypeError, ZeroDivisionError, IndexError, AttributeError,
                KeyError, OverflowError, ArithmeticError) as e:
            self.errors.warn(None, f"{_where(elem, tag)} skipped: {e}")
        except Exception as e:   # a geometry library's own failure: named, not raised
            self.errors.warn(None, f"{_where(elem, tag)} skipped: {type(e).__name__}: {e}")

    def _element(self, elem: Element, tag: str, ctx: Ctx) -> None:
        style, own = cascade(elem, tag, ctx.style, self.sheet)
        if own.get("display", "").strip() == "none":
            return
        ctx = replace(ctx, style=style, opacity=ctx.opacity * opacity(own.get("opacity")),
                      depth=ctx.depth + 1)
        if ctx.opacity <= 0:
            self.invisible += 1
            return
        if own.get("transform"):
            ctx = replace(ctx, m=compose(ctx.m, self._transform(elem, tag, own)))
        clip_id = url_id(own.get("clip-path"))
        if clip_id is not None:
            ctx = self._clipped(ctx, clip_id, elem, tag)
            if ctx.clip is not None and ctx.clip.is_empty:
                return
        mask_id = url_id(own.get("mask"))
        if mask_id is not None:
            ctx = self._masked(ctx, mask_id, elem, tag)
            if ctx.clip is not None and ctx.clip.is_empty:
                self.invisible += 1
                return
        if tag in ("g", "a"):
            names = [n for n in (elem.get("id"), elem.get(f"{INKSCAPE}label")) if n]
            self.found_names.update(names)
            if elem.get(f"{INKSCAPE}groupmode") == "layer" and ctx.layer is None:
                ctx = replace(ctx, layer=elem.get(f"{INKSCAPE}label") or elem.get("id")
                              or f"layer {len(self.layers) + 1}")
            self.children(elem, replace(ctx, chain=ctx.chain + tuple(names)))
        elif tag == "switch":
            for child in elem:
                ctag = local(child.tag)
                if ctag is not None and self._condition(child):
                    self.element(child, ctx)
                    break
        elif tag == "svg":
            self._viewport(elem, elem, ctx, None, None)
        elif tag == "use":
            self._use(elem, ctx)
        elif tag in SHAPES:
            self._shape(elem, tag, ctx)
        elif tag == "text":
            self._text(elem, ctx)

    @staticmethod
    def _condition(elem: Element) -> bool:
        if elem.get("requiredExtensions") is not None:
            return False
        langs = elem.get("systemLanguage")
        if langs is not None:
            return any(lang.strip().lower().split("-")[0] in LANGUAGES
                       for lang in langs.split(","))
        return True

    def _viewport(self, elem: Element, sized: Element, ctx: Ctx, w_default: str | None,
                  h_default: str | None,
                  size: tuple[str | None, str | None] = (None, None)) -> None:
        """A nested <svg> or a <symbol> placed by a <use> (`sized` carries x, y,
        width and height; the use for a symbol; `size` overrides width and height)."""
        x = length(sized.get("x"), ctx.vw)
        y = length(sized.get("y"), ctx.vh)
        w = length(size[0] or sized.get("width") or w_default or "100%", ctx.vw)
        h = length(size[1] or sized.get("height") or h_default or "100%", ctx.vh)
        if w <= 0 or h <= 0:
            return
        vb = numbers(elem.get("viewBox"))
        m = ctx.m
        vw, vh = w, h
        if len(vb) == 4 and vb[2] > 0 and vb[3] > 0:
            m = compose(m, viewbox_transform(vb, x, y, w, h, elem.get("preserveAspectRatio")))
            vw, vh = vb[2], vb[3]
        else:
            m = compose(m, (1.0, 0.0, 0.0, 1.0, x, y))
        overflow = (elem.get("overflow") or "").strip()
        if overflow not in ("visible", "auto"):
            corners = curves.apply(ctx.m, np.array([[x, y], [x + w, y], [x + w, y + h],
                                                    [x, y + h]]))
            ctx = self._intersect(ctx, Polygon(corners))
            if ctx.clip is not None and ctx.clip.is_empty:
                return
        self.children(elem, replace(ctx, m=m, vw=vw, vh=vh))

    def _use(self, elem: Element, ctx: Ctx) -> None:
        ident = href(elem)
        target = self.ids.get(ident) if ident else None
        if target is None:
            self.errors.warn(None, f"{_where(elem, 'use')}: its target "
                                   f"'#{ident or ''}' does not exist; skipped")
            return
        if ident in ctx.uses:
            self.errors.warn(None, f"{_where(elem, 'use')}: refers to itself through "
                                   f"'#{ident}'; skipped")
            return
        ctx = replace(ctx, uses=ctx.uses | {ident})
        ttag = local(target.tag)
        if ttag == "symbol":
            style, own = cascade(target, "symbol", ctx.style, self.sheet)
            if own.get("display", "").strip() == "none":
                return
            ctx = replace(ctx, style=style, opacity=ctx.opacity * opacity(own.get("opacity")))
            ctx = replace(ctx, m=compose(ctx.m, self._transform(target, "symbol", own)))
            self._viewport(target, elem, ctx, target.get("width"), target.get("height"))
            return
        x = length(elem.get("x"), ctx.vw)
        y = length(elem.get("y"), ctx.vh)
        if ttag == "svg":      # the use's width and height, when given, size it
            self._viewport(target, target, replace(ctx, m=compose(ctx.m, (1, 0, 0, 1, x, y))),
                           None, None, (elem.get("width"), elem.get("height")))
            return
        self.element(target, replace(ctx, m=compose(ctx.m, (1.0, 0.0, 0.0, 1.0, x, y))))

    # ---- shapes --------------------------------------------------------------------

    def _geometry(self, elem: Element, tag: str, ctx: Ctx) -> list[tuple[np.ndarray, bool]]:
        """(points, closed) in the element's user units."""
        tol = self.tol_mm / max(curves.scale_of(ctx.m), 1e-12)
        vw, vh = ctx.vw, ctx.vh
        g = elem.get
        if tag == "path":
            geo, error = curves.path_data(g("d") or "", tol)
            if error:
                self._warn_once(elem, tag, f"path data drawn up to its error: {error}")
            return geo
        if tag == "rect":
            w, h = length(g("width"), vw), length(g("height"), vh)
            if w <= 0 or h <= 0:
                return []
            rx_s, ry_s = g("rx"), g("ry")
            rx = length(rx_s, vw) if rx_s not in (None, "auto") else None
            ry = length(ry_s, vh) if ry_s not in (None, "auto") else None
            rx = ry if rx is None else rx
            ry = rx if ry is None else ry
            rx, ry = min(max(rx or 0.0, 0.0), w / 2), min(max(ry or 0.0, 0.0), h / 2)
            return [(curves.rounded_rect(length(g("x"), vw), length(g("y"), vh), w, h, rx, ry,
                                         tol), True)]
        if tag in ("circle", "ellipse"):
            if tag == "circle":
                r = length(g("r"), math.hypot(vw, vh) / math.sqrt(2))
                rx = ry = r
            else:      # SVG 2: a radius missing or `auto` is the other one
                rx_s, ry_s = g("rx"), g("ry")
                rx = length(rx_s, vw) if rx_s not in (None, "auto") else None
                ry = length(ry_s, vh) if ry_s not in (None, "auto") else None
                rx = ry if rx is None else rx
                ry = rx if ry is None else ry
                rx, ry = rx or 0.0, ry or 0.0
            if rx <= 0 or ry <= 0:
                return []
            return [(curves.ellipse(length(g("cx"), vw), length(g("cy"), vh), rx, ry, tol), True)]
        if tag == "line":
            return [(np.array([[length(g("x1"), vw), length(g("y1"), vh)],
                               [length(g("x2"), vw), length(g("y2"), vh)]]), False)]
        vals, error = pathdata.numbers(g("points"))
        if error or len(vals) % 2:
            self._warn_once(elem, tag, "points drawn up to their error: "
                                       f"{error or 'an odd number of coordinates'}")
        if len(vals) < 4:
            return []
        pts = np.array(vals[: len(vals) // 2 * 2], dtype=float).reshape(-1, 2)
        if tag == "polygon":
            return [(np.vstack([pts, pts[:1]]), True)]
        return [(pts, False)]

    def _transform(self, elem: Element, tag: str, own: dict[str, str]) -> Affine:
        """The element's transform (the CSS property, else the attribute); one that
        cannot be read is left out with a warning, as a browser ignores it."""
        try:
            return curves.parse_transform(own.get("transform"))
        except ValueError as e:
            self._warn_once(elem, tag, f"transform not read, drawn untransformed: {e}")
            return curves.IDENTITY

    def _warn_once(self, elem: Element, tag: str, message: str) -> None:
        key = (id(elem), message)
        if key not in self._warned:
            self._warned.add(key)
            self.errors.warn(None, f"{_where(elem, tag)}: {message}")

    def _visible_stroke(self, ctx: Ctx) -> str | None:
        style = ctx.style
        p = paint(style, "stroke")
        if p is None or p[1] <= 0:
            return None
        if opacity(style.get("stroke-opacity")) <= 0:
            return None
        if style.get("visibility", "visible").strip() in ("hidden", "collapse"):
            return None
        try:
            if length(style.get("stroke-width"), math.hypot(ctx.vw, ctx.vh) / math.sqrt(2),
                      default=1.0) <= 0:
                return None
        except ValueError:
            pass
        return p[0]

    def _visible_fill(self, ctx: Ctx) -> str | None:
        style = ctx.style
        p = paint(style, "fill")
        if p is None or p[1] <= 0 or opacity(style.get("fill-opacity")) <= 0:
            return None
        if style.get("visibility", "visible").strip() in ("hidden", "collapse"):
            return None
        return p[0]

    def _shape(self, elem: Element, tag: str, ctx: Ctx) -> None:
        if tag in MARKED:
            self._markers(elem, tag, ctx)
        stroke = self._visible_stroke(ctx)
        fill_colour = self._visible_fill(ctx) if tag != "line" else None   # no area
        fills = self.fills.fill_for(((ctx.layer,) if ctx.layer else ()) + ctx.chain, fill_colour)
        mode = fills.mode
        if stroke is None and (fill_colour is None or mode == "none"):
            if fill_colour is not None:
                self.filled_only += 1
            else:
                self.invisible += 1
            return
        if not self._selected(ctx, stroke or fill_colour):
            return
        geo = self._geometry(elem, tag, ctx)
        if not geo:
            return
        page = [(curves.apply(ctx.m, p), closed) for p, closed in geo]
        if stroke is not None:
            self.emit(ctx, stroke, [p for p, _ in page if len(p) > 1])
        if fill_colour is not None and mode != "none" and self._capture is None:
            self._note_fill(ctx, stroke or fill_colour, page)
            if mode == "outline" and stroke is None:     # subpaths with an area
                self.emit(ctx, fill_colour, [np.vstack([p, p[:1]]) if not c else p
                                             for p, c in page if _area(p) > 1e-9])
            elif mode == "hatch":
                area = fill.region([p for p, _ in page], ctx.style.get("fill-rule", "nonzero"))
                self.emit(ctx, fill_colour, fill.hatch(area, fills.spacing, fills.angle,
                                                       fills.cross))

    def _note_fill(self, ctx: Ctx, colour: str, page: list[tuple[np.ndarray, bool]]) -> None:
        """The outline of a shape drawn for its fill, for the preview (at most
        MAX_FILL_POINTS points in all, each ring at most 256)."""
        if self.fill_points >= MAX_FILL_POINTS:
            return
        key = ctx.layer if ctx.layer is not None else colour
        layer = self.layers.get(key)
        if layer is None:
            layer = self.layers[key] = Layer(name=key, colour=colour)
        for p, _ in page:
            if len(p) > 2:
                ring = p[:: max(1, len(p) // 256)]
                self.fill_points += len(ring)
                layer.fills.append(list(map(tuple, ring.tolist())))

    def _selected(self, ctx: Ctx, colour: str | None) -> bool:
        layers = self.options.layers
        if not layers:
            return True
        if any(name in layers for name in ctx.chain):
            return True
        return colour is not None and any(named_colour(name) == colour for name in layers)

    def emit(self, ctx: Ctx, colour: str, lines: list[np.ndarray]) -> None:
        lines = [ln for ln in lines if len(ln) > 1 and np.isfinite(ln).all()]
        if not lines:
            return
        if self._capture is not None:
            self._capture.extend(lines)
            return
        deferred = False
        if ctx.clip is not None:
            if ctx.clip_box is not None:
                # Clipped to the page only: done for all such shapes at once at the end.
                deferred = not fill.inside_rect(lines, ctx.clip_box)
            else:
                lines = fill.clip_lines(lines, ctx.clip)
            if not lines:
                return
        key = ctx.layer if ctx.layer is not None else colour
        layer = self.layers.get(key)
        if layer is None:
            layer = self.layers[key] = Layer(name=key, colour=colour)
        if deferred:
            self._page_clip.append((layer, len(layer.strokes), lines))
            layer.strokes.append(None)      # the clipped lines go here, in drawing order
        else:
            layer.strokes.extend(list(map(tuple, ln.tolist())) for ln in lines)

    def _clip_to_page(self) -> None:
        """Clips the lines that cross the page's edge, all at once (geos.clip_each)."""
        if not self._page_clip:
            return
        flat = [ln for _, _, lines in self._page_clip for ln in lines]
        owner = [k for k, (_, _, lines) in enumerate(self._page_clip) for _ in lines]
        pts = np.vstack(flat)
        w, h = self.page
        for k, top in ((0, w), (1, h)):    # points just off an edge onto it
            col = pts[:, k]
            col[(col < 0) & (col >= -EDGE_MM)] = 0.0
            col[(col > top) & (col <= top + EDGE_MM)] = top
        # an intersection keeps what lies on the page's edge (clip_by_rect drops it)
        clipped = geos.clip_each(pts, [len(ln) for ln in flat], fill.rect(0.0, 0.0, w, h))
        pieces: list[list] = [[] for _ in self._page_clip]
        for k, found in zip(owner, clipped, strict=True):
            pieces[k].extend(list(map(tuple, coords.tolist())) for coords in found)
        slots: dict[int, dict[int, list]] = {}
        for (layer, index, _), found in zip(self._page_clip, pieces, strict=True):
            slots.setdefault(id(layer), {})[index] = found
        for layer in self.layers.values():
            filled = slots.get(id(layer))
            if filled:
                layer.strokes = [p for k, s in enumerate(layer.strokes)
                                 for p in (filled[k] if s is None else (s,))]

    # ---- text ----------------------------------------------------------------------

    def _text(self, elem: Element, ctx: Ctx) -> None:
        font = self.options.font
        runs: list[tuple[str, Ctx]] = []
        # (first run, end run, position lists) of each element, descendants first
        marks: list[tuple[int, int, dict[str, list[float]]]] = []
        preserve = elem.get("{http://www.w3.org/XML/1998/namespace}space") == "preserve"

        self._collect_runs(elem, ctx, preserve, runs, marks)
        if runs and not preserve:   # leading and trailing white space of the element
            runs[0] = (runs[0][0].lstrip(), runs[0][1])
            runs[-1] = (runs[-1][0].rstrip(), runs[-1][1])
        chars: list[svgtext.Char] = []
        starts = []
        for n, (text, rctx) in enumerate(runs):
            starts.append(len(chars))
            size, letter, word = self._metrics(rctx)
            anchor = rctx.style.get("text-anchor", "start").strip()
            chars.extend(svgtext.Char(ch, n, size, letter, word, anchor) for ch in text)
        starts.append(len(chars))
        for first, end, lists in marks:
            svgtext.assign(chars[starts[first]:starts[end]], lists)
        for n, strokes in sorted(svgtext.layout(font, chars).items()):
            self._emit_text(elem, runs[n][1], runs[n][0], strokes)

    def _collect_runs(self, node: Element, ctx: Ctx, preserve: bool,
                      runs: list[tuple[str, Ctx]],
                      marks: list[tuple[int, int, dict[str, list[float]]]]) -> None:
        """The text runs of `node` and its tspans into `runs`, each element's position
        lists into `marks` (descendants first). (A method, not a closure: one that calls
        itself is a reference cycle, left to the collector with all it holds.)"""
        first = len(runs)
        if node.text:
            runs.append((svgtext.collapse(node.text, preserve), ctx))
        for child in node:
            ctag = local(child.tag)
            if ctag == "tspan":
                cstyle, cown = cascade(child, ctag, ctx.style, self.sheet)
                if cown.get("display", "").strip() != "none":
                    self._collect_runs(child, replace(ctx, style=cstyle), preserve, runs, marks)
            elif ctag == "textPath":
                self._text_path(child, ctx, self.options.font, preserve)
            if child.tail:
                runs.append((svgtext.collapse(child.tail, preserve), ctx))
        lists = self._positions(node, ctx)
        if lists:
            marks.append((first, len(runs), lists))

    def _positions(self, node: Element, ctx: Ctx) -> dict[str, list[float]]:
        """The x, y, dx and dy lists of a text or tspan, in user units, and its rotate
        list in degrees."""
        size = length(ctx.style.get("font-size"), 16.0, default=16.0)
        out = {}
        for key, ref in (("x", ctx.vw), ("y", ctx.vh), ("dx", ctx.vw), ("dy", ctx.vh)):
            raw = node.get(key)
            if raw and raw.strip():
                out[key] = [length(v, ref, font=size) for v in re.split(r"[\s,]+", raw.strip())
                            if v]
        raw = node.get("rotate")
        if raw and raw.strip():
            out["rotate"] = svgtext.angles(raw)
        return out

    def _metrics(self, ctx: Ctx) -> tuple[float, float, float]:
        size = length(ctx.style.get("font-size"), 16.0, default=16.0)
        def spacing(key: str) -> float:
            v = ctx.style.get(key, "normal").strip()
            return 0.0 if v == "normal" else length(v, size, font=size)
        return size, spacing("letter-spacing"), spacing("word-spacing")

    def _emit_text(self, elem: Element, ctx: Ctx, text: str,
                   strokes: list[np.ndarray]) -> None:
        colour = self._visible_fill(ctx) or self._visible_stroke(ctx)
        if colour is None:
            self.invisible += 1
            return
        if self._capture is None and not self._selected(ctx, colour):
            return
        missing, plain = svgtext.unlike(text)
        for chars, how in ((missing, "not in the single-stroke fonts, drawn as '?'"),
                           (plain, "drawn without their accents")):
            if chars:
                names = ", ".join(f"'{c}' U+{ord(c):04X}" for c in chars[:10])
                more = f" and {len(chars) - 10} more" if len(chars) > 10 else ""
                self._warn_once(elem, "text", f"text '{text[:40]}': {names}{more} {how}")
        family = ctx.style.get("font-family", "").strip()
        if not svgtext.HERSHEY_NAMES.search(family):
            note = {"element": _where(elem, "text"), "text": text[:60], "font": family,
                    "substitute": self.options.font}
            if note not in self.substitutions and len(self.substitutions) < 100:
                self.substitutions.append(note)
        self.emit(ctx, colour, [curves.apply(ctx.m, s) for s in strokes if len(s) > 1])

    def _text_path(self, node: Element, ctx: Ctx, font: str, preserve: bool) -> None:
        style, _ = cascade(node, "textPath", ctx.style, self.sheet)
        ctx = replace(ctx, style=style)
        target = self.ids.get(href(node) or "")
        if target is None or local(target.tag) != "path":
            self.errors.warn(None, f"{_where(node, 'textPath')}: its path "
                                   f"'#{href(node) or ''}' does not exist; skipped")
            return
        text = svgtext.collapse("".join(node.itertext()), preserve).strip()
        pm = self._transform(target, "path", cascade(target, "path", ROOT_STYLE, self.sheet)[1])
        tol = self.tol_mm / max(curves.scale_of(ctx.m), 1e-12)
        subs = curves.path_subpaths(target.get("d") or "", tol)
        if not subs or not text:
            return
        path = curves.apply(pm, subs[0][0])
        seg = np.diff(path, axis=0)
        total = float(np.hypot(seg[:, 0], seg[:, 1]).sum())
        size, letter, word = self._metrics(ctx)
        offset = length(node.get("startOffset"), total, font=size)
        width = svgtext.advance(font, text, size, letter, word)
        anchor = style.get("text-anchor", "start").strip()
        offset += {"middle": -width / 2, "end": -width}.get(anchor, 0.0)
        strokes = svgtext.along(font, text, path, offset, size, letter, word)
        self._emit_text(node, ctx, text, strokes)


def read_svg(source: Path, options: ImportOptions, errors: ErrorLog) -> list[Layer]:
    """The visible drawing of an SVG file as layers of pen-down polylines in mm."""
    root = parse_svg_xml(source.read_bytes())
    if options.font not in svgtext.FONTS:
        raise ImportFailed.one(422, f"font must be one of {', '.join(svgtext.FONTS)}")
    reader = SvgReader(root, options, errors)
    layers = reader.read()
    reader.fills.warn_unused(errors)
    for note in reader.substitutions:
        errors.warn(None, f"text '{note['text']}' in {note['element']}: font "
                          f"'{note['font'] or 'unspecified'}' set in the single-stroke font "
                          f"'{note['substitute']}'")
    errors.substitutions = reader.substitutions
    if not layers:
        if options.layers:
            errors.add(None, f"no shapes in layers {', '.join(options.layers)}; the document "
                             f"has groups: {', '.join(sorted(reader.found_names)) or 'none'}")
        elif reader.filled_only:
            errors.add(None, f"nothing visible to draw: {reader.filled_only} shapes are filled "
                             "but have no stroke; import with fill=outline or fill=hatch to "
                             "draw them")
        else:
            errors.add(None, "nothing visible to draw: the SVG has no visible shapes "
                             f"({reader.invisible} invisible ones skipped)")
    return layers
