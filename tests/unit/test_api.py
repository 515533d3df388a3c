"""API unit tests: the real app around a scripted fake link and a fake importer."""

from __future__ import annotations

import asyncio
import json
import threading
import time
from types import SimpleNamespace

import httpx
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from plotbridge.jobs.imports import Importer
from plotbridge.plotter.stoppoint import MARK_FILE
from plotbridge.resume import Mark, ResumePoint
from plotbridge.upload import parse_upload_fields
from starlette.testclient import TestClient
from starlette.websockets import WebSocketDisconnect

from tests.fixtures.fake_app import AUTH, TOKEN, fake_import, make_app, serving, upload
from tests.fixtures.waits import settle


@pytest.fixture
async def api(tmp_path, monkeypatch):
    monkeypatch.setattr(Importer, "_import", fake_import)
    app, link = make_app(tmp_path, max_upload_mb=1)
    async with serving(app) as client:
        queue = app.state.components.queue
        yield SimpleNamespace(app=app, link=link, client=client, queue=queue)


# ---- auth -----------------------------------------------------------------------


async def test_health_needs_no_token(api):
    response = await api.client.get("/api/health", headers={"Authorization": ""})
    assert response.json() == {"status": "ok"}


@pytest.mark.parametrize("header", ["", "Bearer wrong", "Basic dGVzdA==", f"Bearer {TOKEN}x"])
async def test_wrong_token_is_401(api, header):
    for path in ("/api/jobs", "/api/machine", "/api/server"):
        response = await api.client.get(path, headers={"Authorization": header})
        assert response.status_code == 401
        assert "token" in response.json()["detail"]


async def test_login_sets_httponly_strict_cookie(api):
    bad = await api.client.post("/api/login", json={"token": "nope"})
    assert bad.status_code == 401
    response = await api.client.post("/api/login", json={"token": TOKEN})
    assert response.status_code == 204
    cookie = response.headers["set-cookie"].lower()
    assert "httponly" in cookie and "samesite=strict" in cookie
    session = response.cookies["plotbridge_session"]
    transport = httpx.ASGITransport(app=api.app)
    async with httpx.AsyncClient(transport=transport, base_url="http://test") as browser:
        ok = await browser.get("/api/jobs", headers={"Cookie": f"plotbridge_session={session}"})
        assert ok.status_code == 200
        forged = await browser.get("/api/jobs", headers={"Cookie": "plotbridge_session=abc"})
        assert forged.status_code == 401


async def test_login_link_redirects_with_cookie(api):
    response = await api.client.get(f"/login?token={TOKEN}")
    assert response.status_code == 303 and response.headers["location"] == "/"
    assert "plotbridge_session" in response.cookies
    assert (await api.client.get("/login?token=bad")).status_code == 401


async def test_no_cors_headers(api):
    response = await api.client.options(
        "/api/jobs",
        headers={"Origin": "http://evil.example", "Access-Control-Request-Method": "POST"},
    )
    assert "access-control-allow-origin" not in response.headers


# ---- bad input ------------------------------------------------------------------


async def test_malformed_json_is_422(api):
    response = await api.client.post(
        "/api/machine/jog", content=b"{not json", headers={"Content-Type": "application/json"}
    )
    assert response.status_code == 422 and "detail" in response.json()
    response = await api.client.post("/api/machine/pen", json={"down": "sideways"})
    assert response.status_code == 422
    response = await api.client.post("/api/machine/jog", json={"dx": 1, "feed": -5})
    assert response.status_code == 422


async def test_unknown_job_is_404(api):
    for method, path in [
        ("GET", "/api/jobs/nope"), ("POST", "/api/jobs/nope/start"),
        ("POST", "/api/jobs/nope/cancel"), ("DELETE", "/api/jobs/nope"),
        ("GET", "/api/jobs/nope/preview"), ("POST", "/api/jobs/nope/pause"),
    ]:  # fmt: skip
        response = await api.client.request(method, path)
        assert response.status_code == 404, path
        assert "nope" in response.json()["detail"]


async def test_empty_upload_is_refused(api):
    response = await upload(api.client, "")
    assert response.status_code == 422
    assert response.json()["detail"]["errors"][0]["message"] == "the upload is empty"
    raw = await api.client.post("/api/jobs?name=x", content=b"   \n")
    assert raw.status_code == 422


async def test_binary_upload_is_415(api):
    response = await api.client.post(
        "/api/jobs", files={"file": ("a.gcode", b"\x89PNG\r\n\x1a\n\x00\x00\x00")}
    )
    assert response.status_code == 415
    assert "binary" in response.json()["detail"]["errors"][0]["message"]


async def test_too_large_upload_is_413_and_keeps_nothing(api, tmp_path):
    big = "G1 X1 Y1\n" * (1024 * 1024 // 9 + 100)
    response = await upload(api.client, big)
    assert response.status_code == 413
    raw = await api.client.post("/api/jobs?name=big", content=big.encode())
    assert raw.status_code == 413
    assert list((tmp_path / "tmp").iterdir()) == []
    assert (await api.client.get("/api/jobs")).json() == []


async def test_invalid_upload_is_422_with_lines_and_keeps_nothing(api, tmp_path):
    response = await upload(api.client, "G1 X1\nG1 X2\nINVALID\n")
    assert response.status_code == 422
    assert response.json() == {"detail": {"errors": [{"line": 3, "message": "unknown command"}]}}
    assert [p.name for p in (tmp_path / "jobs").iterdir()] == []
    assert (await api.client.get("/api/jobs")).json() == []


async def test_bad_placement_field_is_422(api):
    response = await upload(api.client, rotate="45")
    assert response.status_code == 422
    assert "rotate" in response.json()["detail"]["errors"][0]["message"]
    response = await upload(api.client, start="maybe")
    assert response.status_code == 422


async def test_missing_file_is_422(api):
    response = await api.client.post("/api/jobs", data={"name": "x"})
    assert response.status_code == 422
    assert "file" in response.json()["detail"]["errors"][0]["message"]


def test_parse_upload_fields():
    options, placement, start = parse_upload_fields(
        {"paper": "A4-landscape", "fit": "true", "rotate": "90", "layers": "a, b", "start": "1"}
    )
    assert options["paper"] == "A4-landscape" and options["fit"] is True
    assert options["rotate"] == 90 and options["layers"] == ["a", "b"] and start is True
    assert "layers" not in placement
    with pytest.raises(ValueError, match="paper"):
        parse_upload_fields({"paper": "A0"})


# ---- jobs -------------------------------------------------------------------------


async def test_upload_keeps_original_under_generated_name(api, tmp_path):
    response = await api.client.post(
        "/api/jobs", files={"file": ("../../etc/evil name.gcode", "G1 X1\n")}
    )
    assert response.status_code == 201
    job = response.json()
    assert job["state"] == "queued" and job["lines_total"] == 20 and job["name"]
    files = sorted(p.name for p in (tmp_path / "jobs" / job["id"]).iterdir())
    assert files == ["original.gcode", "preview.json", "program.gcode"]
    preview = await api.client.get(f"/api/jobs/{job['id']}/preview")
    assert preview.json()["strokes"] == [[[0, 0], [1, 0]]]


async def test_upload_with_start(api):
    started = (await upload(api.client, start="true")).json()
    assert started["state"] == "running" and "start_error" not in started
    waiting = (await upload(api.client, start="1")).json()
    assert waiting["state"] == "waiting" and started["id"] in waiting["waiting"]
    assert "start_error" not in waiting
    api.link.auto_ack = True
    api.link.step()
    await settle(lambda: api.queue.jobs[waiting["id"]].state == "done")  # by itself, after it
    assert api.queue.jobs[started["id"]].finished_at <= api.queue.jobs[waiting["id"]].started_at


async def test_upload_refuses_an_unknown_after_action(api):
    response = await upload(api.client, after="dance")
    assert response.status_code == 422
    assert "after" in response.json()["detail"]["errors"][0]["message"]


async def test_raw_body_upload(api):
    response = await api.client.post("/api/jobs?name=raw%20one", content=b"G1 X1 Y1\n")
    assert response.status_code == 201 and response.json()["name"] == "raw one"


async def test_start_runs_to_done(api):
    job = (await upload(api.client)).json()
    api.link.auto_ack = True
    response = await api.client.post(f"/api/jobs/{job['id']}/start")
    assert response.status_code == 200 and response.json()["state"] == "running"
    await settle(lambda: api.queue.jobs[job["id"]].state == "done")
    done = (await api.client.get(f"/api/jobs/{job['id']}")).json()
    assert done["lines_done"] == 20 and done["progress"] == 1.0 and done["eta_s"] == 0
    assert [n for n, _ in api.link.streamed] == list(range(1, 21))


async def test_start_waits_for_the_machine(api):
    first = (await upload(api.client)).json()
    second = (await upload(api.client)).json()
    api.link.set_state("Alarm", alarm=1)
    response = await api.client.post(f"/api/jobs/{first['id']}/start")
    assert response.status_code == 200
    assert response.json()["state"] == "waiting" and "$X" in response.json()["waiting"]
    api.link.status.connected = False
    response = await api.client.post(f"/api/jobs/{second['id']}/start")
    assert response.json()["state"] == "waiting" and "not connected" in response.json()["waiting"]
    again = await api.client.post(f"/api/jobs/{first['id']}/start")  # it waits already
    assert again.status_code == 409 and again.json()["detail"]["state"] == "waiting"
    assert again.json()["detail"]["actions"] == ["cancel", "frame", "move", "delete"]
    api.link.status.connected = True
    api.link.set_state("Idle", alarm=None)  # e.g. homed: the first in queue order starts
    assert api.queue.jobs[first["id"]].state == "running"
    assert api.queue.jobs[second["id"]].state == "waiting"
    assert first["id"] in api.queue.jobs[second["id"]].waiting
    assert (await api.client.delete(f"/api/jobs/{first['id']}")).status_code == 409
    assert (await api.client.post("/api/machine/jog", json={"dx": 1})).status_code == 409
    response = await api.client.post("/api/machine/command", json={"line": "G0 X1"})
    assert response.status_code == 409
    cancelled = await api.client.post(f"/api/jobs/{second['id']}/cancel")
    assert cancelled.json()["state"] == "cancelled"


async def test_a_job_too_large_for_the_work_area_is_refused(api):
    job = (await upload(api.client)).json()
    api.link.settings[130] = 10.0  # the fake program is 15 mm wide
    response = await api.client.post(f"/api/jobs/{job['id']}/start")
    assert response.status_code == 409 and "work area" in response.json()["detail"]
    assert api.queue.jobs[job["id"]].state == "queued"


@pytest.mark.parametrize(("action", "expected"), [
    ("park", ["M5", "G0 X5.000 Y7.500", "G4 P0"]), ("home", ["M5", "$H"]), ("none", [])])
async def test_after_the_job(tmp_path, monkeypatch, action, expected):
    monkeypatch.setattr(Importer, "_import", fake_import)
    app, link = make_app(tmp_path, after_job="home", park=(5.0, 7.5))
    link.auto_ack = True
    async with serving(app) as client:
        queue = app.state.components.queue
        first = (await upload(client, start="true", after=action)).json()
        second = (await upload(client, start="true")).json()  # the server's default: home
        await settle(lambda: queue.jobs[second["id"]].state == "done")
        assert queue.jobs[first["id"]].after == action
        assert link.commands == [*expected, "M5", "$H"]  # the second waited for the first's


async def test_home_on_connect_homes_a_plotter_in_alarm(tmp_path, monkeypatch):
    monkeypatch.setattr(Importer, "_import", fake_import)
    app, link = make_app(tmp_path, home_on_connect=True)
    async with serving(app) as client:
        link.status.state = "Alarm"
        link.emit("connected")
        link.set_state("Alarm")
        await settle(lambda: link.commands == ["$H"])
        link.set_state("Idle")
        job = (await upload(client, start="true")).json()
        assert job["state"] == "running"
        link.emit("connected")  # connected in Idle: no homing
        link.set_state("Idle")
        await asyncio.sleep(0.1)
        assert link.commands == ["$H"]


async def test_estop_stops_running_job_at_last_ack(api):
    job = (await upload(api.client)).json()
    await api.client.post(f"/api/jobs/{job['id']}/start")
    for n in range(1, 6):
        api.link.step()
        await settle(lambda n=n: api.queue.jobs[job["id"]].lines_acked == n, within=10.0)
    response = await api.client.post("/api/machine/estop")
    assert response.status_code == 202
    assert api.link.estop_calls == 1
    stopped = (await api.client.get(f"/api/jobs/{job['id']}")).json()
    assert stopped["state"] == "stopped" and stopped["lines_done"] <= 5  # never ahead of acks
    assert stopped["resume_line"] is not None and stopped["resume_line"] <= 6
    assert (await api.client.get("/api/machine")).json()["state"] == "Alarm"


async def test_the_stop_point_is_the_first_report_after_the_resets_banner(api, tmp_path):
    job = (await upload(api.client)).json()
    await api.client.post(f"/api/jobs/{job['id']}/start")
    for n in range(1, 4):
        api.link.step()
        await settle(lambda n=n: api.queue.jobs[job["id"]].lines_acked == n)
    api.link.set_state("Run", x=1.0, y=0.0)
    await api.client.post("/api/machine/estop")
    await settle(lambda: api.queue.jobs[job["id"]].state == "stopped")
    api.link.awaiting_banner = True
    api.link.set_state("Alarm", x=2.0, y=0.0)  # sent before the reset, read after it
    api.link.awaiting_banner = False
    api.link.set_state("Alarm", x=3.0, y=0.0)  # the first one after the banner: kept
    api.link.set_state("Alarm", x=4.0, y=0.0)  # later ones are not the stop point
    mark = tmp_path / "jobs" / job["id"] / MARK_FILE
    await settle(lambda: (m := Mark.load(mark)) is not None and m.x == 3.0)


async def test_a_resume_starts_from_the_stop_point_while_its_write_is_slow(api, monkeypatch):
    import plotbridge.plotter.stoppoint as stoppoint

    job = (await upload(api.client)).json()
    await api.client.post(f"/api/jobs/{job['id']}/start")
    api.link.step()
    await settle(lambda: api.queue.jobs[job["id"]].lines_acked == 1)
    api.link.set_state("Run", x=1.0, y=0.0)
    await api.client.post("/api/machine/estop")
    await settle(lambda: api.queue.jobs[job["id"]].state == "stopped")
    save, located = Mark.save, []

    def busy_disk(mark: Mark, path) -> None:
        time.sleep(0.5)  # the write of the stop point lands after the resume asked
        save(mark, path)

    monkeypatch.setattr(Mark, "save", busy_disk)
    monkeypatch.setattr(stoppoint, "locate", lambda program, mark: located.append(mark)
                        or ResumePoint(1))  # fmt: skip
    api.link.set_state("Alarm", x=3.0, y=0.0)  # the stop point, told at once
    api.link.set_state("Idle")  # unlocked
    api.link.auto_ack = True
    assert (await api.client.post(f"/api/jobs/{job['id']}/resume")).status_code == 200
    await settle(lambda: located)
    assert located[0] is not None and located[0].x == 3.0, located


async def test_estop_does_not_wait_for_a_stuck_disk(api, monkeypatch):
    job = (await upload(api.client)).json()
    await api.client.post(f"/api/jobs/{job['id']}/start")
    api.link.step()
    disk = threading.Event()
    monkeypatch.setattr(api.queue.store, "write", lambda *_: disk.wait(10))
    api.queue.store.save(api.queue.jobs[job["id"]], 0)  # the store's one thread is now stuck
    began = time.monotonic()
    response = await api.client.post("/api/machine/estop")
    took = time.monotonic() - began
    disk.set()
    assert response.status_code == 202 and api.link.estop_calls == 1
    assert took < 0.5, f"the stop waited {took:.2f} s"
    assert api.queue.jobs[job["id"]].state == "stopped"


async def test_program_unreadable_mid_job_fails_it_and_stops_the_board(api, monkeypatch):
    import plotbridge.program.reader as reader

    def unreadable(file, count):
        raise OSError(5, "Input/output error")

    monkeypatch.setattr(reader, "_read_block", unreadable)
    job = (await upload(api.client)).json()
    await api.client.post(f"/api/jobs/{job['id']}/start")
    await settle(lambda: api.queue.jobs[job["id"]].state == "failed")
    assert "Input/output error" in api.queue.jobs[job["id"]].error
    await settle(lambda: "M5" in api.link.commands)  # hold, reset, pen up
    assert api.link.realtime_bytes == [b"!"] and api.link.estop_calls == 1
    assert api.queue.first.job is None


async def test_estop_when_idle_is_accepted(api):
    assert (await api.client.post("/api/machine/estop")).status_code == 202
    assert api.link.estop_calls == 1


async def test_pause_resume_cancel(api):
    job = (await upload(api.client)).json()
    jid = job["id"]
    await api.client.post(f"/api/jobs/{jid}/start")
    assert (await api.client.post(f"/api/jobs/{jid}/resume")).status_code == 409
    assert (await api.client.post(f"/api/jobs/{jid}/pause")).json()["state"] == "paused"
    assert api.link.realtime_bytes == [b"!"]
    assert (await api.client.post(f"/api/jobs/{jid}/resume")).json()["state"] == "running"
    assert api.link.realtime_bytes == [b"!", b"~"]
    response = await api.client.post(f"/api/jobs/{jid}/cancel")
    assert response.status_code == 200 and response.json()["state"] == "cancelled"
    assert api.link.realtime_bytes == [b"!", b"~", b"!"]
    assert api.link.estop_calls == 1 and api.link.commands[-2:] == ["$X", "M5"]
    assert (await api.client.post(f"/api/jobs/{jid}/cancel")).status_code == 409


async def test_board_error_fails_job_with_line(api):
    from plotbridge.plotter.link import StreamAborted

    job = (await upload(api.client)).json()
    await api.client.post(f"/api/jobs/{job['id']}/start")
    api.link.step()
    await settle(lambda: api.queue.jobs[job["id"]].lines_acked == 1)  # streaming: line 2 next
    api.link.abort(StreamAborted("error", 1, 2, "error:33 invalid target"))
    await settle(lambda: api.queue.jobs[job["id"]].state == "failed")
    failed = (await api.client.get(f"/api/jobs/{job['id']}")).json()
    assert "line 2" in failed["error"] and "error:33" in failed["error"]
    # what the board still held is stopped: hold, reset, unlock, pen up
    await settle(lambda: "M5" in api.link.commands)
    assert api.link.realtime_bytes == [b"!"] and api.link.estop_calls == 1


async def interrupted_after_12_lines(api) -> str:
    """A job started, 12 lines acknowledged, then the link lost: its id."""
    from plotbridge.plotter.link import StreamAborted

    jid = (await upload(api.client)).json()["id"]
    await api.client.post(f"/api/jobs/{jid}/start")
    for done in range(1, 13):  # one step per acknowledgement (two could merge into one)
        api.link.step()
        await settle(lambda done=done: api.queue.jobs[jid].lines_acked >= done)
    api.link.set_state("Run", planner_free=15)  # planner empty, segment buffer maybe not
    api.link.abort(StreamAborted("disconnected", 12, None, "link lost"))
    await settle(lambda: api.queue.jobs[jid].state == "interrupted")
    return jid


async def test_link_lost_interrupts_then_resume_uses_preamble(api, monkeypatch):
    jid = await interrupted_after_12_lines(api)
    interrupted = (await api.client.get(f"/api/jobs/{jid}")).json()
    assert interrupted["resume_line"] == 5  # the last SEGMENT_BLOCKS moves are not known done
    def preamble(program, point):
        return point.line, ["M5", "G0 X6 Y0"]

    monkeypatch.setattr("plotbridge.plotter.stoppoint.resume_preamble", preamble)
    api.link.set_state("Idle", planner_free=15)
    api.link.auto_ack = True
    response = await api.client.post(f"/api/jobs/{jid}/resume")
    assert response.status_code == 200
    await settle(lambda: api.queue.jobs[jid].state == "done")
    resumed = api.link.streamed[12:]
    # streamed in the compact wire format (program/wire.py)
    assert resumed[:2] == [(0, "M5"), (0, "G0X6Y0")] and resumed[2][0] == 5


async def test_move_and_delete(api, tmp_path):
    ids = [(await upload(api.client)).json()["id"] for _ in range(3)]
    response = await api.client.post(f"/api/jobs/{ids[2]}/move", json={"position": 0})
    assert [j["id"] for j in response.json()] == [ids[2], ids[0], ids[1]]
    response = await api.client.post(f"/api/jobs/{ids[0]}/move", json={"position": -1})
    assert response.status_code == 422
    assert (await api.client.delete(f"/api/jobs/{ids[0]}")).status_code == 204
    assert not (tmp_path / "jobs" / ids[0]).exists()
    assert [j["id"] for j in (await api.client.get("/api/jobs")).json()] == [ids[2], ids[1]]


async def test_machine_endpoints_send_commands(api):
    await api.client.post("/api/machine/jog", json={"dx": 5, "dy": -2.5, "feed": 1200})
    await api.client.post("/api/machine/pen", json={"down": True})
    await api.client.post("/api/machine/unlock")
    assert api.link.commands == ["$J=G91 G21 X5.000 Y-2.500 F1200", "M3", "$X"]
    bad = await api.client.post("/api/machine/command", json={"line": "G0 X1 ! "})
    assert bad.status_code == 422
    ok = await api.client.post("/api/machine/command", json={"line": "G0 X1"})
    assert ok.json() == {"responses": ["ok"]}
    # ?, ! and ~ alone are sent as realtime bytes, not refused and not as a line
    for line in ("?", " ! ", "~"):
        sent = await api.client.post("/api/machine/command", json={"line": line})
        assert sent.status_code == 200 and "realtime byte" in sent.json()["responses"][0]
    assert api.link.realtime_bytes == [b"?", b"!", b"~"]
    assert api.link.commands[-1] == "G0 X1"


async def test_settings_have_metadata(api):
    settings = (await api.client.get("/api/machine/settings")).json()["settings"]
    by_id = {s["id"]: s for s in settings}
    assert by_id[110]["value"] == 6000.0 and by_id[110]["unit"] == "mm/min"
    assert by_id[999]["name"] is None
    response = await api.client.put("/api/machine/settings", json={"settings": {"110": 5000}})
    assert response.status_code == 200 and "$110=5000" in api.link.commands
    bad = await api.client.put("/api/machine/settings", json={"settings": {"x": 1}})
    assert bad.status_code == 422


async def test_settings_out_of_range_are_refused_before_the_board(api):
    api.link.settings.update({60: 1000.0, 61: 2000.0, 2: 0.0, 20: 0.0, 22: 0.0, 30: 1000.0})
    by_id = {s["id"]: s for s in (await api.client.get("/api/machine/settings")).json()["settings"]}
    assert by_id[61]["range"] == {"kind": "integer", "min": 500, "max": 2500,
                                  "min_exclusive": False, "text": "500 to 2500 (a whole number)"}
    assert by_id[2]["range"]["kind"] == "mask" and by_id[22]["range"]["kind"] == "bool"
    assert by_id[110]["range"]["min_exclusive"] is True and by_id[999]["range"] is None
    sent = len(api.link.commands)
    for body, reason in (
        ({"61": 3000, "110": 5000}, "$61=3000 is out of range: $61 takes 500 to 2500"),
        ({"2": 4}, "$2 takes 0 to 3"), ({"0": 2.5}, "whole number"),
        ({"110": 0}, "more than 0"), ({"30": 2000}, "fixed at 1000"),
        ({"20": 1}, "soft limits need homing"),
    ):  # fmt: skip
        refused = await api.client.put("/api/machine/settings", json={"settings": body})
        assert refused.status_code == 422 and reason in refused.json()["detail"], refused.text
    answer = await api.client.post("/api/machine/command", json={"line": "$61=3000"})
    assert answer.status_code == 422 and "500 to 2500" in answer.json()["detail"]
    assert len(api.link.commands) == sent  # nothing reached the board
    ok = await api.client.put("/api/machine/settings", json={"settings": {"22": 1, "20": 1}})
    assert ok.status_code == 200 and api.link.commands[-2:] == ["$22=1", "$20=1"]
    assert (await api.client.post("/api/machine/command", json={"line": "$61=2100"})).is_success
    del api.link.settings[60]  # not our firmware (no pen servo): its own limits apply
    assert (await api.client.post("/api/machine/command", json={"line": "$61=3000"})).is_success


async def test_sim_trace_is_404_without_virtual_plotter(api):
    response = await api.client.get("/api/sim/trace")
    assert response.status_code == 404 and "virtual" in response.json()["detail"]


async def test_server_info(api, tmp_path):
    info = (await api.client.get("/api/server")).json()
    assert info["virtual"] is False and info["serial"] == "/dev/fake"
    assert info["upload_limit"] == 1024 * 1024 and info["data_dir"] == str(tmp_path)


async def test_restart_marks_running_job_interrupted(tmp_path, monkeypatch):
    monkeypatch.setattr(Importer, "_import", fake_import)
    app, link = make_app(tmp_path)
    async with serving(app) as client:
        jid = (await upload(client)).json()["id"]
        queued = (await upload(client)).json()["id"]
        await client.post(f"/api/jobs/{jid}/start")
        for _ in range(4):
            link.step()
            await asyncio.sleep(0.01)
        queue = app.state.components.queue
        queue.store.save(queue.jobs[jid], 0).result()
    again, _ = make_app(tmp_path)
    jobs = {job["id"]: job for job in again.state.components.queue.list()}
    assert jobs[jid]["state"] == "interrupted" and jobs[jid]["resume_line"] >= 1
    assert jobs[queued]["state"] == "queued"
    assert list(jobs) == [jid, queued]


# ---- WebSocket --------------------------------------------------------------------


@pytest.fixture
def sync_client(tmp_path, monkeypatch):
    monkeypatch.setattr(Importer, "_import", fake_import)
    app, link = make_app(tmp_path)
    with TestClient(app) as client:  # its WebSocket requests say Host: testserver
        client.link = link
        yield client


def test_ws_requires_token_and_same_origin(sync_client):
    """Refusals are close codes after the handshake (a browser sees no HTTP status)."""
    with pytest.raises(WebSocketDisconnect) as info, sync_client.websocket_connect("/api/ws") as ws:
        ws.receive_text()
    assert info.value.code == 4401
    with pytest.raises(WebSocketDisconnect) as info, sync_client.websocket_connect(
        f"/api/ws?token={TOKEN}", headers={"origin": "http://evil.example"}
    ) as ws:
        ws.receive_text()
    assert info.value.code == 4403
    with sync_client.websocket_connect(
        f"/api/ws?token={TOKEN}", headers={"origin": "http://testserver"}
    ) as ws:
        assert ws.receive_json()["type"] == "machine"


def test_ws_snapshot_and_commands(sync_client):
    session = sync_client.post("/api/login", json={"token": TOKEN}).cookies["plotbridge_session"]
    cookie = {"cookie": f"plotbridge_session={session}"}
    with sync_client.websocket_connect("/api/ws", headers=cookie) as ws:
        first, second = ws.receive_json(), ws.receive_json()
        assert first["type"] == "machine" and first["machine"]["state"] == "Idle"
        assert second == {"type": "jobs", "jobs": []}
        ws.send_json({"type": "estop"})
        assert _next_of(ws, "ack") == {"type": "ack", "command": "estop"}
        assert sync_client.link.estop_calls == 1
        ws.send_json({"type": "pause"})
        assert _next_of(ws, "error")["command"] == "pause"
        ws.send_text("not json")
        assert _next_of(ws, "error")["command"] is None
        ws.send_json({"type": "bogus"})
        assert "unknown" in _next_of(ws, "error")["detail"]
        ws.send_bytes(b"\xff\x00")
        assert _next_of(ws, "error")["command"] is None
        ws.send_bytes(b'{"type": "estop"}')
        assert _next_of(ws, "ack") == {"type": "ack", "command": "estop"}


def test_ws_estop_is_not_held_back_by_a_slow_command(sync_client):
    release = threading.Event()
    threading.Timer(60.0, release.set).start()  # without it the test would hang, not fail
    sent: list[str] = []

    async def slow_command(line: str, timeout: float = 10) -> list[str]:  # noqa: ASYNC109
        sent.append(line)
        await asyncio.to_thread(release.wait)
        return []

    sync_client.link.command = slow_command
    with sync_client.websocket_connect(f"/api/ws?token={TOKEN}") as ws:
        ws.send_json({"type": "command", "line": "G4 P10"})
        ws.send_json({"type": "estop"})
        assert _next_of(ws, "ack") == {"type": "ack", "command": "estop"}
        assert sync_client.link.estop_calls == 1 and not release.is_set()
        for n in range(20):  # 16 may wait behind the running one; the rest are refused
            ws.send_json({"type": "command", "line": f"G0 X{n}"})
        refused = [_next_of(ws, "error")["detail"] for _ in range(4)]
        assert all("too many commands" in detail for detail in refused)
        ws.send_text(json.dumps({"type": "estop", "pad": "x" * 5000}))
        assert "longer than" in _next_of(ws, "error")["detail"]
        release.set()
        answers = [_next_of(ws, "ack") for _ in range(17)]
        assert {a["command"] for a in answers} == {"command"}
    assert sent[:2] == ["G4 P10", "G0 X0"] and len(sent) == 17


def test_ws_stop_tells_every_client_which_page_stopped(sync_client):
    with (sync_client.websocket_connect(f"/api/ws?token={TOKEN}") as one,
          sync_client.websocket_connect(f"/api/ws?token={TOKEN}") as two):  # fmt: skip
        one.send_json({"type": "estop", "page": "page-one_1"})
        told = _next_of(two, "stopped")
        assert told["origin"] == "page-one_1" and told["via"] == "WebSocket"
        assert _next_of(one, "stopped")["origin"] == "page-one_1"
        one.send_json({"type": "estop", "page": "<script>" + "x" * 80})  # not an id: dropped
        assert _next_of(two, "stopped")["origin"] is None
        rest = sync_client.post(
            "/api/machine/estop", headers={**AUTH, "X-Plotbridge-Page": "rest-page"}
        )
        assert rest.status_code == 202
        assert _next_of(two, "stopped") == {
            "type": "stopped", "plotter": told["plotter"], "origin": "rest-page", "via": "REST"
        }  # the page's own id, nothing of the session or the token


def _next_of(ws, kind: str) -> dict:
    for _ in range(20):
        message = ws.receive_json()
        if message["type"] == kind:
            return message
    raise AssertionError(f"no {kind} message")


async def test_machine_buttons_pause_and_resume_the_job(api):
    job = (await upload(api.client)).json()
    await api.client.post(f"/api/jobs/{job['id']}/start")
    api.link.set_state("Hold")
    assert api.queue.jobs[job["id"]].state == "paused"
    api.link.set_state("Run")
    assert api.queue.jobs[job["id"]].state == "running"


async def test_real_import_runs_in_a_worker_process(tmp_path):
    """No fake importer here: the upload goes through the real importer in its process."""
    app, _ = make_app(tmp_path)
    async with serving(app) as client:
        gcode = "G21\nG90\nG0 X10 Y10\nM3\nG1 X20 Y10 F3000\nM5\n"
        response = await client.post("/api/jobs", files={"file": ("a.nc", gcode)})
        assert response.status_code == 201, response.text
        job = response.json()
        assert job["format"] == "gcode" and job["bounds"]["max_x"] == 20
        bad = await client.post("/api/jobs", files={"file": ("a.gcode", "G1 X1\nG7 Q\n")})
        assert bad.status_code == 422
        assert all(isinstance(e["line"], int) for e in bad.json()["detail"]["errors"])
        assert not [p for p in (tmp_path / "jobs").iterdir() if p.name != job["id"]]
        names = (await client.get("/api/patterns")).json()["patterns"]
        assert names and {"name", "description"} <= set(names[0])
        pattern = await client.post("/api/jobs?pattern=nosuch")
        assert pattern.status_code == 422


async def test_settings_and_jog_refuse_non_finite_numbers(api):
    for body in ('{"settings": {"110": Infinity}}', '{"settings": {"300": 1}}',
                 '{"settings": {"110": NaN}}'):  # fmt: skip
        response = await api.client.put(
            "/api/machine/settings", content=body, headers={"Content-Type": "application/json"}
        )
        assert response.status_code == 422, body
    response = await api.client.post(
        "/api/machine/jog", content='{"dx": NaN}', headers={"Content-Type": "application/json"}
    )
    assert response.status_code == 422
    assert api.link.commands == []


async def test_patch_renames_and_reimports_queued_job(api):
    job = (await upload(api.client)).json()
    first = await api.client.get(f"/api/jobs/{job['id']}/preview")
    assert first.headers["cache-control"] == "no-cache" and first.headers["etag"]
    response = await api.client.patch(
        f"/api/jobs/{job['id']}", json={"name": "renamed", "placement": {"rotate": 90}}
    )
    assert response.status_code == 200
    # the preview is never served stale: the re-import gives it a new validator
    second = await api.client.get(f"/api/jobs/{job['id']}/preview",
                                  headers={"If-None-Match": first.headers["etag"]})  # fmt: skip
    assert second.status_code == 200 and second.headers["etag"] != first.headers["etag"]
    assert response.json()["name"] == "renamed" and response.json()["placement"]["rotate"] == 90
    bad = await api.client.patch(f"/api/jobs/{job['id']}", json={"placement": {"rotate": 45}})
    assert bad.status_code == 422
    api.link.auto_ack = True
    await api.client.post(f"/api/jobs/{job['id']}/start")
    await settle(lambda: api.queue.jobs[job["id"]].state == "done")
    late = await api.client.patch(f"/api/jobs/{job['id']}", json={"name": "x"})
    assert late.status_code == 409


async def test_placement_turns_paper_to_fit_and_a_patch_changes_only_what_it_names(api):
    # the fake board's work area is 300 x 220 mm: A4 upright does not fit, on its side it does
    job = (await upload(api.client, paper="A4", rotate="90", margin="5")).json()
    assert job["placement"]["paper"] == "A4-landscape"
    assert any("placed in landscape" in w["message"] for w in job["warnings"])
    assert (await upload(api.client, paper="A5")).json()["placement"]["paper"] == "A5"
    assert (await upload(api.client, paper="A3")).status_code == 201  # too large both ways:
    # the importer refuses it (the fake one here does not place)
    changed = await api.client.patch(f"/api/jobs/{job['id']}", json={"placement": {"dx": 5}})
    placed = changed.json()["placement"]
    assert (placed["paper"], placed["rotate"], placed["margin"], placed["dx"]) == (
        "A4-landscape", 90, 5, 5)
    cleared = await api.client.patch(f"/api/jobs/{job['id']}", json={"placement": {"paper": None}})
    assert cleared.json()["placement"]["paper"] is None


async def test_auto_start_runs_the_queue(tmp_path, monkeypatch):
    monkeypatch.setattr(Importer, "_import", fake_import)
    app, link = make_app(tmp_path, auto_start=True)
    link.auto_ack = True
    async with serving(app) as client:
        first = (await upload(client)).json()["id"]
        second = (await upload(client)).json()["id"]
        queue = app.state.components.queue
        await settle(lambda: queue.jobs[second].state == "done")
        assert queue.jobs[first].state == "done"


JSON = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(max_size=20),
    lambda inner: st.lists(inner, max_size=4)
    | st.dictionaries(st.text(max_size=8), inner, max_size=4),
    max_leaves=10,
)
BODY_ENDPOINTS = [
    ("POST", "/api/machine/jog"), ("POST", "/api/machine/pen"), ("POST", "/api/machine/motors"),
    ("POST", "/api/machine/command"), ("PUT", "/api/machine/settings"), ("POST", "/api/login"),
    ("PATCH", "/api/jobs/{id}"), ("POST", "/api/jobs/{id}/move"),
]  # fmt: skip


@settings(
    max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(endpoint=st.sampled_from(BODY_ENDPOINTS), body=JSON | st.binary(max_size=40))
def test_no_body_gets_a_5xx(sync_client, endpoint, body):
    if not hasattr(sync_client, "job_id"):
        upload = sync_client.post(
            "/api/jobs", files={"file": ("a.gcode", "G1 X1\n")}, headers=AUTH
        )
        sync_client.job_id = upload.json()["id"]
    method, path = endpoint
    content = body if isinstance(body, bytes) else json.dumps(body).encode()
    response = sync_client.request(
        method, path.format(id=sync_client.job_id), content=content,
        headers={**AUTH, "Content-Type": "application/json"},
    )  # fmt: skip
    assert response.status_code < 500, (endpoint, body, response.text)
    if response.status_code >= 400:
        assert "detail" in response.json()


@pytest.fixture
def real_import_client(tmp_path):
    app, _ = make_app(tmp_path)
    with TestClient(app) as client:
        client.data_dir = tmp_path
        yield client


GCODE_WORDS = st.sampled_from([
    "G0", "G1", "G2", "G3", "M3", "M5", "X1", "Y-2", "F3000", "I1",
    "Z0", "G91", "G20", "S50", "M300", "(c)", ";x", "%", "X", "1e9",
])  # fmt: skip
GCODE = st.lists(st.lists(GCODE_WORDS, max_size=5).map(" ".join), max_size=12).map("\n".join)


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    name=st.sampled_from(["a.gcode", "a.svg", "a.txt", "a", "../x.nc"]),
    body=GCODE | st.text(max_size=200) | st.binary(max_size=200),
)
def test_no_upload_gets_a_5xx_or_leaves_files(real_import_client, name, body):
    response = real_import_client.post("/api/jobs", files={"file": (name, body)}, headers=AUTH)
    assert response.status_code in (201, 413, 415, 422), response.text
    if response.status_code != 201:
        errors = response.json()["detail"]["errors"]
        assert errors and all(e["message"] for e in errors)
    jobs_dir = real_import_client.data_dir / "jobs"
    assert not [p for p in jobs_dir.iterdir() if p.name.startswith(".")]
    assert not list((real_import_client.data_dir / "tmp").iterdir())


def test_leftovers_of_a_crash_are_removed_at_start(tmp_path):
    (tmp_path / "jobs" / ".abc.partial").mkdir(parents=True)
    (tmp_path / "jobs" / ".abc.partial" / "program.gcode").write_text("G1\n")
    (tmp_path / "tmp").mkdir()
    (tmp_path / "tmp" / "upload-x1").write_text("half")
    make_app(tmp_path)
    assert list((tmp_path / "jobs").iterdir()) == []
    assert list((tmp_path / "tmp").iterdir()) == []


def test_a_flooding_ws_client_is_closed_and_its_stops_are_never_limited(sync_client):
    with sync_client.websocket_connect(f"/api/ws?token={TOKEN}") as ws:
        for n in range(400):
            ws.send_json({"type": "estop"} if n % 40 == 0 else {"type": "pause"})
        with pytest.raises(WebSocketDisconnect) as closed:
            while True:
                ws.receive_text()
    assert closed.value.code == 1008
    assert sync_client.link.estop_calls >= 3  # the stops before the close all went out


async def test_frame_traces_the_bounds_with_the_pen_up(api):
    job = (await upload(api.client)).json()
    response = await api.client.post(f"/api/jobs/{job['id']}/frame")
    assert response.status_code == 200 and response.json()["state"] == "queued"
    corners = ["0.000 Y0.000", "15.000 Y0.000", "15.000 Y0.000", "0.000 Y0.000", "0.000 Y0.000"]
    assert api.link.commands == ["M5", *(f"G0 X{c}" for c in corners), "G4 P0"]
    api.link.set_state("Alarm", alarm=1)
    refused = await api.client.post(f"/api/jobs/{job['id']}/frame")
    assert refused.status_code == 409 and "Alarm" in refused.json()["detail"]
    missing = await api.client.post("/api/jobs/nope/frame")
    assert missing.status_code == 404


async def test_hold_and_continue_without_a_job(api):
    refused = await api.client.post("/api/machine/hold")
    assert refused.status_code == 409 and "Idle" in refused.json()["detail"]
    api.link.set_state("Jog")
    assert (await api.client.post("/api/machine/hold")).status_code == 200
    api.link.set_state("Hold")
    assert (await api.client.post("/api/machine/continue")).status_code == 200
    assert api.link.realtime_bytes == [b"!", b"~"]


async def test_hold_and_continue_of_the_running_job(api):
    job = (await upload(api.client, start="true")).json()
    assert (await api.client.post("/api/machine/hold")).status_code == 200
    assert api.queue.jobs[job["id"]].state == "paused"
    assert (await api.client.post("/api/plotters/plotter1/machine/continue")).status_code == 200
    assert api.queue.jobs[job["id"]].state == "running"
    assert api.link.realtime_bytes == [b"!", b"~"]


async def test_restart_runs_an_interrupted_job_from_its_first_line(api):
    jid = await interrupted_after_12_lines(api)
    kept = api.queue.jobs[jid].resume_line
    api.link.set_state("Alarm", planner_free=15)
    response = await api.client.post(f"/api/jobs/{jid}/restart")  # waits, as a start does
    assert response.status_code == 200 and response.json()["state"] == "waiting"
    assert kept and "Alarm" in response.json()["waiting"]
    api.link.auto_ack = True
    sent = len(api.link.streamed)
    api.link.set_state("Idle", planner_free=15)  # homed: it starts by itself
    await settle(lambda: api.queue.jobs[jid].state == "done")
    again = api.link.streamed[sent:]
    assert again[0][0] == 1 and all(n != 0 for n, _ in again), "no resume preamble"
    assert [n for n, _ in again] == list(range(1, len(again) + 1))
    # a running job cannot be restarted; an unknown one is 404
    assert (await api.client.post("/api/jobs/nope/restart")).status_code == 404
