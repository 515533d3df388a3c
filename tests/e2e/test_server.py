"""End to end: a real `plotbridge serve` process, the real firmware in the simulator.

Every test homes the machine first (the firmware starts in Alarm with homing on),
then drives it only through the REST and WebSocket API.
"""

from __future__ import annotations

import json
import sqlite3
import time
from concurrent.futures import ThreadPoolExecutor

import pytest
from plotbridge.plotter.runner import JOB_POLL_HZ
from websockets.sync.client import connect

from tests.fixtures.attacks import import_workers
from tests.fixtures.drawings import FEED, drawing, many_circles_svg, square_stroke
from tests.fixtures.server import running_server
from tests.fixtures.trace import (
    ESTOP_REDRAW_MM,
    assert_same_drawing,
    assert_stopped,
    drawn_once_mm,
    rest_stop_mid_stroke,
    stop_clock,
    stroke_length,
    wait_still,
)
from tests.fixtures.waits import wait_until

pytestmark = pytest.mark.e2e

def test_plot_matches_preview(server, plotter):
    server.home()
    plotter.clear()
    job = server.submit(drawing(circles=2))
    done = server.wait_job(job["id"], ("done", "failed", "stopped", "interrupted"), 120)
    assert done["state"] == "done", done
    assert done["lines_done"] == done["lines_total"] and done["progress"] == 1.0
    expected = server.preview(job["id"])["strokes"]
    trace = plotter.trace()
    assert len(trace["strokes"]) == len(expected)
    assert_same_drawing(expected, trace["strokes"])
    assert abs(trace["draw_mm"] - stroke_length(expected)) < 1.0
    assert sum(trace["violations"].values()) == 0


def test_estop_rest_mid_job_then_resume(server, plotter):
    server.home()
    once = drawn_once_mm(server, plotter, square_stroke())
    plotter.clear()
    job = rest_stop_mid_stroke(server, plotter)
    # the next job waits until the alarm is cleared, saying why
    other = server.submit(drawing(), start=False)
    waiting = server.client.post(f"/api/jobs/{other['id']}/start").json()
    assert waiting["state"] == "waiting" and "$H" in waiting["waiting"]
    assert server.client.post(f"/api/jobs/{other['id']}/cancel").status_code == 200
    # after homing, the stopped job can be resumed and the drawing completed
    server.home()
    assert server.client.post(f"/api/jobs/{job['id']}/resume").status_code == 200
    assert server.wait_job(job["id"], ("done", "failed", "stopped"), 120)["state"] == "done"
    expected = server.preview(job["id"])["strokes"]
    trace = plotter.trace()
    assert_same_drawing(expected, trace["strokes"])
    # resumed where the steps stopped (the first report after the reset tells it)
    redrawn = trace["draw_mm"] - once
    print(f"estop: {redrawn:.4f} mm drawn twice (allowed {ESTOP_REDRAW_MM})")
    assert redrawn <= ESTOP_REDRAW_MM, f"{redrawn:.3f} mm drawn twice"


def test_estop_does_not_wait_for_an_import(server, plotter):
    server.home()
    job = server.submit(square_stroke(laps=4))  # long enough to outlast the upload's start
    server.wait_drawing(job["id"])
    big = many_circles_svg(20_000)  # seconds of import work
    with ThreadPoolExecutor(1) as pool:
        uploading = pool.submit(
            server.client.post, "/api/jobs", files={"file": ("big.svg", big)}, timeout=300
        )
        assert server.proc is not None
        wait_until(lambda: import_workers(server.proc.pid), bool, 30, "an import worker")
        assert not uploading.done()
        assert server.job(job["id"])["lines_done"] < 780, "the job ran out before the stop"
        sent = stop_clock(plotter)
        response = server.client.post("/api/machine/estop")
        answered = time.monotonic() - sent.at
        assert response.status_code == 202 and answered < 0.2
        assert_stopped(server, plotter, job["id"], sent)
        assert uploading.result().status_code in (201, 422)


def test_estop_websocket_mid_job(server, plotter):
    server.home()
    job = server.submit(square_stroke())
    url = server.url.replace("http", "ws") + f"/api/ws?token={server.token}"
    with connect(url) as ws:
        first = json.loads(ws.recv(5))
        assert first["type"] == "machine"
        server.wait_drawing(job["id"])
        sent = stop_clock(plotter)
        ws.send(json.dumps({"type": "estop"}))
        seen_ack = seen_stopped = False
        deadline = time.monotonic() + 5
        while not (seen_ack and seen_stopped) and time.monotonic() < deadline:
            message = json.loads(ws.recv(5))
            seen_ack |= message == {"type": "ack", "command": "estop"}
            seen_stopped |= message["type"] == "job" and message["job"]["state"] == "stopped"
        assert seen_ack and seen_stopped
    assert_stopped(server, plotter, job["id"], sent)


def test_pause_resume(server, plotter):
    server.home()
    plotter.clear()
    job = server.submit(drawing(circles=10))
    server.wait_progress(job["id"], 30)
    paused = server.client.post(f"/api/jobs/{job['id']}/pause")
    assert paused.status_code == 200 and paused.json()["state"] == "paused"
    server.wait_machine(lambda m: m["state"] == "Hold", 20)
    held = wait_still(plotter, 5)["steps"]  # the deceleration ends
    time.sleep(0.3)  # a window in which nothing may move
    assert plotter.trace()["steps"] == held, "the machine moved during a feed hold"
    assert server.job(job["id"])["state"] == "paused"
    resumed = server.client.post(f"/api/jobs/{job['id']}/resume")
    assert resumed.status_code == 200 and resumed.json()["state"] == "running"
    # the machine's own pause and resume buttons drive the job state too
    server.wait_machine(lambda m: m["state"] == "Run", 20)
    plotter.press("pause")
    server.wait_job(job["id"], ("paused",), 20)
    plotter.release("pause")
    plotter.press("resume")
    server.wait_job(job["id"], ("running", "done"), 20)
    plotter.release("resume")
    done = server.wait_job(job["id"], ("done", "failed", "stopped", "interrupted"), 120)
    assert done["state"] == "done", done
    assert_same_drawing(server.preview(job["id"])["strokes"], plotter.trace()["strokes"])


def test_machine_stop_button_fails_the_job_with_line_and_alarm(server, plotter):
    server.home()
    job = server.submit(drawing(circles=6))
    server.wait_drawing(job["id"])
    plotter.press("estop")
    failed = server.wait_job(job["id"], ("failed", "stopped", "interrupted", "done"), 20)
    plotter.release("estop")
    assert failed["state"] == "failed", failed
    assert "ALARM:10" in failed["error"] and failed["error"].startswith("line ")
    machine = server.wait_machine(lambda m: m["state"] == "Alarm", 20)
    assert machine["alarm"] == 10


def test_plotter_killed_mid_job_then_resumed(server, plotter):
    server.home()
    once = drawn_once_mm(server, plotter, drawing(circles=6))
    plotter.clear()
    job = server.submit(drawing(circles=6))
    started = time.monotonic()
    sim_start = plotter.trace()["sim_time"]
    server.wait_progress(job["id"], 150)
    # SIGTERM: the simulator dies mid-move all the same, but writes its final trace
    # (after SIGKILL the file can lag the pen by 50 ms, which would fake a gap).
    plotter.stop()
    killed_at = time.monotonic()
    interrupted = server.wait_job(job["id"], ("interrupted",), 20)
    # the closed port tells at once, well before the 5 s silence limit could
    assert time.monotonic() - killed_at < 4.0, "link loss noticed too late"
    assert 1 <= interrupted["resume_line"] <= interrupted["lines_done"] + 1
    before = plotter.trace()  # the trace file the stopped simulator left
    sim_rate = (before["sim_time"] - sim_start) / (killed_at - started)  # sim s per wall s
    x, y = before["position"]["x"], before["position"]["y"]
    plotter.restart(start=(x, y))
    server.wait_machine(lambda m: m["connected"], 15)
    server.home()
    resumed = server.client.post(f"/api/jobs/{job['id']}/resume")
    assert resumed.status_code == 200, resumed.text
    done = server.wait_job(job["id"], ("done", "failed", "stopped", "interrupted"), 120)
    assert done["state"] == "done", done
    after = plotter.trace()
    expected = server.preview(job["id"])["strokes"]
    assert_same_drawing(expected, before["strokes"] + after["strokes"])
    # Redrawn: the travel since the last status report, at most one report interval
    # (two, for a report that a busy machine delays), nothing of the strokes before it.
    status_interval = 1 / JOB_POLL_HZ * max(sim_rate, 1.0)  # simulated s between reports
    allowance = FEED / 60 * 2 * status_interval + ESTOP_REDRAW_MM
    redrawn = before["draw_mm"] + after["draw_mm"] - once
    print(f"resumed at line {interrupted['resume_line']} of {interrupted['lines_done']} acked;"
          f" {redrawn:.2f} mm drawn twice (allowed {allowance:.1f})")
    assert redrawn <= allowance, f"{redrawn:.1f} mm drawn twice (allowed {allowance:.1f})"


def test_server_killed_mid_job_keeps_queue(plotter_factory, tmp_path):
    # A plotter at 3x real time: the job must still be running when the server dies,
    # however fast the unthrottled simulation would be on this machine.
    plotter = plotter_factory(speed=3)
    with running_server(tmp_path / "server-data", ["--serial", str(plotter.port)]) as server:
        server.home()
        job = server.submit(drawing(circles=15))
        waiting = [server.submit(drawing(), start=False)["id"] for _ in range(2)]
        moved = server.client.post(f"/api/jobs/{waiting[1]}/move", json={"position": 0})
        assert moved.status_code == 200
        server.wait_progress(job["id"], 60)
        wait_until(lambda: server.stored_job(job["id"]).get("lines_done", 0), lambda n: n >= 60,
                   30, "progress written to the store", errors=(sqlite3.Error,))
        server.kill()
        server.start()
        jobs = server.client.get("/api/jobs").json()
        assert [j["id"] for j in jobs] == [job["id"], waiting[1], waiting[0]]
        assert [j["state"] for j in jobs] == ["interrupted", "queued", "queued"]
        assert jobs[0]["resume_line"] and jobs[0]["lines_done"] >= 60
        server.wait_machine(lambda m: m["state"] == "Idle", 30)
        resumed = server.client.post(f"/api/jobs/{job['id']}/resume")
        assert resumed.status_code == 200, resumed.text
        final = server.wait_job(job["id"], ("done", "failed", "interrupted"), 120)
        assert final["state"] == "done"


def test_virtual_mode_serves_the_trace(server_virtual):
    info = server_virtual.client.get("/api/server").json()
    assert info["virtual"] is True and info["serial"] is None
    server_virtual.home()
    changed = server_virtual.client.put("/api/machine/settings", json={"settings": {"62": 120}})
    assert changed.status_code == 200, changed.text
    settings = server_virtual.client.get("/api/machine/settings").json()["settings"]
    assert {s["id"]: s["value"] for s in settings}[62] == 120
    answer = server_virtual.client.post("/api/machine/command", json={"line": "G0 X5 Y5"})
    assert answer.json() == {"responses": ["ok"]}
    server_virtual.wait_machine(lambda m: m["position"] == {"x": 5.0, "y": 5.0}, 10)
    job = server_virtual.submit(drawing())
    assert server_virtual.wait_job(job["id"], ("done", "failed"), 120)["state"] == "done"
    trace = server_virtual.client.get("/api/sim/trace").json()
    assert_same_drawing(server_virtual.preview(job["id"])["strokes"], trace["strokes"])
