"""plotsim's machine model alone (firmware/sim/src/machine.c), fed with
scripted pin edges through firmware/sim/build/model_replay: decoding,
kinematics, limit switches, driver checks and stroke simplification."""

from __future__ import annotations

import itertools
import json
import math
import subprocess
from collections.abc import Sequence
from typing import Any

import pytest

from tests.fixtures.plotsim import SimBuild

CYCLES_PER_US = 16
SPM = 80  # steps per mm (default)


class Edges:
    """Builds a pin edge script: 'CYCLE PIN LEVEL' lines at 16 MHz."""

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.cycle = 0
        self.dirs = {"x": 0, "y": 0}

    def emit(self, pin: str, level: int) -> None:
        self.lines.append(f"{self.cycle} {pin} {level}")

    def wait_us(self, us: float) -> None:
        self.cycle += round(us * CYCLES_PER_US)

    def servo(self, width_us: float) -> Edges:
        self.emit("servo", 1)
        self.wait_us(width_us)
        self.emit("servo", 0)
        self.wait_us(20000 - width_us)
        return self

    def enable(self, on: bool) -> Edges:
        self.emit("en", 0 if on else 1)
        return self

    def tick(self, steps: dict[str, int], high_us: float = 4, period_us: float = 100) -> None:
        """One step period: direction first (1 us setup), then the pulses together."""
        changed = False
        for axis, sign in steps.items():
            level = 0 if sign > 0 else 1  # GRBL: direction pin LOW = positive
            if self.dirs[axis] != level:
                self.dirs[axis] = level
                self.emit("d" + axis, level)
                changed = True
        if changed:
            self.wait_us(1)
        for axis in steps:
            self.emit("s" + axis, 1)
        self.wait_us(high_us)
        for axis in steps:
            self.emit("s" + axis, 0)
        self.wait_us(period_us - high_us)

    def motors(self, da: int, db: int, **kw: float) -> Edges:
        """A straight move of the two motors, Bresenham style, as a firmware steps it."""
        n = max(abs(da), abs(db))
        err_a = err_b = 0
        for _ in range(n):
            err_a += abs(da)
            err_b += abs(db)
            steps = {}
            if err_a >= n:
                err_a -= n
                steps["x"] = 1 if da > 0 else -1
            if err_b >= n:
                err_b -= n
                steps["y"] = 1 if db > 0 else -1
            self.tick(steps, **kw)
        return self

    def move(self, dx: int, dy: int, corexy: bool = False, **kw: float) -> Edges:
        """A move by (dx, dy) steps in x and y."""
        return self.motors(dx + dy, dx - dy, **kw) if corexy else self.motors(dx, dy, **kw)


def replay(build: SimBuild, edges: Edges, args: Sequence[str] = ()) -> dict[str, Any]:
    result = subprocess.run(
        [str(build.model_replay), *args, "-"],
        input="\n".join(edges.lines) + "\n",
        capture_output=True, text=True, timeout=30, check=True,
    )  # fmt: skip
    return json.loads(result.stdout)


def xy(trace: dict[str, Any], i: int = 0) -> list[tuple[float, float]]:
    return [(round(p[0], 4), round(p[1], 4)) for p in trace["strokes"][i]]


@pytest.mark.parametrize("d", [(800, 300), (800, 800), (123, 457), (-500, 211), (7, -1600)])
def test_a_straight_line_is_two_points(sim_build: SimBuild, d: tuple[int, int]) -> None:
    edges = Edges().servo(2000).move(*d).servo(1000)
    trace = replay(sim_build, edges, ["--start", "100,100"])
    end = (100 + d[0] / SPM, 100 + d[1] / SPM)
    assert xy(trace) == [(100.0, 100.0), (round(end[0], 4), round(end[1], 4))]
    assert trace["draw_mm"] == pytest.approx(math.hypot(*d) / SPM, abs=1e-3)
    assert trace["pen_lifts"] == 1


@pytest.mark.parametrize("d", [(800, 0), (0, 800), (800, 400), (-300, 555)])
def test_corexy_line_is_two_points(sim_build: SimBuild, d: tuple[int, int]) -> None:
    edges = Edges().servo(2000).move(*d, corexy=True).servo(1000)
    trace = replay(sim_build, edges, ["--corexy", "--start", "100,100"])
    end = (round(100 + d[0] / SPM, 4), round(100 + d[1] / SPM, 4))
    assert xy(trace) == [(100.0, 100.0), end]
    assert trace["position"] == {"x": end[0], "y": end[1]}


def test_square_keeps_exact_corners(sim_build: SimBuild) -> None:
    edges = Edges().servo(2000)
    for d in [(400, 0), (0, 400), (-400, 0), (0, -400)]:
        edges.move(*d)
    trace = replay(sim_build, edges.servo(1000), ["--start", "10,10"])
    assert xy(trace) == [(10, 10), (15, 10), (15, 15), (10, 15), (10, 10)]
    assert trace["draw_mm"] == pytest.approx(20)


def test_going_back_along_a_line_keeps_the_turn(sim_build: SimBuild) -> None:
    edges = Edges().servo(2000).move(800, 0).move(-400, 0).servo(1000)
    trace = replay(sim_build, edges, ["--start", "10,10"])
    assert xy(trace) == [(10, 10), (20, 10), (15, 10)]


def test_circle_vertices_stay_on_the_circle(sim_build: SimBuild) -> None:
    r = 20 * SPM
    pts = [
        (round(r * math.cos(2 * math.pi * k / 72)), round(r * math.sin(2 * math.pi * k / 72)))
        for k in range(73)
    ]
    edges = Edges().servo(2000)
    for (x0, y0), (x1, y1) in itertools.pairwise(pts):
        edges.move(x1 - x0, y1 - y0)
    trace = replay(sim_build, edges.servo(1000), ["--start", "150,110"])
    stroke = trace["strokes"][0]
    assert 30 <= len(stroke) <= 73
    for x, y, _t in stroke:
        assert math.hypot(x - 130, y - 110) == pytest.approx(20, abs=2 / SPM)
    assert trace["draw_mm"] == pytest.approx(2 * math.pi * 20, rel=0.01)


def test_pen_up_moves_are_travel(sim_build: SimBuild) -> None:
    edges = Edges().move(800, 0).servo(2000).move(0, 400).servo(1000).move(-800, 0)
    trace = replay(sim_build, edges, ["--start", "10,10"])
    assert xy(trace) == [(20, 10), (20, 15)]
    assert trace["travel_mm"] == pytest.approx(20)
    assert trace["draw_mm"] == pytest.approx(5)
    assert trace["position"] == {"x": 10.0, "y": 15.0}


def test_timestamps_are_simulated_seconds(sim_build: SimBuild) -> None:
    edges = Edges().servo(2000).move(1000, 0, period_us=100).servo(1000)
    trace = replay(sim_build, edges, ["--start", "10,10"])
    (_, _, t0), (_, _, t1) = trace["strokes"][0]
    assert t1 - t0 == pytest.approx(0.018 + 999 * 100e-6 + 4e-6, abs=2e-5)
    assert trace["max_step_rate"]["x"] == pytest.approx(10000, rel=1e-3)


@pytest.mark.parametrize(
    ("width", "args", "pen"),
    [
        (1400, [], "up"),
        (1600, [], "down"),
        (1600, ["--pen-up-us", "2000", "--pen-down-us", "1000"], "up"),
        (50, [], "up"),  # a glitch, not a servo pulse: ignored
    ],
)
def test_pen_is_the_nearer_pulse_width(
    sim_build: SimBuild, width: float, args: list[str], pen: str
) -> None:
    trace = replay(sim_build, Edges().servo(width), args)
    assert trace["pen"] == pen
    assert trace["pen_us"] == (0 if width < 100 else pytest.approx(width))


def test_limit_switches_close_outside_the_area(sim_build: SimBuild) -> None:
    at_zero = replay(sim_build, Edges())
    assert at_zero["limits"] == {"x": False, "y": False}
    left = replay(sim_build, Edges().move(-1, 0))
    assert left["limits"] == {"x": True, "y": False}
    back = replay(sim_build, Edges().move(-1, -1).move(1, 1))
    assert back["limits"] == {"x": False, "y": False}
    right = replay(sim_build, Edges().move(1, 1), ["--start", "300,220"])
    assert right["limits"] == {"x": True, "y": True}
    on_edge = replay(sim_build, Edges().move(10, 10), ["--start", "299.875,219.875"])
    assert on_edge["limits"] == {"x": False, "y": False}


def test_corexy_limits_use_cartesian_position(sim_build: SimBuild) -> None:
    # +x in CoreXY steps both motors; the half-way point (one motor stepped)
    # is x = 0.5 step, y = 0.5 step: inside
    trace = replay(sim_build, Edges().move(-1, 0, corexy=True), ["--corexy", "--start", "0,5"])
    assert trace["limits"] == {"x": True, "y": False}
    assert trace["position"] == {"x": -0.0125, "y": 5.0}


def test_driver_checks(sim_build: SimBuild) -> None:
    edges = Edges()
    edges.tick({"x": 1}, high_us=0.5)  # short high
    edges.wait_us(100)
    edges.emit("sx", 1)  # short low: 0.5 us after the previous fall
    edges.wait_us(0.5)
    edges.emit("sx", 0)
    edges.wait_us(0.9)
    edges.emit("sx", 1)
    edges.wait_us(5)
    edges.emit("sx", 0)
    edges.wait_us(100)
    edges.emit("dx", 1)  # 125 ns direction setup
    edges.cycle += 2
    edges.emit("sx", 1)
    edges.wait_us(5)
    edges.emit("sx", 0)
    edges.wait_us(100)
    edges.emit("dx", 0)  # 250 ns: enough
    edges.cycle += 4
    edges.emit("sx", 1)
    edges.wait_us(5)
    edges.emit("sx", 0)
    trace = replay(sim_build, edges)
    assert trace["violations"] == {
        "short_pulse": 3, "dir_setup": 1, "step_while_disabled": 0, "overspeed": 1,
    }  # fmt: skip
    assert trace["min_pulse_us"] == 0.5


def test_steps_while_disabled_do_not_move(sim_build: SimBuild) -> None:
    edges = Edges().move(10, 0).enable(False).move(10, 5).enable(True).move(1, 0)
    trace = replay(sim_build, edges)
    assert trace["violations"]["step_while_disabled"] == 15
    assert trace["steps"] == {"x": 11, "y": 0}
    assert trace["pulses"] == {"x": 21, "y": 5}


def test_overspeed_is_counted_per_fast_step(sim_build: SimBuild) -> None:
    edges = Edges().move(100, 0, period_us=50).move(100, 0, period_us=20)
    trace = replay(sim_build, edges, ["--max-step-rate", "30000"])
    # 50 us = 20 kHz, 20 us = 50 kHz: 99 intervals of 20 us
    assert trace["violations"]["overspeed"] == 99
    assert trace["max_step_rate"]["x"] == pytest.approx(50000)


def test_bad_event_lines_are_rejected(sim_build: SimBuild) -> None:
    result = subprocess.run(
        [str(sim_build.model_replay), "-"], input="0 sx 1\n5 warp 1\n",
        capture_output=True, text=True, timeout=10,
    )  # fmt: skip
    assert result.returncode == 2
    assert "line 2" in result.stderr
