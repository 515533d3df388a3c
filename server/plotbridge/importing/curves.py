"""SVG geometry to polylines: path data, basic shapes, affine transforms.

Path data is read by pathdata.py; transforms here, both in one linear pass.
"""

from __future__ import annotations

import math
import re

import numpy as np

from . import pathdata

Affine = tuple[float, float, float, float, float, float]   # a b c d e f (SVG matrix())
IDENTITY: Affine = (1.0, 0.0, 0.0, 1.0, 0.0, 0.0)
MAX_SEGMENT_POINTS = pathdata.MAX_SEGMENT_POINTS


def compose(m: Affine, n: Affine) -> Affine:
    """m · n: apply n first, then m."""
    a, b, c, d, e, f = m
    a2, b2, c2, d2, e2, f2 = n
    return (a * a2 + c * b2, b * a2 + d * b2, a * c2 + c * d2, b * c2 + d * d2,
            a * e2 + c * f2 + e, b * e2 + d * f2 + f)


# A transform list (the attribute, or the CSS property with units) read in one linear
# pass: a function name and its parenthesised arguments, each a number with a unit.
_TF_TOKEN = re.compile(rf"[ \t\n\f\r,]*(?:([A-Za-z]+)[ \t\n\f\r]*\(|({pathdata.NUMBER})"
                       r"([A-Za-z%]*)|(\))|(.))", re.S)
_TF_ARGS = {"matrix": (6,), "translate": (1, 2), "translatex": (1,), "translatey": (1,),
            "scale": (1, 2), "scalex": (1,), "scaley": (1,), "rotate": (1, 3),
            "skewx": (1,), "skewy": (1,), "skew": (1, 2)}
_ANGLE = {"": 1.0, "deg": 1.0, "rad": 180 / math.pi, "grad": 0.9, "turn": 360.0}
_LENGTH_UNITS = {"": 1.0, "px": 1.0, "mm": 96 / 25.4, "cm": 96 / 2.54, "in": 96.0,
                 "pt": 96 / 72, "pc": 16.0}


def _tf_one(name: str, v: list[float]) -> Affine:
    if name == "matrix":
        return (v[0], v[1], v[2], v[3], v[4], v[5])
    if name.startswith("translate"):
        tx, ty = (v[0], v[1] if len(v) > 1 else 0.0) if name == "translate" else \
            ((v[0], 0.0) if name == "translatex" else (0.0, v[0]))
        return (1.0, 0.0, 0.0, 1.0, tx, ty)
    if name.startswith("scale"):
        sx, sy = (v[0], v[1] if len(v) > 1 else v[0]) if name == "scale" else \
            ((v[0], 1.0) if name == "scalex" else (1.0, v[0]))
        return (sx, 0.0, 0.0, sy, 0.0, 0.0)
    if name == "rotate":
        a = math.radians(v[0])
        c, s = math.cos(a), math.sin(a)
        r: Affine = (c, s, -s, c, 0.0, 0.0)
        if len(v) == 3:
            r = compose((1.0, 0.0, 0.0, 1.0, v[1], v[2]),
                        compose(r, (1.0, 0.0, 0.0, 1.0, -v[1], -v[2])))
        return r
    ax = math.tan(math.radians(v[0])) if name in ("skewx", "skew") else 0.0
    ay = math.tan(math.radians(v[1] if name == "skew" and len(v) > 1 else
                               v[0] if name == "skewy" else 0.0))
    return (1.0, ay, ax, 1.0, 0.0, 0.0)


def parse_transform(text: str | None) -> Affine:
    """The transform list of an attribute or of the CSS `transform` property (angles in
    deg, rad, grad or turn, lengths in px or absolute units); `none` is the identity.
    ValueError naming what is wrong."""
    m = IDENTITY
    if text is None or text.strip() in ("", "none"):
        return m
    name = ""
    vals: list[float] = []
    for tok in _TF_TOKEN.finditer(text.rstrip(" \t\n\f\r")):
        fn, num, unit, close, bad = tok.groups()
        if fn is not None:
            if name:
                raise ValueError(f"'{fn}(' inside '{name}(' in transform '{text[:60]}'")
            name = fn.lower()
            if name not in _TF_ARGS:
                raise ValueError(f"unknown transform function '{fn}'")
            vals = []
        elif num is not None:
            if not name:
                raise ValueError(f"number outside a function in transform '{text[:60]}'")
            unit = unit.lower()
            angle = name.startswith(("rotate", "skew")) and (name != "rotate" or not vals)
            table = _ANGLE if angle else _LENGTH_UNITS if name.startswith(("translate", "rotate")) \
                else {"": 1.0}
            if unit not in table:
                raise ValueError(f"'{num}{unit}' in {name}() of transform '{text[:60]}'")
            vals.append(float(num) * table[unit])
        elif close is not None:
            if not name:
                raise ValueError(f"unexpected ')' in transform '{text[:60]}'")
            if len(vals) not in _TF_ARGS[name]:
                counts = " or ".join(map(str, _TF_ARGS[name]))
                raise ValueError(f"{name}() takes {counts} numbers in transform '{text[:60]}'")
            m = compose(m, _tf_one(name, vals))
            name = ""
        else:
            raise ValueError(f"unexpected '{bad}' in transform '{text[:60]}'")
    if name:
        raise ValueError(f"'{name}(' is not closed in transform '{text[:60]}'")
    return m


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


def path_data(d: str, tol: float) -> tuple[list[tuple[np.ndarray, bool]], str | None]:
    """(points, closed) of each subpath of path data in user units, drawn up to the
    first error, and that error."""
    pd = pathdata.parse(d)
    return pathdata.flatten(pd, tol), pd.error


def path_subpaths(d: str, tol: float) -> list[tuple[np.ndarray, bool]]:
    return path_data(d, tol)[0]


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


def viewbox_transform(vb: list[float], x: float, y: float, w: float, h: float,
                      par: str | None) -> Affine:
    """The viewBox mapped into the viewport (x, y, w, h) as preserveAspectRatio says."""
    vx, vy, vw, vh = vb
    sx, sy = w / vw, h / vh
    words = (par or "xMidYMid meet").split()
    align = words[0] if words else "xMidYMid"
    if align == "defer" and len(words) > 1:
        words = words[1:]
        align = words[0]
    if align == "none":
        return (sx, 0.0, 0.0, sy, x - vx * sx, y - vy * sy)
    s = max(sx, sy) if len(words) > 1 and words[1] == "slice" else min(sx, sy)
    tx, ty = x - vx * s, y - vy * s
    if "xMid" in align:
        tx += (w - vw * s) / 2
    elif "xMax" in align:
        tx += w - vw * s
    if "YMid" in align:
        ty += (h - vh * s) / 2
    elif "YMax" in align:
        ty += h - vh * s
    return (s, 0.0, 0.0, s, tx, ty)
