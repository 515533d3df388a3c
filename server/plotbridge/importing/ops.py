"""The intermediate program every format is turned into before it is written.

An op is a tuple whose first item is its kind and whose second is the source line
(None when the source has no lines):

- ``(PEN, line, down)``
- ``(MOVE, line, x, y, feed)``: feed in mm/min, ``None`` for a rapid (G0)
- ``(MOVES, line, xs, ys, feeds)``: MOVE ops of consecutive source lines from `line`
  on (or of no line, None) as numpy arrays, feeds NaN for rapids: G-code's common
  lines and long strokes travel as these, so that the writer takes them in bulk
- ``(ARC, line, x, y, i, j, feed, cw)``: centre offset (i, j) from the start point
- ``(PATH, line, kinds, xs, ys, feeds)``: consecutive source lines from `line` on, each
  a move or a pen change, as numpy arrays: kinds are gcodescan's (RAPID and LINE: a
  MOVE, feeds NaN for rapids; PEN_DOWN and PEN_UP: a PEN op; OTHER: a line that does
  nothing): a G-code drawing's strokes travel as these, so that the writer takes a
  chunk of the file at once
- ``(DWELL, line, seconds)``
- ``(LAYER, line, name, colour)``: what follows is a new layer (a pen change before it)

Coordinates are absolute millimetres.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field

import numpy as np

from ..native.gcodescan import LINE, PEN_DOWN, PEN_UP, RAPID

PEN, MOVE, ARC, DWELL, LAYER, MOVES, PATH = 0, 1, 2, 3, 4, 5, 6

Stroke = list[tuple[float, float]]
_BULK = 16      # points of a stroke from which it is written as one MOVES op
# Colours for layers whose source names none (G-code tool changes, coordinates).
PALETTE = ("#000000", "#1f5fbf", "#c0282d", "#2e8b3e", "#8a4fb5", "#d77a12", "#0e8c8c")


@dataclass
class Layer:
    """Strokes drawn with one pen: a layer of the job (docs/INTERNALS.md, "Layers")."""

    name: str
    colour: str
    strokes: list[Stroke] = field(default_factory=list)
    fills: list[Stroke] = field(default_factory=list)   # outlines of its filled shapes (preview)


def arc_sweep(sx: float, sy: float, x: float, y: float, i: float, j: float,
              cw: bool) -> tuple[float, float, float, float]:
    """Centre, radius and signed sweep angle (radians) of an arc; a full circle when the
    end equals the start."""
    cx, cy = sx + i, sy + j
    r = math.hypot(i, j)
    a0 = math.atan2(sy - cy, sx - cx)
    a1 = math.atan2(y - cy, x - cx)
    sweep = a1 - a0
    if cw:
        if sweep >= -1e-12:
            sweep -= 2 * math.pi
    elif sweep <= 1e-12:
        sweep += 2 * math.pi
    return cx, cy, r, sweep


def arc_points(sx: float, sy: float, x: float, y: float, i: float, j: float, cw: bool,
               tolerance: float) -> Iterator[tuple[float, float]]:
    """Points along an arc (excluding the start, including the end) with chords that stay
    within `tolerance` of it."""
    cx, cy, r, sweep = arc_sweep(sx, sy, x, y, i, j, cw)
    a0 = math.atan2(sy - cy, sx - cx)
    tol = min(tolerance, r)
    step = 2 * math.acos(1 - tol / r) if r > 0 else math.pi
    n = max(1, math.ceil(abs(sweep) / max(step, 1e-6)))
    for k in range(1, n):
        a = a0 + sweep * k / n
        yield cx + r * math.cos(a), cy + r * math.sin(a)
    yield x, y


def arc_extent(sx: float, sy: float, x: float, y: float, i: float, j: float,
               cw: bool) -> tuple[float, float, float, float]:
    """Bounding box (min_x, min_y, max_x, max_y) of an arc."""
    cx, cy, r, sweep = arc_sweep(sx, sy, x, y, i, j, cw)
    xs, ys = [sx, x], [sy, y]
    a0 = math.atan2(sy - cy, sx - cx)
    lo, hi = (a0, a0 + sweep) if sweep > 0 else (a0 + sweep, a0)
    for k in range(math.ceil(lo / (math.pi / 2)), math.floor(hi / (math.pi / 2)) + 1):
        a = k * math.pi / 2
        xs.append(cx + r * math.cos(a))
        ys.append(cy + r * math.sin(a))
    return min(xs), min(ys), max(xs), max(ys)


def single_moves(ops: Iterable[tuple]) -> Iterator[tuple]:
    """The ops with each MOVES op as its MOVE ops and each PATH op as its MOVE and PEN
    ops, for readers that take one at a time."""
    for op in ops:
        if op[0] == PATH:
            line = op[1]
            for k, (c, x, y, f) in enumerate(zip(op[2].tolist(), op[3].tolist(),
                                                 op[4].tolist(), op[5].tolist(), strict=True)):
                if c == RAPID or c == LINE:
                    yield (MOVE, line + k, x, y, None if f != f else f)
                elif c == PEN_DOWN or c == PEN_UP:
                    yield (PEN, line + k, c == PEN_DOWN)
            continue
        if op[0] != MOVES:
            yield op
            continue
        line = op[1]
        for k, (x, y, f) in enumerate(zip(op[2].tolist(), op[3].tolist(), op[4].tolist(),
                                          strict=True)):
            yield (MOVE, None if line is None else line + k, x, y, None if f != f else f)


def layers_to_ops(layers: Iterable[Layer], feed: float) -> Iterator[tuple]:
    """Each layer's marker, then pen-up travel to each stroke's start and pen down along it."""
    for layer in layers:
        yield (LAYER, None, layer.name, layer.colour)
        yield from strokes_to_ops(layer.strokes, feed)


def strokes_to_ops(strokes: Iterable[Stroke], feed: float) -> Iterator[tuple]:
    """Pen-up travel to each stroke's start, then pen down along it."""
    for stroke in strokes:
        x0, y0 = stroke[0]
        yield (PEN, None, False)
        yield (MOVE, None, x0, y0, None)
        yield (PEN, None, True)
        if len(stroke) > _BULK:
            pts = np.array(stroke[1:], dtype=float)
            yield (MOVES, None, pts[:, 0], pts[:, 1], np.full(len(pts), feed, dtype=float))
            continue
        for x, y in stroke[1:]:
            yield (MOVE, None, x, y, feed)
    yield (PEN, None, False)


def ops_to_layers(ops: Iterable[tuple], tolerance: float) -> tuple[list[Layer], float]:
    """Pen-down polylines (arcs flattened) by layer, and the feed they were drawn at (the
    most recent drawing feed; used when the strokes are written again)."""
    layers = [Layer(name="layer 1", colour=PALETTE[0])]
    strokes = layers[0].strokes
    cur: Stroke | None = None
    x = y = 0.0
    down = False
    feed = 0.0
    for op in single_moves(ops):
        kind = op[0]
        if kind == LAYER:
            if layers[-1].strokes:
                layers.append(Layer(name=op[2], colour=op[3]))
            else:
                layers[-1] = Layer(name=op[2], colour=op[3])
            strokes = layers[-1].strokes
            cur = None
            continue
        if kind == PEN:
            down = op[2]
            cur = None
            continue
        if kind == DWELL:
            continue
        if kind == MOVE:
            pts: Iterable[tuple[float, float]] = ((op[2], op[3]),)
            if op[4] is not None and down:
                feed = op[4]
        else:
            pts = arc_points(x, y, op[2], op[3], op[4], op[5], op[7], tolerance)
            if down:
                feed = op[6]
        if down:
            if cur is None:
                cur = [(x, y)]
                strokes.append(cur)
            cur.extend(pts)
        x, y = op[2], op[3]
    return [lay for lay in layers if lay.strokes], feed
