"""The real firmware in plotsim: the virtual plotter as the server sees it.

Protocol facts from DESIGN.md / INTERNALS.md (GRBL 1.1): banner on reset,
`Pn:` lists active inputs (X, Y limits; R stop, H pause, S resume), `$`
settings live in EEPROM, homing goes to the minimum and ends `pull-off` mm
from the switch.
"""

from __future__ import annotations

import re
import time

import pytest
import serial

from tests.fixtures.plotsim import Plotter, PlotterFactory

pytestmark = pytest.mark.e2e

BANNER = "Grbl 1.1h ['$' for help]"


class Grbl:
    """A minimal line-at-a-time GRBL client over the plotter's pty."""

    def __init__(self, plotter: Plotter) -> None:
        self.port = serial.Serial(plotter.port, 115200, timeout=5)
        self.port.write(b"\x18")  # soft reset: a banner we are sure to see
        self.wait_for(lambda line: line == BANNER)

    def readline(self) -> str:
        raw = self.port.readline()
        if not raw:
            raise AssertionError("no line from the firmware within 5 s")
        return raw.decode(errors="replace").strip()

    def wait_for(self, pred, limit: int = 50) -> str:
        for _ in range(limit):
            line = self.readline()
            if pred(line):
                return line
        raise AssertionError("expected line never came")

    def send(self, line: str) -> list[str]:
        """Sends one line; returns the lines up to and including its ok."""
        self.port.write(line.encode() + b"\n")
        lines = []
        while True:
            answer = self.readline()
            lines.append(answer)
            if answer == "ok" or answer.startswith("error:"):
                assert answer == "ok", f"{line!r} -> {lines}"
                return lines

    def status(self) -> str:
        self.port.write(b"?")
        return self.wait_for(lambda line: line.startswith("<"))

    def pins(self) -> str:
        match = re.search(r"\|Pn:([A-Z]+)", self.status())
        return match.group(1) if match else ""

    def wait_idle(self, timeout: float = 20) -> str:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            status = self.status()
            if status.startswith("<Idle"):
                return status
            time.sleep(0.02)
        raise AssertionError(f"not idle within {timeout} s: {status}")


def unlocked(plotter: Plotter) -> Grbl:
    grbl = Grbl(plotter)
    grbl.send("$X")
    return grbl


def test_banner_status_and_pen_servo(plotter: Plotter) -> None:
    grbl = Grbl(plotter)
    assert re.match(r"<\w+\|MPos:0\.000,0\.000,0\.000\|", grbl.status())
    trace = plotter.trace()
    assert trace["pen"] == "up"
    assert trace["pen_us"] == pytest.approx(1000, abs=10)


def test_buttons_show_in_pn(plotter: Plotter) -> None:
    grbl = unlocked(plotter)
    assert grbl.pins() == ""
    for name, letter in (("pause", "H"), ("resume", "S"), ("estop", "R")):
        plotter.press(name)
        assert letter in grbl.pins()
        plotter.release(name)
        assert letter not in grbl.pins()


def test_limit_switch_shows_in_pn(plotter_factory: PlotterFactory) -> None:
    p = plotter_factory(start=(-1, 5))  # carriage past the X switch
    grbl = Grbl(p)
    assert p.trace()["limits"] == {"x": True, "y": False}
    assert "X" in grbl.pins()


def test_drawing_shows_in_the_trace(plotter: Plotter) -> None:
    grbl = unlocked(plotter)
    for line in ["G21 G90", "G0 X10 Y10", "M3", "G1 X30 Y10 F3000", "G1 X30 Y25", "M5"]:
        grbl.send(line)
    assert grbl.wait_idle().startswith("<Idle|MPos:30.000,25.000,")
    trace = plotter.trace()
    strokes = [[(round(x, 3), round(y, 3)) for x, y, _t in s] for s in trace["strokes"]]
    assert strokes == [[(10, 10), (30, 10), (30, 25)]]
    assert trace["position"] == {"x": 30.0, "y": 25.0}
    assert trace["pen"] == "up"
    assert trace["pen_lifts"] == 1
    assert trace["violations"] == {
        "short_pulse": 0, "dir_setup": 0, "step_while_disabled": 0, "overspeed": 0,
    }  # fmt: skip
    assert trace["min_pulse_us"] >= 1


def test_settings_persist_across_restart(plotter: Plotter) -> None:
    grbl = unlocked(plotter)
    grbl.send("$110=4321")
    grbl.port.close()
    time.sleep(0.3)  # plotsim saves the EEPROM within 0.1 s of a change
    plotter.restart()
    grbl = Grbl(plotter)
    assert "$110=4321.000" in grbl.send("$$")


def test_homing_ends_pull_off_from_the_switches(plotter_factory: PlotterFactory) -> None:
    p = plotter_factory(start=(40, 30))
    grbl = Grbl(p)
    grbl.send("$H")
    status = grbl.wait_idle(timeout=60)
    assert status.startswith("<Idle|MPos:1.000,1.000,")  # $27 pull-off 1 mm
    trace = p.trace()
    # the switch trips one step past 0, so machine 0 is one step below physical 0
    for axis in "xy":
        assert trace["position"][axis] == pytest.approx(1.0, abs=2 / 80)
    assert trace["limits"] == {"x": False, "y": False}


def test_corexy_drawing_matches(plotter_factory: PlotterFactory) -> None:
    p = plotter_factory(args=["--corexy"])
    grbl = unlocked(p)
    grbl.send("$63=1")  # the firmware's kinematics setting, as the machine is built
    for line in ["G21 G90", "G0 X10 Y10", "M3", "G1 X30 Y10 F3000", "G1 X30 Y25", "M5"]:
        grbl.send(line)
    grbl.wait_idle()
    trace = p.trace()
    strokes = [[(round(x, 3), round(y, 3)) for x, y, _t in s] for s in trace["strokes"]]
    assert strokes == [[(10, 10), (30, 10), (30, 25)]]
    assert sum(trace["violations"].values()) == 0


def test_stop_button_halts_the_steppers(plotter: Plotter) -> None:
    grbl = unlocked(plotter)
    grbl.send("G1 X290 F3000")
    plotter.wait_trace(lambda t: t["position"]["x"] > 5)
    plotter.press("estop")
    pressed = time.monotonic()
    time.sleep(0.3)
    first = plotter.trace()
    time.sleep(0.3)
    later = plotter.trace()
    assert later["position"] == first["position"]  # nothing moves any more
    assert first["position"]["x"] < 280
    # the last step came right after the press (the model runs several times
    # faster than real time, so this bounds the reaction in simulated time too)
    assert first["last_step_monotonic"] < pressed + 0.2
    assert grbl.status().startswith("<Alarm")
    plotter.release("estop")
