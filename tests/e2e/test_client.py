"""`plotbridge.client.Plotbridge` against a real server driving the virtual plotter."""

from __future__ import annotations

import asyncio
from typing import Any

import pytest
from plotbridge.client import Plotbridge, PlotbridgeError, SetupError

from tests.fixtures.drawings import LONG
from tests.fixtures.server import running_server

SQUARE_SVG = b"""<svg xmlns="http://www.w3.org/2000/svg" width="40mm" height="40mm"
viewBox="0 0 40 40"><path d="M 5 5 L 35 5 L 35 35 L 5 35 Z" stroke="black" fill="none"/></svg>"""
@pytest.fixture
def pb(server_virtual):
    with Plotbridge(server_virtual.url, server_virtual.token) as client:
        yield client


@pytest.mark.e2e
def test_upload_in_memory_with_placement_start_wait_and_state(pb, server_virtual):
    server_virtual.home()
    job = pb.upload(SQUARE_SVG, filename="square.svg", paper="A5", dx=0)
    assert job["state"] == "queued" and job["format"] == "svg" and job["name"] == "square.svg"
    assert job["placement"]["paper"] == "A5"
    assert [j["id"] for j in pb.jobs()] == [job["id"]]
    seen: list[dict[str, Any]] = []
    pb.start(job["id"])
    done = pb.wait(job["id"], seen.append, timeout=120, poll=0.05)
    assert done["state"] == "done" and done["progress"] == 1
    assert seen[-1]["state"] == "done"
    progress = [j["progress"] for j in seen]
    assert progress == sorted(progress)
    machine = pb.machine()
    assert machine["state"] == "Idle" and machine["pen"] == "up"
    plotters = pb.plotters()
    assert len(plotters) >= 1 and plotters[0]["machine"]["connected"] is True
    strokes = pb.trace()["strokes"]
    assert len(strokes) == 1 and len(strokes[0]) >= 5  # the square, one closed stroke
    assert pb.server()["virtual"] is True and pb.health()


@pytest.mark.e2e
def test_upload_a_file_and_start_in_one_call(pb, server_virtual, tmp_path):
    server_virtual.home()
    drawing = tmp_path / "lines.svg"
    drawing.write_bytes(SQUARE_SVG)
    job = pb.upload(drawing, name="from disk", start=True, fit=True, paper="A6")
    assert job["name"] == "from disk" and job["state"] in ("running", "waiting", "done")
    assert pb.wait(job["id"], timeout=120, poll=0.05)["state"] == "done"


@pytest.mark.e2e
def test_events_pause_resume_and_emergency_stop(pb, server_virtual):
    server_virtual.home()
    job = pb.upload(LONG.encode(), filename="long.gcode", start=True)

    async def follow() -> list[str]:
        states: list[str] = []
        events = pb.events()
        async for event in events:
            if event["type"] != "job" or event["job"]["id"] != job["id"]:
                continue
            state = event["job"]["state"]
            if states and states[-1] == state:
                continue  # progress, not a transition: each transition is acted on once
            states.append(state)
            if state == "running" and "paused" not in states:
                await asyncio.to_thread(pb.pause)
            elif state == "paused":
                await asyncio.to_thread(pb.resume)
            elif state == "running" and "paused" in states:
                await asyncio.to_thread(pb.stop)
            elif state == "stopped":
                await events.aclose()
                return states
        return states

    states = asyncio.run(asyncio.wait_for(follow(), 120))
    assert states[-3:] == ["paused", "running", "stopped"], states
    assert pb.job(job["id"])["state"] == "stopped"


@pytest.mark.e2e
def test_errors_say_what_went_wrong(server_virtual, tmp_path, monkeypatch):
    with Plotbridge(server_virtual.url, "a-wrong-token-of-enough-length") as wrong:
        with pytest.raises(PlotbridgeError) as refused:
            wrong.jobs()
    assert refused.value.status == 401
    token_file = tmp_path / "token"
    token_file.write_text(server_virtual.token + "\n")
    monkeypatch.delenv("PLOTBRIDGE_TOKEN", raising=False)
    with Plotbridge(server_virtual.url, token_file=token_file) as pb:
        with pytest.raises(PlotbridgeError) as bad:
            pb.upload(b"G21\nG1 X10 Y10 F1000\nG1 X10 Q5\n", filename="bad.gcode")
        assert bad.value.status == 422 and "line 3" in str(bad.value)
        with pytest.raises(PlotbridgeError, match="no job is running"):
            pb.pause()
        with pytest.raises(PlotbridgeError) as missing:
            pb.job("no-such-job")
        assert missing.value.status == 404
        with pytest.raises(PlotbridgeError, match="no such file"):
            pb.upload(tmp_path / "absent.svg")
    with pytest.raises(SetupError, match="no token"):
        Plotbridge(server_virtual.url)
    with pytest.raises(SetupError, match="cannot read the token file"):
        Plotbridge(server_virtual.url, token_file=tmp_path / "nope")
    with Plotbridge("http://127.0.0.1:9", server_virtual.token) as nowhere:
        with pytest.raises(PlotbridgeError, match="cannot reach") as unreachable:
            nowhere.machine()
    assert unreachable.value.status is None


@pytest.mark.e2e
def test_plotters_and_a_job_on_a_named_plotter(tmp_path):
    link = ["--virtual", "2", "--sim-speed", "0"]
    with running_server(tmp_path / "data", link) as server, \
            Plotbridge(server.url, server.token) as pb:  # fmt: skip
        names = [p["name"] for p in pb.plotters()]
        assert names == ["plotter1", "plotter2"]
        server.wait_machine(lambda _: pb.machine("plotter2")["connected"], 60)
        assert pb.home("plotter2")["machine"]["state"] == "Idle"
        assert pb.machine("plotter1")["state"] == "Alarm"  # not homed: untouched
        job = pb.upload(SQUARE_SVG, filename="square.svg", plotter="plotter2")
        pb.start(job["id"], plotter="plotter2")
        assert pb.wait(job["id"], timeout=120, poll=0.05)["state"] == "done"
        assert len(pb.trace("plotter2")["strokes"]) == 1
        assert pb.trace("plotter1")["strokes"] == []
        with pytest.raises(PlotbridgeError) as unknown:
            pb.machine("plotter9")
        assert unknown.value.status == 404
