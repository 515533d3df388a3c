"""G-code reading: dialects of pen lifting, units, relative moves, arcs, validation.

`read_ops` turns chunks of source lines into ops (see ops.py) in absolute millimetres,
reporting every line it cannot accept to an ErrorLog instead of stopping at the first.
"""

from __future__ import annotations

import itertools
import math
import queue
import re
import threading
from collections.abc import Iterable, Iterator
from typing import TypeVar

import numpy as np

from ..native.gcodescan import LINE, OTHER, PEN_DOWN, PEN_UP, RAPID, scan
from .fields import PEN_DIALECTS as UPLOAD_DIALECTS
from .models import ErrorLog, ImportOptions
from .ops import ARC, DWELL, LAYER, MOVE, MOVES, PALETTE, PATH, PEN

# Dialects whose G4 P is in milliseconds: Unicorn's (M300) and Makelangelo's (M280)
# files are written for Marlin, where P is milliseconds and S seconds.
MS_DWELL = frozenset({"m300", "m280"})
MAX_LINE = 256          # characters of commands on a line (comments do not count)
MAX_RAW_LINE = 1 << 16  # characters of a line with its comments
PEN_DIALECTS = (*UPLOAD_DIALECTS, "servo-z")
M280_DOWN_MAX = 50.0    # M280 servo angles at or below this lower the pen
M300_DOWN_MAX = 40.0    # M300 S30 lowers the pen, S50 (and S255, servo off) lift it
# Dialects where the motion mode decides the pen: G0 travels, G1/G2/G3 draw (laser: while
# the laser is on, M3/M4 to M5; none: always).
MOTION_PEN = ("laser", "none")
_PAUSE = re.compile(r"\s*(?:N\d+\s*)?M0*([01])(?![0-9.])\s*(.*)", re.I)
_CONSOLE = ("$", "?", "~", "!")
_BLOCK = re.compile(r"(?:[A-Z][-+]?(?:\d+(?:\.\d*)?|\.\d+))*")
_WORD = re.compile(r"([A-Z])([-+]?(?:\d+(?:\.\d*)?|\.\d+))")
# A parenthesised comment runs to its ')' or the line's end (never failing: linear).
_COMMENT = re.compile(r"\([^)\n]*\)?|;.*")
_SEMICOLON_COMMENT = re.compile(r";.*")
# G words accepted without effect on a plotter (plane XY, feed per minute, work
# coordinate system 1, path control, cancel cutter/length compensation, cancel canned cycle).
_NOOP_G = {17.0, 94.0, 54.0, 61.0, 64.0, 40.0, 49.0, 80.0, 91.1}
# M words accepted without effect: program end, coolant.
_NOOP_M = {2.0, 30.0, 7.0, 8.0, 9.0}
# M words dropped with a warning: motors on and off (the server manages the motors).
_MOTOR_M = {17.0, 18.0, 84.0}
_AXIS_WORDS = frozenset("XYZIJRFSPNT")
PLAIN_LINES = 256       # plain lines whose words GcodeReader keeps
ARC_RADIUS_ABS = 0.005
ARC_RADIUS_REL = 0.001
T = TypeVar("T")


def _num(v: float) -> str:
    return f"{v:g}"


def _no_feed(mode: int, feed: float) -> str:
    return (f"G{mode} with no feed rate before it: drawn at {feed:g} mm/min "
            "(the import's feed)")


def strip_line(raw: str, line_no: int, errors: ErrorLog) -> str | None:
    """The words of a line, upper case and without spaces, comments, N number or
    checksum; None when the line cannot be accepted (already reported)."""
    text = raw.strip()
    if not text:
        return ""
    if "*" in text:
        body, _, check = text.rpartition("*")
        if not check.strip().isdecimal():
            errors.add(line_no, f"malformed checksum '*{check.strip()}'")
            return None
        computed = 0
        for ch in body.encode("latin-1", "replace"):
            computed ^= ch
        if computed != int(check):
            errors.add(line_no,
                       f"checksum mismatch: line says {check.strip()}, computed {computed}")
            return None
        text = body
    if "(" in text or ";" in text:
        if text.count("(") != text.count(")"):
            errors.add(line_no, "unbalanced parenthesis in comment")
            return None
        text = _COMMENT.sub("", text)
    text = text.replace(" ", "").replace("\t", "").upper()
    if text == "%":
        return ""
    if text.startswith("N"):
        k = 1
        while k < len(text) and text[k].isdecimal():
            k += 1
        text = text[k:]
    return text


def _ahead(items: Iterator[T], depth: int = 2) -> Iterator[T]:
    """The items, made up to `depth` ahead on a thread of their own: reading a chunk of
    the file and gcodescan.c's scan of it let go of the GIL, so they run beside the
    importer's work on the chunk before. An error making an item is raised in its place."""
    q: queue.Queue = queue.Queue(depth)
    stop = threading.Event()

    def work() -> None:
        try:
            for item in items:
                if stop.is_set():
                    return
                q.put((True, item))
            q.put((False, None))
        except BaseException as e:  # raised to the reader in the item's place
            q.put((False, e))

    worker = threading.Thread(target=work, daemon=True, name="gcode-scan")
    worker.start()
    try:
        while True:
            more, item = q.get()
            if not more:
                if item is not None:
                    raise item
                return
            yield item
    finally:
        stop.set()
        while worker.is_alive():    # the reader stopped early: free a put that waits
            try:
                q.get(timeout=0.05)
            except queue.Empty:
                pass


class GcodeReader:
    """State machine over G-code lines; iterate `ops(lines)`."""

    def __init__(self, options: ImportOptions, errors: ErrorLog, fast: bool = True) -> None:
        self.errors = errors
        self.fast = fast            # False: every line through the general parser (tests)
        dialect = options.pen_dialect
        if dialect not in PEN_DIALECTS:
            raise ValueError(f"pen_dialect must be one of {', '.join(PEN_DIALECTS)}")
        if dialect == "auto" and options.servo_down_angle is not None:
            dialect = "servo-z"
        self.dialect = dialect
        self.z_threshold = options.z_threshold
        self.servo_down = options.servo_down_angle
        self.motion = 0
        self.inches = False
        self.relative = False
        self.feed: float | None = None
        self.x = self.y = 0.0
        self.z: float | None = None
        self.pen: bool | None = None
        self.off_x = self.off_y = self.off_z = 0.0     # G92 offsets (machine - program)
        self.g30 = (0.0, 0.0)
        self.laser = False          # laser dialect: on from M3/M4 to M5
        self.drawn = False          # something drawn since the last layer started
        self.layer_count = 1
        self.pending_layer: str | None = None
        self.tool: float | None = None
        self.default_feed = options.feed
        # The words of plain lines read before (M3, M5, ...: a file repeats a few of them
        # thousands of times), each read the same way every time.
        self._plain: dict[str, list[tuple[str, str]]] = {}

    def ops(self, chunks: Iterable[str | bytes]) -> Iterator[tuple]:
        """The ops of the source, given as chunks of whole lines (text ending with a
        newline, or its UTF-8), numbered from 1. The common lines (G0/G1 X Y [F]
        [; comment], read by the native fast path, native/gcodescan.c) become MOVES ops,
        a run at a time, and with the pen lines among them (M3, M4, M5, in the auto and
        m3 dialects) PATH ops; every other line goes through the general parser."""
        if self.dialect == "servo-z" and self.servo_down is None:
            self.errors.add(None, "pen dialect servo-z needs servo_down_angle")
            return
        out: list[tuple] = []
        # the largest kind read in bulk: pen lines too where M3/M5 move the pen
        bulk = (PEN_UP if self.dialect in ("auto", "m3") else LINE) if self.fast else OTHER
        first = 1   # the chunk's first line
        for lines in _ahead(scan(text, MAX_LINE) for text in chunks):
            kind = lines.kind
            common = (kind != OTHER) & (kind <= bulk)
            cuts = [0, *(np.flatnonzero(common[1:] != common[:-1]) + 1).tolist(), len(kind)]
            firsts = common[cuts[:-1]].tolist()     # is each stretch common lines?
            for a, b, is_common in zip(cuts[:-1], cuts[1:], firsts, strict=True):
                if is_common and not self.relative and not self.inches:
                    self._path(out, first + a, kind[a:b], lines.x[a:b], lines.y[a:b],
                               lines.feed[a:b])
                else:
                    # any other line, or a common one in relative or inch mode (a run
                    # of common lines changes neither)
                    for k in range(a, b):
                        self._line(out, first + k, lines.line(k))
                        if out:     # before the next line: errors keep the source's order
                            yield from out
                            out.clear()
                if out:
                    yield from out
                    out.clear()
            first += len(kind)

    def _feeds(self, first: int, draw: np.ndarray, feed: np.ndarray) -> np.ndarray:
        """The feed of each line of a run: the last F given at or before it, else the one
        before the run; a G1 with no feed ever given warns once and takes the default.
        (The feeds are NaN only before the run's first F.) Keeps the last as the feed in
        effect."""
        if feed[0] != feed[0]:
            before = self.feed
            if before is None:
                unfed = np.flatnonzero(draw & np.isnan(feed))
                if len(unfed):
                    self.errors.warn(first + int(unfed[0]), _no_feed(1, self.default_feed))
                    before = self.default_feed
            if before is not None:
                feed = np.where(np.isnan(feed), before, feed)
        last = float(feed[-1])
        if last == last:
            self.feed = last
        return feed

    def _path(self, out: list[tuple], first: int, kind: np.ndarray, x: np.ndarray,
              y: np.ndarray, feed: np.ndarray) -> None:
        """Appends the ops of consecutive common and pen lines (absolute millimetres): one
        PATH op (MOVES ops when there are no pen lines: `_run`). A pen line changing
        nothing becomes OTHER (no PEN op); the first pen down after a pause or tool
        change, which starts a layer, is taken alone (`_pen`)."""
        at = np.flatnonzero(kind >= PEN_DOWN)
        if not len(at):
            self._run(out, first, kind, x, y, feed)
            return
        down = kind[at] == PEN_DOWN
        if self.pending_layer is not None and down.any():
            p = int(at[np.argmax(down)])
            if p:
                self._path(out, first, kind[:p], x[:p], y[:p], feed[:p])
            self._pen(out, first + p, True)
            if p + 1 < len(kind):
                self._path(out, first + p + 1, kind[p + 1:], x[p + 1:], y[p + 1:],
                           feed[p + 1:])
            return
        before = np.empty(len(down), bool)
        before[1:] = down[:-1]
        before[0] = bool(self.pen)
        same = down == before
        if self.pen is None:
            same[0] = False
        kind = kind.copy()
        kind[at[same]] = OTHER
        self.pen = bool(down[-1])
        if down.any():
            self.drawn = True
        draw = kind == LINE
        moving = np.flatnonzero((kind == RAPID) | draw)
        feed = self._feeds(first, draw, feed)
        x = x + self.off_x
        y = y + self.off_y
        if len(moving):
            last = int(moving[-1])
            self.motion = 1 if draw[last] else 0
            self.x, self.y = float(x[last]), float(y[last])
        out.append((PATH, first, kind, x, y, np.where(draw, feed, np.nan)))

    def _run(self, out: list[tuple], first: int, kind: np.ndarray, x: np.ndarray,
             y: np.ndarray, feed: np.ndarray) -> None:
        """Appends the ops of consecutive common lines (absolute millimetres) as MOVES ops;
        `feed`: the last F given in the run at or before each line (NaN when none is)."""
        n = len(kind)
        if n == 1 and self.dialect not in MOTION_PEN:
            self._one(out, first, int(kind[0]) == LINE, float(x[0]) + self.off_x,
                      float(y[0]) + self.off_y, float(feed[0]))
            return
        draw = kind == LINE
        x = x + self.off_x
        y = y + self.off_y
        feed = self._feeds(first, draw, feed)
        feeds = np.where(draw, feed, np.nan)
        self.motion = 1 if draw[-1] else 0
        self.x, self.y = float(x[-1]), float(y[-1])
        if self.dialect not in MOTION_PEN:
            out.append((MOVES, first, x, y, feeds))
            return
        # The pen follows the motion mode: one MOVES op per stretch of the same pen.
        pen = draw if self.dialect == "none" or self.laser else np.zeros(n, bool)
        cuts = [0, *(np.flatnonzero(pen[1:] != pen[:-1]) + 1).tolist(), n]
        for a, b in itertools.pairwise(cuts):
            self._pen(out, first + a, bool(pen[a]))
            out.append((MOVES, first + a, x[a:b], y[a:b], feeds[a:b]))

    def _one(self, out: list[tuple], line_no: int, draw: bool, x: float, y: float,
             feed: float) -> None:
        """`_run` for a run of one line, with Python's floats (the same arithmetic) rather
        than arrays: a stroke's travel is such a run."""
        before = self.feed
        if before is None and draw and feed != feed:
            self.errors.warn(line_no, _no_feed(1, self.default_feed))
            before = self.default_feed
        if before is not None and feed != feed:
            feed = before
        if feed == feed:
            self.feed = feed
        self.motion = 1 if draw else 0
        self.x, self.y = x, y
        out.append((MOVE, line_no, x, y, feed if draw else None))

    def _line(self, out: list[tuple], line_no: int, raw: str) -> None:
        """Appends the ops of one line read by the general parser."""
        words = self._plain.get(raw)
        if words is not None:
            self._block(out, line_no, words)
            return
        if len(raw) > MAX_LINE:
            if len(raw) > MAX_RAW_LINE:
                self.errors.add(line_no, f"line longer than {MAX_RAW_LINE} characters")
                return
            if len(_COMMENT.sub("", raw)) > MAX_LINE:
                self.errors.add(line_no, f"line longer than {MAX_LINE} characters "
                                         "(without its comments)")
                return
        head = raw.lstrip()
        if head[:1] in _CONSOLE:
            self.errors.warn(line_no, f"console command '{head[:20]}' dropped: it is "
                                      "for a terminal, not part of a drawing")
            return
        pause = _PAUSE.fullmatch(raw)
        if pause is not None and not _BLOCK_AFTER_PAUSE.match(pause.group(2)):
            message = _COMMENT.sub("", pause.group(2)).strip() or None
            self._boundary(message)
            return
        plain = not ("*" in raw or "(" in raw or ";" in raw or "N" in raw or "n" in raw
                     or "%" in raw)
        if plain:
            text = raw.replace(" ", "").replace("\t", "").upper()
        else:
            text = strip_line(raw, line_no, self.errors)
        if not text:
            return
        if _BLOCK.fullmatch(text) is None:
            self.errors.add(line_no, f"cannot parse '{raw.strip()[:60]}'")
            return
        words = _WORD.findall(text)
        if plain and len(self._plain) < PLAIN_LINES:
            self._plain[raw] = words
        self._block(out, line_no, words)

    def _dwell(self, vals: dict[str, float]) -> float | None:
        """G4's time in seconds: P in seconds (GRBL), but in milliseconds in the servo
        dialects (M300, M280: Marlin-based firmware, where S gives seconds)."""
        p = vals.get("P")
        if self.dialect in MS_DWELL:
            if p is None and vals.get("S") is not None and vals["S"] >= 0:
                return vals["S"]
            return None if p is None or p < 0 else p / 1000
        return None if p is None or p < 0 else p

    def _pen(self, out: list[tuple], line_no: int, down: bool) -> None:
        if down and self.pending_layer is not None:
            if not self.drawn and self.pending_layer and self.layer_count == 1:
                out.append((LAYER, line_no, self.pending_layer, PALETTE[0]))   # names layer 1
            elif self.drawn:
                self.layer_count += 1
                name = self.pending_layer or f"layer {self.layer_count}"
                out.append((LAYER, line_no, name, PALETTE[(self.layer_count - 1) % len(PALETTE)]))
                self.drawn = False
            self.pending_layer = None
        if down:
            self.drawn = True
        if self.pen is not down:
            self.pen = down
            out.append((PEN, line_no, down))

    def _motion_pen(self, out: list[tuple], line_no: int, mode: int) -> None:
        self._pen(out, line_no, mode != 0 and (self.dialect == "none" or self.laser))

    def _boundary(self, name: str | None) -> None:
        """A pause or tool change: what is drawn after it is a new layer (made when the pen
        next goes down, so a pause before anything is drawn makes none)."""
        if not self.pending_layer:     # the first name given (a pause's message) stays
            self.pending_layer = name or ""

    def _block(self, out: list[tuple], line_no: int, words: list[tuple[str, str]]) -> None:
        """Appends the ops of one line to `out` (a plain function: this runs per line)."""
        errors = self.errors
        gs: list[float] = []
        ms: list[float] = []
        vals: dict[str, float] = {}
        for letter, num in words:
            v = float(num)
            if letter == "G":
                gs.append(v)
            elif letter == "M":
                ms.append(v)
            elif letter in _AXIS_WORDS:
                if letter in vals:
                    errors.add(line_no, f"word {letter} repeated")
                    return
                vals[letter] = v
            else:
                errors.add(line_no, f"unsupported word {letter}{num}")
                return
        motion = None
        dwell = False
        home: float | None = None
        for g in gs:
            if g in (0.0, 1.0, 2.0, 3.0):
                motion = int(g)
            elif g == 4.0:
                dwell = True
            elif g in (28.0, 30.0, 92.0, 92.1, 30.1, 28.1):
                home = g
            elif g == 20.0:
                self.inches = True
            elif g == 21.0:
                self.inches = False
            elif g == 90.0:
                self.relative = False
            elif g == 91.0:
                self.relative = True
            elif g not in _NOOP_G:
                errors.add(line_no, f"unsupported command G{_num(g)}")
                return
        unit = 25.4 if self.inches else 1.0
        if "F" in vals:
            if vals["F"] <= 0:
                errors.add(line_no, "feed rate F must be positive")
                return
            self.feed = vals["F"] * unit
        if "T" in vals and 280.0 not in ms:     # T on an M280 line is the servo's time
            self.tool = vals["T"]
            if 6.0 not in ms:
                self._boundary(f"tool T{_num(vals['T'])}")
        for m in ms:
            if m in (3.0, 4.0, 5.0):
                if self.dialect in ("auto", "m3"):
                    self._pen(out, line_no, m != 5.0)
                elif self.dialect == "laser":
                    self.laser = m != 5.0
                    if not self.laser:
                        self._pen(out, line_no, False)
            elif m == 6.0:
                tool = f"tool T{_num(self.tool)}" if self.tool is not None else None
                self._boundary(tool)
            elif m in (0.0, 1.0):
                self._boundary(None)
            elif m == 280.0:
                s_angle = vals.get("S")
                if s_angle is None:
                    errors.add(line_no, "M280 needs a servo angle S")
                    return
                if self.dialect in ("auto", "m280"):
                    if self.servo_down is not None:
                        down = abs(s_angle - self.servo_down) < 0.5
                    else:
                        down = s_angle <= M280_DOWN_MAX
                    self._pen(out, line_no, down)
            elif m in _MOTOR_M:
                errors.warn(line_no, f"M{_num(m)} (motors on/off) dropped: the server "
                                     "manages the motors")
            elif m == 300.0:
                s = vals.get("S")
                if s is None:
                    errors.add(line_no, "M300 needs a servo angle S (S30 pen down, S50 up)")
                    return
                self._pen(out, line_no, s <= M300_DOWN_MAX)
            elif m not in _NOOP_M:
                errors.add(line_no, f"unsupported command M{_num(m)}")
                return
        if home is not None:
            self._home(out, line_no, home, vals, unit)
            return
        if dwell:
            seconds = self._dwell(vals)
            if seconds is None:
                errors.add(line_no, "G4 needs a dwell time P in "
                                    f"{'milliseconds' if self.dialect in MS_DWELL else 'seconds'}"
                                    " (P >= 0)")
                return
            out.append((DWELL, line_no, seconds))
            return
        if "Z" in vals:
            z = vals["Z"] * unit + (0.0 if self.relative else self.off_z)
            if self.relative and self.dialect != "servo-z":
                z += self.z or 0.0
            self.z = z
            if self.dialect == "servo-z":
                assert self.servo_down is not None
                self._pen(out, line_no, abs(vals["Z"] - self.servo_down) < 0.5)
            elif self.dialect in ("auto", "z"):
                self._pen(out, line_no, z <= self.z_threshold)
        if motion is not None:
            self.motion = motion
        has_xy = "X" in vals or "Y" in vals
        has_arc = "I" in vals or "J" in vals or "R" in vals
        if not has_xy and not (has_arc and self.motion in (2, 3)):
            if motion in (2, 3):
                errors.add(line_no, f"G{motion} needs I/J or R")
            return
        x, y = self.x, self.y
        if self.relative:
            tx, ty = x + vals.get("X", 0.0) * unit, y + vals.get("Y", 0.0) * unit
        else:
            tx = vals["X"] * unit + self.off_x if "X" in vals else x
            ty = vals["Y"] * unit + self.off_y if "Y" in vals else y
        mode = self.motion
        if self.dialect in MOTION_PEN:
            self._motion_pen(out, line_no, mode)
        if mode != 0 and self.feed is None:
            errors.warn(line_no, _no_feed(mode, self.default_feed))
            self.feed = self.default_feed
        if mode in (0, 1):
            self.x, self.y = tx, ty
            out.append((MOVE, line_no, tx, ty, None if mode == 0 else self.feed))
            return
        cw = mode == 2
        if "R" in vals:
            centre = self._centre_from_radius(line_no, x, y, tx, ty, vals["R"] * unit, cw)
            if centre is None:
                self.x, self.y = tx, ty
                return
            i, j = centre
        elif "I" in vals or "J" in vals:
            i, j = vals.get("I", 0.0) * unit, vals.get("J", 0.0) * unit
            r0 = math.hypot(i, j)
            r1 = math.hypot(tx - x - i, ty - y - j)
            delta = abs(r1 - r0)
            if delta > ARC_RADIUS_ABS and (delta > 0.5 or delta > ARC_RADIUS_REL * r0):
                errors.add(line_no, f"arc radius inconsistent: {r0:.4f} mm at the start, "
                                    f"{r1:.4f} mm at the end")
                self.x, self.y = tx, ty
                return
            if r0 == 0:
                errors.add(line_no, "arc with zero radius")
                return
        else:
            errors.add(line_no, f"G{mode} needs I/J or R")
            return
        self.x, self.y = tx, ty
        out.append((ARC, line_no, tx, ty, i, j, self.feed, cw))

    def _home(self, out: list[tuple], line_no: int, g: float, vals: dict[str, float],
              unit: float) -> None:
        """G92 (offsets), G28/G30 (pen-up travel home or to the stored position, through
        the point given), G28.1/G30.1 (store the position)."""
        if g == 92.0:
            if not any(k in vals for k in "XYZ"):
                self.errors.add(line_no, "G92 needs an axis word (X, Y or Z)")
                return
            if "X" in vals:
                self.off_x = self.x - vals["X"] * unit
            if "Y" in vals:
                self.off_y = self.y - vals["Y"] * unit
            if "Z" in vals:
                self.off_z = (self.z or 0.0) - vals["Z"] * unit
            return
        if g == 92.1:
            self.off_x = self.off_y = self.off_z = 0.0
            return
        if g == 30.1:
            self.g30 = (self.x, self.y)
            return
        if g == 28.1:
            return
        # Only the axes named go home; with none named, all do. The pen goes up first.
        named = [a for a in "XYZ" if a in vals]
        self._pen(out, line_no, False)
        axes = [a for a in "XY" if a in vals] if named else ["X", "Y"]
        if not axes:
            return
        if named:
            if self.relative:
                ix, iy = self.x + vals.get("X", 0.0) * unit, self.y + vals.get("Y", 0.0) * unit
            else:
                ix = vals["X"] * unit + self.off_x if "X" in vals else self.x
                iy = vals["Y"] * unit + self.off_y if "Y" in vals else self.y
            out.append((MOVE, line_no, ix, iy, None))
        hx, hy = (0.0, 0.0) if g == 28.0 else self.g30
        self.x = hx if "X" in axes else self.x
        self.y = hy if "Y" in axes else self.y
        out.append((MOVE, line_no, self.x, self.y, None))

    def _centre_from_radius(self, line_no: int, x: float, y: float, tx: float, ty: float,
                            r: float, cw: bool) -> tuple[float, float] | None:
        dx, dy = tx - x, ty - y
        d = math.hypot(dx, dy)
        if d == 0:
            self.errors.add(line_no, "arc in radius form (R) needs an end point "
                                     "other than the start")
            return None
        h2 = r * r - d * d / 4
        if h2 < -1e-6 * r * r - ARC_RADIUS_ABS:
            self.errors.add(line_no, f"arc radius R{abs(r):g} is too small for the "
                                     f"distance {d:.4f}")
            return None
        h = math.sqrt(max(h2, 0.0))
        # The centre is on the right of the chord for a clockwise arc of under 180°
        # (R > 0) and on the left for one of over 180° (R < 0); mirrored for G3.
        side = -1.0 if cw else 1.0
        if r < 0:
            side = -side
        mx, my = x + dx / 2, y + dy / 2
        cx = mx - side * h * dy / d
        cy = my + side * h * dx / d
        return cx - x, cy - y


_LASER_SNIFF = 1 << 16
_BLOCK_AFTER_PAUSE = re.compile(r"[GMXYZFST]\s*[-+.\d]", re.I)
_Z_WORD = re.compile(r"Z\s*([-+]?(?:\d+(?:\.\d*)?|\.\d+))", re.I)
# M300 and M280 are searched for in the text with m made M: a case-insensitive search
# costs 10 times as much, and only m and M fold to m.
_M300 = re.compile(r"M\s*300\b")
_M280 = re.compile(r"M\s*280\b")
_M3 = re.compile(r"^[^\n]*?\bM0*[34](?![0-9.])", re.I | re.M)
_SPINDLE = re.compile(r"\bM0*([345])(?![0-9.])", re.I)
_G0_XY = re.compile(r"\s*G0*0(?![0-9.])[^\n]*[XY]", re.I)
_G1 = re.compile(r"\s*G0*1(?![0-9.])", re.I)


def _laser(text: str) -> bool:
    """M3/M4 switched on, then a G0 line with X or Y, then a G1 line, with no M5 between
    (a laser's file), read line by line: linear in the text."""
    state = 0               # 0 off, 1 on, 2 on and a G0 travel seen
    for line in text.split("\n"):
        if state == 2 and _G1.match(line):
            return True
        if state == 1 and _G0_XY.match(line):
            state = 2
        words = _SPINDLE.findall(line)
        if words:
            if words[-1] == "5":
                state = 0
            elif state == 0 or "5" in words:
                state = 1
    return False


def sniff_dialect(head: str) -> str:
    """The pen dialect a file's beginning shows: M300 or M280 words; Z moving between at
    least two heights (M3/M5 are then the spindle of a Z-axis machine); M3 switched on
    and then G0 travel between G1 strokes with no M5 (a laser's file: G0 is pen-up
    travel, as GRBL's laser mode); M3/M5; no pen command at all: every G1 draws."""
    # (without parentheses only ';' comments: that search is 3 times as fast)
    text = (_COMMENT if "(" in head else _SEMICOLON_COMMENT).sub("", head)
    # Each search only where its words' plain text occurs (a search is 100 times slower
    # than looking for a substring, and this is a megabyte).
    folded = text.replace("m", "M") if "300" in text or "280" in text else text
    if "300" in text and _M300.search(folded):
        return "m300"
    if "280" in text and _M280.search(folded):
        return "m280"
    if ("Z" in text or "z" in text) and len({float(z) for z in _Z_WORD.findall(text)}) >= 2:
        return "z"
    if _M3.search(text) is None:
        return "none"
    if _laser(text[:_LASER_SNIFF]):
        return "laser"
    return "m3"


def read_ops(chunks: Iterable[str | bytes], options: ImportOptions, errors: ErrorLog,
             fast: bool = True) -> Iterator[tuple]:
    """The ops of G-code given as chunks of whole lines (detect.line_chunks)."""
    return GcodeReader(options, errors, fast).ops(chunks)
