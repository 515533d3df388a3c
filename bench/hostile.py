"""Hostile-LAN benchmark: the emergency stop and streaming beside full-size attacks.

A real `plotbridge serve --virtual 4` (four plotters: real firmware in the
simulator, real time) runs under a 1,024 open-file limit. For idle and for each
attack (from 127.0.0.2, or a crowd of addresses 127.0.1.x): plotters 2-4 stream
long jobs throughout; plotter1's streaming rate of a job of short moves, then
its REST and WebSocket stop latencies (a fresh connection per REST stop, the
answer comes after the reset byte is written), and the server's peak memory.
Prints each figure, its ratio to idle and MET / NOT MET against the goals: stop
p99 <= 20 ms, streaming >= 90 % of idle. Full size: a crowd of 60 addresses
holding 1,100 sockets, a token-holding flood from 60 addresses with 200
WebSockets that never read, 100 MB no-token bodies.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import signal
import sys
import tempfile
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from tests.fixtures import attacks
from tests.fixtures.drawings import short_moves
from tests.fixtures.server import LimitedServer, ServerProcess

STOP_GOAL = 0.020  # s, p99
STREAM_GOAL = 0.90  # of the idle rate


class Peak:
    def __init__(self, pid: int) -> None:
        self.pid, self.peak = pid, 0.0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(0.1):
            with contextlib.suppress(OSError):
                self.peak = max(self.peak, attacks.rss_mb(self.pid))

    def stop(self) -> float:
        self._stop.set()
        self._thread.join()
        return self.peak


OTHERS = ("plotter2", "plotter3", "plotter4")  # stream throughout every measurement


def upload_moves(server: ServerProcess, plotter: str = "plotter1", lines: int = 4000,
                 start: bool = False) -> dict:  # fmt: skip
    """Uploaded before an attack starts: the killed-worker attack kills every import."""
    answer = server.client.post(
        "/api/jobs", files={"file": ("moves.gcode", short_moves(lines))}, timeout=300,
        params={"plotter": plotter, "start": "true" if start else "false"},
    )  # fmt: skip
    assert answer.status_code == 201, answer.text
    return answer.json()


def others_streaming(server: ServerProcess) -> list[str]:
    """Plotters 2-4 each start a long job (cancelled by `others_done`)."""
    jobs = []
    for name in OTHERS:
        server.client.post(f"/api/plotters/{name}/machine/unlock")
        server.wait_plotter(name, lambda m: m["state"] == "Idle", 30)
        jobs.append(upload_moves(server, name, 12000, start=True)["id"])
    return jobs


def others_done(server: ServerProcess, jobs: list[str]) -> int:
    """Cancels the others' jobs; how many were still running (all should be)."""
    running = 0
    for job_id in jobs:
        running += server.job(job_id)["state"] == "running"
        server.client.post(f"/api/jobs/{job_id}/cancel")
        server.wait_job(job_id, ("cancelled", "done", "stopped", "failed"), 30)
        server.client.delete(f"/api/jobs/{job_id}")
    return running


def streaming_rate(server: ServerProcess, job: dict, seconds: float) -> float:
    server.client.post("/api/machine/unlock")
    server.wait_machine(lambda m: m["state"] == "Idle", 30)
    assert server.client.post(f"/api/jobs/{job['id']}/start").status_code == 200
    deadline = time.monotonic() + 60
    while server.job(job["id"])["lines_done"] < 100 and time.monotonic() < deadline:
        time.sleep(0.05)
    start_lines, started = server.job(job["id"])["lines_done"], time.monotonic()
    while time.monotonic() - started < seconds:  # polled: the connection stays open (a new
        time.sleep(1.0)  # one would be refused while a crowd fills the server)
        done = server.job(job["id"])
    rate = (done["lines_done"] - start_lines) / (time.monotonic() - started)
    server.client.post(f"/api/jobs/{job['id']}/cancel")
    server.wait_job(job["id"], ("cancelled", "done", "stopped", "failed"), 30)
    server.client.delete(f"/api/jobs/{job['id']}")
    return rate


class Page:
    """A WebSocket opened before the attack (as a page's is), every message read by a
    thread as a browser does; `stop()` times a stop of plotter1 to its ack. Dropped by
    the server (it fell behind), it connects again as the page does; `reconnects` counts."""

    def __init__(self, server: ServerProcess) -> None:
        self.url = server.url.replace("http", "ws") + f"/api/ws?token={server.token}"
        self.reconnects = 0
        self.acked = threading.Event()
        self._open()

    def _open(self) -> None:
        self.ws = connect(self.url, max_size=None)
        threading.Thread(target=self._read, args=(self.ws,), daemon=True).start()

    def _read(self, ws) -> None:
        with contextlib.suppress(Exception):
            for text in ws:
                if json.loads(text) == {"type": "ack", "command": "estop"}:
                    self.acked.set()

    def stop(self) -> float:
        self.acked.clear()
        started = time.perf_counter()
        try:
            self.ws.send(json.dumps({"type": "estop", "plotter": "plotter1"}))
        except ConnectionClosed:
            self.reconnects += 1
            self._open()
            self.ws.send(json.dumps({"type": "estop", "plotter": "plotter1"}))
        if not self.acked.wait(30):
            raise RuntimeError("no WebSocket stop acknowledgement within 30 s")
        return time.perf_counter() - started

    def close(self) -> None:
        self.ws.close()


def stop_latencies(server: ServerProcess, page: Page, samples: int) -> tuple[list, list]:
    """REST stops of plotter1 on fresh connections; WebSocket stops on the page's."""
    rest, ws_times = [], []
    for _ in range(samples):
        rest.append(attacks.rest_stop(server.url, server.token))
        ws_times.append(page.stop())
        time.sleep(0.02)
    return rest, ws_times


def verdict(ok: bool) -> str:
    return "MET" if ok else "NOT MET"


def measure(server: ServerProcess, name: str, attack, args, idle: dict | None) -> dict:
    peak = Peak(server.proc.pid)
    job = upload_moves(server)
    others = others_streaming(server)
    page = Page(server)
    if attack is not None:
        attack.start()
        time.sleep(args.warmup)
    try:
        rate = streaming_rate(server, job, args.stream_seconds)
        rest, ws_times = stop_latencies(server, page, args.samples)
    finally:
        if attack is not None:
            attack.stop()
        page.close()
    streaming = others_done(server, others)
    result = {
        "rate": rate, "rest": attacks.summary(rest), "ws": attacks.summary(ws_times),
        "peak_mb": peak.stop(), "errors": attack.server_errors() if attack else 0,
        "statuses": dict(attack.statuses) if attack else {}, "reconnects": page.reconnects,
    }  # fmt: skip
    base = idle or result
    print(f"\n== {name}")
    for path in ("rest", "ws"):
        s, b = result[path], base[path]
        print(f"  {path.upper():4s} stop  median {s['median'] * 1000:7.2f} ms  p99 "
              f"{s['p99'] * 1000:7.2f} ms  worst {s['worst'] * 1000:7.2f} ms  "
              f"(x{s['median'] / b['median']:.2f} / x{s['p99'] / b['p99']:.2f} idle)  "
              f"p99 <= 20 ms: {verdict(s['p99'] <= STOP_GOAL)}")  # fmt: skip
    ratio = rate / base["rate"]
    print(f"  streaming {rate:6.1f} lines/s ({ratio * 100:5.1f} % of idle)  "
          f">= 90 %: {verdict(ratio >= STREAM_GOAL)}")
    print(f"  plotters 2-4 still streaming after it: {streaming} of 3")
    print(f"  peak memory {result['peak_mb']:.0f} MB; 5xx answers: {result['errors']}; "
          f"attacker saw {result['statuses']}; the page reconnected {result['reconnects']} "
          "times (dropped for falling behind)")
    return result


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--samples", type=int, default=100, help="stops per path per attack")
    parser.add_argument("--stream-seconds", type=float, default=5.0)
    parser.add_argument("--warmup", type=float, default=1.0, help="attack running before measuring")
    parser.add_argument("--only", help="run only attacks whose name contains this")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        server = LimitedServer(Path(tmp) / "data", ["--virtual", "4", "--sim-speed", "1"])
        server.start()
        try:
            for name in ("plotter1", *OTHERS):
                server.wait_plotter(name, lambda m: m["connected"], 60)
                server.client.post(f"/api/plotters/{name}/machine/home")
            for name in ("plotter1", *OTHERS):
                server.wait_plotter(name, lambda m: m["state"] == "Idle", 60)
            idle = measure(server, "idle", None, args, None)
            svg = attacks.identical_paths_svg(100_000)

            def uploads(attack: attacks.Attack) -> None:
                answer = server.client.post("/api/jobs", files={"file": ("many.svg", svg)})
                attack.got(answer.status_code)

            def killer(attack: attacks.Attack) -> None:
                answer_box: list = []
                thread = threading.Thread(target=lambda: answer_box.append(server.client.post(
                    "/api/jobs", files={"file": ("k.svg", svg)}, timeout=300)))  # fmt: skip
                thread.start()
                attack.wait(1.0)
                for pid in attacks.import_workers(server.proc.pid):
                    os.kill(pid, signal.SIGKILL)
                thread.join()
                attack.got(answer_box[0].status_code if answer_box else 0)

            suite = {
                "crowd: 60 addresses holding 1,100 sockets (1,024 file limit)": lambda: (
                    attacks.crowd(server.url, addresses=60, sockets=1100)),
                "token-holding flood: 60 addresses, 60 KB frames, console, bad JSON, "
                "200 never reading": lambda: attacks.authenticated_flood(
                    server.url, server.token, addresses=60, silent=200),
                "100 MB no-token bodies": lambda: attacks.huge_bodies(server.url, 100),
                "1M-key bodies, no token": lambda: attacks.big_bodies(
                    server.url, megabytes=250, keys=1_000_000, threads=4),
                "1,100 half-sent headers (1,024 file limit)": lambda: attacks.slow_headers(
                    server.url, connections=1100),
                "200 silent WebSockets, 1 MiB frames, reconnects": lambda: (
                    attacks.silent_websockets(server.url, server.token, clients=200)),
                "wrong logins": lambda: attacks.wrong_logins(server.url),
                "100,000-path SVG imports": lambda: attacks.Attack("svg", 1, uploads),
                "killed import worker": lambda: attacks.Attack("killer", 1, killer),
            }
            for name, make in suite.items():
                if args.only and args.only not in name:
                    continue
                measure(server, name, make(), args, idle)
        except Exception:
            print(server.log()[-3000:])
            raise
        finally:
            server.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
