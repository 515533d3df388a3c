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

from tests.fixtures.grbl import Grbl, unlocked
from tests.fixtures.plotsim import Plotter, PlotterFactory
from tests.fixtures.waits import wait_until

pytestmark = pytest.mark.e2e


def connected(plotter: Plotter) -> Grbl:
    """A client after a soft reset (the banner went out before it connected)."""
    grbl = Grbl(plotter.port)
    grbl.reset(10)
    return grbl


def pins(grbl: Grbl) -> str:
    match = re.search(r"\|Pn:([A-Z]+)", grbl.status())
    return match.group(1) if match else ""


def test_banner_status_and_pen_servo(plotter: Plotter) -> None:
    grbl = connected(plotter)
    assert re.match(r"<\w+\|MPos:0\.000,0\.000,0\.000\|", grbl.status())
    trace = plotter.trace()
    assert trace["pen"] == "up"
    assert trace["pen_us"] == pytest.approx(1000, abs=10)


def test_buttons_show_in_pn(plotter: Plotter) -> None:
    grbl = unlocked(connected(plotter))
    assert pins(grbl) == ""
    for name, letter in (("pause", "H"), ("resume", "S"), ("estop", "R")):
        plotter.press(name)
        assert letter in pins(grbl)
        plotter.release(name)
        assert letter not in pins(grbl)


def test_limit_switch_shows_in_pn(plotter_factory: PlotterFactory) -> None:
    p = plotter_factory(start=(-1, 5))  # carriage past the X switch
    grbl = connected(p)
    assert p.trace()["limits"] == {"x": True, "y": False}
    assert "X" in pins(grbl)


def test_drawing_shows_in_the_trace(plotter: Plotter) -> None:
    grbl = unlocked(connected(plotter))
    for line in ["G21 G90", "G0 X10 Y10", "M3", "G1 X30 Y10 F3000", "G1 X30 Y25", "M5"]:
        grbl.ok(line)
    assert grbl.wait_state("Idle").startswith("<Idle|MPos:30.000,25.000,")
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
    grbl = unlocked(connected(plotter))
    eeprom = plotter.eeprom_path
    saved = eeprom.read_bytes() if eeprom.exists() else b""
    grbl.ok("$110=4321")
    # plotsim writes a changed EEPROM to its file within 0.1 s, as a power cut would keep it
    wait_until(eeprom.read_bytes, lambda now: now != saved, 15, "the EEPROM file",
               errors=(FileNotFoundError,))
    grbl.close()
    plotter.restart()
    grbl = connected(plotter)
    assert "$110=4321.000" in grbl.ok("$$")


def test_homing_ends_pull_off_from_the_switches(plotter_factory: PlotterFactory) -> None:
    p = plotter_factory(start=(40, 30))
    grbl = connected(p)
    grbl.ok("$H")
    status = grbl.wait_state("Idle", 60)
    assert status.startswith("<Idle|MPos:1.000,1.000,")  # $27 pull-off 1 mm
    trace = p.trace()
    # the switch trips one step past 0, so machine 0 is one step below physical 0
    for axis in "xy":
        assert trace["position"][axis] == pytest.approx(1.0, abs=2 / 80)
    assert trace["limits"] == {"x": False, "y": False}


def test_corexy_drawing_matches(plotter_factory: PlotterFactory) -> None:
    p = plotter_factory(args=["--corexy"])
    grbl = unlocked(connected(p))
    grbl.ok("$63=1")  # the firmware's kinematics setting, as the machine is built
    for line in ["G21 G90", "G0 X10 Y10", "M3", "G1 X30 Y10 F3000", "G1 X30 Y25", "M5"]:
        grbl.ok(line)
    grbl.wait_state("Idle")
    trace = p.trace()
    strokes = [[(round(x, 3), round(y, 3)) for x, y, _t in s] for s in trace["strokes"]]
    assert strokes == [[(10, 10), (30, 10), (30, 25)]]
    assert sum(trace["violations"].values()) == 0


def test_stop_button_halts_the_steppers(plotter: Plotter) -> None:
    grbl = unlocked(connected(plotter))
    grbl.ok("G1 X290 F3000")
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
