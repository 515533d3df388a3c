"""Several plotters behind one queue: the API around three scripted fake links."""

from __future__ import annotations

from types import SimpleNamespace

import pytest
from plotbridge.app import Board, create_app
from plotbridge.config import Config, PlotterConfig
from plotbridge.jobs.imports import Importer
from plotbridge.plotter.plotter import WorkArea

from tests.fixtures.fake_app import TOKEN, FakeLink, fake_import, serving, upload
from tests.fixtures.waits import settle

NAMES = ("a", "b", "c")


@pytest.fixture
async def farm(tmp_path, monkeypatch):
    monkeypatch.setattr(Importer, "_import", fake_import)
    links = {name: FakeLink(f"/dev/{name}") for name in NAMES}
    boards = [Board(name, links[name]) for name in NAMES[:2]]
    boards.append(Board("c", links["c"], work_area=WorkArea(10, 10)))  # too small for the jobs
    config = Config(data_dir=tmp_path,
                    plotters=[PlotterConfig(n, f"/dev/{n}") for n in NAMES],
                    allowed_hosts=("test",))  # fmt: skip
    app = create_app(config, boards, TOKEN)
    async with serving(app) as client:
        yield SimpleNamespace(client=client, links=links, queue=app.state.components.queue)


async def test_jobs_go_to_free_plotters_that_fit_and_wait_in_order(farm):
    jobs = [(await upload(farm.client, start="true")).json() for _ in range(3)]
    assert [job["plotter"] for job in jobs[:2]] == ["a", "b"]
    assert jobs[2]["state"] == "waiting" and "work area" in jobs[2]["waiting"]
    listed = (await farm.client.get("/api/plotters")).json()
    assert [(p["name"], p["job"]) for p in listed] == [
        ("a", jobs[0]["id"]), ("b", jobs[1]["id"]), ("c", None)]
    assert listed[2]["work_area"] == {"width": 10, "height": 10}
    # each carries its job's actions, the lifecycle's (the same list as the job's own)
    running = (await farm.client.get(f"/api/jobs/{jobs[0]['id']}")).json()
    assert listed[0]["actions"] == running["actions"] == ["hold", "stop", "cancel"]
    assert listed[2]["actions"] == []
    await farm.client.post(f"/api/jobs/{jobs[0]['id']}/hold")
    held = (await farm.client.get("/api/plotters")).json()[0]
    assert held["actions"] == farm.queue.jobs[jobs[0]["id"]].actions
    assert "continue" in held["actions"]
    await farm.client.post(f"/api/jobs/{jobs[0]['id']}/continue")
    farm.links["b"].auto_ack = True
    farm.links["b"].step()
    await settle(lambda: farm.queue.jobs[jobs[2]["id"]].state == "done")  # started by itself
    assert farm.queue.jobs[jobs[1]["id"]].state == "done"
    assert farm.queue.jobs[jobs[2]["id"]].plotter == "b"  # where it fits, once free
    assert farm.queue.jobs[jobs[0]["id"]].state == "running"


async def test_a_named_plotter_is_used_or_waited_for(farm):
    first = (await upload(farm.client, start="true", plotter="b")).json()
    assert first["plotter"] == "b" and first["target"] == "b"
    second = (await upload(farm.client, plotter="b")).json()
    started = await farm.client.post(f"/api/jobs/{second['id']}/start")
    assert started.json()["state"] == "waiting" and "runs job" in started.json()["waiting"]
    assert farm.links["a"].streamed == []  # a was free, but b was asked for
    unknown = await farm.client.post(f"/api/jobs/{second['id']}/start?plotter=zz")
    assert unknown.status_code == 404 and "zz" in unknown.json()["detail"]
    refused = await upload(farm.client, plotter="zz")
    assert refused.status_code == 404


async def test_estop_one_leaves_the_others_and_estop_all_stops_all(farm):
    jobs = [(await upload(farm.client, start="true")).json() for _ in range(2)]
    response = await farm.client.post("/api/plotters/a/machine/estop")
    assert response.status_code == 202
    assert [link.estop_calls for link in farm.links.values()] == [1, 0, 0]
    assert farm.queue.jobs[jobs[0]["id"]].state == "stopped"
    assert farm.queue.jobs[jobs[1]["id"]].state == "running"
    assert (await farm.client.post("/api/estop")).status_code == 202
    assert [link.estop_calls for link in farm.links.values()] == [2, 1, 1]
    assert farm.queue.jobs[jobs[1]["id"]].state == "stopped"


async def test_interrupted_job_resumes_on_a_plotter_of_the_same_size(farm):
    from plotbridge.plotter.link import StreamAborted

    job = (await upload(farm.client, start="true", plotter="a")).json()
    await settle(lambda: farm.links["a"].status.state == "Run")  # streaming
    farm.links["a"].abort(StreamAborted("disconnected", 0, None, "link lost"))
    farm.links["a"].step()
    await settle(lambda: farm.queue.jobs[job["id"]].state == "interrupted")
    small = await farm.client.post(f"/api/jobs/{job['id']}/resume?plotter=c")
    assert small.status_code == 409 and "work area" in small.json()["detail"]
    farm.links["b"].auto_ack = True
    moved = await farm.client.post(f"/api/jobs/{job['id']}/resume?plotter=b")
    assert moved.status_code == 200 and moved.json()["plotter"] == "b"
    await settle(lambda: farm.queue.jobs[job["id"]].state == "done")


async def test_machine_verbs_per_plotter(farm):
    await farm.client.post("/api/plotters/b/machine/pen", json={"down": True})
    await farm.client.post("/api/machine/unlock")  # the first plotter
    assert farm.links["b"].commands == ["M3"] and farm.links["a"].commands == ["$X"]
    missing = await farm.client.get("/api/plotters/zz/machine")
    assert missing.status_code == 404
