"""Pen changes between a job's layers: the real app around the scripted fake link."""

from __future__ import annotations

from plotbridge.jobs.imports import Importer

from tests.fixtures.fake_app import layered_import, layered_program, make_app, serving, upload
from tests.fixtures.waits import settle


async def test_pen_change_parks_prompts_and_continues(tmp_path, monkeypatch):
    monkeypatch.setattr(Importer, "_import", layered_import)
    program, layers = layered_program()
    app, link = make_app(tmp_path, park=(2.0, 3.0))
    link.auto_ack = True
    async with serving(app) as client:
        queue = app.state.components.queue
        job = (await upload(client, start="true")).json()
        await settle(lambda: queue.jobs[job["id"]].state == "pen_change")
        changing = (await client.get(f"/api/jobs/{job['id']}")).json()
        prompt = changing["pen_change"]
        assert prompt["layer"] == 2 and prompt["layers"] == 3 and prompt["name"] == "b"
        assert prompt["message"] == "Layer 2 of 3, 'b': load its pen, then continue"  # no code
        first_m0 = layers[1]["first_line"] - 1
        assert [n for n, _ in link.streamed] == list(range(1, first_m0))  # not the M0
        assert link.commands == ["M5", "G0 X2.000 Y3.000", "G4 P0"]  # pen up, parked
        assert changing["lines_done"] == first_m0
        # nothing else may take the plotter meanwhile
        other = (await upload(client, start="true")).json()
        assert other["state"] == "waiting"

        resumed = await client.post(f"/api/jobs/{job['id']}/resume")  # the UI's Continue
        assert resumed.status_code == 200 and resumed.json()["state"] == "running"
        await settle(lambda: queue.jobs[job["id"]].state == "pen_change")
        assert queue.jobs[job["id"]].pen_change["layer"] == 3
        link.set_state("Idle", pins="S")  # the board's resume button
        await settle(lambda: queue.jobs[job["id"]].state == "done")
        m0s = {layer["first_line"] - 1 for layer in layers[1:]}
        back = 4  # after each change, pen up (M5 G21 G90) and back to where the layer ended
        mine = link.streamed[: len(program) - len(m0s) + back * len(m0s)]
        assert [n for n, _ in mine if n] == [n for n in range(1, len(program) + 1) if n not in m0s]
        travels = [text for n, text in mine if n == 0]
        assert travels[back - 1::back] == ["G0X5Y0", "G0X15Y0"], travels
        assert queue.jobs[job["id"]].pen_change is None
        await settle(lambda: queue.jobs[other["id"]].state == "pen_change")  # the next job


async def test_stop_during_a_pen_change_makes_the_job_resumable(tmp_path, monkeypatch):
    monkeypatch.setattr(Importer, "_import", layered_import)
    app, link = make_app(tmp_path)
    link.auto_ack = True
    async with serving(app) as client:
        queue = app.state.components.queue
        job = (await upload(client, start="true")).json()
        await settle(lambda: queue.jobs[job["id"]].state == "pen_change")
        assert (await client.post("/api/machine/estop")).status_code == 202
        await settle(lambda: queue.first.job is None and queue.first.runner.busy is None)
        stopped = queue.jobs[job["id"]]
        assert stopped.state == "stopped" and stopped.resume_line is not None


def test_the_progress_label_shows_the_pen_change_prompt():
    from plotbridge.progress import describe

    job = {"state": "pen_change", "pen_change": {"message": "Layer 2 of 3, 'b': load its pen"}}
    assert describe("d.svg", job) == "d.svg [pen_change]: Layer 2 of 3, 'b': load its pen"
    assert describe("d.svg", {"state": "waiting", "waiting": "plotter1 is in Alarm"}).endswith(
        ": plotter1 is in Alarm")
    assert describe("d.svg", {"state": "running"}) == "d.svg [running]"
