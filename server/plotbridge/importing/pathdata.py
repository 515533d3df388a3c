"""SVG path and number data read in one linear pass, drawn up to the first error.

Every token is taken by one regular expression whose alternatives cannot overlap (a
number is `sign? (digits (. digits)? | . digits) exponent?`, anything else is one
character), so no input makes it backtrack: the time is linear in the data's length.
What follows an error is dropped, as browsers do (SVG 2, "Error handling in path
data"); the error is named (what, and at which character) for the import's warning.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

_WS = "[ \\t\\n\\f\\r]"
NUMBER = r"[-+]?(?:[0-9]+(?:\.[0-9]+)?|\.[0-9]+)(?:[eE][-+]?[0-9]+)?"
_NUMBER = re.compile(NUMBER)
# (comma, command, number, any other character): each match takes at least a character.
_TOKEN = re.compile(rf"{_WS}*(,?){_WS}*(?:([MmLlHhVvZzCcSsQqTtAa])|({NUMBER})|(.))", re.S)
ARGS = {"M": 2, "L": 2, "H": 1, "V": 1, "Z": 0, "C": 6, "S": 4, "Q": 4, "T": 2, "A": 7}


@dataclass
class Subpath:
    """One subpath's segments in user units: ("L", points incl. the start),
    ("C", 4 points), ("Q", 3 points), ("A", (start, end, rx, ry, phi, large, sweep))."""
    start: tuple[float, float]
    segments: list[tuple[str, object]] = field(default_factory=list)
    closed: bool = False


@dataclass
class PathData:
    subpaths: list[Subpath]
    error: str | None = None


def _where(d: str, pos: int) -> str:
    near = d[max(pos - 12, 0):pos + 12].replace("\n", " ")
    return f"character {pos + 1} (near '{near}')"


def tokens(d: str) -> tuple[list[tuple[str, str, int]], str | None]:
    """("c", letter, position) and ("n", number text, position) in order, and the first
    error of the token stream (its tokens before the error are kept)."""
    out: list[tuple[str, str, int]] = []
    d = d.rstrip(" \t\n\f\r")
    after_number = False
    for m in _TOKEN.finditer(d):
        comma, cmd, num, bad = m.groups()
        if comma and not after_number:
            return out, f"unexpected ',' at {_where(d, m.start(1))}"
        if cmd:
            out.append(("c", cmd, m.start(2)))
            after_number = False
        elif num:
            out.append(("n", num, m.start(3)))
            after_number = True
        else:
            return out, f"unexpected '{bad}' at {_where(d, m.start(4))}"
    if d.endswith(","):
        return out, f"unexpected ',' at {_where(d, len(d) - 1)}"
    return out, None


def numbers(text: str | None) -> tuple[list[float], str | None]:
    """A list of numbers separated by white space and/or one comma (points, viewBox),
    read up to the first error."""
    if not text:
        return [], None
    toks, error = tokens(text)
    out: list[float] = []
    for kind, value, pos in toks:
        if kind != "n":
            return out, f"unexpected '{value}' at {_where(text, pos)}"
        out.append(float(value))
    return out, error


def _commands(d: str) -> tuple[list[tuple[str, list[str]]], str | None]:
    """The commands with their argument texts (arc flags split off numbers such as
    `01` or `1.5`), complete groups only, and the first error."""
    toks, error = tokens(d)
    out: list[tuple[str, list[str]]] = []
    args: list[str] = []
    cmd = ""
    n = 0

    def incomplete() -> bool:
        """Drops the last command's unfinished group; True when it had one."""
        if not n or (args and not len(args) % n):
            return False
        del args[len(args) - len(args) % n:]
        if not args:
            out.pop()
        return True

    pending: list[tuple[str, str, int]] = []
    it = iter(toks)
    while True:
        if pending:
            kind, value, pos = pending.pop()
        else:
            tok = next(it, None)
            if tok is None:
                break
            kind, value, pos = tok
        if kind == "c":
            if cmd and incomplete():
                return out, f"'{cmd}' has too few numbers before {_where(d, pos)}"
            if not cmd and value not in "Mm":
                return out, (f"path data must start with a moveto, not '{value}' at "
                             f"{_where(d, pos)}")
            cmd, args, n = value, [], ARGS[value.upper()]
            out.append((cmd, args))
            continue
        if not cmd:
            return out, f"path data must start with a moveto, not '{value}' at {_where(d, pos)}"
        if n == 0:
            return out, f"number '{value}' after '{cmd}' at {_where(d, pos)}"
        if cmd in "Aa" and len(args) % 7 in (3, 4):
            if value[0] not in "01":
                incomplete()
                return out, f"arc flag must be 0 or 1, not '{value}' at {_where(d, pos)}"
            rest = value[1:]
            if rest:
                if _NUMBER.fullmatch(rest) is None:
                    incomplete()
                    return out, f"unexpected '{rest}' at {_where(d, pos + 1)}"
                pending.append(("n", rest, pos + 1))
            value = value[0]
        args.append(value)
    if cmd and incomplete():
        error = error or f"'{cmd}' has too few numbers at the end"
    return out, error


def _line_to(sub: Subpath, start: tuple[float, float], pts: list[tuple[float, float]]) -> None:
    """Lines from `start` through `pts`, joined to a line run the subpath ends with (a
    Python list until `parse` ends: no array a command)."""
    if not pts:
        return
    last = sub.segments[-1] if sub.segments else None
    if last is not None and last[0] == "L" and isinstance(last[1], list):
        last[1].extend(pts)
    else:
        sub.segments.append(("L", [start, *pts]))


def parse(d: str) -> PathData:
    """The path data as absolute segments, up to the first error."""
    commands, error = _commands(d)
    subs: list[Subpath] = []
    sub: Subpath | None = None
    x = y = 0.0
    prev = ""                   # the last command (upper case), for S and T
    ctrl = (0.0, 0.0)           # its last control point
    for cmd, args in commands:
        up = cmd.upper()
        rel = cmd != up
        if up == "Z":
            if sub is not None:
                if (x, y) != sub.start:
                    _line_to(sub, (x, y), [sub.start])
                sub.closed = True
                x, y = sub.start
            prev = "Z"
            continue
        if up in ("M", "L", "H", "V"):
            vals = [float(a) for a in args]
            pts: list[tuple[float, float]] = []
            if up in ("M", "L"):
                if rel:
                    px, py = x, y
                    for k in range(0, len(vals), 2):
                        px += vals[k]
                        py += vals[k + 1]
                        pts.append((px, py))
                else:
                    pts = list(zip(vals[0::2], vals[1::2], strict=True))
            else:
                px, py = x, y
                for v in vals:
                    if up == "H":
                        px = px + v if rel else v
                    else:
                        py = py + v if rel else v
                    pts.append((px, py))
            if up == "M":
                sub = Subpath(pts[0])
                subs.append(sub)
                _line_to(sub, pts[0], pts[1:])      # the pairs after the first are linetos
            else:
                sub = _ensure(subs, sub, x, y)
                _line_to(sub, (x, y), pts)
            x, y = pts[-1]
            prev = up
            continue
        sub = _ensure(subs, sub, x, y)
        v = np.array(args, dtype=float)
        step = ARGS[up]
        for j in range(0, len(v), step):
            a = v[j:j + step]
            ox, oy = (x, y) if rel else (0.0, 0.0)
            if up == "C":
                p = np.array([[x, y], [a[0] + ox, a[1] + oy], [a[2] + ox, a[3] + oy],
                              [a[4] + ox, a[5] + oy]])
            elif up == "S":
                c1 = (2 * x - ctrl[0], 2 * y - ctrl[1]) if prev in ("C", "S") else (x, y)
                p = np.array([[x, y], c1, [a[0] + ox, a[1] + oy], [a[2] + ox, a[3] + oy]])
            elif up == "Q":
                p = np.array([[x, y], [a[0] + ox, a[1] + oy], [a[2] + ox, a[3] + oy]])
            elif up == "T":
                c1 = (2 * x - ctrl[0], 2 * y - ctrl[1]) if prev in ("Q", "T") else (x, y)
                p = np.array([[x, y], c1, [a[0] + ox, a[1] + oy]])
            else:   # A
                end = (float(a[5] + ox), float(a[6] + oy))
                sub.segments.append(("A", ((x, y), end, abs(float(a[0])), abs(float(a[1])),
                                           float(a[2]), bool(a[3]), bool(a[4]))))
                x, y = end
                prev = up
                continue
            sub.segments.append(("C" if len(p) == 4 else "Q", p))
            ctrl = (float(p[-2, 0]), float(p[-2, 1]))
            x, y = float(p[-1, 0]), float(p[-1, 1])
            prev = up
    for one in subs:
        one.segments = [(kind, np.array(data, dtype=float)) if isinstance(data, list)
                        else (kind, data) for kind, data in one.segments]
    return PathData(subs, error)


def _ensure(subs: list[Subpath], sub: Subpath | None, x: float, y: float) -> Subpath:
    """The subpath a drawing command goes on: after a closepath a new one starts at the
    closed one's start point (where the pen is)."""
    if sub is None or sub.closed:
        sub = Subpath((x, y))
        subs.append(sub)
    return sub


# ---- flattening -------------------------------------------------------------------

MAX_SEGMENT_POINTS = 1 << 14


def bezier(p: np.ndarray, tol: float) -> np.ndarray:
    """Points of a quadratic (3 control points) or cubic (4) Bézier after the start; the
    chord error of n equal parameter steps is at most max|B''| / (8 n²)."""
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


def arc_centre(start: tuple[float, float], end: tuple[float, float], rx: float, ry: float,
               phi_deg: float, large: bool, sweep: bool
               ) -> tuple[float, float, float, float, float, float, float] | None:
    """(cx, cy, rx, ry, phi, theta1, dtheta) of an endpoint-parameterized arc (SVG 1.1
    F.6.5, radii scaled up when too small), None when it is a straight line."""
    (x1, y1), (x2, y2) = start, end
    if rx == 0 or ry == 0:
        return None
    phi = math.radians(phi_deg % 360)
    cp, sp = math.cos(phi), math.sin(phi)
    hx, hy = (x1 - x2) / 2, (y1 - y2) / 2
    xp, yp = cp * hx + sp * hy, -sp * hx + cp * hy
    lam = (xp / rx) ** 2 + (yp / ry) ** 2
    if lam > 1:
        s = math.sqrt(lam)
        rx, ry = rx * s, ry * s
    num = rx * rx * ry * ry - rx * rx * yp * yp - ry * ry * xp * xp
    den = rx * rx * yp * yp + ry * ry * xp * xp
    coef = math.sqrt(max(num / den, 0.0)) if den else 0.0
    if large == sweep:
        coef = -coef
    cxp, cyp = coef * rx * yp / ry, -coef * ry * xp / rx
    cx = cp * cxp - sp * cyp + (x1 + x2) / 2
    cy = sp * cxp + cp * cyp + (y1 + y2) / 2
    t1 = math.atan2((yp - cyp) / ry, (xp - cxp) / rx)
    t2 = math.atan2((-yp - cyp) / ry, (-xp - cxp) / rx)
    dt = t2 - t1
    if sweep and dt < 0:
        dt += 2 * math.pi
    elif not sweep and dt > 0:
        dt -= 2 * math.pi
    return cx, cy, rx, ry, phi, t1, dt


def arc(params: tuple, tol: float) -> np.ndarray:
    """Points of an arc segment after its start."""
    start, end = params[0], params[1]
    if start == end:
        return np.empty((0, 2))
    c = arc_centre(*params)
    if c is None:
        return np.array([end], dtype=float)
    cx, cy, rx, ry, phi, t1, dt = c
    r = max(rx, ry)
    step = 2 * math.acos(max(1 - tol / r, -1.0))
    n = min(max(1, math.ceil(abs(dt) / max(step, 1e-9))), MAX_SEGMENT_POINTS)
    t = t1 + dt * np.linspace(0.0, 1.0, n + 1)[1:]
    cp, sp = math.cos(phi), math.sin(phi)
    ct, st = np.cos(t), np.sin(t)
    pts = np.column_stack([cx + rx * ct * cp - ry * st * sp, cy + rx * ct * sp + ry * st * cp])
    pts[-1] = end
    return pts


def flatten(pd: PathData, tol: float) -> list[tuple[np.ndarray, bool]]:
    """(points, closed) of each subpath; a subpath of a moveto alone is one point."""
    out: list[tuple[np.ndarray, bool]] = []
    for sub in pd.subpaths:
        parts: list[np.ndarray] = [np.array([sub.start], dtype=float)]
        for kind, data in sub.segments:
            if kind == "L":
                parts.append(data[1:])
            elif kind == "A":
                parts.append(arc(data, tol))
            else:
                parts.append(bezier(data, tol))
        out.append((np.vstack(parts) if len(parts) > 1 else parts[0], sub.closed))
    return out


# ---- vertices (markers) -----------------------------------------------------------

def _direction(dx: float, dy: float) -> float | None:
    return math.atan2(dy, dx) if dx or dy else None


def _ends(kind: str, data) -> tuple[list[tuple[float, float]], float | None, float | None,
                                    list[float | None]]:
    """A segment's vertices after its start, its start and end directions and the
    directions at its inner vertices (a polyline's)."""
    if kind == "L":
        pts = np.asarray(data)
        d = np.diff(pts, axis=0)
        dirs = [_direction(float(a), float(b)) for a, b in d]
        return [(float(a), float(b)) for a, b in pts[1:]], dirs[0], dirs[-1], dirs
    if kind == "A":
        start, end = data[0], data[1]
        pts = np.vstack([[start], arc(data, 1e-3 * max(data[2], data[3], 1e-9))])
        if len(pts) < 2:
            return [end], None, None, []
        d0, d1 = pts[1] - pts[0], pts[-1] - pts[-2]
        return [end], _direction(*d0), _direction(*d1), []
    p = np.asarray(data)
    first = next((p[k] - p[0] for k in range(1, len(p)) if (p[k] != p[0]).any()), None)
    last = next((p[-1] - p[k] for k in range(len(p) - 2, -1, -1) if (p[k] != p[-1]).any()),
                None)
    return ([(float(p[-1, 0]), float(p[-1, 1]))],
            None if first is None else _direction(*first),
            None if last is None else _direction(*last), [])


def _bisect(a: float | None, b: float | None) -> float:
    if a is None:
        return b or 0.0
    if b is None:
        return a
    return math.atan2(math.sin(a) + math.sin(b), math.cos(a) + math.cos(b)) \
        if abs(math.remainder(a - b, 2 * math.pi)) < math.pi - 1e-12 else a + math.pi / 2


def vertices(pd: PathData) -> list[tuple[float, float, float]]:
    """(x, y, orientation in radians) of every vertex of the path, in order, the
    orientation as `orient="auto"` places a marker: the bisector of the incoming and
    outgoing directions, the outgoing one at a subpath's start and the incoming one at
    its end (both directions at a closed subpath's start)."""
    out: list[tuple[float, float, float]] = []
    for sub in pd.subpaths:
        pts: list[tuple[float, float]] = [sub.start]
        into: list[float | None] = [None]
        outof: list[float | None] = []
        for kind, data in sub.segments:
            ends, d0, d1, inner = _ends(kind, data)
            if kind == "L":
                outof.extend(inner)
                into.extend(inner)
            else:
                outof.append(d0)
                into.append(d1)
            pts.extend(ends)
        outof.append(None)
        if sub.closed and len(pts) > 1:
            into[0] = into[-1]
            outof[-1] = outof[0]
        for (x, y), a, b in zip(pts, into, outof, strict=True):
            out.append((x, y, _bisect(a, b)))
    return out
