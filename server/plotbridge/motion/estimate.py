"""The plot time estimate: the program's lines, collected as arrays and run through the
firmware's own motion code (library.py) in batches on a thread beside the caller, with
the host-side timing of timing.py. Each line costs the bytes the server sends for it:
its compact wire form (program/wire.py), counted batch by batch (native/wirebytes.c)
on a thread just ahead of the library's."""

from __future__ import annotations

import ctypes
import queue
import threading

import numpy as np

from ..importing.models import MachineProfile
from ..native.wirebytes import WireBytes
from ..program.wire import plain
from . import library as lib
from .library import ARC_CCW, ARC_CW, DWELL, LINE, OTHER, RAPID
from .timing import RX_SIZE

# WireBytes takes a motion line's kind as its G number
assert (RAPID, LINE, ARC_CW, ARC_CCW) == (0, 1, 2, 3)

TIMELINE_SAMPLES = 2000
# Lines the library runs at a time, while the next batch is collected: small (~5 ms of
# the library's CPU), so the estimate starts soon after the import does and ends soon
# after it (with 65,536 the import bench under load waited 50-280 ms for it after
# preview.json, one core idle; with 8,192 its thread cost ~0.015 s more CPU).
BATCH = 1 << 14
QUEUED = 8          # full batches waiting for the library at most (bounded memory)


def _config(p: MachineProfile, library: ctypes.CDLL) -> lib.Config:
    """The library's configuration for the profile (`library`: the build it runs in)."""
    c = lib.Config()
    c.steps_per_mm[:] = p.steps_per_mm
    c.max_rate[:] = p.max_rate
    c.accel[:] = p.accel
    c.junction_deviation = p.junction_deviation
    c.arc_tolerance = p.arc_tolerance
    c.pen_settle_s = p.pen_settle_s
    c.corexy = int(p.corexy)
    c.depth = p.planner_blocks or library.motion_plan_size()
    c.byte_s = 10.0 / p.baud if p.baud else 0.0
    c.line_cpu_s = p.plan_block_s
    c.rx_size = RX_SIZE
    return c


def _library(p: MachineProfile) -> ctypes.CDLL:
    """The library build that models the profile's board (its depth, its profile)."""
    return lib.load(lib.build_holding(p.build, p.planner_blocks))


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


class _Batch:
    """The library's inputs for up to BATCH lines (motion.c's motion_feed)."""

    def __init__(self) -> None:
        self.kind = np.empty(BATCH, np.uint8)
        self.x, self.y, self.i, self.j, self.feed = (np.empty(BATCH, np.float32)
                                                     for _ in range(5))
        self.bytes = np.empty(BATCH, np.uint16)
        self.keeps = np.empty(BATCH, np.uint8)    # a line that is no motion keeps the modes
        self.n = 0

    def count_bytes(self, wire: WireBytes) -> None:
        """Each line's bytes on the wire (a line that is no motion came with its own)."""
        n = self.n
        wire.count(self.kind[:n], self.x[:n], self.y[:n], self.i[:n], self.j[:n],
                   self.feed[:n], self.keeps[:n], self.bytes[:n])

    def args(self) -> tuple:
        """The arrays as motion_feed and motion_plan take them."""
        return (self.n, self.kind, self.x, self.y, self.i, self.j, self.feed, self.bytes)


_ABORT = object()


class _Runner:
    """The library on a thread of its own, run through the batches put in `queue` in
    order, then None (the end: `time`) or _ABORT, each batch's wire bytes counted first
    on a thread before it. The library's thread holds its lock from the first batch to
    the end (the firmware code keeps its state in globals)."""

    def __init__(self, profile: MachineProfile) -> None:
        self.queue: queue.Queue = queue.Queue(QUEUED)
        self._counted: queue.Queue = queue.Queue(2)     # batches with their wire bytes
        self.acks: list[np.ndarray] = []
        self.time = 0.0
        self.error: BaseException | None = None
        wire = WireBytes(profile.steps_per_mm, profile.line_numbers)
        self.counter = threading.Thread(target=self._count, args=(wire,), daemon=True,
                                        name="estimate-wire")
        self.thread = threading.Thread(target=self._work, args=(profile,), daemon=True,
                                       name="estimate")
        self.counter.start()
        self.thread.start()

    def _count(self, wire: WireBytes) -> None:
        """Each batch's bytes on the wire, a stage before the library (its own thread:
        the two run side by side), everything passed on in order, to the end."""
        while True:
            item = self.queue.get()
            if isinstance(item, _Batch) and self.error is None:
                try:
                    item.count_bytes(wire)
                except BaseException as e:     # given to the caller by Estimator.wait
                    self.error = e
            self._counted.put(item)
            if not isinstance(item, _Batch):
                return

    def _work(self, profile: MachineProfile) -> None:
        item: object = self
        try:
            library = _library(profile)
            config = _config(profile, library)
            with lib.run_lock:
                library.motion_configure(ctypes.byref(config))
                while isinstance(item := self._counted.get(), _Batch):
                    if self.error is not None:
                        continue    # the counting failed: the rest only drains
                    ack = np.empty(item.n)
                    library.motion_feed(*item.args(), ack)
                    self.acks.append(ack)
                if item is None and self.error is None:
                    self.time = library.motion_end()
        except BaseException as e:     # given to the caller by Estimator.wait
            self.error = e
            while item is not None and item is not _ABORT:   # the caller goes on putting
                item = self._counted.get()


class Estimator:
    """Feed it the program line by line (`receive`, then what the line does; runs of
    lines at once with `moves`); after `flush`, `time` is the estimate and `timeline()`
    the progress samples. The start is (0, 0) with the pen up, as the firmware after
    homing. The library runs on a thread of its own, given each batch of BATCH lines as
    it fills while the caller goes on (ctypes lets go of the GIL), the last one at
    `end`; `end` then `wait` (what `flush` does) let the caller work while the last
    batch runs; `close` drops a program not to be finished."""

    def __init__(self, profile: MachineProfile, start: tuple[float, float] = (0.0, 0.0)):
        if start != (0.0, 0.0):
            raise ValueError("the estimate starts at (0, 0)")
        self.profile = profile
        self._batch = _Batch()
        self._runner: _Runner | None = None
        self.ack = np.empty(0)
        self.time = 0.0

    def _send(self) -> _Batch:
        """The full batch goes to the library; returns the next one."""
        if self._runner is None:
            self._runner = _Runner(self.profile)
        self._runner.queue.put(self._batch)
        self._batch = _Batch()
        return self._batch

    def receive(self, text: str) -> None:
        """The next program line (`move`, `arc` or `stop` then say what it does)."""
        b = self._batch if self._batch.n < BATCH else self._send()
        k = b.n
        b.kind[k] = OTHER
        nbytes, b.keeps[k] = plain(text)
        b.bytes[k] = min(nbytes, 65535)
        b.x[k] = b.y[k] = b.i[k] = b.j[k] = b.feed[k] = 0.0
        b.n = k + 1

    def _set(self, kind: int, x: float, y: float, feed: float, i: float = 0.0,
             j: float = 0.0) -> None:
        b = self._batch
        k = b.n - 1
        b.kind[k] = kind
        b.x[k] = x
        b.y[k] = y
        b.feed[k] = feed
        b.i[k] = i
        b.j[k] = j

    def move(self, line: int, x: float, y: float, feed: float | None) -> None:
        self._set(RAPID if feed is None else LINE, x, y, feed or 0.0)

    def moves(self, kind: np.ndarray, x: np.ndarray, y: np.ndarray, feed: np.ndarray,
              nbytes: np.ndarray) -> None:
        """`receive` and `move` for each of a run of lines, given as the library takes
        them: kind (uint8, RAPID or LINE; DWELL for a pen change), x, y, feed (float32, 0
        for rapids), bytes (uint16; a motion line's are counted on the wire instead)."""
        done, n = 0, len(kind)
        while done < n:
            b = self._batch if self._batch.n < BATCH else self._send()
            k = min(BATCH - b.n, n - done)
            to, src = slice(b.n, b.n + k), slice(done, done + k)
            b.kind[to] = kind[src]
            b.bytes[to] = nbytes[src]
            b.keeps[to] = 1     # the pen changes (M3, M5)
            b.x[to] = x[src]
            b.y[to] = y[src]
            b.feed[to] = feed[src]
            b.i[to] = 0.0
            b.j[to] = 0.0
            b.n += k
            done += k

    def arc(self, line: int, x: float, y: float, i: float, j: float, feed: float,
            cw: bool) -> None:
        self._set(ARC_CW if cw else ARC_CCW, x, y, feed, i, j)

    def stop(self, line: int, seconds: float) -> None:
        """Wait for motion to end, then hold still for `seconds` (pen settle, dwell)."""
        self._set(DWELL, seconds, 0.0, 0.0)

    def end(self) -> None:
        """The program is complete: its last lines go to the library (`wait` for the
        result)."""
        if self._runner is None and not self._batch.n:
            return      # nothing to run
        if self._batch.n:
            self._send()
        assert self._runner is not None
        self._runner.queue.put(None)

    def wait(self) -> None:
        """The estimate of the program ended with `end`: `time`, `ack`."""
        runner, self._runner = self._runner, None
        self._batch = _Batch()
        if runner is None:
            self.time, self.ack = 0.0, np.empty(0)
            return
        runner.thread.join()
        if runner.error is not None:
            raise runner.error
        self.time = runner.time
        self.ack = np.concatenate(runner.acks) if runner.acks else np.empty(0)

    def flush(self) -> None:
        self.end()
        self.wait()

    def timeline(self, line: int, total: float) -> list[tuple[int, float]]:
        """After `wait`: the progress samples of the program, `line` lines long."""
        return thin_timeline(self.ack, line, total)

    def close(self) -> None:
        """Drops the program (after a failed import); nothing runs on."""
        runner, self._runner = self._runner, None
        self._batch = _Batch()
        if runner is not None:
            runner.queue.put(_ABORT)
            runner.thread.join()

    def planned_blocks(self) -> list[bytes]:
        """Plans the lines received so far (at most BATCH) with nothing executing and
        returns the queued planner blocks, oldest first, as the firmware lays them out in
        RAM (the differential test compares them with the board's)."""
        if self._runner is not None:
            raise ValueError(f"planned_blocks plans at most {BATCH} lines")
        library = _library(self.profile)
        size = library.motion_block_size()
        out = ctypes.create_string_buffer(size * 256)
        with lib.run_lock:
            library.motion_configure(ctypes.byref(_config(self.profile, library)))
            library.motion_plan(*self._batch.args()[:7])
            n = library.motion_blocks(out, 256)
        self._batch = _Batch()
        return [out.raw[k * size:(k + 1) * size] for k in range(n)]
