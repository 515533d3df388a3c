"""End to end: a job's progress follows what the pen did (issue 26), through the real
firmware in the simulator (it numbers its lines: `Ln:`) and a real `plotbridge serve`:
progress is the share of the plan's time, not of lines; after a stop or a server killed
mid-job, `drawn_mm` is what the simulator's pen drew and nothing past the resume point
counts as done; a re-ink interval that falls on the last stroke asks for nothing."""

from __future__ import annotations

import contextlib
import os
import signal

import pytest
from plotbridge.plotter.stoppoint import MARK_FILE

from tests.fixtures.drawings import LONG_STROKE, STROKE
from tests.fixtures.drawings import PROGRESS_THREE_LAYERS as THREE_LAYERS
from tests.fixtures.server import running_server
from tests.fixtures.trace import (
    DRAWN_TOL_MM,
    assert_nothing_past_the_resume_point,
    settled_drawn,
    wait_still,
)  # fmt: skip
from tests.fixtures.waits import wait_until

pytestmark = pytest.mark.e2e

def test_progress_at_the_first_pen_change_is_the_share_of_the_plans_time(server, plotter):
    server.home()
    job = server.submit(THREE_LAYERS)
    layers = job["layers"]
    share = layers[0]["estimate_s"] / job["estimate_s"]
    assert 0.5 < share < 0.75, (share, layers)  # the drawing is what the test is about
    changing = server.wait_pen_change(job["id"], 2, 120)
    by_lines = changing["lines_done"] / changing["lines_total"]
    print(f"at the first pen change: progress {changing['progress']:.3f}, plan's share "
          f"{share:.3f}, lines {by_lines:.3f}")
    assert by_lines < 0.10
    assert changing["progress"] == pytest.approx(share, abs=0.05)
    assert [layer["progress"] for layer in changing["layers"]] == [1, 0, 0]
    assert changing["eta_s"] == pytest.approx(job["estimate_s"] * (1 - share), rel=0.15)
    assert changing["layers"][0]["drawn_mm"] == pytest.approx(600, abs=DRAWN_TOL_MM)
    assert changing["drawn_mm"] == pytest.approx(plotter.trace()["draw_mm"], abs=DRAWN_TOL_MM)
    assert changing["actions"] == ["continue", "stop", "cancel"]
    continued = server.client.post(f"/api/jobs/{job['id']}/continue")
    assert continued.status_code == 200, continued.text
    server.wait_pen_change(job["id"], 3, 120)
    assert server.client.post(f"/api/jobs/{job['id']}/continue").status_code == 200
    done = server.wait_job(job["id"], ("done", "failed", "stopped"), 120)
    assert done["state"] == "done" and done["progress"] == 1 and done["eta_s"] == 0
    assert done["drawn_mm"] == pytest.approx(plotter.trace()["draw_mm"], abs=DRAWN_TOL_MM)


def test_stop_mid_stroke_counts_what_the_pen_drew(server, plotter):
    server.home()
    job = server.submit(STROKE)
    server.wait_progress(job["id"], 15)
    server.wait_machine(lambda m: m["line"] is not None, 10)
    assert server.client.post("/api/machine/estop").status_code == 202
    server.wait_job(job["id"], ("stopped",), 10)
    stopped, drawn = settled_drawn(server, plotter, job["id"])
    print(f"stopped: drawn_mm {stopped['drawn_mm']:.3f}, the pen drew {drawn:.3f}")
    assert 0 < stopped["progress"] < 1 and stopped["summary"].startswith("stopped at X ")
    assert_nothing_past_the_resume_point(stopped)
    assert stopped["actions"] == ["resume", "home_then_resume", "resume_from", "restart",
                                  "cancel", "frame", "delete"]  # fmt: skip
    resumed = server.client.post(f"/api/jobs/{job['id']}/home_then_resume")
    assert resumed.status_code == 200, resumed.text
    done = server.wait_job(job["id"], ("done", "failed", "stopped"), 60)
    assert done["state"] == "done" and done["drawn_mm"] == pytest.approx(160, abs=0.01)


def test_a_server_killed_mid_job_counts_what_the_pen_drew_after_restart(plotter_factory,
                                                                         tmp_path):  # fmt: skip
    plotter = plotter_factory(speed=2)
    with running_server(tmp_path / "data", ["--serial", str(plotter.port)]) as server:
        server.home()
        job = server.submit(LONG_STROKE)
        server.wait_progress(job["id"], 12)
        mark = server.data_dir / "jobs" / job["id"] / MARK_FILE
        wait_until(mark.exists, bool, 30, "the job's first resume mark")
        killed = server.proc.pid if server.proc else None
        server.kill()
        if killed is not None:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(killed, signal.SIGKILL)
        wait_still(plotter, 60, every=0.5)  # the board runs out of moves
        server.start()
        server.wait_job(job["id"], ("interrupted",), 10)
        server.wait_machine(lambda m: m["connected"], 30)
        interrupted, drawn = settled_drawn(server, plotter, job["id"])
        print(f"after kill -9: drawn_mm {interrupted['drawn_mm']:.3f}, the pen drew {drawn:.3f}")
        assert_nothing_past_the_resume_point(interrupted)
        assert 0 < interrupted["progress"] < 1 and 0 < drawn < 159, drawn  # it ran out part-way
        assert "resume" in interrupted["actions"]


def test_a_reink_due_on_the_last_stroke_asks_nothing(server, plotter):
    server.home()
    made = server.client.post("/api/pens", json={"name": "inky", "reink_m": 0.15})
    assert made.status_code in (200, 201), made.text
    response = server.client.post("/api/jobs", files={"file": ("s.gcode", STROKE)},
                                  data={"pens": "1=inky", "start": "true"})  # fmt: skip
    assert response.status_code == 201, response.text
    job = response.json()
    assert job["layers"][0]["pen"] == made.json()["id"]
    states = []

    def seen() -> dict:
        current = server.job(job["id"])
        states.append(current["state"])
        return current

    done = wait_until(seen, lambda j: j["state"] in ("done", "failed", "stopped", "pen_change"),
                      60, "the job's end", every=0.05)  # fmt: skip
    assert done["state"] == "done", done  # 160 mm drawn: 150 passed on the only stroke
    assert "pen_change" not in states
    pens = {p["name"]: p for p in server.client.get("/api/pens").json()}
    assert pens["inky"]["odometer_m"] == pytest.approx(0.16, abs=0.001)
