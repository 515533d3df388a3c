"""SVG: every visible shape as pen-down polylines in millimetres, plotter-oriented.

The XML is first parsed with defusedxml, which refuses DTDs and entities (no
billion laughs, no external files); svgelements then resolves transforms, viewBox,
physical units and styles. SVG's Y axis points down the page, the plotter's away
from the operator: the page is flipped so the drawing reads the same on paper.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import svgelements as se
from defusedxml import ElementTree as SafeET
from defusedxml.common import DefusedXmlException

from .models import ErrorLog, ImportFailed, ImportOptions
from .ops import Stroke

PX_MM = 25.4 / 96.0
INKSCAPE_LABEL = "{http://www.inkscape.org/namespaces/inkscape}label"
MAX_SEGMENT_POINTS = 1 << 14


def _flatten(seg, tol_px: float) -> np.ndarray:
    """Points along a curve segment (t in (0, 1]) with chords within tol_px of it."""
    n = 8
    while True:
        ts = np.linspace(0.0, 1.0, n + 1)
        pts = np.asarray(seg.npoint(ts), dtype=float)
        mids = np.asarray(seg.npoint((ts[:-1] + ts[1:]) / 2), dtype=float)
        dev = np.hypot(*(mids - (pts[:-1] + pts[1:]) / 2).T)
        if dev.max(initial=0.0) <= tol_px or n >= MAX_SEGMENT_POINTS:
            return pts[1:]
        n *= 4


def path_strokes(path: se.Path, tol_px: float) -> list[list[tuple[float, float]]]:
    strokes: list[list[tuple[float, float]]] = []
    cur: list[tuple[float, float]] = []
    for seg in path.segments():
        if isinstance(seg, se.Move):
            if len(cur) > 1:
                strokes.append(cur)
            cur = [(seg.end.x, seg.end.y)]
            continue
        if seg.start is None or seg.end is None:
            continue
        if not cur:
            cur = [(seg.start.x, seg.start.y)]
        if isinstance(seg, (se.Line, se.Close)):
            cur.append((seg.end.x, seg.end.y))
        else:
            cur.extend(map(tuple, _flatten(seg, tol_px).tolist()))
    if len(cur) > 1:
        strokes.append(cur)
    return strokes


def _selected(chain: list[str], element: se.Shape, layers: list[str]) -> bool:
    if any(name in layers for name in chain):
        return True
    stroke = element.stroke
    if stroke is None or stroke.value is None:
        return False
    return any(colour == stroke for colour in _colours(layers))


def _colours(layers: list[str]) -> list[se.Color]:
    """The layer names that are colours (svgelements reads any unknown name as black)."""
    out = []
    for layer in layers:
        colour = se.Color(layer)
        if colour != se.Color("black") or layer.strip().lower() in ("black", "#000", "#000000"):
            out.append(colour)
    return out


def read_svg(source: Path, options: ImportOptions, errors: ErrorLog) -> list[Stroke]:
    data = source.read_bytes()
    try:
        SafeET.fromstring(data, forbid_dtd=True)
    except DefusedXmlException as e:
        raise ImportFailed.one(422, f"SVG refused: {e.__class__.__name__} "
                                    "(DTDs and entities are not accepted)") from None
    except SafeET.ParseError as e:
        line = e.position[0] if getattr(e, "position", None) else None
        raise ImportFailed.one(422, f"SVG is not well-formed XML: {e}", line) from None
    try:
        import io
        doc = se.SVG.parse(io.BytesIO(data), reify=True, ppi=96.0)
    except Exception as e:  # svgelements raises many kinds on odd documents
        raise ImportFailed.one(422, f"SVG could not be read: {e}") from None
    height_mm = float(doc.height or 0.0) * PX_MM
    tol_px = max(min(options.tolerance, 0.02) / 4, 0.002) / PX_MM
    layers = options.layers
    out: list[Stroke] = []
    found_layers: set[str] = set()

    def walk(node, chain: list[str]) -> None:
        for child in node:
            if isinstance(child, se.Group):
                names = [n for n in (child.id, child.values.get(INKSCAPE_LABEL)) if n]
                found_layers.update(names)
                walk(child, chain + names)
            elif isinstance(child, se.Shape):
                if child.values.get("visibility") in ("hidden", "collapse"):
                    continue
                if layers and not _selected(chain, child, layers):
                    continue
                for s in path_strokes(se.Path(child), tol_px):
                    out.append([(x * PX_MM, height_mm - y * PX_MM) for x, y in s])

    walk(doc, [])
    if not out:
        if layers:
            errors.add(None, f"no shapes in layers {', '.join(layers)}; the document has "
                             f"groups: {', '.join(sorted(found_layers)) or 'none'}")
        else:
            errors.add(None, "the SVG has no visible shapes to draw")
    return out
