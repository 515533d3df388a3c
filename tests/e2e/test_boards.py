"""Every board profile (firmware/src/boards/) through the virtual plotter.

One plotsim per profile, all started at once and driven concurrently (the
profiles are independent), each running that profile's firmware build on its
own chip and wiring: step/dir pins, or four-wire coil sequences decoded into
steps with illegal phase jumps counted as missed steps. Drawings are compared
with the commanded path within one motor step; and one `plotbridge serve
--virtual --board NAME` per profile plots a job end to end.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest

from tests.fixtures.grbl import Grbl
from tests.fixtures.plotsim import FIRMWARE_DIR, PLOTSIM, REPO, Plotter, board_firmware
from tests.fixtures.server import running_server

pytestmark = pytest.mark.e2e

BOARDS = ["uno-cnc-shield", "uno-uln2003", "mega-l298n", "mega-stepdir", "mega-ramps14"]
# the header's defaults the tests rely on (firmware/src/boards/NAME.h)
STEPS_PER_MM = {"uno-cnc-shield": 80, "uno-uln2003": 32.6, "mega-l298n": 5,
                "mega-stepdir": 160, "mega-ramps14": 80}  # fmt: skip
SWITCHES = {"uno-cnc-shield": "one", "uno-uln2003": None, "mega-l298n": None,
            "mega-stepdir": "min+max", "mega-ramps14": "min+max"}  # fmt: skip
FOUR_WIRE = {"uno-uln2003", "mega-l298n"}
FEED = 1500  # mm/min: within every profile's $110 (the 28BYJ-48's is 1800)


def elf(board: str) -> Path:
    build = "build" if board == "uno-cnc-shield" else f"build/{board}"  # firmware/Makefile
    return FIRMWARE_DIR / build / "plotbridge.elf"


def parallel(fn: Callable[[str], Any]) -> dict[str, Any]:
    with ThreadPoolExecutor(len(BOARDS)) as pool:
        return dict(zip(BOARDS, pool.map(fn, BOARDS), strict=True))


@pytest.fixture(scope="module")
def builds(sim_build) -> None:
    for board in BOARDS:
        board_firmware(board)


@pytest.fixture(scope="module")
def plotters(builds, tmp_path_factory) -> Iterator[dict[str, tuple[Plotter, Grbl]]]:
    tmp = tmp_path_factory.mktemp("boards")
    started: dict[str, tuple[Plotter, Grbl]] = {}
    try:
        for board in BOARDS:
            p = Plotter(PLOTSIM, elf(board), tmp / f"{board}.eeprom", 0, (0, 0),
                        ["--board", board]).start()
            g = Grbl(p.port)
            started[board] = (p, g)
        parallel(lambda b: boot(started[b][1]))
        yield started
    finally:
        for p, g in started.values():
            g.close()
            p.cleanup()


def boot(g: Grbl) -> None:
    g.reset(30)  # the banner went out before we connected
    g.ok("$X")


# --- the drawing: square, diagonal, G2 circle, 200-segment polyline ---------

SQUARE = [(10, 10), (40, 10), (40, 40), (10, 40), (10, 10)]
DIAGONAL = [(10, 50), (50, 80)]
CIRCLE_C, CIRCLE_R = (90.0, 30.0), 10.0
# as sent: three decimals
POLYLINE = [(round(20 + 0.3 * i, 3), round(100 + 5 * math.sin(0.2 * i), 3)) for i in range(201)]


def drawing() -> list[str]:
    def stroke(points) -> list[str]:
        (x0, y0), rest = points[0], points[1:]
        return [f"G0 X{x0:.3f} Y{y0:.3f}", "M3",
                *(f"G1 X{x:.3f} Y{y:.3f} F{FEED}" for x, y in rest), "M5"]
    cx, cy = CIRCLE_C
    return ["G21 G90", *stroke(SQUARE), *stroke(DIAGONAL),
            f"G0 X{cx + CIRCLE_R:g} Y{cy:g}", "M3",
            f"G2 X{cx + CIRCLE_R:g} Y{cy:g} I{-CIRCLE_R:g} J0 F{FEED}",
            "M5", *stroke(POLYLINE), "G4 P0"]


def dist_to_polyline(p, line) -> float:
    """Per-axis (Chebyshev) distance to the path: each motor is within this
    many mm of a point of the commanded path."""
    best = math.inf
    for a, b in itertools.pairwise(line):
        ex, ey = p[0] - a[0], p[1] - a[1]
        dx, dy = b[0] - a[0], b[1] - a[1]
        # max(|ex - t dx|, |ey - t dy|) is convex in t: its minimum is at an
        # end, where one term is zero, or where the two terms are equal
        ts = [0.0, 1.0]
        ts += [ex / dx] if dx else []
        ts += [ey / dy] if dy else []
        ts += [(ex - ey) / (dx - dy)] if dx != dy else []
        ts += [(ex + ey) / (dx + dy)] if dx != -dy else []
        for t in ts:
            if 0 <= t <= 1:
                best = min(best, max(abs(ex - t * dx), abs(ey - t * dy)))
    return best


@pytest.fixture(scope="module")
def drawn(plotters) -> dict[str, dict]:
    def draw(board: str) -> dict:
        p, g = plotters[board]
        p.clear()
        for line in drawing():
            g.ok(line, timeout=300)
        g.wait_state("Idle", 300)
        return p.trace()
    return parallel(draw)


def clean(trace: dict) -> None:
    assert trace["violations"] == {
        "short_pulse": 0, "dir_setup": 0, "step_while_disabled": 0, "overspeed": 0
    }, trace["violations"]  # fmt: skip
    assert trace["missed_steps"] == 0


@pytest.mark.parametrize("board", BOARDS)
def test_drawing_within_one_step(drawn, board: str) -> None:
    trace = drawn[board]
    step = 1 / STEPS_PER_MM[board]
    tol = step + 1e-3  # a step, and the trace's 4-decimal rounding
    clean(trace)
    assert trace["pen_lifts"] == 4
    strokes = [[(x, y) for x, y, _t in s] for s in trace["strokes"]]
    assert len(strokes) == 4, [len(s) for s in strokes]
    square, diagonal, circle, poly = strokes
    for got, want in ((square, SQUARE), (diagonal, DIAGONAL), (poly, POLYLINE)):
        # the firmware can only aim at whole steps: each commanded vertex
        # rounds to the step grid (half a step), and the motors stay within
        # a step of the lines between those
        grid = [(math.floor(x / step + 0.5) * step, math.floor(y / step + 0.5) * step)
                for x, y in want]
        worst = max(dist_to_polyline(pt, grid) for pt in got)
        assert worst <= tol, (board, worst)
        for end, target in ((got[0], want[0]), (got[-1], want[-1])):
            assert max(abs(end[0] - target[0]), abs(end[1] - target[1])) <= step / 2 + 1e-3
    # the arc: the firmware's chords ($12 = 0.002 mm) plus a step on each
    # axis, which is up to sqrt(2) steps along the radius
    worst = max(abs(math.dist(pt, CIRCLE_C) - CIRCLE_R) for pt in circle)
    assert worst <= math.sqrt(2) * step + 0.002 + 1e-3, (board, worst)
    assert math.dist(circle[0], circle[-1]) <= 2 * step
    # every corner of the square is reached
    for corner in SQUARE:
        assert min(math.dist(corner, pt) for pt in square) <= tol


@pytest.mark.parametrize("board", BOARDS)
def test_pen_follows_the_profiles_servo_pin(drawn, board: str) -> None:
    trace = drawn[board]
    assert trace["pen"] == "up" and trace["pen_us"] == pytest.approx(1000, abs=20)
    assert trace["draw_mm"] > 4 * 30 + 50 + 2 * math.pi * CIRCLE_R + 60


@pytest.mark.parametrize("board", BOARDS)
def test_idle_deenergize_reset_and_move_lose_no_step(plotters, board: str) -> None:
    """$1 de-energizes (coils off, or the enable line) after the idle delay; a
    soft reset keeps the phase; the next moves continue from the rotor's state."""
    p, g = plotters[board]
    spm = STEPS_PER_MM[board]
    g.ok("$1=30")
    g.ok("G90 G1 X5 Y5 F3000")
    g.wait_state("Idle", 300)
    p.wait_trace(lambda t: not t["enabled"], timeout=20)
    if board in FOUR_WIRE:
        assert p.trace()["coils"] == {"x": 0, "y": 0}
    for target in ((7.33, 6.17), (3.07, 9.01)):
        g.ok(f"G1 X{target[0]} Y{target[1]} F1000")
        g.wait_state("Idle", 300)
        p.wait_trace(lambda t: not t["enabled"], timeout=20)
        g.reset(30)  # soft reset while de-energized
        g.send("$X")  # boards with switches boot locked; the others answer ok as well
        t = p.trace()
        want = {"x": math.floor(target[0] * spm + 0.5), "y": math.floor(target[1] * spm + 0.5)}
        assert t["steps"] == want, board
    g.ok("$1=255")
    clean(p.trace())


@pytest.mark.parametrize("board", BOARDS)
def test_direction_convention_as_grbl(plotters, board: str) -> None:
    """GRBL's settings documentation: $3 "inverts the direction signal"
    (../shared/grbl/setting_codes_en_US.csv), and with $3=0 a LOW direction
    pin moves the axis positive. The simulator is wired for $3=0: with $3=3
    the same command moves both motors the other way."""
    p, g = plotters[board]
    spm = STEPS_PER_MM[board]
    moved = {}
    for mask in (0, 3):
        g.ok("$3=0")
        g.ok("G90 G1 X20 Y20 F1000")
        g.wait_state("Idle", 300)
        before = p.trace()["steps"]
        g.ok(f"$3={mask}")
        g.ok("G91 G1 X2 Y1 F1000")
        g.ok("G90")
        g.wait_state("Idle", 300)
        t = p.trace()
        moved[mask] = (t["steps"]["x"] - before["x"], t["steps"]["y"] - before["y"])
        if board not in FOUR_WIRE:  # a direction pin to look at
            assert t["dir_pins"] == ({"x": 0, "y": 0} if mask == 0 else {"x": 1, "y": 1})
    assert moved[0] == (round(2 * spm), round(1 * spm))
    assert moved[3] == (-moved[0][0], -moved[0][1])
    g.ok("$3=0")  # the simulated carriage is now 4 mm and 2 mm short of the firmware's idea


@pytest.mark.parametrize("board", [b for b in BOARDS if SWITCHES[b]])
def test_homing_and_limit_hits(plotters, board: str) -> None:
    p, g = plotters[board]
    g.ok("$H", timeout=300)
    t = p.trace()
    assert t["limit_ends"] == {"x_min": False, "x_max": False, "y_min": False, "y_max": False}
    assert abs(t["position"]["x"]) < 2 and abs(t["position"]["y"]) < 2
    g.ok("$20=0")  # soft limits off: let the carriage reach the far switch
    g.ser.write(b"G1 X310 F3000\n")
    g.wait_for(r"^ALARM:1$", 300)
    t = p.trace()
    assert t["limit_ends"]["x_max"] and not t["limit_ends"]["x_min"]
    # the near end: back inside, then past the min switch
    g.ok("$X")
    g.ok("G1 X100 F3000")
    g.wait_state("Idle", 300)
    g.ser.write(b"G1 X-20 F3000\n")
    g.wait_for(r"^ALARM:1$", 300)
    assert p.trace()["limit_ends"]["x_min"]
    g.ok("$X")
    g.ok("G1 X10 F3000")
    g.wait_state("Idle", 300)
    g.ok("$20=1")


@pytest.mark.parametrize("board", [b for b in BOARDS if not SWITCHES[b]])
def test_boards_without_switches_boot_idle(plotters, board: str) -> None:
    p, g = plotters[board]
    p.restart()
    g2 = Grbl(p.port)
    try:
        g2.reset(30)
        assert g2.status().startswith("<Idle")
        settings = g2.ok("$$")
        assert "$22=0" in settings and "$21=0" in settings
        g2.ok("G1 X1 F500")  # no $X needed
    finally:
        g2.close()
    g.ser.close()
    g.ser.open()


@pytest.mark.parametrize("board", BOARDS)
def test_serve_virtual_board(builds, tmp_path, board: str) -> None:
    """`plotbridge serve --virtual --board NAME` plots a square on that board."""
    link = ["--virtual", "--sim-speed", "0", "--board", board]
    with running_server(tmp_path / "data", link) as s:
        if SWITCHES[board]:
            s.home()
        else:
            s.wait_machine(lambda m: m["state"] == "Idle", timeout=60)
        program = "G90\nG0 X10 Y10\nM3\nG1 X30 Y10 F1500\nG1 X30 Y30\nG1 X10 Y30\nG1 X10 Y10\nM5\n"
        r = s.client.post("/api/jobs?name=square&start=true", content=program)
        assert r.status_code == 201, r.text
        s.wait_job(r.json()["id"], "done", timeout=120)
        strokes = s.client.get("/api/sim/trace").json()["strokes"]
        step = 1 / STEPS_PER_MM[board]
        assert len(strokes) == 1
        pts = [(x, y) for x, y, *_ in strokes[0]]
        want = [(10, 10), (30, 10), (30, 30), (10, 30), (10, 10)]
        assert max(dist_to_polyline(pt, want) for pt in pts) <= step + 1e-3
        assert math.dist(pts[-1], (10, 10)) <= step
    assert (REPO / "firmware").is_dir()
