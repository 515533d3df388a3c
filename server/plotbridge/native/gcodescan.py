"""gcodescan.c: the G-code importer's fast path, reading the common lines of a chunk."""

from __future__ import annotations

import ctypes
from typing import NamedTuple

import numpy as np

from . import array, function

_f64, _u8, _long = array(np.float64), array(np.uint8), array(np.int_)
OTHER, RAPID, LINE, PEN_DOWN, PEN_UP = 0, 1, 2, 3, 4


def _scanner():
    return function("gcodescan", "gcode_scan",
                    [ctypes.c_char_p, ctypes.c_long, ctypes.c_int, ctypes.c_long,
                     ctypes.c_long, _u8, _f64, _f64, _f64, _f64, _long], ctypes.c_long)


class Scan(NamedTuple):
    """A chunk's lines: kind (OTHER, RAPID (G0), LINE (G1), PEN_DOWN (M3, M4) or PEN_UP
    (M5)) and, for the common ones, X, Y, F (NaN when absent; pen lines: 0, 0, NaN) and
    the feed in effect: the last F given at or before the line in its run of consecutive
    common and pen lines (NaN when none is)."""

    kind: np.ndarray
    x: np.ndarray
    y: np.ndarray
    f: np.ndarray
    feed: np.ndarray
    data: bytes
    start: np.ndarray

    def line(self, k: int) -> str:
        """The text of line k, without its newline."""
        return self.data[self.start[k]:self.start[k + 1] - 1].decode("utf-8",
                                                                     "surrogateescape")


def newlines(data: bytes) -> int:
    """How many b"\n" `data` holds (numpy counts 6 times as fast as bytes.count)."""
    return int(np.count_nonzero(np.frombuffer(data, np.uint8) == 10))


def scan(text: str | bytes, max_line: int) -> Scan:
    """The lines of `text` (which ends with a newline; bytes: its UTF-8); a common line
    is G0/G1 X Y [F] [; comment] of at most `max_line` characters whose F, when given, is
    positive; a pen line is M3, M4 or M5 [; comment]."""
    data = text if isinstance(text, bytes) else text.encode("utf-8", "surrogateescape")
    # Room for its lines (its newlines, and a last line without one): arrays of a line
    # per byte cost more to map than numpy takes to count.
    room = newlines(data) + 1
    kind = np.empty(room, np.uint8)
    x, y, f, feed = np.empty(room), np.empty(room), np.empty(room), np.empty(room)
    start = np.empty(room + 1, np.int_)
    n = _scanner()(data, len(data), text.isascii(), room, max_line, kind, x, y, f, feed,
                   start)
    return Scan(kind[:n], x[:n], y[:n], f[:n], feed[:n], data, start[:n + 1])
