"""End to end: the queue waits for the machine. A job started while the board is in
Alarm (or busy) waits and starts by itself once the board is Idle; `--home-on-connect`
homes a board that comes up in Alarm; the "after the job" action parks the carriage."""

from __future__ import annotations

import pytest

from tests.fixtures.drawings import drawing
from tests.fixtures.server import running_server

pytestmark = pytest.mark.e2e


def upload(server, gcode: str, **fields: str) -> dict:
    response = server.client.post(
        "/api/jobs", files={"file": ("drawing.gcode", gcode)}, data={"start": "true", **fields}
    )
    assert response.status_code == 201, response.text
    return response.json()


def test_started_in_alarm_waits_then_runs_after_homing_and_the_next_after_it(server, plotter):
    server.wait_machine(lambda m: m["state"] == "Alarm", 30)  # homing on: boots in Alarm
    first = upload(server, drawing())
    assert first["state"] == "waiting" and "Alarm" in first["waiting"], first
    assert "start_error" not in first
    second = upload(server, drawing())
    assert second["state"] == "waiting", second
    assert server.client.post("/api/machine/home").status_code == 200
    done = server.wait_job(first["id"], ("done", "failed", "stopped", "interrupted"), 120)
    assert done["state"] == "done", done
    after = server.wait_job(second["id"], ("done", "failed", "stopped", "interrupted"), 120)
    assert after["state"] == "done", after
    assert after["started_at"] >= done["finished_at"]
    assert len(plotter.trace()["strokes"]) == 2 * 2  # each drawing: a square and a circle


def test_home_on_connect_and_park_after_the_job(plotter, tmp_path):
    extra = ["--home-on-connect", "--after-job", "park", "--park", "5,7"]
    with running_server(tmp_path / "data", ["--serial", str(plotter.port)], extra) as server:
        server.wait_machine(lambda m: m["state"] == "Idle", 60)  # homed without being asked
        job = upload(server, drawing())
        assert job["state"] == "running", job
        done = server.wait_job(job["id"], ("done", "failed", "stopped", "interrupted"), 120)
        assert done["state"] == "done", done
        machine = server.wait_machine(
            lambda m: m["state"] == "Idle" and abs(m["position"]["x"] - 5) < 0.02, 30)
        assert abs(machine["position"]["y"] - 7) < 0.02 and machine["pen"] == "up"
        trace = plotter.trace()
        assert abs(trace["position"]["x"] - 5) < 0.02 and trace["pen"] == "up"
        stay = upload(server, drawing(), after="none")  # the job's own choice wins
        server.wait_job(stay["id"], ("done",), 120)
        assert server.machine()["position"]["x"] > 10  # where the drawing ended (20, 20)
