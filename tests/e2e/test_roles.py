"""People and roles through a real server process and the simulator: keys made by the
command line while the server runs, a submitter's upload, an operator's plot (traced),
a viewer's STOP, a revoked key refused at once (its WebSocket too), the audit log, a
client that sends its key only to the server holding it, and a data directory from
before people."""

from __future__ import annotations

import http.server
import json
import os
import sqlite3
import subprocess
import sys
import threading
import time
from contextlib import closing
from typing import Any, ClassVar

import httpx
import pytest
from plotbridge.client import Plotbridge, proves
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from tests.fixtures.drawings import drawing, square_stroke
from tests.fixtures.people import cli_key, plotbridge_cli
from tests.fixtures.server import ServerProcess, running_server
from tests.fixtures.trace import assert_same_drawing, assert_stopped, stop_clock

STOP_BOUND = 0.25  # s, as tests/e2e/test_hostile_lan.py
pytestmark = pytest.mark.e2e


def as_key(server: ServerProcess, key: str) -> httpx.Client:
    return httpx.Client(base_url=server.url, timeout=30, headers={"Authorization": f"Bearer {key}"})


def audit(server: ServerProcess, wanted: int) -> list[dict[str, Any]]:
    deadline = time.monotonic() + 10
    while True:
        log = server.client.get("/api/audit", params={"limit": 1000}).json()
        if len(log) >= wanted or time.monotonic() > deadline:
            return log
        time.sleep(0.1)


def test_submitter_operator_viewer_and_a_revoked_key(server, plotter):
    data = server.data_dir
    keys = {role: cli_key(data, f"{role}-1", role) for role in ("submitter", "operator", "viewer")}
    submitter, operator, viewer = (as_key(server, keys[r]) for r in keys)
    with submitter, operator, viewer:
        # a submitter uploads and asks to start: it waits for approval; reads no settings,
        # cancels no one else's job
        server.home()
        files = {"file": ("a.gcode", drawing(circles=0))}
        job = submitter.post("/api/jobs", files=files, data={"start": "true"}).json()
        assert job["state"] == "awaiting_approval" and job["owner"] == "key submitter-1"
        assert submitter.get("/api/machine/settings").status_code == 403
        others = server.submit(drawing(circles=0), start=False)
        assert submitter.post(f"/api/jobs/{others['id']}/cancel").status_code == 403
        assert [j["id"] for j in submitter.get("/api/jobs").json()] == [job["id"]]
        # an operator approves it: it plots, and the trace is the drawing
        plotter.clear()
        approved = operator.post(f"/api/jobs/{job['id']}/approve")
        assert approved.status_code == 200, approved.text
        assert server.wait_job(job["id"], ("done", "failed", "stopped"), 120)["state"] == "done"
        assert_same_drawing(server.preview(job["id"])["strokes"], plotter.trace()["strokes"])
        # another is declined (by the command line, the operator's key): its sender sees why
        refused = submitter.post("/api/jobs", files=files).json()
        reason = "please use the A5 paper"
        env = {k: v for k, v in os.environ.items() if not k.startswith("PLOTBRIDGE_")}
        declined = subprocess.run(
            [sys.executable, "-m", "plotbridge", "act", refused["id"], "decline", "--reason",
             reason, "--url", server.url, "--json"], env={**env, "PLOTBRIDGE_TOKEN":
             keys["operator"]}, capture_output=True, text=True, timeout=60)  # fmt: skip
        assert declined.returncode == 0, declined.stderr
        assert json.loads(declined.stdout)["state"] == "cancelled"
        seen = submitter.get(f"/api/jobs/{refused['id']}").json()
        assert seen["state"] == "cancelled" and seen["approval"]["reason"] == reason
        # a viewer stops a running job within the usual bound
        running = operator.post("/api/jobs", files={"file": ("b.gcode", square_stroke())}).json()
        assert operator.post(f"/api/jobs/{running['id']}/start").status_code == 200
        server.wait_drawing(running["id"])
        sent = stop_clock(plotter)
        stopped = viewer.post("/api/machine/estop", headers={"x-plotbridge-page": "page-9"})
        assert stopped.status_code == 202 and time.monotonic() - sent.at < STOP_BOUND
        assert_stopped(server, plotter, running["id"], sent)
        # a key removed by the command line is refused at once, its WebSocket closed
        url = server.url.replace("http", "ws") + f"/api/ws?token={keys['operator']}"
        with connect(url) as ws:
            assert json.loads(ws.recv(10))["type"] == "machine"
            plotbridge_cli("keys", "remove", "operator-1", "--data-dir", str(data))
            assert operator.get("/api/jobs").status_code == 401
            deadline = time.monotonic() + 5
            with pytest.raises(ConnectionClosed) as closed:
                while time.monotonic() < deadline:
                    ws.recv(5)
            assert closed.value.rcvd is not None and closed.value.rcvd.code == 4401
    log = audit(server, 8)
    steps = {(entry["who"], entry["action"], entry["target"]) for entry in log}
    assert ("key submitter-1", "POST /api/jobs", None) in steps
    assert ("key operator-1", "POST /api/jobs/{job_id}/approve", job["id"]) in steps
    assert ("key operator-1", "POST /api/jobs/{job_id}/decline", refused["id"]) in steps
    assert ("key operator-1", "POST /api/jobs/{job_id}/start", running["id"]) in steps
    assert ("key submitter-1", "POST /api/jobs/{job_id}/cancel", others["id"]) not in steps
    stop = next(e for e in log if e["action"] == "POST /api/machine/estop")
    assert stop["who"] == "key viewer-1" and stop["detail"]["page"] == "page-9"


class Impostor(http.server.BaseHTTPRequestHandler):
    """Announces itself as plotbridge and records every Authorization header sent to it."""

    seen: ClassVar[list[str]] = []

    def do_GET(self) -> None:
        Impostor.seen.append(self.headers.get("authorization") or "")
        body = json.dumps({"server": "impostor", "proof": "0" * 64, "status": "ok"}).encode()
        self.send_response(200)
        self.send_header("content-type", "application/json")
        self.send_header("content-length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def log_message(self, *_: Any) -> None:
        pass


def test_a_client_sends_its_key_only_to_the_server_holding_it(server_virtual, monkeypatch):
    key = cli_key(server_virtual.data_dir, "script", "operator")
    impostor = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Impostor)
    threading.Thread(target=impostor.serve_forever, daemon=True).start()
    fake = f"http://127.0.0.1:{impostor.server_address[1]}"
    try:
        assert proves(server_virtual.url, key) and proves(server_virtual.url, server_virtual.token)
        assert not proves(fake, key)
        found = [type("Found", (), {"url": url, "name": url}) for url in (fake, server_virtual.url)]
        monkeypatch.setattr("plotbridge.mdns.discover", lambda timeout: found)
        monkeypatch.delenv("PLOTBRIDGE_URL", raising=False)
        monkeypatch.delenv("PLOTBRIDGE_SERVER", raising=False)
        with Plotbridge(token=key) as pb:  # zeroconf proposes both; only one proves it
            assert pb.url == server_virtual.url and pb.jobs() == []
        server_id = server_virtual.client.get("/api/server").json()["id"]
        with Plotbridge(server_virtual.url, key, server_id=server_id) as pb:
            assert pb.machine()["connected"]
    finally:
        impostor.shutdown()
    assert all(key not in seen and server_virtual.token not in seen for seen in Impostor.seen)


def test_a_data_directory_from_before_people_keeps_its_token_and_jobs(tmp_path):
    data = tmp_path / "data"
    link = ["--virtual", "--sim-speed", "0"]
    with running_server(data, link) as server:
        job = server.submit(drawing(circles=0), start=False)
        session = server.client.post("/api/login", json={"token": server.token}
                                     ).cookies["plotbridge_session"]  # fmt: skip
        token = server.token
    with closing(sqlite3.connect(data / "plotbridge.db")) as db:  # as today's code left it
        for table in ("people", "api_keys", "sessions", "login_links", "audit",
                      "access_settings"):  # fmt: skip
            db.execute(f"DROP TABLE {table}")
        db.commit()
    digest = __import__("hashlib").sha256(session.encode()).hexdigest()
    (data / "sessions.json").write_text(json.dumps({digest: time.time() + 3600}))
    with running_server(data, link) as server:
        assert server.token == token
        me = server.client.get("/api/me").json()
        assert me == {"name": "admin", "kind": "token", "role": "admin",
                      "who": "token (first admin)"}  # fmt: skip
        assert [j["id"] for j in server.client.get("/api/jobs").json()] == [job["id"]]
        cookie = {"cookie": f"plotbridge_session={session}", "authorization": ""}
        assert server.client.get("/api/me", headers=cookie).status_code == 200
