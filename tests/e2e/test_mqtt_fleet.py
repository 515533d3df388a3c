"""End to end: two bridges on one Mosquitto, one virtual plotter each (the real firmware in
the simulator): the fleet view, STOP EVERYTHING across bridges, the fleet queue
(exactly once; a bridge that dies before starting gives the job back)."""

from __future__ import annotations

import json
import os
import signal

import pytest

from tests.fixtures.cli import run_cli
from tests.fixtures.drawings import drawing
from tests.fixtures.mqtt_bridges import bridge_server
from tests.fixtures.waits import wait_until

pytestmark = pytest.mark.e2e

ACCEPT = ("--mqtt-accept", "stop,hold,continue,home,start")


@pytest.fixture
def two_bridges(broker, tmp_path):
    started = []
    try:
        for name, speed in (("A", "1"), ("B", "0")):
            started.append(bridge_server(tmp_path / name, ["--virtual", "--sim-speed", speed],
                                         broker, name, *ACCEPT))
        for server in started:
            server.home()
        yield started
    finally:
        for server in started:
            server.close()


def fleet(server) -> dict:
    return server.client.get("/api/fleet", timeout=15).json()


def fleet_plotters(server) -> set[tuple[str, str]]:
    return {(b["bridge"], p["name"]) for b in fleet(server)["bridges"] for p in b["plotters"]}


def fleet_upload(server, gcode: str, name: str) -> dict:
    response = server.client.post("/api/jobs", files={"file": (f"{name}.gcode", gcode)},
                                  data={"fleet": "true", "name": name})  # fmt: skip
    assert response.status_code == 201, response.text
    return response.json()


def jobs_named(server, name: str) -> list[dict]:
    return [j for j in server.client.get("/api/jobs", timeout=15).json() if j["name"] == name]


def fleet_job(server, job_id: str) -> dict:
    return next(j for j in fleet(server)["jobs"] if j["id"] == job_id)


def test_each_bridge_sees_the_fleet_and_stop_everything_reaches_the_other(two_bridges):
    a, b = two_bridges
    both = {("A", "plotter1"), ("B", "plotter1")}
    for server in (a, b):
        wait_until(lambda s=server: fleet_plotters(s), lambda seen: seen == both, 20,
                   "both plotters in the fleet view")
    job = a.submit(drawing(circles=20))  # A plots in real time
    a.wait_progress(job["id"], 40, timeout=60)
    response = b.client.post("/api/fleet/estop")
    assert response.status_code == 202 and response.json()["fleet"] is True
    assert a.wait_job(job["id"], ("stopped",), 10)["state"] == "stopped"
    a.wait_machine(lambda m: m["state"] == "Alarm", 10)
    wait_until(lambda: fleet(b)["bridges"], lambda bridges: any(
        p["state"] == "Alarm" for br in bridges if br["bridge"] == "A" for p in br["plotters"]),
        10, "B's fleet view shows A's plotter in Alarm")


def test_fleet_job_plots_once_on_the_free_bridge(two_bridges):
    a, b = two_bridges
    busy = a.submit(drawing(circles=20))  # real time: A stays busy for a while
    a.wait_progress(busy["id"], 20, timeout=60)
    path = a.data_dir.parent / "fleet-once.gcode"
    path.write_text(drawing(circles=2))
    submitted = run_cli(a, "submit", str(path), "--name", "fleet-once", "--fleet", "--wait",
                        "--json")  # follows the fleet job until it has settled where it ran
    assert submitted.returncode == 0, submitted.stderr
    answer = json.loads(submitted.stdout)
    assert answer["fleet"]["state"] == "done" and answer["fleet"]["bridge"] == "B"
    done = jobs_named(b, "fleet-once")
    assert len(done) == 1 and done[0]["state"] == "done", done
    assert not jobs_named(a, "fleet-once"), "the fleet held the job, not A's queue"
    placed = fleet_job(a, answer["fleet"]["id"])
    assert placed["bridge"] == "B" and placed["state"] == "committed" and placed["settled"]
    assert placed["job_state"] == "done" and placed["progress"] == 1.0


def test_bridge_killed_before_starting_gives_the_job_back(two_bridges, broker):
    a, b = two_bridges
    busy = a.submit(drawing(circles=3))
    a.wait_progress(busy["id"], 10, timeout=60)
    spy = broker.listener("intruder", ("plotbridge/default/B/grant", "plotbridge/default/A/claim"))
    try:
        offered = fleet_upload(a, drawing(circles=2), "fleet-back")
        spy.wait(lambda s: any(t.endswith("/B/grant") and b'"grant"' in p
                               for _, t, p, _ in s.messages), 30, "A's grant to B")
        assert b.proc is not None
        os.kill(b.proc.pid, signal.SIGSTOP)  # B has the file; it has not answered "taken"
        assert not any(b'"taken"' in p for _, t, p, _ in spy.messages), "B took it already"
        b.kill()
    finally:
        spy.close()
    done = wait_until(lambda: jobs_named(a, "fleet-back"), lambda jobs: jobs and all(
        j["state"] == "done" for j in jobs), 120, "the job given back, plotted on A")
    assert len(done) == 1
    assert fleet_job(a, offered["id"])["bridge"] == "A"
