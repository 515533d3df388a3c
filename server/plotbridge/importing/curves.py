"""SVG geometry to polylines: path data, basic shapes, affine transforms.

Curves are cut into as many chords as their curvature needs for the tolerance,
computed once per segment (no adaptive refinement): for a Bézier the chord error of
n equal parameter steps is at most max|B''| / (8 n²).
"""

from __future__ import annotations

import math
import re

import numpy as np
import svgelements as se

Affine = tuple[float, float, float, float, float, float]   # a b c d e f (SVG matrix())
IDENTITY: Affine = (1.0, 0.0, 0.0, 1.0, 0.0, 0.0)
MAX_SEGMENT_POINTS = 1 << 14


def compose(m: Affine, n: Affine) -> Affine:
    """m · n: apply n first, then m."""
    a, b, c, d, e, f = m
    a2, b2, c2, d2, e2, f2 = n
    return (a * a2 + c * b2, b * a2 + d * b2, a * c2 + c * d2, b * c2 + d * d2,
            a * e2 + c * f2 + e, b * e2 + d * f2 + f)


def parse_transform(text: str) -> Affine:
    m = se.Matrix(text)
    return (m.a, m.b, m.c, m.d, m.e, m.f)


def scale_of(m: Affine) -> float:
    """The largest factor by which m stretches a length."""
    a, b, c, d = m[:4]
    p = (a * a + b * b + c * c + d * d) / 2
    q = math.sqrt(max(p * p - (a * d - b * c) ** 2, 0.0))
    return math.sqrt(p + q)


def apply(m: Affine, pts: np.ndarray) -> np.ndarray:
    a, b, c, d, e, f = m
    out = np.empty_like(pts)
    out[:, 0] = a * pts[:, 0] + c * pts[:, 1] + e
    out[:, 1] = b * pts[:, 0] + d * pts[:, 1] + f
    return out


def _bezier(p: np.ndarray, tol: float) -> np.ndarray:
    """Points of a quadratic (3 control points) or cubic (4) Bézier after the start."""
    if len(p) == 3:
        acc = 2 * np.hypot(*(p[0] - 2 * p[1] + p[2]))
    else:
        acc = 6 * max(np.hypot(*(p[0] - 2 * p[1] + p[2])), np.hypot(*(p[1] - 2 * p[2] + p[3])))
    n = min(max(1, math.ceil(math.sqrt(acc / (8 * tol)))), MAX_SEGMENT_POINTS)
    if n == 1:
        return p[-1:]
    t = np.linspace(0.0, 1.0, n + 1)[1:, None]
    u = 1 - t
    if len(p) == 3:
        return u * u * p[0] + 2 * u * t * p[1] + t * t * p[2]
    return u * u * u * p[0] + 3 * u * u * t * p[1] + 3 * u * t * t * p[2] + t * t * t * p[3]


def _arc(seg: se.Arc, tol: float) -> np.ndarray:
    r = max(abs(seg.rx or 0.0), abs(seg.ry or 0.0))
    if r <= 0 or not seg.sweep:
        return np.array([[seg.end.x, seg.end.y]])
    step = 2 * math.acos(max(1 - tol / r, -1.0))
    n = min(max(1, math.ceil(abs(seg.sweep) / max(step, 1e-9))), MAX_SEGMENT_POINTS)
    return np.asarray(seg.npoint(np.linspace(0.0, 1.0, n + 1)[1:]), dtype=float)


# Path data of lines and Béziers only (what plotting tools mostly write) is read here in
# bulk; anything else (arcs, smooth curves, unusual syntax) by svgelements, segment by
# segment. The number grammar and separators are svgelements' own, so both read the
# same numbers; the unit tests compare the two.
_NUM = r"[-+]?[0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?"
_PATH_BULK = re.compile(rf"[ ,\t\n\f\r]*[Mm](?:[ ,\t\n\f\r]+|[MmLlHhVvZzCcQq]|{_NUM})*")
_PATH_TOKEN = re.compile(rf"([MmLlHhVvZzCcQq])|({_NUM})")
_PAIRS = {"M": 2, "L": 2, "H": 1, "V": 1, "Z": 0, "C": 6, "Q": 4}


def _bulk_subpaths(d: str, tol: float) -> list[tuple[np.ndarray, bool]] | None:
    """path_subpaths for path data of M, L, H, V, Z, C and Q commands; None for other
    path data."""
    if _PATH_BULK.fullmatch(d) is None:
        return None
    commands: list[tuple[str, list[str]]] = []
    for cmd, num in _PATH_TOKEN.findall(d):
        if cmd:
            commands.append((cmd, []))
        else:
            commands[-1][1].append(num)
    out: list[tuple[np.ndarray, bool]] = []
    cur: list[np.ndarray] = []
    closed = False
    x = y = sx = sy = 0.0
    started = False
    for cmd, nums in commands:
        up = cmd.upper()
        size = _PAIRS[up]
        if (len(nums) == 0) != (size == 0) or (size and len(nums) % size):
            return None
        rel = cmd != up and started
        if up == "Z":
            cur.append(np.array([[sx, sy]]))
            closed = True
            x, y = sx, sy
            continue
        v = np.array(nums, dtype=float)
        if up in ("M", "L"):
            pts = v.reshape(-1, 2)
            if rel:
                pts = np.cumsum(np.vstack([[x, y], pts]), axis=0)[1:]
            elif cmd == "m" and len(pts) > 1:    # the first pair absolute, then relative
                pts = np.cumsum(pts, axis=0)
            if up == "M":
                if cur:
                    out.append((np.vstack(cur), closed))
                cur, closed = [], False
                sx, sy = pts[0]
                started = True
            cur.append(pts)
        elif up in ("H", "V"):
            k = 0 if up == "H" else 1
            run = np.cumsum(np.concatenate([[(x, y)[k]], v]))[1:] if rel else v
            pts = np.empty((len(v), 2))
            pts[:, k] = run
            pts[:, 1 - k] = (y, x)[k]
            cur.append(pts)
        else:
            n = size // 2
            ctrl = v.reshape(-1, n, 2)
            px, py = x, y
            for seg in ctrl:
                if rel:
                    seg = np.add(seg, (px, py))
                cur.append(_bezier(np.vstack([[px, py], seg]), tol))
                px, py = float(seg[-1][0]), float(seg[-1][1])
            x, y = px, py
            continue
        x, y = float(pts[-1][0]), float(pts[-1][1])
    if cur:
        out.append((np.vstack(cur), closed))
    return out


def path_subpaths(d: str, tol: float) -> list[tuple[np.ndarray, bool]]:
    """(points, closed) of each subpath of path data, in user units."""
    bulk = _bulk_subpaths(d, tol)
    if bulk is not None:
        return bulk
    path = se.Path(d)
    out: list[tuple[np.ndarray, bool]] = []
    cur: list = []
    closed = False

    def flush() -> None:
        if cur:
            pts = np.vstack(cur) if len(cur) > 1 else np.asarray(cur[0], dtype=float)
            out.append((pts.reshape(-1, 2), closed))

    for seg in path:
        if isinstance(seg, se.Move):
            flush()
            cur, closed = [np.array([[seg.end.x, seg.end.y]])], False
            continue
        if seg.start is None or seg.end is None:
            continue
        if not cur:
            cur = [np.array([[seg.start.x, seg.start.y]])]
        if isinstance(seg, se.Close):
            cur.append(np.array([[seg.end.x, seg.end.y]]))
            closed = True
        elif isinstance(seg, se.Line):
            cur.append(np.array([[seg.end.x, seg.end.y]]))
        elif isinstance(seg, se.QuadraticBezier):
            cur.append(_bezier(np.array([[seg.start.x, seg.start.y], [seg.control.x, seg.control.y],
                                         [seg.end.x, seg.end.y]]), tol))
        elif isinstance(seg, se.CubicBezier):
            cur.append(_bezier(np.array([[seg.start.x, seg.start.y],
                                         [seg.control1.x, seg.control1.y],
                                         [seg.control2.x, seg.control2.y],
                                         [seg.end.x, seg.end.y]]), tol))
        elif isinstance(seg, se.Arc):
            cur.append(_arc(seg, tol))
    flush()
    return out


def ellipse(cx: float, cy: float, rx: float, ry: float, tol: float) -> np.ndarray:
    r = max(rx, ry)
    step = 2 * math.acos(max(1 - tol / r, -1.0)) if r > 0 else math.pi
    n = min(max(8, math.ceil(2 * math.pi / max(step, 1e-9))), MAX_SEGMENT_POINTS)
    a = np.linspace(0.0, 2 * math.pi, n + 1)
    a[-1] = 0.0
    return np.column_stack([cx + rx * np.cos(a), cy + ry * np.sin(a)])


def rounded_rect(x: float, y: float, w: float, h: float, rx: float, ry: float,
                 tol: float) -> np.ndarray:
    if rx <= 0 or ry <= 0:
        return np.array([[x, y], [x + w, y], [x + w, y + h], [x, y + h], [x, y]], dtype=float)
    n = (len(ellipse(0.0, 0.0, rx, ry, tol)) - 1) // 4
    a = np.linspace(0.0, math.pi / 2, max(n, 2) + 1)
    corner = np.column_stack([np.cos(a) * rx, np.sin(a) * ry])   # 0..90°: +x to +y
    parts = [
        corner[::-1] * (1, -1) + (x + w - rx, y + ry),           # top right: -90..0
        corner + np.array((x + w - rx, y + h - ry)),              # bottom right: 0..90
        corner[::-1] * (-1, 1) + (x + rx, y + h - ry),            # bottom left: 90..180
        corner * (-1, -1) + (x + rx, y + ry),                     # top left: 180..270
    ]
    pts = np.vstack(parts)
    return np.vstack([pts, pts[:1]])
