"""The real firmware in the virtual plotter, spoken to as GRBL 1.1 over its pty.

Each test drives plotsim's serial port with pyserial and compares what the
pen drew (plotsim's trace, decoded from the step/dir/servo pins) with what
was commanded.
"""

from __future__ import annotations

import itertools
import math
import random
import time

import pytest
from plotbridge.motion import library

from tests.fixtures.grbl import Grbl, clean, mpos, no_false_acks, unlocked

pytestmark = pytest.mark.e2e

STEP_MM = 1 / 80
TOL = 0.02  # mm: a step and a bit


def stroke_points(trace: dict) -> list[list[tuple[float, float]]]:
    return [[(p[0], p[1]) for p in s] for s in trace["strokes"]]


def straight_stroke(plotter, start: tuple[float, float], end: tuple[float, float]) -> dict:
    """The trace holds one pen-down stroke, straight from `start` to `end`; returns the trace.
    plotsim keeps a vertex only where the path bends by more than a step, so a staircase
    (X then Y) or a kink would show up as extra vertices."""
    trace = plotter.trace()
    clean(trace)
    (stroke,) = stroke_points(trace)
    assert len(stroke) == 2, stroke
    assert math.dist(stroke[0], start) < TOL and math.dist(stroke[1], end) < TOL, stroke
    return trace


def dist_to_segment(p, a, b) -> float:
    ax, ay = a
    bx, by = b
    px, py = p
    dx, dy = bx - ax, by - ay
    L2 = dx * dx + dy * dy
    t = 0.0 if L2 == 0 else max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / L2))
    return math.hypot(px - ax - t * dx, py - ay - t * dy)


def test_boot_banner_status_and_defaults(grbl: Grbl) -> None:
    status = grbl.status()
    depth = library.planner_depth()  # the planner ring the build holds (config.h PLAN_SIZE - 1)
    assert status.startswith(f"<Alarm|MPos:0.000,0.000,0.000|Bf:{depth},128|FS:0,0"), status
    lines = grbl.ok("$$")
    settings = dict(line[1:].split("=") for line in lines[:-1])
    assert settings["100"] == "80.000" and settings["110"] == "6000.000"
    assert settings["130"] == "300.000" and settings["131"] == "220.000"
    assert settings["22"] == "1" and settings["62"] == "150" and settings["11"] == "0.020"
    assert grbl.send("G0 X1")[-1] == "error:9"  # locked until $X or $H
    unlocked(grbl)
    assert grbl.status().startswith("<Idle|")


def test_square_is_drawn_exactly(plotter, grbl: Grbl) -> None:
    unlocked(grbl)
    for line in ["G21", "G90", "G0 X10 Y10", "M3", "G1 X60 Y10 F3000", "G1 X60 Y60",
                 "G1 X10 Y60", "G1 X10 Y10", "M5"]:
        grbl.ok(line)
    grbl.wait_state("Idle")
    trace = plotter.trace()
    clean(trace)
    strokes = stroke_points(trace)
    assert len(strokes) == 1, strokes
    corners = [(10, 10), (60, 10), (60, 60), (10, 60), (10, 10)]
    assert len(strokes[0]) == len(corners), strokes[0]
    for got, want in zip(strokes[0], corners, strict=True):
        assert math.dist(got, want) < TOL, (got, want)
    assert trace["pen"] == "up" and trace["pen_lifts"] >= 1


def test_diagonal_is_one_straight_stroke(plotter, grbl: Grbl) -> None:
    unlocked(grbl)
    for line in ["G0 X5 Y5", "M3", "G1 X205.3 Y77.7 F4000", "M5"]:
        grbl.ok(line)
    grbl.wait_state("Idle")
    trace = straight_stroke(plotter, (5, 5), (205.3, 77.7))
    assert mpos(grbl.status()) == (205.3, 77.7)
    assert trace["steps"] == {"x": round(205.3 * 80), "y": round(77.7 * 80)}


@pytest.mark.parametrize("how", ["g2", "g1"])
def test_circle(plotter, grbl: Grbl, how: str) -> None:
    unlocked(grbl)
    cx, cy, r = 100.0, 100.0, 30.0
    grbl.ok(f"G0 X{cx + r} Y{cy}")
    grbl.ok("M3")
    if how == "g2":
        grbl.ok(f"G2 X{cx + r} Y{cy} I{-r} J0 F3000")
    else:
        n = 180
        for k in range(1, n + 1):
            a = 2 * math.pi * k / n
            grbl.ok(f"G1 X{cx + r * math.cos(a):.3f} Y{cy + r * math.sin(a):.3f} F3000")
    grbl.ok("M5")
    grbl.wait_state("Idle")
    trace = plotter.trace()
    clean(trace)
    (stroke,) = stroke_points(trace)
    assert len(stroke) > 20
    for p in stroke:
        assert abs(math.dist(p, (cx, cy)) - r) < 0.05, p
    assert math.dist(stroke[0], (cx + r, cy)) < TOL and math.dist(stroke[-1], (cx + r, cy)) < TOL
    # the whole circumference is covered
    angles = sorted(math.atan2(p[1] - cy, p[0] - cx) for p in stroke)
    gaps = [b - a for a, b in itertools.pairwise(angles)]
    assert max(gaps) < 0.2
    assert abs(trace["draw_mm"] - 2 * math.pi * r) < 0.5


def test_pen_sequence_and_settle(plotter, grbl: Grbl) -> None:
    unlocked(grbl)
    for i in range(3):
        x = 20 + 20 * i
        for line in [f"G0 X{x} Y20", "M3", f"G1 X{x + 10} Y20 F3000", "M5"]:
            grbl.ok(line)
    status_down = None
    grbl.ok("M300 S30")
    status_down = grbl.status()
    assert "|A:S" in status_down
    trace = plotter.trace()
    assert trace["pen"] == "down" and trace["pen_us"] == pytest.approx(2000, abs=15)
    grbl.ok("M300 S50")
    assert "|A:S" not in grbl.status()
    grbl.ok("G1 Z-1 F1000")  # Z at or below 0: pen down
    assert plotter.trace()["pen"] == "down"
    grbl.ok("G0 Z2")
    grbl.wait_state("Idle")
    trace = plotter.trace()
    clean(trace)
    assert trace["pen"] == "up" and trace["pen_us"] == pytest.approx(1000, abs=15)
    strokes = [s for s in stroke_points(trace) if len(s) > 1]
    assert len(strokes) == 3
    for i, s in enumerate(strokes):
        x = 20 + 20 * i
        assert math.dist(s[0], (x, 20)) < TOL and math.dist(s[-1], (x + 10, 20)) < TOL
    # every pen move waits for the settle time: no step within 150 ms after M3
    times = [(p[2]) for s in trace["strokes"] for p in s]
    assert times == sorted(times)


def test_homing_from_anywhere(plotter_factory) -> None:
    plotter = plotter_factory(start=(57.3, 31.9))
    g = Grbl(plotter.port)
    try:
        g.reset()
        g.ok("$H", timeout=120)
        status = g.status()
        assert status.startswith("<Idle|MPos:1.000,1.000,"), status
        trace = plotter.trace()
        assert trace["position"]["x"] == pytest.approx(1.0, abs=1e-6)
        assert trace["position"]["y"] == pytest.approx(1.0, abs=1e-6)
        assert trace["limits"] == {"x": False, "y": False}
        # G28 goes to machine zero: the switch edge, still open
        g.ok("G28")
        g.wait_state("Idle")
        trace = plotter.trace()
        assert trace["position"] == {"x": 0.0, "y": 0.0}
        assert trace["limits"] == {"x": False, "y": False}
        clean(trace)
        no_false_acks(g.lines)
    finally:
        g.close()


def test_soft_limit_rejects_before_moving(plotter, grbl: Grbl) -> None:
    unlocked(grbl)
    grbl.ok("G0 X10 Y10")
    got = grbl.send("G0 X301")
    assert got[-2:] == ["ALARM:2", "error:9"], got
    grbl.wait_state("Alarm")
    assert plotter.trace()["position"] == {"x": 10.0, "y": 10.0}
    unlocked(grbl)
    # jogs outside the work area are refused with error:15
    assert grbl.send("$J=G91 X-20 F1000")[-1] == "error:15"


@pytest.mark.parametrize(("start", "arc", "outside"), [
    ((295, 100), "G3 X295 Y120 I0 J10", True),   # counter-clockwise through +X: (305, 110)
    ((295, 100), "G2 X295 Y120 I0 J10", False),  # clockwise the other way: (285, 110)
    ((100, 4), "G3 X110 Y4 I5 J0", True),        # counter-clockwise through -Y: (105, -1)
    ((100, 4), "G2 X110 Y4 I5 J0", False),       # clockwise through +Y: (105, 9)
    ((150, 100), "G2 X150 Y100 I0 J-97", True),  # a full circle: all four extremes
    ((150, 110), "G2 X150 Y110 I0 J-50", False),
])
def test_soft_limit_checks_an_arcs_extremes(plotter, grbl: Grbl, start, arc: str,
                                            outside: bool) -> None:
    """An arc whose ends are inside is refused before moving when it swings past
    the work area (its axis extremes between its end angles), and not otherwise."""
    unlocked(grbl)
    grbl.ok(f"G0 X{start[0]} Y{start[1]}")
    grbl.wait_state("Idle")
    got = grbl.send(arc + " F3000")
    if outside:
        assert got[-2:] == ["ALARM:2", "error:9"], got
        assert plotter.trace()["position"] == {"x": float(start[0]), "y": float(start[1])}
        unlocked(grbl)
    else:
        assert got[-1] == "ok", got
        grbl.wait_state("Idle")


def test_soft_limit_edges_keep_their_tolerance(plotter, grbl: Grbl) -> None:
    # within 0.0005 mm of the work area is inside; past it, the line is refused
    unlocked(grbl)
    grbl.ok("G0 X300.0004 Y-0.0004")
    got = grbl.send("G0 X-0.001")
    assert got[-2:] == ["ALARM:2", "error:9"], got
    unlocked(grbl)
    got = grbl.send("G0 X300.001")
    assert got[-2:] == ["ALARM:2", "error:9"], got


def test_hard_limit_hit(plotter, grbl: Grbl) -> None:
    unlocked(grbl)
    grbl.ok("$20=0")  # soft limits off, so the move reaches the switch
    grbl.ok("G0 X5 Y5")
    grbl.ser.write(b"G1 X-20 F2000\n")
    lines = grbl.wait_for(r"^ALARM:1$", 30)
    assert lines[0] == "ok"  # the G1 was queued before the switch closed
    status = grbl.wait_state("Alarm")
    assert "Pn:X" in status
    trace = plotter.trace()
    # stopped within a step of the switch closing (x < 0)
    assert -2 * STEP_MM <= trace["position"]["x"] < 0
    assert mpos(status)[0] == pytest.approx(trace["position"]["x"], abs=0.001)
    assert grbl.send("G0 X10")[-1] == "error:9"
    unlocked(grbl)
    grbl.ok("G0 X10")
    grbl.wait_state("Idle")
    assert plotter.trace()["position"]["x"] == pytest.approx(10.0, abs=1e-3)


def test_feed_hold_and_resume(plotter, grbl: Grbl) -> None:
    """A pen-safe hold: stopped on the path, pen lifted; lowered at the same point on resume."""
    unlocked(grbl)
    grbl.ok("G0 X10 Y10")
    grbl.ok("M3")
    grbl.ok("G1 X210 Y10 F1500")
    time.sleep(0.2)
    grbl.ser.write(b"!")
    held = grbl.wait_state("Hold:0", 30)
    plotter.wait_trace(lambda t: t["pen"] == "up", 10)
    x_held = plotter.trace()["position"]["x"]
    assert 10 < x_held < 210
    time.sleep(0.3)
    assert plotter.trace()["position"]["x"] == x_held  # really stopped
    assert mpos(held)[0] == pytest.approx(x_held, abs=0.001)
    assert "|A:S" in grbl.status()  # the program's pen is still down: it comes back on resume
    grbl.ser.write(b"~")
    grbl.wait_state("Run", 10)
    grbl.ok("M5")
    grbl.wait_state("Idle", 60)
    trace = plotter.trace()
    clean(trace)
    first, second = [s for s in stroke_points(trace) if len(s) > 1]
    # two straight pieces meeting at the hold point (within a step), ending exactly at the target
    assert math.dist(first[-1], (x_held, 10)) <= STEP_MM + 1e-9
    assert math.dist(second[0], (x_held, 10)) <= STEP_MM + 1e-9
    assert len(second) == 2 and math.dist(second[-1], (210, 10)) < TOL


def test_soft_reset_mid_move(plotter, grbl: Grbl) -> None:
    unlocked(grbl)
    grbl.ser.write(b"G1 X250 Y150 F3000\n")
    grbl.wait_state("Run", 10)
    time.sleep(0.1)
    lines = grbl.reset(10)
    assert "ALARM:3" in lines
    status = grbl.wait_state("Alarm")
    trace = plotter.trace()
    x, y = mpos(status)
    assert 0 < x < 250
    # the firmware's position is the true one, to the step
    assert trace["steps"]["x"] == round(x * 80) and trace["steps"]["y"] == round(y * 80)
    time.sleep(0.2)
    assert plotter.trace()["steps"] == trace["steps"]  # nothing moves after the reset
    assert grbl.send("G0 X0")[-1] == "error:9"
    unlocked(grbl)


def test_estop_button(plotter, grbl: Grbl) -> None:
    unlocked(grbl)
    grbl.ser.write(b"G1 X200 F2000\n")
    grbl.wait_state("Run", 10)
    plotter.press("estop")
    grbl.wait_for(r"^ALARM:10$", 5)
    status = grbl.wait_state("Alarm")
    assert "Pn:R" in status
    steps = plotter.trace()["steps"]
    time.sleep(0.2)
    assert plotter.trace()["steps"] == steps
    assert grbl.send("$X")[-1] == "error:9"  # not while the button is pressed
    plotter.release("estop")
    unlocked(grbl)


def test_bad_input_gives_errors_and_keeps_working(plotter, grbl: Grbl) -> None:
    unlocked(grbl)
    assert grbl.send("G1 X" + "9" * 40 + " F100")[-1] == "error:2"
    assert grbl.send("X" * 200)[-1] == "error:11"
    grbl.ser.write(bytes([0, 1, 2, 0xFE, 0x41]) + b"\n")
    assert grbl.wait_for(r"^(ok|error:\d+)$")[-1].startswith("error:")
    assert grbl.send("G1 X1 Q5 F100")[-1] == "error:20"
    assert grbl.send("G2 X10 Y0 F100")[-1] == "error:35"
    assert grbl.send("$999=1")[-1] == "error:3"
    assert grbl.send("G0 X1 (comment) ; trailing")[-1] == "ok"
    grbl.ok("")
    grbl.wait_state("Idle")
    assert mpos(grbl.status()) == (1.0, 0.0)


def test_half_a_line_in_keeps_the_board_serviced(plotter, grbl: Grbl) -> None:
    """The main loop sleeps through a line's bytes until its end: with half a
    line waiting, status requests are still answered, the $1 idle delay still
    switches the motors off, and the line runs once its end comes."""
    unlocked(grbl)
    grbl.ok("$1=30")
    grbl.ok("G0 X5 Y5")
    grbl.wait_state("Idle")
    plotter.wait_trace(lambda t: t["enabled"] is False, 20)  # the idle delay, nothing pending
    grbl.ok("G0 X2")
    grbl.wait_state("Idle")
    grbl.ser.write(b"G0 X1")  # no line end yet
    assert grbl.status().startswith("<Idle|")
    plotter.wait_trace(lambda t: t["enabled"] is False, 20)  # the 1 ms tick still polls
    grbl.ser.write(b"2.5 Y3\n")
    assert grbl.wait_for(r"^(ok|error:\d+)$")[-1] == "ok"
    grbl.wait_state("Idle")
    assert mpos(grbl.status()) == (12.5, 3.0)
    grbl.ok("$1=255")


def test_check_mode_moves_nothing(plotter, grbl: Grbl) -> None:
    unlocked(grbl)
    grbl.ok("$C")
    assert grbl.status().startswith("<Check|")
    grbl.ok("G1 X50 Y50 F1000")
    grbl.ok("M3")
    grbl.ok("G2 X50 Y50 I10 F1000")
    assert grbl.send("G1 X1 Q1")[-1] == "error:20"
    got = grbl.ok("$C")
    assert any("Disabled" in line for line in got)
    grbl.wait_for(r"^Grbl 1\.1h")  # leaving check mode resets
    trace = plotter.trace()
    assert trace["steps"] == {"x": 0, "y": 0} and trace["pen"] == "up"


def test_random_bytes_never_crash(plotter, grbl: Grbl) -> None:
    """Seeded binary noise and shuffled G-code words: errors, then business as usual."""
    unlocked(grbl)
    rng = random.Random(1234)
    realtime = {0x18, ord("!"), ord("~"), ord("?"), 0x85}
    junk = bytes(b for b in rng.randbytes(6000) if b not in realtime)
    words = b"G0 G1 G2 X Y I J F M3 M5 $ = ( ) ; 1 -2.5 99999999999 \n".split(b" ")
    junk += b"".join(rng.choice(words) for _ in range(1500))
    for i in range(0, len(junk), 100):  # paced, so the receive buffer is not the only thing tested
        grbl.ser.write(junk[i:i + 100])
        time.sleep(0.01)
    grbl.ser.write(b"\n$X\n")
    time.sleep(1.0)
    grbl.read_lines(2.0)
    grbl.queue.clear()
    grbl.ok("$X")
    grbl.ok("G90 G21")
    grbl.ok("G53 G0 X5 Y5")
    grbl.wait_state("Idle", 60)
    assert plotter.trace()["position"] == {"x": 5.0, "y": 5.0}
    clean(plotter.trace())


def test_corexy_kinematics_and_homing(plotter_factory) -> None:
    plotter = plotter_factory(args=["--corexy"], start=(40.0, 30.0))
    g = Grbl(plotter.port)
    try:
        g.reset()
        g.ok("$63=1")
        g.ok("$H", timeout=120)
        assert mpos(g.status()) == (1.0, 1.0)
        for line in ["G0 X10 Y10", "M3", "G1 X60 Y30 F3000", "M5"]:
            g.ok(line)
        g.wait_state("Idle")
        straight_stroke(plotter, (10, 10), (60, 30))  # both motors together, not a staircase
        no_false_acks(g.lines)
    finally:
        g.close()


def test_long_move_split_into_pieces_stays_exact_and_straight(plotter_factory) -> None:
    # 400 steps/mm: the 200 mm move is 80,000 step events, cut into equal pieces by the firmware
    plotter = plotter_factory(args=["--steps-per-mm", "400"])
    g = Grbl(plotter.port)
    try:
        g.reset()
        for line in ["$100=400", "$101=400", "$X", "G0 X1 Y1", "M3", "G1 X201 Y151 F3000", "M5"]:
            g.ok(line)
        g.wait_state("Idle")
        trace = straight_stroke(plotter, (1, 1), (201, 151))  # no kink where the pieces meet
        assert trace["steps"] == {"x": 201 * 400, "y": 151 * 400}
        assert mpos(g.status()) == (201.0, 151.0)
        no_false_acks(g.lines)
    finally:
        g.close()
