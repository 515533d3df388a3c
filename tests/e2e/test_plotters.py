"""Several plotters on one server: three virtual plotters (plotsim) behind one queue.

The simulators are the test's own (`plotter_factory`), so a test can stop one
and read each trace; the server drives them with `--serial` repeated. The
server's own `--virtual N` is checked too.
"""

from __future__ import annotations

import time

import pytest

from tests.fixtures.drawings import drawing
from tests.fixtures.server import ServerProcess, running_server
from tests.fixtures.trace import assert_no_step_after, assert_same_drawing, stop_clock

pytestmark = pytest.mark.e2e

NAMES = ("plotter1", "plotter2", "plotter3")
ENDED = ("done", "failed", "stopped", "interrupted", "cancelled")


@pytest.fixture
def three(plotter_factory, tmp_path):
    """Three simulators at twice real time (jobs overlap on a busy machine) and a server."""
    plotters = [plotter_factory(speed=2) for _ in NAMES]
    serial = [arg for p in plotters for arg in ("--serial", str(p.port))]
    with running_server(tmp_path / "server-data", serial) as server:
        for name in NAMES:
            home(server, name)
        for plotter in plotters:
            plotter.clear()
        yield server, dict(zip(NAMES, plotters, strict=True))


def home(server: ServerProcess, name: str) -> None:
    server.wait_plotter(name, lambda m: m["connected"], 30)
    response = server.client.post(f"/api/plotters/{name}/machine/home", timeout=130)
    assert response.status_code == 200, response.text
    server.wait_plotter(name, lambda m: m["state"] == "Idle", 30)


def upload(server: ServerProcess, gcode: str, **fields: str) -> dict:
    response = server.client.post(
        "/api/jobs", files={"file": ("drawing.gcode", gcode)}, data={"start": "true", **fields}
    )
    assert response.status_code == 201, response.text
    return response.json()


def test_three_at_once_then_the_fourth_when_one_frees(three):
    server, sims = three
    jobs = [upload(server, drawing(circles=3 + index)) for index in range(3)]
    fourth = upload(server, drawing(circles=1))
    assert sorted(job["plotter"] for job in jobs) == list(NAMES)
    assert all(job["state"] == "running" for job in jobs)
    assert fourth["state"] == "waiting" and "runs job" in fourth["waiting"], fourth
    assert [server.job(job["id"])["state"] for job in jobs] == ["running"] * 3  # at once
    finished = [server.wait_job(job["id"], ENDED, 180) for job in jobs]
    assert [job["state"] for job in finished] == ["done"] * 3, finished
    last = server.wait_job(fourth["id"], ENDED, 180)
    assert last["state"] == "done" and last["plotter"] in NAMES, last
    drawn_by: dict[str, list] = {name: [] for name in NAMES}
    for job in [*finished, last]:
        drawn_by[job["plotter"]] += server.preview(job["id"])["strokes"]
    for name, expected in drawn_by.items():
        assert_same_drawing(expected, sims[name].trace()["strokes"])


def test_estop_on_one_leaves_the_others_and_estop_all_stops_all(three):
    server, sims = three
    jobs = {name: upload(server, drawing(circles=12), plotter=name) for name in NAMES}
    for job in jobs.values():
        server.wait_progress(job["id"], 40, 60)
    stopped = server.client.post("/api/plotters/plotter2/machine/estop")
    assert stopped.status_code == 202
    assert server.wait_job(jobs["plotter2"]["id"], ("stopped",), 5)["plotter"] == "plotter2"
    for name in ("plotter1", "plotter3"):
        before = server.job(jobs[name]["id"])["lines_done"]
        server.wait_progress(jobs[name]["id"], before + 20, 60)  # still plotting
    sent = {name: stop_clock(sim) for name, sim in sims.items()}
    assert server.client.post("/api/estop").status_code == 202
    for name in ("plotter1", "plotter3"):
        assert server.wait_job(jobs[name]["id"], ("stopped",), 5)["state"] == "stopped"
    time.sleep(0.3)  # a window in which nothing may move
    for name, sim in sims.items():
        trace = sim.trace()
        if name != "plotter2":
            assert_no_step_after(sim, sent[name], trace)
        time.sleep(0.2)
        assert sim.trace()["steps"] == trace["steps"], f"{name} still moves"


def test_a_plotter_that_drops_out_interrupts_only_its_job_which_resumes(three):
    server, sims = three
    jobs = {name: upload(server, drawing(circles=8), plotter=name) for name in NAMES}
    for job in jobs.values():
        server.wait_progress(job["id"], 100, 60)
    sims["plotter2"].stop()
    interrupted = server.wait_job(jobs["plotter2"]["id"], ("interrupted",), 20)
    assert interrupted["resume_line"] and interrupted["plotter"] == "plotter2"
    assert {server.job(jobs[n]["id"])["state"] for n in ("plotter1", "plotter3")} == {"running"}
    before = sims["plotter2"].trace()
    sims["plotter2"].restart(start=(before["position"]["x"], before["position"]["y"]))
    home(server, "plotter2")  # a board that comes back is homed before it resumes
    resumed = server.client.post(f"/api/jobs/{jobs['plotter2']['id']}/resume")
    assert resumed.status_code == 200, resumed.text
    assert resumed.json()["plotter"] == "plotter2"
    for job in jobs.values():
        assert server.wait_job(job["id"], ENDED, 180)["state"] == "done"
    expected = server.preview(jobs["plotter2"]["id"])["strokes"]
    assert_same_drawing(expected, before["strokes"] + sims["plotter2"].trace()["strokes"])


def test_virtual_n_runs_n_simulators(tmp_path):
    args = ["--virtual", "2", "--sim-speed", "0"]
    with running_server(tmp_path / "server-data", args) as server:
        listed = server.client.get("/api/plotters").json()
        assert [(p["name"], p["virtual"]) for p in listed] == [(n, True) for n in NAMES[:2]]
        home(server, "plotter2")
        answer = server.client.post(
            "/api/plotters/plotter2/machine/command", json={"line": "G0 X5 Y7"}
        )
        assert answer.json() == {"responses": ["ok"]}
        server.wait_plotter("plotter2", lambda m: m["position"] == {"x": 5.0, "y": 7.0}, 10)
        assert server.machine()["position"] == {"x": 0.0, "y": 0.0}  # /api/machine: plotter1
        trace = server.client.get("/api/plotters/plotter2/sim/trace").json()
        assert trace["position"]["x"] == pytest.approx(5.0, abs=0.05)
        missing = server.client.get("/api/plotters/nope/machine")
        assert missing.status_code == 404 and "plotter1" in missing.json()["detail"]
