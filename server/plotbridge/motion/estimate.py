"""The plot time estimate: the program's lines, collected as arrays and run through the
firmware's own motion code in one call (library.py), with the host-side timing of
timing.py."""

from __future__ import annotations

import ctypes
from array import array

import numpy as np

from ..importing.models import MachineProfile
from . import library as lib
from .library import ARC_CCW, ARC_CW, DWELL, LINE, OTHER, RAPID

TIMELINE_SAMPLES = 2000


def _config(p: MachineProfile) -> lib.Config:
    c = lib.Config()
    c.steps_per_mm[:] = p.steps_per_mm
    c.max_rate[:] = p.max_rate
    c.accel[:] = p.accel
    c.junction_deviation = p.junction_deviation
    c.arc_tolerance = p.arc_tolerance
    c.pen_settle_s = p.pen_settle_s
    c.corexy = int(p.corexy)
    c.depth = p.planner_blocks or lib.planner_depth()
    c.byte_s = 10.0 / p.baud if p.baud else 0.0
    c.line_cpu_s = p.plan_block_s
    c.rx_size = 128
    return c


def _ptr(a: array, ctype):
    return ctypes.cast(a.buffer_info()[0], ctypes.POINTER(ctype))


def thin_timeline(ack: np.ndarray, line: int, total: float,
                  limit: int = TIMELINE_SAMPLES) -> list[tuple[int, float]]:
    """(line, seconds elapsed when the board acknowledged it) samples, at most `limit`,
    ending with (line, total)."""
    n = len(ack)
    stride = max(1, -(-n // (limit - 1)))
    idx = np.arange(stride - 1, n, stride)
    out = [(int(k) + 1, round(float(ack[k]), 3)) for k in idx if k + 1 < line]
    out.append((line, round(total, 3)))
    return out[-limit:]


class Timeline:
    def __init__(self, owner: Estimator) -> None:
        self.owner = owner

    def finish(self, line: int, t: float) -> list[tuple[int, float]]:
        return thin_timeline(np.frombuffer(self.owner.ack, dtype=np.float64), line, t)


class Estimator:
    """Feed it the program line by line (`receive`, then what the line does); after
    `flush`, `time` is the estimate and `timeline` the progress samples. The start is
    (0, 0) with the pen up, as the firmware after homing."""

    def __init__(self, profile: MachineProfile, start: tuple[float, float] = (0.0, 0.0)):
        if start != (0.0, 0.0):
            raise ValueError("the estimate starts at (0, 0)")
        self.profile = profile
        self.kind = array("B")
        self.x = array("f")
        self.y = array("f")
        self.i = array("f")
        self.j = array("f")
        self.feed = array("f")
        self.bytes = array("H")
        self.ack = array("d")
        self.time = 0.0
        self.timeline = Timeline(self)

    def receive(self, nbytes: int) -> None:
        """The next program line, `nbytes` long with its newline."""
        self.kind.append(OTHER)
        self.bytes.append(min(nbytes, 65535))
        for a in (self.x, self.y, self.i, self.j, self.feed):
            a.append(0.0)

    def _set(self, kind: int, x: float, y: float, feed: float, i: float = 0.0,
             j: float = 0.0) -> None:
        self.kind[-1] = kind
        self.x[-1] = x
        self.y[-1] = y
        self.feed[-1] = feed
        self.i[-1] = i
        self.j[-1] = j

    def move(self, line: int, x: float, y: float, feed: float | None) -> None:
        self._set(RAPID if feed is None else LINE, x, y, feed or 0.0)

    def moves(self, kind: np.ndarray, x: np.ndarray, y: np.ndarray, feed: np.ndarray,
              nbytes: np.ndarray) -> None:
        """`receive` and `move` for each of a run of lines, given as the library takes
        them: kind (uint8, RAPID or LINE), x, y, feed (float32, 0 for rapids), bytes
        (uint16)."""
        self.kind.frombytes(kind)
        self.bytes.frombytes(nbytes.view(np.uint8))
        self.x.frombytes(x.view(np.uint8))
        self.y.frombytes(y.view(np.uint8))
        self.feed.frombytes(feed.view(np.uint8))
        zeros = bytes(4 * len(x))
        self.i.frombytes(zeros)
        self.j.frombytes(zeros)

    def arc(self, line: int, x: float, y: float, i: float, j: float, feed: float,
            cw: bool) -> None:
        self._set(ARC_CW if cw else ARC_CCW, x, y, feed, i, j)

    def stop(self, line: int, seconds: float) -> None:
        """Wait for motion to end, then hold still for `seconds` (pen settle, dwell)."""
        self._set(DWELL, seconds, 0.0, 0.0)

    def flush(self) -> None:
        n = len(self.kind)
        self.ack = array("d", bytes(8 * n))
        if not n:
            self.time = 0.0
            return
        library = lib.load()
        with lib.run_lock:
            library.motion_configure(ctypes.byref(_config(self.profile)))
            f = ctypes.c_float
            self.time = library.motion_run(
                n, _ptr(self.kind, ctypes.c_uint8), _ptr(self.x, f), _ptr(self.y, f),
                _ptr(self.i, f), _ptr(self.j, f), _ptr(self.feed, f),
                _ptr(self.bytes, ctypes.c_uint16), _ptr(self.ack, ctypes.c_double))
        self._clear()

    def planned_blocks(self) -> list[bytes]:
        """Plans the lines received so far with nothing executing and returns the queued
        planner blocks, oldest first, as the firmware lays them out in RAM (the
        differential test compares them with the board's)."""
        library = lib.load()
        size = library.motion_block_size()
        out = ctypes.create_string_buffer(size * 256)
        with lib.run_lock:
            library.motion_configure(ctypes.byref(_config(self.profile)))
            f = ctypes.c_float
            library.motion_plan(
                len(self.kind), _ptr(self.kind, ctypes.c_uint8), _ptr(self.x, f),
                _ptr(self.y, f), _ptr(self.i, f), _ptr(self.j, f), _ptr(self.feed, f))
            n = library.motion_blocks(out, 256)
        self._clear()
        return [out.raw[k * size:(k + 1) * size] for k in range(n)]

    def _clear(self) -> None:
        """The inputs are no longer needed."""
        for name in ("kind", "x", "y", "i", "j", "feed", "bytes"):
            setattr(self, name, array(getattr(self, name).typecode))
