"""Writing the normalized program (docs/INTERNALS.md); `plotbridge.program.reader` reads it."""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

from ..motion import library as motion
from ..motion.estimate import Estimator
from ..native.gcodescan import OTHER, PEN_DOWN, PEN_UP, RAPID
from ..native.movelines import EV_DOWN, EV_DRAW, EV_TRAVEL, Lines, MoveLines, State
from .models import ErrorLog, MachineProfile
from .ops import ARC, DWELL, LAYER, MOVE, MOVES, PALETTE, PATH, PEN, arc_extent, arc_points
from .placement import Transform
from .preview import PreviewBuilder

HEADER = ("G21", "G90", "M5")
EPS = 1e-6
PREVIEW_ARC_TOL = 0.05
SHORT_RUN = 4      # moves: fewer cost less written one by one than in bulk


class FeedTexts:
    """A feed's text in the program, remembered (movelines.c asks for each new one)."""

    def __init__(self) -> None:
        self._texts: dict[float, str] = {}

    def __call__(self, feed: float) -> str:
        f = self._texts.get(feed)
        if f is None:
            if len(self._texts) >= 256:    # a file of ever new feeds
                self._texts.clear()
            f = self._texts[feed] = f"{round(feed, 1):g}"
        return f


class ProgramWriter:
    """Writes ops (source coordinates, mapped through `transform`) as the normalized
    program while checking the work area, simulating the planner, building the preview
    and counting stats. Line numbers in errors are the source's."""

    def __init__(self, out, transform: Transform, profile: MachineProfile,
                 errors: ErrorLog, start: tuple[float, float] = (0.0, 0.0)) -> None:
        self.out = out
        self.t = transform
        self.profile = profile
        self.errors = errors
        self.planner = Estimator(profile, start)
        self.preview = PreviewBuilder()
        self.line = 0
        self.x, self.y = start
        self.down = False
        self.pen_down_mm = 0.0
        self.travel_mm = 0.0
        self.pen_lifts = 0
        self.bounds = [math.inf, math.inf, -math.inf, -math.inf]
        self._area = (-EPS, -EPS, profile.width + EPS, profile.height + EPS)
        self._buf: list[bytes] = []  # whole lines (ASCII), each ending with a newline
        self._buffered = 0           # lines in _buf
        self.last = ""
        # not a bound method: MoveLines keeps it, and the cycle would keep the writer's
        # buffers until the collector's next full pass (a worker grew 17 MB an import)
        self._feed_text = FeedTexts()
        self._runs = MoveLines(self._area, self._feed_text, motion.RAPID, motion.LINE,
                               motion.DWELL, profile.pen_settle_s)
        self.layers: list[dict] = []
        # Pen-up travel that left the work area (source line, x, y): clamped to the
        # area with a warning, an error when the next stroke starts at the clamped point.
        self._outside: tuple[int | None, float, float] | None = None
        for text in HEADER:
            self._write(text)
        # The pen is up when a job starts: the firmware skips the settle time of a pen
        # command that does not move the pen (it still waits for motion to stop).
        self.planner.stop(3, 0.0)

    def _write(self, text: str) -> None:
        self.last = text
        self.line += 1
        self.planner.receive(text)
        self._buf.append(f"{text}\n".encode("ascii"))
        self._buffered += 1
        if self._buffered >= 4096:
            self.flush()

    def flush(self) -> None:
        if self._buf:
            self.out.write(b"".join(self._buf))
            self._buf = []
            self._buffered = 0

    def _check(self, src_line: int | None, x: float, y: float) -> bool:
        """Within the work area? Reports the source line when not."""
        a = self._area
        if a[0] <= x <= a[2] and a[1] <= y <= a[3]:
            return True
        p = self.profile
        self.errors.add(src_line, f"move to X{x:.3f} Y{y:.3f} is outside the work area "
                                  f"(0..{p.width:g} x 0..{p.height:g} mm)")
        return False

    def _grow(self, x0: float, y0: float, x1: float, y1: float) -> None:
        b = self.bounds
        if x0 < b[0]:
            b[0] = x0
        if y0 < b[1]:
            b[1] = y0
        if x1 > b[2]:
            b[2] = x1
        if y1 > b[3]:
            b[3] = y1

    def write_ops(self, ops: Iterable[tuple]) -> None:
        t = self.t
        ident = t.identity
        for op in ops:
            kind = op[0]
            if kind == MOVE:
                x, y = (op[2], op[3]) if ident else t.apply(op[2], op[3])
                self.move(op[1], x, y, op[4])
            elif kind == MOVES:
                xs, ys = (op[2], op[3]) if ident else t.apply(op[2], op[3])
                self.moves(op[1], xs, ys, op[4])
            elif kind == PATH:
                xs, ys = (op[3], op[4]) if ident else t.apply(op[3], op[4])
                self.path(op[1], op[2], xs, ys, op[5])
            elif kind == PEN:
                self.pen(op[1], op[2])
            elif kind == ARC:
                x, y = t.apply(op[2], op[3])
                i, j = t.linear(op[4], op[5])
                self.arc(op[1], x, y, i, j, op[6], op[7])
            elif kind == DWELL:
                self._write(f"G4 P{op[2]:.3f}")
                self.planner.stop(self.line, op[2])
            elif kind == LAYER:
                self.layer(op[2], op[3])

    def layer(self, name: str, colour: str) -> None:
        """Starts a layer. Between layers the program lifts the pen and has an `M0`
        line: the pen-change pause (docs/INTERNALS.md, "Layers")."""
        if self.layers:
            self.pen(None, False)
            lay = self.layers[-1]
            if self.pen_lifts == lay["strokes"]:      # nothing drawn in it yet: renamed
                lay.update(name=name, colour=colour)
                self.preview.colour = colour
                return
            self._end_layer()
            self._write("M0")
            self.planner.stop(self.line, 0.0)
        self.layers.append({"name": name, "colour": colour, "first_line": self.line + 1,
                            "pen_down_mm": self.pen_down_mm, "strokes": self.pen_lifts})
        self.preview.end_stroke()
        self.preview.colour = colour

    def _end_layer(self) -> None:
        lay = self.layers[-1]
        lay["last_line"] = self.line
        lay["pen_down_mm"] = round(self.pen_down_mm - lay["pen_down_mm"], 3)
        lay["strokes"] = self.pen_lifts - lay["strokes"]

    def pen(self, src_line: int | None, down: bool) -> None:
        if down == self.down:
            return
        if down and not self.layers:
            self.layer("layer 1", PALETTE[0])
        self.down = down
        if down and self._outside is not None:
            line, ox, oy = self._outside
            cx = min(max(ox, 0.0), self.profile.width)
            cy = min(max(oy, 0.0), self.profile.height)
            if (round(cx, 3), round(cy, 3)) == (self.x, self.y):
                self._check(line, ox, oy)       # the stroke would start at the clamped point
            else:                               # travel came back: only an excursion
                self._clamped(line, ox, oy)
            self._outside = None
        self._write("M3" if down else "M5")
        if down:
            self.preview.pen_down(self.line)
            self._grow(self.x, self.y, self.x, self.y)
        else:
            self.preview.pen_up(self.line)
            self.pen_lifts += 1
        self.planner.stop(self.line, self.profile.pen_settle_s)

    def move(self, src_line: int | None, x: float, y: float, feed: float | None) -> None:
        # Formatted once: the value of the text is round(x, 3), the point written.
        xt, yt = f"{x:.3f}", f"{y:.3f}"
        x, y = float(xt), float(yt)
        x0, y0 = self.x, self.y
        if x == x0 and y == y0:
            return
        a = self._area
        if not (a[0] <= x <= a[2] and a[1] <= y <= a[3]):
            if self.down:
                self._check(src_line, x, y)
                self.x, self.y = x, y     # the import fails; only keep finding errors
                return
            if self._outside is None:
                self._outside = (src_line, x, y)
            x = min(max(x, 0.0), self.profile.width)
            y = min(max(y, 0.0), self.profile.height)
            xt, yt = f"{x:.3f}", f"{y:.3f}"
            x, y = float(xt), float(yt)
            if x == x0 and y == y0:
                return
        if feed is None:
            self._write(f"G0 X{xt} Y{yt}")
        else:
            self._write(f"G1 X{xt} Y{yt} F{self._feed_text(feed)}")
        self.planner.move(self.line, x, y, feed)
        dx, dy = x - x0, y - y0
        d = math.sqrt(dx * dx + dy * dy)    # as movelines.c sums a run's moves
        if self.down:
            self.pen_down_mm += d
            self.preview.draw(x0, y0, x, y)
            b = self.bounds    # the stroke's first point was added at pen down
            if x < b[0]:
                b[0] = x
            elif x > b[2]:
                b[2] = x
            if y < b[1]:
                b[1] = y
            elif y > b[3]:
                b[3] = y
        else:
            self.travel_mm += d
            self.preview.move(x0, y0, x, y)
        self.x, self.y = x, y

    def moves(self, first: int | None, xs: np.ndarray, ys: np.ndarray,
              feeds: np.ndarray) -> None:
        """`move` for each point in turn (feeds NaN for rapids; source lines from `first`
        on), done for all at once (`_bulk`); a short run goes point by point."""
        if len(xs) >= SHORT_RUN:
            self._bulk(first, None, xs, ys, feeds)
            return
        for k, (px, py, f) in enumerate(zip(xs.tolist(), ys.tolist(), feeds.tolist(),
                                            strict=True)):
            self.move(None if first is None else first + k, px, py, None if f != f else f)

    def path(self, first: int, kinds: np.ndarray, xs: np.ndarray, ys: np.ndarray,
             feeds: np.ndarray) -> None:
        """A PATH op (ops.py): `move` and `pen` for each of its elements in turn, done
        for all at once (`_bulk`)."""
        self._bulk(first, kinds, xs, ys, feeds)

    def _bulk(self, first: int | None, kinds: np.ndarray | None, xs: np.ndarray,
              ys: np.ndarray, feeds: np.ndarray) -> None:
        """Moves and pen changes (kinds as in a PATH op; None: all moves) written by
        native/movelines.c, with the estimate's rows, the preview's calls and the
        running totals; an element it leaves (a point outside the work area, a pen down
        starting the first layer or after travel outside the area) goes through `move`
        or `pen`, and movelines.c goes on after it. Two such elements in a row (a
        stretch outside the area): the rest goes element by element."""

        def one(k: int) -> None:
            line = None if first is None else first + k
            c = RAPID if kinds is None else int(kinds[k])    # RAPID: a move (feed or not)
            if c == PEN_DOWN or c == PEN_UP:
                self.pen(line, c == PEN_DOWN)
            elif c != OTHER:
                f = float(feeds[k])
                self.move(line, float(xs[k]), float(ys[k]), None if f != f else f)

        runs = self._runs
        runs.load(kinds, xs, ys, feeds)
        n, k = len(xs), 0
        while k < n:
            state = State(self.x, self.y, self.down, self.line, self.pen_lifts,
                          self.pen_down_mm, self.travel_mm, self.bounds)
            lines = runs.run(k, state, bool(self.layers) and self._outside is None)
            if lines.text:
                self._took(state, lines)
            if lines.stop == n:
                return
            one(lines.stop)
            if lines.stop == k and k:
                break
            k = lines.stop + 1
        for k in range(lines.stop + 1, n):
            one(k)

    def _took(self, state: State, lines: Lines) -> None:
        """The program lines, estimate rows, preview calls and state movelines.c wrote
        from `state`."""
        self.planner.moves(lines.kind, lines.x32, lines.y32, lines.f32, lines.nbytes)
        text = lines.text
        self.last = text[text.rfind(b"\n", 0, -1) + 1:-1].decode("ascii")
        self._buf.append(text)
        s = lines.state
        self._buffered += s.line - self.line
        (self.x, self.y, self.down, self.line, self.pen_lifts, self.pen_down_mm,
         self.travel_mm, self.bounds) = s
        if self._buffered >= 4096:
            self.flush()
        preview = self.preview
        xy = lines.xy
        if len(xy):     # the points with the run's start before them (drawn from there)
            xy = np.empty((len(xy) + 1, 2))
            xy[0] = state.x, state.y
            xy[1:] = lines.xy
        for ev, a, b in zip(*lines.events, strict=True):
            if ev == EV_DRAW:
                preview.draw_path(xy[a:b + 1])
            elif ev == EV_TRAVEL:
                x0, y0, x, y = xy[a:b + 1:b - a].ravel().tolist()
                preview.move(x0, y0, x, y)
            elif ev == EV_DOWN:
                preview.pen_down(a)
            else:
                preview.pen_up(a)

    def arc(self, src_line: int | None, x: float, y: float, i: float, j: float,
            feed: float, cw: bool) -> None:
        x0, y0 = self.x, self.y
        cx, cy = x0 + i, y0 + j      # centre from the unrounded start
        x, y = round(x, 3), round(y, 3)
        i, j = round(cx - x0, 3), round(cy - y0, 3)
        ext = arc_extent(x0, y0, x, y, i, j, cw)
        if not (self._check(src_line, ext[0], ext[1]) and self._check(src_line, ext[2], ext[3])):
            self.x, self.y = x, y     # the import fails; do not simulate a huge arc
            return
        self._write(f"{'G2' if cw else 'G3'} X{x:.3f} Y{y:.3f} I{i:.3f} J{j:.3f} "
                    f"F{self._feed_text(feed)}")
        self.planner.arc(self.line, x, y, i, j, feed, cw)
        px, py = x0, y0
        length = 0.0
        for qx, qy in arc_points(x0, y0, x, y, i, j, cw, PREVIEW_ARC_TOL):
            length += math.hypot(qx - px, qy - py)
            if self.down:
                self.preview.draw(px, py, qx, qy)
            px, py = qx, qy
        if self.down:
            self.pen_down_mm += length
            self._grow(*ext)
        else:
            self.travel_mm += length
            self.preview.move(x0, y0, x, y)
        self.x, self.y = x, y

    def finish(self) -> None:
        if self.down:
            self.pen(None, False)
        elif self.last != "M5":
            self._write("M5")
            self.planner.stop(self.line, 0.0)
        if self._outside is not None:
            self._clamped(*self._outside)
        if self.layers:
            self._end_layer()
        self.planner.end()    # the caller waits for the estimate (Estimator.wait)
        self.flush()

    def _clamped(self, line: int | None, x: float, y: float) -> None:
        self.errors.warn(line, f"pen-up travel to X{x:.3f} Y{y:.3f} is outside the work "
                               "area: clamped to its edge")

    def bounds_dict(self) -> dict[str, float]:
        b = self.bounds
        if b[0] > b[2]:
            return {"min_x": 0.0, "min_y": 0.0, "max_x": 0.0, "max_y": 0.0}
        return {"min_x": round(b[0], 3), "min_y": round(b[1], 3),
                "max_x": round(b[2], 3), "max_y": round(b[3], 3)}

