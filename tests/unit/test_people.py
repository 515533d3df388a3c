"""People, keys, sessions, the credential failure limit and the audit log, through the real
app (plotbridge.people). The role table itself: test_access_matrix.py."""

from __future__ import annotations

import hashlib
import json
import os
import sqlite3
import threading
import time
from contextlib import closing

import pytest
from plotbridge import auth as authmod
from plotbridge.access import Role
from plotbridge.jobs.imports import Importer
from plotbridge.people.store import PeopleStore
from starlette.testclient import TestClient
from starlette.websockets import WebSocketDisconnect

from tests.fixtures.fake_app import TOKEN, fake_import, make_app
from tests.fixtures.people import bearer, keys_per_role

PAGE = {"x-plotbridge-page": "page-1"}


@pytest.fixture
def app_client(tmp_path, monkeypatch):
    monkeypatch.setattr(Importer, "_import", fake_import)
    app, _ = make_app(tmp_path, token_file=tmp_path / "token")
    (tmp_path / "token").write_text(TOKEN + "\n")
    with TestClient(app) as client:
        yield app, client, tmp_path


def closed_code(ws) -> int:
    """The close code of a WebSocket the server closes (it keeps sending until then)."""
    deadline = time.monotonic() + 10
    with pytest.raises(WebSocketDisconnect) as info:
        while time.monotonic() < deadline:
            ws.receive_json()
    return info.value.code


def test_a_key_removed_by_another_process_is_refused_at_once_and_its_websocket_closed(
    app_client,
):
    app, client, data = app_client
    keys = keys_per_role(app)
    key = bearer(keys["operator"])
    assert client.get("/api/jobs", headers=key).status_code == 200
    with client.websocket_connect(f"/api/ws?token={keys['operator']}") as ws:
        ws.receive_json()
        other = PeopleStore(data / "plotbridge.db")  # as `plotbridge keys remove` would
        assert other.remove_key("operator-key")
        other.close()
        assert client.get("/api/jobs", headers=key).status_code == 401
        assert closed_code(ws) == 4401
    assert client.get("/api/jobs", headers=bearer(keys["viewer"])).status_code == 200


def test_writes_to_the_jobs_tables_do_not_reload_the_people(app_client, monkeypatch):
    """The jobs share the database file and write it all the time: a request checks a
    stamp the people writes leave, not SQLite, and reloads only after such a write."""
    app, client, data = app_client
    key = bearer(keys_per_role(app)["operator"])
    assert client.get("/api/jobs", headers=key).status_code == 200
    loads = []
    store = app.state.components.access.store
    monkeypatch.setattr(store, "snapshot", lambda real=store.snapshot: loads.append(1) or real())
    with closing(sqlite3.connect(data / "plotbridge.db")) as other:  # another connection
        other.execute("CREATE TABLE IF NOT EXISTS busy (n)")
        for n in range(20):
            other.execute("INSERT INTO busy VALUES (?)", (n,))
            other.commit()
            assert client.get("/api/jobs", headers=key).status_code == 200
    assert loads == []
    other_store = PeopleStore(data / "plotbridge.db")
    other_store.add_person("bea", Role.viewer)
    other_store.close()
    assert client.get("/api/jobs", headers=key).status_code == 200
    assert loads == [1]


def test_a_person_logs_in_once_by_link_and_is_removed(app_client):
    _app, client, _ = app_client
    made = client.post("/api/people", json={"name": "ann", "role": "viewer"}, headers=bearer(TOKEN))
    assert made.status_code == 201
    code = made.json()["link"].split("#", 1)[1]
    login = client.post("/api/login", json={"link": code})
    assert login.status_code == 204
    client.cookies.clear()
    assert client.post("/api/login", json={"link": code}).status_code == 401  # used up
    cookie = {"cookie": f"plotbridge_session={login.cookies['plotbridge_session']}",
              "x-plotbridge": "1"}  # fmt: skip
    client.cookies.clear()
    assert client.get("/api/me", headers=cookie).json()["role"] == "viewer"
    assert client.post("/api/jobs", files={"file": ("a.gcode", "G1 X1\n")},
                       headers=cookie).status_code == 403  # fmt: skip
    assert client.post("/api/estop", headers=cookie).status_code == 202  # STOP for everyone
    with client.websocket_connect("/api/ws", headers=cookie) as ws:
        ws.receive_json()
        assert client.delete("/api/people/ann", headers=bearer(TOKEN)).status_code == 204
        assert closed_code(ws) == 4401
    assert client.get("/api/me", headers=cookie).status_code == 401


def test_logout_and_a_rotated_token_close_their_websockets(app_client):
    _app, client, data = app_client
    session = client.post("/api/login", json={"token": TOKEN}).cookies["plotbridge_session"]
    client.cookies.clear()
    cookie = {"cookie": f"plotbridge_session={session}", "x-plotbridge": "1"}
    with client.websocket_connect("/api/ws", headers=cookie) as ws:
        ws.receive_json()
        assert client.post("/api/logout", headers=cookie).status_code == 204
        assert closed_code(ws) == 4401
    again = client.post("/api/login", json={"token": TOKEN}).cookies["plotbridge_session"]
    client.cookies.clear()
    with client.websocket_connect(f"/api/ws?token={TOKEN}") as by_token:
        by_token.receive_json()
        authmod.write_private(data / "token", "n" * 24 + "\n")
        os.utime(data / "token", ns=(1, 1))
        assert closed_code(by_token) == 4401
    assert client.get("/api/me", headers={"cookie": f"plotbridge_session={again}"}
                      ).status_code == 401  # fmt: skip
    assert client.get("/api/me", headers=bearer("n" * 24)).json()["role"] == "admin"


def test_a_logout_holds_while_its_write_waits_and_another_writer_changes_the_file(app_client):
    """The jobs and pens write the same file: a reload then must not bring back a session
    this process ended but has not written yet."""
    app, client, data = app_client
    access = app.state.components.access
    session = client.post("/api/login", json={"token": TOKEN}).cookies["plotbridge_session"]
    client.cookies.clear()
    cookie = {"cookie": f"plotbridge_session={session}", "x-plotbridge": "1"}
    assert client.get("/api/me", headers=cookie).status_code == 200
    gate = threading.Event()
    access._writer.submit(gate.wait, 10)  # the writer thread is busy: the logout's write waits
    try:
        assert client.post("/api/logout", headers=cookie).status_code == 204
        with closing(sqlite3.connect(data / "plotbridge.db")) as other, other:
            other.execute("CREATE TABLE IF NOT EXISTS elsewhere (x)")  # another writer
            other.execute("INSERT INTO elsewhere VALUES (1)")
        assert client.get("/api/me", headers=cookie).status_code == 401
    finally:
        gate.set()
    access.refresh()
    assert client.get("/api/me", headers=cookie).status_code == 401


def test_every_way_of_sending_a_credential_counts_and_the_right_one_is_never_held(app_client):
    _, client, _ = app_client
    wrong = "w" * 24
    assert client.get("/api/jobs", headers=bearer(wrong)).status_code == 401
    assert client.get("/api/jobs", headers={"cookie": f"plotbridge_session={wrong}"}
                      ).status_code == 401  # fmt: skip
    client.cookies.clear()
    refused = pytest.raises(WebSocketDisconnect)
    with refused, client.websocket_connect(f"/api/ws?token={wrong}") as ws:
        ws.receive_json()
    assert client.post("/api/login", json={"token": wrong}).status_code == 401
    assert client.post("/api/login", json={"link": wrong}).status_code == 401
    started = time.monotonic()
    assert client.post("/api/login", json={"token": wrong + "x"}).status_code == 401
    assert time.monotonic() - started >= 0.45  # the sixth failure from this address is held
    started = time.monotonic()
    assert client.get("/api/jobs", headers=bearer(TOKEN)).status_code == 200  # never held
    assert client.post("/api/login", json={"token": TOKEN}).status_code == 204


def test_a_submitter_sees_only_their_own_jobs_and_actions_fit_the_role(app_client):
    app, client, _ = app_client
    keys = keys_per_role(app)
    files = {"file": ("a.gcode", "G1 X1 Y1\n")}
    theirs = client.post("/api/jobs", files=files, headers=bearer(keys["operator"])).json()
    mine = client.post("/api/jobs", files=files, headers=bearer(keys["submitter"])).json()
    assert mine["owner"] == "key submitter-key" and theirs["owner"] == "key operator-key"
    seen = client.get("/api/jobs", headers=bearer(keys["submitter"])).json()
    assert [job["id"] for job in seen] == [mine["id"]]
    assert client.get(f"/api/jobs/{theirs['id']}", headers=bearer(keys["submitter"])
                      ).status_code == 403  # fmt: skip
    assert client.post(f"/api/jobs/{theirs['id']}/cancel", headers=bearer(keys["submitter"])
                       ).status_code == 403  # fmt: skip
    assert len(client.get("/api/jobs", headers=bearer(keys["viewer"])).json()) == 2
    with client.websocket_connect(f"/api/ws?token={keys['submitter']}") as ws:
        first = ws.receive_json()
        while first["type"] != "jobs":
            first = ws.receive_json()
        assert [job["id"] for job in first["jobs"]] == [mine["id"]]


def test_the_audit_log_holds_who_did_what_and_exports_json_lines(app_client):
    app, client, _ = app_client
    keys = keys_per_role(app)
    client.post("/api/jobs", files={"file": ("a.gcode", "G1 X1\n")},
                headers=bearer(keys["submitter"]))  # fmt: skip
    client.post("/api/machine/estop", headers={**bearer(keys["viewer"]), **PAGE})
    client.put("/api/settings/approval", json={"mode": "all"}, headers=bearer(TOKEN))
    client.get("/api/jobs", headers=bearer("w" * 24))
    assert client.get("/api/audit", headers=bearer(keys["operator"])).status_code == 403
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        log = client.get("/api/audit", headers=bearer(TOKEN)).json()
        if len(log) >= 4:
            break
    steps = {(e["who"], e["action"]) for e in log}
    assert ("key submitter-key", "POST /api/jobs") in steps
    assert ("key viewer-key", "POST /api/machine/estop") in steps
    assert ("token (first admin)", "PUT /api/settings/approval") in steps
    assert ("nobody", "login_failed") in steps
    stop = next(e for e in log if e["action"] == "POST /api/machine/estop")
    assert stop["detail"]["page"] == "page-1" and stop["via"] == "bearer"
    export = client.get("/api/audit/export", headers=bearer(TOKEN))
    lines = [json.loads(line) for line in export.text.splitlines()]
    assert [e["id"] for e in lines] == sorted(e["id"] for e in log)


def test_sessions_outlive_a_restart_and_old_sessions_move_into_the_store(tmp_path, monkeypatch):
    hashed = hashlib.sha256(b"old-session").hexdigest()
    (tmp_path / "sessions.json").write_text(json.dumps({hashed: time.time() + 3600}))
    app, _ = make_app(tmp_path)
    with TestClient(app) as client:
        assert not (tmp_path / "sessions.json").exists()
        old = {"cookie": "plotbridge_session=old-session"}
        assert client.get("/api/me", headers=old).json()["kind"] == "token"
        session = client.post("/api/login", json={"token": TOKEN}).cookies["plotbridge_session"]
    app, _ = make_app(tmp_path)
    with TestClient(app) as client:
        again = {"cookie": f"plotbridge_session={session}"}
        assert client.get("/api/me", headers=again).status_code == 200


def test_a_submitters_upload_waits_for_approval_and_a_decline_says_why(app_client):
    app, client, _ = app_client
    keys = keys_per_role(app)
    sub, op = bearer(keys["submitter"]), bearer(keys["operator"])
    files = {"file": ("a.gcode", "G1 X1 Y1\n")}
    first = client.post("/api/jobs", files=files, data={"start": "true"}, headers=sub).json()
    assert first["state"] == "awaiting_approval" and first["owner"] == "key submitter-key"
    assert first["approval"] == {"start": True, "decision": None}
    assert client.get(f"/api/jobs/{first['id']}", headers=sub).json()["actions"] == ["cancel"]
    assert client.get(f"/api/jobs/{first['id']}", headers=op).json()["actions"] == [
        "cancel", "approve", "decline"]
    assert client.post(f"/api/jobs/{first['id']}/approve", headers=sub).status_code == 403
    approved = client.post(f"/api/jobs/{first['id']}/approve", headers=op).json()
    assert approved["state"] in ("running", "waiting")  # its sender asked to start it
    assert approved["approval"]["decision"] == "approved"
    assert approved["approval"]["by"] == "key operator-key"
    second = client.post("/api/jobs", files=files, headers=sub).json()
    assert client.post(f"/api/jobs/{second['id']}/decline", headers=op,
                       json={}).status_code == 422  # a reason is needed  # fmt: skip
    declined = client.post(f"/api/jobs/{second['id']}/decline", headers=op,
                           json={"reason": "too big for the A4 paper"}).json()  # fmt: skip
    seen = client.get(f"/api/jobs/{second['id']}", headers=sub).json()
    assert declined["state"] == seen["state"] == "cancelled"
    assert seen["approval"]["reason"] == "too big for the A4 paper"
    assert "too big for the A4 paper" in seen["error"]
    assert client.post(f"/api/jobs/{second['id']}/approve", headers=op).status_code == 409
    # the setting: no upload waits, or every upload waits
    client.put("/api/settings/approval", json={"mode": "none"}, headers=bearer(TOKEN))
    assert client.post("/api/jobs", files=files, headers=sub).json()["state"] == "queued"
    client.put("/api/settings/approval", json={"mode": "all"}, headers=bearer(TOKEN))
    assert client.post("/api/jobs", files=files, headers=op).json()["state"] == "awaiting_approval"


def test_an_upload_that_waits_for_approval_is_not_handed_to_the_fleet(app_client):
    """`fleet=true` from a submitter: the job waits here for an operator (no MQTT here, so
    an operator's `fleet=true` is refused 409: the field was looked at)."""
    app, client, _ = app_client
    keys = keys_per_role(app)
    files = {"file": ("a.gcode", "G1 X1 Y1\n")}
    waiting = client.post("/api/jobs", files=files, data={"fleet": "true"},
                          headers=bearer(keys["submitter"]))  # fmt: skip
    assert waiting.status_code == 201 and waiting.json()["state"] == "awaiting_approval"
    assert "fleet" not in waiting.json()
    offered = client.post("/api/jobs", files=files, data={"fleet": "true"},
                          headers=bearer(keys["operator"]))  # fmt: skip
    assert offered.status_code == 409 and "--mqtt" in offered.text
