"""wirebytes.c: the bytes each program line takes on the wire, for the estimate."""

from __future__ import annotations

import ctypes

import numpy as np

from . import array, function


class _State(ctypes.Structure):
    """wirebytes.c's wire_state_t."""
    _fields_ = [
        ("spm", ctypes.c_double * 2),
        ("line_numbers", ctypes.c_int),
        ("motion", ctypes.c_int),
        ("feed", ctypes.c_int64),
        ("orig", ctypes.c_int64 * 2),
        ("sent", ctypes.c_int64 * 2),
        ("line", ctypes.c_int64),
    ]


def _fn():
    u8, f32 = array(np.uint8, 1), array(np.float32, 1)
    return function("wirebytes", "wire_bytes",
                    [ctypes.POINTER(_State), ctypes.c_long, u8, f32, f32, f32, f32, f32, u8,
                     array(np.uint16, 1)], None)


class WireBytes:
    """The bytes each program line takes on the wire with its newline (and its N word
    where the board takes one), as `len(numbered(n, Compactor(steps_per_mm).line(text)))
    + 1` (program/wire.py) counts them, from arrays of the lines run after run: `count`
    gets the lines in program order, from line 1, and keeps the modal state between runs.

    Exact for the lines importing/program.py writes (coordinates of 3 decimals below
    8,000 mm, which float32 keeps to the thousandth). A feed is taken to the tenth, as
    its F text is, but from float32: one on a tie (F1000.05, a hair above in the double,
    below in the float) may go to the other tenth, and its F word be counted a few bytes
    off (tests/unit/test_wire_bytes.py)."""

    def __init__(self, steps_per_mm: tuple[float, float], line_numbers: bool) -> None:
        self._state = _State()
        self._state.spm[:] = steps_per_mm
        self._state.line_numbers = int(line_numbers)
        self._state.motion = self._state.feed = -1
        self._ref = ctypes.byref(self._state)
        self._fn = _fn()

    def count(self, kind: np.ndarray, x: np.ndarray, y: np.ndarray, i: np.ndarray,
              j: np.ndarray, feed: np.ndarray, keeps: np.ndarray, nbytes: np.ndarray) -> None:
        """Sets `nbytes` of the next len(kind) lines, in place. kind (uint8): a motion
        line's G number (0-3), above 3 for a line that is no motion, whose `nbytes` (its
        own, `wire.plain`) stay and whose `keeps` (uint8) says it leaves the modal state
        alone; x, y: a motion's end point, i, j: an arc's centre offsets, feed: mm/min
        (float32). C-contiguous arrays (a batch's, or slices of them)."""
        self._fn(self._ref, len(kind), kind, x, y, i, j, feed, keeps, nbytes)
