"""movelines.c: the normalized program's lines for a run of moves and pen changes."""

from __future__ import annotations

import ctypes
import itertools
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from . import function

_LINE_ROOM = 48     # bytes of a line without its feed text (movelines.c)
FEEDS_MAX = 4096    # feed texts kept from run to run (a file of ever new feeds)
EV_DOWN, EV_UP, EV_DRAW, EV_TRAVEL = 0, 1, 2, 3     # the preview's calls (movelines.c)


class _Writer(ctypes.Structure):
    """movelines.c's movelines_t."""
    _fields_ = [
        ("x", ctypes.c_void_p),
        ("y", ctypes.c_void_p),
        ("feed", ctypes.c_void_p),
        ("op", ctypes.c_void_p),
        ("area", ctypes.c_double * 4),
        ("kind_rapid", ctypes.c_uint8),
        ("kind_line", ctypes.c_uint8),
        ("kind_dwell", ctypes.c_uint8),
        ("pen_ok", ctypes.c_int),
        ("settle", ctypes.c_double),
        ("px", ctypes.c_double),
        ("py", ctypes.c_double),
        ("down", ctypes.c_int),
        ("line", ctypes.c_long),
        ("lifts", ctypes.c_long),
        ("down_mm", ctypes.c_double),
        ("travel_mm", ctypes.c_double),
        ("bounds", ctypes.c_double * 4),
        ("text", ctypes.c_void_p),
        ("text_len", ctypes.c_long),
        ("kind", ctypes.c_void_p),
        ("x32", ctypes.c_void_p),
        ("y32", ctypes.c_void_p),
        ("f32", ctypes.c_void_p),
        ("nbytes", ctypes.c_void_p),
        ("rows", ctypes.c_long),
        ("xy", ctypes.c_void_p),
        ("n_xy", ctypes.c_long),
        ("ev", ctypes.c_void_p),
        ("ev_a", ctypes.c_void_p),
        ("ev_b", ctypes.c_void_p),
        ("n_ev", ctypes.c_long),
        ("feed_val", ctypes.c_void_p),
        ("n_feeds", ctypes.c_long),
        ("feed_text", ctypes.c_char_p),
        ("feed_off", ctypes.c_void_p),
        ("unknown", ctypes.c_void_p),
        ("n_unknown", ctypes.c_long),
    ]


def _fn():
    return function("movelines", "moves_lines", [ctypes.POINTER(_Writer), ctypes.c_long,
                                                 ctypes.c_long], ctypes.c_long)


class State(NamedTuple):
    """The writer's state a run starts from and ends with: position, pen down, program
    lines written, pen lifts, pen-down and travel lengths, bounds of the drawing
    (min x, min y, max x, max y)."""

    x: float
    y: float
    down: bool
    line: int
    lifts: int
    down_mm: float
    travel_mm: float
    bounds: list[float]


class Lines(NamedTuple):
    """What a run wrote (arrays valid until the MoveLines' next run): the element it
    stopped at (the run's length when done); the text (ASCII, one line each, with
    newlines); the estimate's inputs (Estimator.moves); the kept points, rounded (n x 2);
    the preview's calls: kind (EV_*), a, b (movelines.c); the state after."""

    stop: int
    text: bytes
    kind: np.ndarray
    x32: np.ndarray
    y32: np.ndarray
    f32: np.ndarray
    nbytes: np.ndarray
    xy: np.ndarray
    events: tuple[list, list, list]
    state: State


class MoveLines:
    """Writes runs of moves and pen changes through movelines.c with buffers kept from
    run to run: a file of short strokes is thousands of runs, and each call's own cost
    counts."""

    def __init__(self, area: tuple[float, float, float, float],
                 feed_text: Callable[[float], str], kind_rapid: int, kind_line: int,
                 kind_dwell: int = 0, settle: float = 0.0) -> None:
        self.feed_text = feed_text
        self._w = _Writer()
        self._w.area[:] = area
        self._w.kind_rapid, self._w.kind_line = kind_rapid, kind_line
        self._w.kind_dwell, self._w.settle = kind_dwell, settle
        self._ref = ctypes.byref(self._w)
        self._fn = _fn()
        self._n = 0
        self._room = 0
        self._set_feeds({})

    def _set_feeds(self, texts: dict[float, bytes]) -> None:
        """The feed texts movelines.c writes from."""
        vals = sorted(texts)
        self._texts = {v: texts[v] for v in vals}
        self._feed_val = np.array(vals, np.float64)
        self._feed_off = np.array([0, *itertools.accumulate(map(len, self._texts.values()))],
                                  np.int64)
        self._feed_text = b"".join(self._texts.values())
        self._longest = max(map(len, self._texts.values()), default=0)
        w = self._w
        w.feed_val, w.n_feeds = self._feed_val.ctypes.data, len(vals)
        w.feed_text, w.feed_off = self._feed_text, self._feed_off.ctypes.data

    def _add_feeds(self, fresh: bool) -> None:
        """Texts for the feeds movelines.c found without one, the others kept unless
        there are too many and `fresh`."""
        new = set(self._unknown[:self._w.n_unknown].tolist())
        texts = {} if fresh and len(self._texts) + len(new) > FEEDS_MAX else self._texts
        self._set_feeds({**texts, **{v: self.feed_text(v).encode("ascii") for v in new}})

    def _grow(self, n: int, room: int) -> None:
        w = self._w
        if n > self._n:
            self._n = n = max(n, 2 * self._n)
            self._xy = np.empty((n, 2))
            self._kind = np.empty(n, np.uint8)
            self._x32, self._y32, self._f32 = (np.empty(n, np.float32) for _ in range(3))
            self._nbytes = np.empty(n, np.uint16)
            self._unknown = np.empty(n)
            self._ev = np.empty(n, np.uint8)
            self._ev_a, self._ev_b = np.empty(n, np.int64), np.empty(n, np.int64)
            # the run is copied in (a copy costs less than asking an array's address)
            self._x, self._y, self._feed = np.empty(n), np.empty(n), np.empty(n)
            self._op = np.empty(n, np.uint8)
            for name in ("x", "y", "feed", "xy", "kind", "x32", "y32", "f32", "nbytes",
                         "unknown", "ev", "ev_a", "ev_b"):
                setattr(w, name, getattr(self, f"_{name}").ctypes.data)
        if room > self._room:
            self._room = max(room, 2 * self._room)
            self._text = np.empty(self._room, np.uint8)
            w.text = self._text.ctypes.data

    def load(self, op: np.ndarray | None, x: np.ndarray, y: np.ndarray,
             feeds: np.ndarray) -> None:
        """The run the next `run` calls write: the kind of each element (gcodescan's
        RAPID, LINE, PEN_DOWN, PEN_UP, OTHER: nothing) or None (all moves), points, feeds
        (NaN for rapids)."""
        n = len(x)
        self._grow(n, n * (_LINE_ROOM + self._longest))
        self._x[:n] = x
        self._y[:n] = y
        self._feed[:n] = feeds
        if op is None:
            self._w.op = None
        else:
            self._op[:n] = op
            self._w.op = self._op.ctypes.data
        self._len = n

    def run(self, start: int, state: State, pen_ok: bool) -> Lines:
        """The lines of the loaded run's elements from `start` on, written from `state`:
        points rounded to 0.001 mm, those equal to the one before dropped, pen changes
        that change nothing too; it stops at a point outside the area (or too large to
        write) and at a pen down when not `pen_ok`. The first run after `load` starts
        at 0 (it finds the feed texts the whole run needs)."""
        n = self._len
        w = self._w
        w.px, w.py, w.down, w.line, w.lifts = state[:5]
        w.down_mm, w.travel_mm = state.down_mm, state.travel_mm
        w.bounds[:] = state.bounds
        w.pen_ok = pen_ok
        k = self._fn(self._ref, start, n)
        fresh = True
        while k == -2:      # at most twice: once more when the texts started afresh
            self._add_feeds(fresh)
            fresh = False
            self._grow(n, n * (_LINE_ROOM + self._longest))
            k = self._fn(self._ref, start, n)
        r, m, e = w.rows, w.n_xy, w.n_ev
        events = (self._ev[:e].tolist(), self._ev_a[:e].tolist(), self._ev_b[:e].tolist())
        return Lines(k, self._text[:w.text_len].tobytes(), self._kind[:r], self._x32[:r],
                     self._y32[:r], self._f32[:r], self._nbytes[:r], self._xy[:m], events,
                     State(w.px, w.py, bool(w.down), w.line, w.lifts, w.down_mm, w.travel_mm,
                           w.bounds[:]))
