"""movelines.c: the normalized program's lines for a run of G0/G1 moves."""

from __future__ import annotations

import ctypes
import itertools
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from . import function

_LINE_ROOM = 48     # bytes of a line without its feed text (movelines.c)
FEEDS_MAX = 4096    # feed texts kept from run to run (a file of ever new feeds)


class _Writer(ctypes.Structure):
    """movelines.c's movelines_t."""
    _fields_ = [
        ("x", ctypes.c_void_p),
        ("y", ctypes.c_void_p),
        ("feed", ctypes.c_void_p),
        ("area", ctypes.c_double * 4),
        ("kind_rapid", ctypes.c_uint8),
        ("kind_line", ctypes.c_uint8),
        ("text", ctypes.c_void_p),
        ("xy", ctypes.c_void_p),
        ("length", ctypes.c_double),
        ("kind", ctypes.c_void_p),
        ("x32", ctypes.c_void_p),
        ("y32", ctypes.c_void_p),
        ("f32", ctypes.c_void_p),
        ("nbytes", ctypes.c_void_p),
        ("text_len", ctypes.c_long),
        ("bounds", ctypes.c_double * 4),
        ("feed_val", ctypes.c_void_p),
        ("n_feeds", ctypes.c_long),
        ("feed_text", ctypes.c_char_p),
        ("feed_off", ctypes.c_void_p),
        ("unknown", ctypes.c_void_p),
        ("n_unknown", ctypes.c_long),
    ]


def _fn():
    return function("movelines", "moves_lines", [ctypes.POINTER(_Writer), ctypes.c_long,
                                                 ctypes.c_double, ctypes.c_double],
                    ctypes.c_long)


class Lines(NamedTuple):
    """The kept moves of a run (arrays valid until the MoveLines' next run): their text
    (ASCII, one line each, with newlines); rounded points (n x 2); the running length given
    plus theirs; the estimate's inputs (Estimator.moves); min x, min y, max x, max y."""

    text: bytes
    xy: np.ndarray
    length: float
    kind: np.ndarray
    x32: np.ndarray
    y32: np.ndarray
    f32: np.ndarray
    nbytes: np.ndarray
    bounds: list[float]


class MoveLines:
    """Writes runs of moves through movelines.c with buffers kept from run to run: a file
    of short strokes is thousands of runs, and each call's own cost counts."""

    def __init__(self, area: tuple[float, float, float, float],
                 feed_text: Callable[[float], str], kind_rapid: int, kind_line: int) -> None:
        self.feed_text = feed_text
        self._w = _Writer()
        self._w.area[:] = area
        self._w.kind_rapid, self._w.kind_line = kind_rapid, kind_line
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
            # the run is copied in (a copy costs less than asking an array's address)
            self._x, self._y, self._feed = np.empty(n), np.empty(n), np.empty(n)
            for name in ("x", "y", "feed", "xy", "kind", "x32", "y32", "f32", "nbytes",
                         "unknown"):
                setattr(w, name, getattr(self, f"_{name}").ctypes.data)
        if room > self._room:
            self._room = max(room, 2 * self._room)
            self._text = np.empty(self._room, np.uint8)
            w.text = self._text.ctypes.data

    def run(self, x: np.ndarray, y: np.ndarray, feeds: np.ndarray, start: tuple[float, float],
            length: float) -> Lines | None:
        """The lines of moves to (x, y) from `start` (feeds NaN for rapids), points rounded
        to 0.001 mm and those equal to the one before dropped, and `length` plus the
        moves' length; None when a rounded point lies outside the area."""
        n = len(x)
        self._w.length = length
        self._grow(n, n * (_LINE_ROOM + self._longest))
        self._x[:n] = x
        self._y[:n] = y
        self._feed[:n] = feeds
        k = self._fn(self._ref, n, start[0], start[1])
        fresh = True
        while k == -2:      # at most twice: once more when the texts started afresh
            self._add_feeds(fresh)
            fresh = False
            self._grow(n, n * (_LINE_ROOM + self._longest))
            k = self._fn(self._ref, n, start[0], start[1])
        if k < 0:
            return None
        w = self._w
        return Lines(self._text[:w.text_len].tobytes(), self._xy[:k], w.length, self._kind[:k],
                     self._x32[:k], self._y32[:k], self._f32[:k], self._nbytes[:k],
                     w.bounds[:])
