"""End to end: every firmware profile numbers lines (`$I` OPT `N`), the Uno's default
uno-cnc-shield firmware and the Mega's mega-ramps14, each through a real
`plotbridge serve --virtual --board ...`: the job goes out with `N` words, every
status report while it runs carries the executing line (`Ln:`, the machine object's
`line`), and a job stopped by the emergency stop resumes from the reported line with
nothing drawn twice."""

from __future__ import annotations

import re
import time

import pytest

from tests.fixtures.grbl import mpos, session, unlocked
from tests.fixtures.plotsim import board_firmware
from tests.fixtures.server import running_server
from tests.fixtures.trace import ESTOP_REDRAW_MM, assert_same_drawing

pytestmark = pytest.mark.e2e

UNO = "uno-cnc-shield"
MEGA = "mega-ramps14"
FEED = 3000  # mm/min
SEGMENT = 0.5  # mm: one planner block a line
FIRST_MOVE = 5  # program line of the first 0.5 mm segment (after G21 G90 G0 M3)


# one stroke of 0.5 mm segments: a row along y=20, 10 mm up, a row back along y=30
POINTS = ([(10 + SEGMENT * k, 20.0) for k in range(1, 161)]
          + [(90.0, 20 + SEGMENT * k) for k in range(1, 21)]
          + [(90 - SEGMENT * k, 30.0) for k in range(1, 161)])  # fmt: skip


def short_segments() -> tuple[str, int, float]:
    """The stroke's G-code, its last segment's line and the pen-down length."""
    lines = ["G21", "G90", "G0 X10 Y20", "M3"]
    lines += [f"G1 X{x:.3f} Y{y:.3f} F{FEED}" for x, y in POINTS]
    return "\n".join([*lines, "M5"]) + "\n", len(lines), SEGMENT * len(POINTS)


def along(x: float, y: float) -> float:
    """How far along the stroke (mm) a point on it lies."""
    if abs(y - 20) < 1e-6:
        return x - 10
    if abs(x - 90) < 1e-6:
        return 80 + (y - 20)
    assert abs(y - 30) < 1e-6, (x, y)
    return 90 + (90 - x)


@pytest.fixture(scope="module", params=[UNO, MEGA])
def board(request, sim_build) -> str:
    """Each profile, its firmware built."""
    board_firmware(request.param)
    return request.param


def test_status_reports_carry_the_line_and_an_estop_resumes_from_it(board, tmp_path):
    gcode, last_move, length = short_segments()
    link = ["--virtual", "--sim-speed", "1", "--board", board]
    with running_server(tmp_path / "data", link) as server:
        server.home()
        assert server.machine()["line"] is None  # idle: nothing executes
        job = server.submit(gcode)
        seen: list[int] = []
        deadline = time.monotonic() + 60
        while len(seen) < 5 and time.monotonic() < deadline:
            machine = server.machine()
            if machine["state"] == "Run" and machine["position"]["x"] > 11:  # past the M3
                assert machine["line"] is not None, machine  # every report while it draws
                seen.append(machine["line"])
            time.sleep(0.1)
        assert seen, (server.job(job["id"]), server.machine())  # it drew while watched
        assert seen == sorted(seen), seen  # the executing line only moves on
        assert FIRST_MOVE <= seen[0] and seen[-1] <= last_move, seen
        assert server.client.post("/api/machine/estop").status_code == 202
        stopped = server.wait_job(job["id"], ("stopped",), 10)
        # the stop came mid-program: the resume starts at the reported line, not before
        assert seen[-1] <= stopped["resume_line"] <= last_move, (seen, stopped)
        server.wait_machine(lambda m: m["state"] == "Alarm", 10)
        resumed = server.client.post(f"/api/jobs/{job['id']}/resume", json={"home": True})
        assert resumed.status_code == 200, resumed.text
        done = server.wait_job(job["id"], ("done", "failed", "stopped", "interrupted"), 120)
        assert done["state"] == "done", done
        trace = server.client.get("/api/sim/trace").json()
        assert_same_drawing(server.preview(job["id"])["strokes"], trace["strokes"])
        redrawn = trace["draw_mm"] - length
        print(f"{board}: estop on 0.5 mm segments, resumed from Ln: {redrawn:.4f} mm drawn twice")
        assert -ESTOP_REDRAW_MM <= redrawn <= ESTOP_REDRAW_MM, f"{redrawn:.3f} mm drawn twice"


def test_a_reports_position_lies_on_its_line_or_past_it(board, plotter_factory):
    """`Ln:` and `MPos:` of one report agree: the position lies on the named line's move
    or a little past it, never before it (an interrupted job resumes from that line at
    that point). Reports are asked for every 10 ms while 0.5 mm segments stream."""
    gcode, _, _ = short_segments()
    plotter = plotter_factory(firmware=board_firmware(board), speed=1, args=("--board", board))
    with session(plotter) as g:
        numbered = [f"N{n}{text}" for n, text in enumerate(gcode.splitlines(), 1)]
        unlocked(g).stream(numbered, timeout=60, poll_s=0.01)
        g.wait_state("Idle")
    step = 1 / 80  # mm: both profiles' default steps/mm
    checked = 0
    for report in g.lines:
        line = re.search(r"\|Ln:(\d+)", report)
        if not report.startswith("<Run") or not line or int(line[1]) < FIRST_MOVE:
            continue
        start = (int(line[1]) - FIRST_MOVE) * SEGMENT  # where the line's move begins
        at = along(*mpos(report))
        assert start - step / 2 <= at <= start + 2 * SEGMENT, (report, start)
        checked += 1
    assert checked >= 50, f"{checked} reports while drawing"
