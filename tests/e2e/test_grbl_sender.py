"""A third-party GRBL sender drives the real firmware in the virtual plotter.

The sender is grbl-streamer 2.0.2 from PyPI (pinned in requirements-dev.txt,
installed by `make setup-test`): it connects (soft reset, waits for the
banner), reads the settings (`$$`), streams a job with arcs, holds and resumes,
overrides the feed its own way (rewriting F words) and resets. The plotted
trace must match the program within one step.
"""

from __future__ import annotations

import itertools
import math
import queue
import time
from typing import Any

import pytest
from grbl_streamer import GrblStreamer

from tests.fixtures.grbl import clean

pytestmark = pytest.mark.e2e

STEP = 1 / 80
ONE_STEP = math.hypot(STEP, STEP)  # within one step on each axis
PROGRAM = [
    "G21 G90", "G0 X20 Y20", "M3", "G1 X60 Y20 F3000",
    "G3 X60 Y60 I0 J20",        # half circle around (60, 40), r 20, counter-clockwise
    "G1 X20 Y60", "G3 X20 Y20 I0 J-20",  # back down around (20, 40), on the left
    "M5", "G0 X0 Y0",
]


def on_path(p: tuple[float, float]) -> float:
    """Distance from p to the program's pen-down path."""
    x, y = p
    d = []
    d.append(abs(y - 20) if 20 <= x <= 60 else math.inf)
    d.append(abs(y - 60) if 20 <= x <= 60 else math.inf)
    if x >= 60:
        d.append(abs(math.dist((x, y), (60, 40)) - 20))
    if x <= 20:
        d.append(abs(math.dist((x, y), (20, 40)) - 20))
    d.append(min(math.dist(p, c) for c in [(20, 20), (60, 20), (60, 60), (20, 60)]))
    return min(d)


def test_grbl_streamer_plots_holds_overrides_and_resets(plotter) -> None:
    events: queue.Queue[tuple[str, tuple[Any, ...]]] = queue.Queue()
    state = {"mode": ""}
    read: list[str] = []

    def callback(event: str, *data: Any) -> None:
        if event == "on_stateupdate":
            state["mode"] = data[0]
        if event == "on_read":
            read.append(str(data[0]).strip())
        events.put((event, data))

    def wait_event(name: str, timeout: float = 60) -> tuple[Any, ...]:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                event, data = events.get(timeout=0.2)
            except queue.Empty:
                continue
            if event == name:
                return data
        raise AssertionError(f"no {name} within {timeout} s")

    def wait_mode(prefix: str, timeout: float = 60) -> None:
        deadline = time.monotonic() + timeout
        while not state["mode"].startswith(prefix):
            assert time.monotonic() < deadline, f"state {state['mode']!r}, want {prefix}"
            time.sleep(0.05)

    sender = GrblStreamer(callback)
    sender.setup_logging()
    sender.cnect(plotter.port, 115200)
    try:
        wait_event("on_boot", 20)
        sender.killalarm()
        sender.poll_start()
        wait_mode("Idle", 20)
        # grbl-streamer parses only GRBL 0.9's "$N=val (comment)" settings lines (stock
        # GRBL 1.1 prints none), so what it read is checked line by line instead
        sender.request_settings()
        deadline = time.monotonic() + 20
        while "$132=10.000" not in read and time.monotonic() < deadline:
            time.sleep(0.05)
        assert "$100=80.000" in read and "$132=10.000" in read, read
        sender.set_feed_override(True)
        sender.request_feed(2400)  # the sender rewrites F3000 to F2400
        sender.write(PROGRAM)
        sender.job_run()
        plotter.wait_trace(lambda t: t["pen"] == "down" and t["position"]["x"] > 30, 60)
        sender.hold()
        wait_mode("Hold:0", 30)
        held = plotter.wait_trace(lambda t: t["pen"] == "up", 10)  # pen-safe hold
        time.sleep(0.3)
        assert plotter.trace()["position"] == held["position"]
        sender.resume()
        wait_event("on_job_completed", 120)
        wait_mode("Idle", 60)
        trace = plotter.trace()
        clean(trace)
        assert trace["pen"] == "up" and trace["position"] == {"x": 0.0, "y": 0.0}
        points = [(p[0], p[1]) for s in trace["strokes"] for p in s]
        assert len(trace["strokes"]) == 2  # split once by the hold, nothing else drawn
        first, second = trace["strokes"]
        assert math.dist(first[-1][:2], second[0][:2]) <= ONE_STEP  # lowered where it was lifted
        assert max(on_path(p) for p in points) <= ONE_STEP
        assert math.dist(points[0], (20, 20)) <= ONE_STEP
        assert math.dist(points[-1], (20, 20)) <= ONE_STEP
        # the plotted length is the program's: two 40 mm lines and two half circles
        drawn = sum(math.dist(a, b) for s in trace["strokes"]
                    for a, b in itertools.pairwise(s))
        assert drawn == pytest.approx(80 + 2 * math.pi * 20, rel=0.01)
        sender.softreset()
        wait_event("on_boot", 20)
    finally:
        sender.disconnect()


def test_forced_stop_hold_then_reset_leaves_the_board_idle(plotter) -> None:
    """CNCjs's "forced stop" (and grbl-streamer's abort): a feed hold, then a soft
    reset once the carriage has stopped. Stock GRBL 1.1h alarms only when a reset
    interrupts motion, so the board comes back Idle, unlocked, where it stopped."""
    read: list[str] = []
    events: queue.Queue[str] = queue.Queue()
    state = {"mode": ""}

    def callback(event: str, *data: Any) -> None:
        if event == "on_stateupdate":
            state["mode"] = data[0]
        if event == "on_read":
            read.append(str(data[0]).strip())
        events.put(event)

    def wait_until(done, what: str, timeout: float = 30) -> None:
        deadline = time.monotonic() + timeout
        while not done():
            assert time.monotonic() < deadline, f"{what}: state {state['mode']!r}, read {read[-5:]}"
            time.sleep(0.05)

    sender = GrblStreamer(callback)
    sender.setup_logging()
    sender.cnect(plotter.port, 115200)
    try:
        wait_until(lambda: "on_boot" in list(events.queue), "banner", 20)
        sender.killalarm()
        sender.poll_start()
        wait_until(lambda: state["mode"].startswith("Idle"), "Idle", 20)
        sender.write(["G1 X100 F600"])
        sender.job_run()
        plotter.wait_trace(lambda t: t["position"]["x"] > 5, 30)
        sender.hold()
        wait_until(lambda: state["mode"].startswith("Hold:0"), "Hold:0")
        held = plotter.trace()["steps"]
        booted = len([line for line in read if line.startswith("Grbl 1.1h")])
        sender.softreset()
        wait_until(lambda: len([line for line in read if line.startswith("Grbl 1.1h")]) > booted,
                   "banner after the reset", 20)
        wait_until(lambda: state["mode"].startswith("Idle"), "Idle after the reset", 20)
        assert not any(line.startswith("ALARM") for line in read), read
        assert plotter.trace()["steps"] == held  # the position kept: motion had stopped
    finally:
        sender.disconnect()
