"""End to end: a real `plotbridge serve` on the simulated plotter posts its events to a
webhook receiver on loopback started here. A three-layer job tells started, two pen
changes and done, each once and in order, the first again after the receiver answered
500; an emergency stop while the receiver hangs is not delayed by it; events waiting
for a receiver that is down when the server is killed (`kill -9`) arrive after the
restart, once each and in order; the board's stop button tells an alarm, and the
simulator going away a lost link."""

from __future__ import annotations

import contextlib
import json
import sqlite3
import threading
import time
from collections.abc import Iterator
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any

import pytest

from tests.fixtures.drawings import THREE_LAYERS, drawing, square_stroke
from tests.fixtures.server import ServerProcess, running_server
from tests.fixtures.trace import assert_stopped, stop_clock
from tests.fixtures.waits import wait_until

pytestmark = pytest.mark.e2e

HANG_LIMIT_S = 60.0  # a hanging answer is released by then at the latest


class Receiver:
    """A webhook receiver: answers scripted statuses (then 200), 503 while `down`, or
    hangs while `go` is cleared; records every request with the status it answered."""

    def __init__(self) -> None:
        self.answers: list[int] = []
        self.down = False
        self.requests: list[dict[str, Any]] = []  # {"event": body, "status": int}
        self.pending = 0
        self.go = threading.Event()  # cleared: requests hang until it is set
        self.go.set()
        self.lock = threading.Lock()
        receiver = self

        class Handler(BaseHTTPRequestHandler):
            def do_POST(self) -> None:
                body = json.loads(self.rfile.read(int(self.headers["Content-Length"])))
                with receiver.lock:
                    receiver.pending += 1
                receiver.go.wait(HANG_LIMIT_S)
                with receiver.lock:
                    receiver.pending -= 1
                    status = (503 if receiver.down else
                              receiver.answers.pop(0) if receiver.answers else 200)  # fmt: skip
                    receiver.requests.append({"event": body, "status": status,
                                              "header": self.headers["X-Plotbridge-Event"]})
                with contextlib.suppress(OSError):  # the server may have given up waiting
                    self.send_response(status)
                    self.send_header("Content-Length", "0")
                    self.end_headers()

            def log_message(self, *args: Any) -> None:
                pass

        self.http = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.http.daemon_threads = True
        self.url = f"http://127.0.0.1:{self.http.server_address[1]}/hook"

    def accepted(self) -> list[dict[str, Any]]:
        """The events answered 2xx, each once (a repeat after a timeout has the same id)."""
        with self.lock:
            seen: dict[str, dict[str, Any]] = {}
            for request in self.requests:
                if request["status"] < 300:
                    seen.setdefault(request["event"]["id"], request["event"])
            return list(seen.values())

    def wait_for(self, event: str, timeout: float = 60) -> list[dict[str, Any]]:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            got = self.accepted()
            if any(e["event"] == event for e in got):
                return got
            time.sleep(0.05)
        raise AssertionError(f"no {event} event reached the receiver: {self.requests}")


@pytest.fixture
def receiver() -> Iterator[Receiver]:
    receiver = Receiver()
    thread = threading.Thread(target=receiver.http.serve_forever, daemon=True)
    thread.start()
    try:
        yield receiver
    finally:
        receiver.go.set()
        receiver.http.shutdown()
        receiver.http.server_close()
        thread.join(10)


def test_layered_job_events_arrive_once_in_order_after_a_500(plotter, tmp_path, receiver):
    receiver.answers = [500]  # the first post fails: the server posts it again
    link = ["--serial", str(plotter.port)]
    with running_server(tmp_path / "server-data", link, ["--webhook", receiver.url]) as server:
        shown = server.client.get("/api/settings/webhooks").json()
        assert shown["fixed"] == [receiver.url] and shown["urls"] == []
        server.home()
        job = server.submit(THREE_LAYERS)  # an SVG: the content tells, not the name
        for layer in (2, 3):
            server.wait_pen_change(job["id"], layer)
            assert server.client.post(f"/api/jobs/{job['id']}/resume").status_code == 200
        assert server.wait_job(job["id"], ("done", "failed", "stopped"), 120)["state"] == "done"
        events = receiver.wait_for("job_done")
        figures = server.client.get("/api/settings/webhooks").json()["webhooks"][0]
    assert [e["event"] for e in events] == ["job_started", "pen_change", "pen_change",
                                            "job_done"]  # fmt: skip
    first, retried = receiver.requests[0], receiver.requests[1]
    assert first["status"] == 500 and retried["status"] == 200
    assert first["event"] == retried["event"] == events[0]  # the same event again
    assert len(receiver.requests) == 5  # four events, one of them twice
    assert [r["header"] for r in receiver.requests] == [r["event"]["event"]
                                                        for r in receiver.requests]
    assert figures["delivered"] == 4 and figures["retries"] == 1 and figures["dropped"] == 0
    for event in events:
        assert event["plotter"] == "plotter1"
        assert event["job"]["id"] == job["id"] and event["job"]["name"] == job["name"]
        assert event["time"] and event["message"]
    assert "Layer 2 of 3, 'shade'" in events[1]["message"]
    assert "Layer 3 of 3, 'detail'" in events[2]["message"]
    assert events[1]["details"]["layer"] == 2


def test_estop_is_not_delayed_by_a_hanging_receiver(plotter, tmp_path, receiver):
    link = ["--serial", str(plotter.port)]
    with running_server(tmp_path / "server-data", link, ["--webhook-allow-local"]) as server:
        estop_beside_a_hanging_receiver(server, plotter, receiver)


def estop_beside_a_hanging_receiver(server: ServerProcess, plotter: Any, receiver: Receiver
                                    ) -> None:  # fmt: skip
    saved = server.client.put("/api/settings/webhooks", json={"urls": [receiver.url]})
    assert saved.status_code == 200, saved.text
    refused = server.client.put("/api/settings/webhooks", json={"urls": ["ftp://host/x"]})
    assert refused.status_code == 422 and "only http:// and https://" in refused.text
    server.home()
    receiver.go.clear()  # from now on the receiver takes the request and never answers
    job = server.submit(square_stroke())
    server.wait_drawing(job["id"])
    deadline = time.monotonic() + 10
    while receiver.pending == 0:  # the job_started post hangs at the receiver
        assert time.monotonic() < deadline, "the server posted no job_started"
        time.sleep(0.02)
    sent = stop_clock(plotter)
    response = server.client.post("/api/machine/estop")
    answered = time.monotonic() - sent.at
    assert response.status_code == 202 and answered < 0.25, answered
    assert_stopped(server, plotter, job["id"], sent)
    assert server.client.get("/api/settings/webhooks").json()["webhooks"][0]["queued"] >= 2
    receiver.go.set()
    events = [e["event"] for e in receiver.wait_for("job_stopped")]
    assert events.index("job_started") < events.index("job_stopped")


def hook(server: ServerProcess) -> dict[str, Any]:
    """The settings API's row for the only webhook."""
    (row,) = server.client.get("/api/settings/webhooks").json()["webhooks"]
    return row


def kept_events(server: ServerProcess) -> list[str]:
    """The events waiting on disk, as the next server start reads them."""
    with contextlib.closing(sqlite3.connect(server.data_dir / "plotbridge.db")) as db:
        return [row[0] for row in db.execute("SELECT event FROM webhook_outbox ORDER BY seq")]


def test_events_waiting_at_a_kill_arrive_once_each_after_the_restart(plotter, tmp_path,
                                                                     receiver):  # fmt: skip
    receiver.down = True  # answers 503: the events wait, the first retried
    link = ["--serial", str(plotter.port)]
    with running_server(tmp_path / "server-data", link, ["--webhook", receiver.url]) as server:
        server.home()
        job = server.submit(drawing(circles=0))  # a square: done in a moment
        assert server.wait_job(job["id"], ("done", "failed", "stopped"), 60)["state"] == "done"
        wait_until(lambda: hook(server), lambda row: row["queued"] == 2 and row["retries"], 30,
                   "job_started retried, job_done behind it")  # fmt: skip
        wait_until(lambda: kept_events(server), lambda kept: len(kept) == 2, 10, "kept")
        server.kill()  # SIGKILL: nothing is flushed or closed
        refused = [r["event"] for r in receiver.requests]
        receiver.down = False
        server.start()
        delivered = wait_until(lambda: hook(server), lambda row: row["queued"] == 0, 30,
                               "the waiting events delivered")  # fmt: skip
        assert kept_events(server) == []
    taken = [r["event"] for r in receiver.requests if r["status"] < 300]
    # At least once, by id: a retry in flight at the kill may be answered 2xx after it
    # (the dead server never saw that answer) and so come again after the restart.
    once = list({e["id"]: e for e in taken}.values())
    assert [e["event"] for e in once] == ["job_started", "job_done"]  # in order
    assert len(taken) - len(once) <= 1 and all(e["job"]["id"] == job["id"] for e in taken)
    assert {e["id"] for e in refused} == {once[0]["id"]}  # the one refused before the kill
    assert delivered["delivered"] == 2 and delivered["dropped"] == 0


def test_stop_button_alarm_and_a_lost_link_are_told(plotter, tmp_path, receiver):
    link = ["--serial", str(plotter.port)]
    with running_server(tmp_path / "server-data", link, ["--webhook-allow-local"]) as server:
        stop_button_alarm_and_lost_link(server, plotter, receiver)


def stop_button_alarm_and_lost_link(server: ServerProcess, plotter: Any, receiver: Receiver
                                    ) -> None:  # fmt: skip
    saved = server.client.put("/api/settings/webhooks", json={"urls": [receiver.url]})
    assert saved.status_code == 200, saved.text
    server.home()
    job = server.submit(drawing(circles=6))
    server.wait_drawing(job["id"])
    plotter.press("estop")  # the board's stop button: ALARM:10 mid-job
    server.wait_machine(lambda m: m["state"] == "Alarm", 10)
    plotter.release("estop")
    (alarm,) = [e for e in receiver.wait_for("alarm") if e["event"] == "alarm"]
    assert alarm["plotter"] == "plotter1" and alarm["job"]["id"] == job["id"]
    assert alarm["details"]["code"] == 10 and "ALARM:10" in alarm["message"]
    plotter.stop()  # the simulator goes away: the serial link is lost
    (lost,) = [e for e in receiver.wait_for("link_lost") if e["event"] == "link_lost"]
    assert lost["plotter"] == "plotter1" and "link to the plotter was lost" in lost["message"]
    told = [e["event"] for e in receiver.accepted()]
    assert told[0] == "job_started" and told[-1] == "link_lost"
    assert sorted(told[1:3]) == ["alarm", "job_failed"] and len(told) == 4
