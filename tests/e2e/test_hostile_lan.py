"""An unfriendly device on the LAN (127.0.0.2) attacks a real server while a job
plots: the job finishes with its trace intact, the emergency stop (REST and
WebSocket) still answers quickly, nothing answers 5xx, memory stays bounded.
Then crowds of devices (127.0.1.x): one exhausting the connections of a server
under the usual 1,024-file limit, one flooding four streaming plotters with the
token; uploads racing for the last of the disk quota; a killed idle import
worker; a plotters.toml that tries to run a shell command or holds inf and nan.

Scaled down to run in a minute or two; bench/hostile.py runs the full sizes
and measures the 20 ms goal. STOP_BOUND is far inside the 10 s the unguarded
server took, and holds on a loaded machine.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import socket
import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor

import httpx
import pytest
from websockets.sync.client import connect

from tests.fixtures import attacks
from tests.fixtures.drawings import drawing, short_moves
from tests.fixtures.server import LimitedServer, ServerProcess, running_server
from tests.fixtures.trace import assert_same_drawing
from tests.fixtures.waits import wait_until

pytestmark = pytest.mark.e2e

STOP_BOUND = 0.25  # s
# A stop through a crowd: before, 19 of 20 were refused with 503 for 40 s. Every one
# must now be answered 202 and act; the bound is for a machine loaded many times over
# (up to 1.6 s seen at a load of 30 on 2 cores); bench/hostile.py measures the latency.
CROWD_STOP_BOUND = 5.0  # s, the worst of several
RSS_BOUND_MB = 400


@pytest.fixture(scope="module")
def target(tmp_path_factory) -> Iterator[ServerProcess]:
    data = tmp_path_factory.mktemp("hostile") / "data"
    args = ["--virtual", "--sim-speed", "2", "--client-connections", "16"]
    with running_server(data, args) as server:
        server.home()
        url = server.url.replace("http", "ws") + f"/api/ws?token={server.token}"
        # held through every attack (see the last test); it buffers what it is sent, as a page would
        with connect(url, max_queue=None, ping_interval=None) as idle:
            server.idle_ws = idle
            yield server


def run_beside(server: ServerProcess, attack: attacks.Attack) -> None:
    """A job plots while `attack` runs; then the stops are timed, still under attack."""
    attack.start()
    try:
        time.sleep(0.5)  # the attack at full tilt
        job = server.submit(drawing(circles=2))
        done = server.wait_job(job["id"], ("done", "failed", "stopped"), 120)
        assert done["state"] == "done", done
        trace = server.client.get("/api/sim/trace").json()
        assert_same_drawing(server.preview(job["id"])["strokes"], trace["strokes"])
        url = server.url.replace("http", "ws") + f"/api/ws?token={server.token}"
        with connect(url) as ws:
            assert json.loads(ws.recv(10))["type"] == "machine"
            ws_latency = attacks.ws_stop(ws)
        rest_latency = attacks.rest_stop(server.url, server.token)
        assert rest_latency < STOP_BOUND, f"REST stop took {rest_latency * 1000:.0f} ms"
        assert ws_latency < STOP_BOUND, f"WebSocket stop took {ws_latency * 1000:.0f} ms"
        assert attacks.rss_mb(server.proc.pid) < RSS_BOUND_MB
    finally:
        attack.stop()
    assert attack.server_errors() == 0, attack.statuses
    assert server.client.post("/api/machine/unlock").status_code == 200  # after the stop


def test_big_bodies_without_a_token(target):
    attack = attacks.big_bodies(target.url, megabytes=200, keys=100_000)
    run_beside(target, attack)
    assert set(attack.statuses) <= {401, 413}, attack.statuses
    assert attack.statuses[413] > 0


def test_half_sent_headers_beyond_the_connection_cap(target):
    attack = attacks.slow_headers(target.url, connections=200)
    run_beside(target, attack)
    assert attack.statuses[503] > 0  # the cap answered; the server stayed reachable


def test_silent_and_flooding_websockets(target):
    run_beside(target, attacks.silent_websockets(target.url, target.token, clients=30))


def test_wrong_credentials_are_held_and_the_right_one_is_not(target):
    """Wrong logins and Bearer tokens from one address share one failure limit: their
    answers are held (doubling), while the right token from that address gets in at once."""
    attack = attacks.wrong_logins(target.url)
    started = time.monotonic()
    run_beside(target, attack)
    took = time.monotonic() - started
    assert set(attack.statuses) == {401}, attack.statuses
    assert attack.statuses[401] < 20 + took, (attack.statuses, took)  # not 1,000s per second
    assert attacks.right_token_from_the_attacker(target.url, target.token) == 200


def test_a_killed_import_worker_and_a_degenerate_svg(target):
    """The worker importing an upload is killed (as the OOM killer would): that
    upload is told, and later uploads work. Then a 20,000-path SVG is imported
    over and over while a job plots."""
    svg = attacks.identical_paths_svg(20_000)
    with ThreadPoolExecutor(1) as pool:
        pending = pool.submit(target.client.post, "/api/jobs", files={"file": ("a.svg", svg)})
        deadline = time.monotonic() + 30
        while not (workers := attacks.import_workers(target.proc.pid)):
            assert time.monotonic() < deadline, "no import worker appeared"
            time.sleep(0.05)
        time.sleep(0.3)  # the worker has the upload now
        for pid in workers:
            os.kill(pid, signal.SIGKILL)
        killed = pending.result()
    if killed.status_code != 201:  # on a fast machine the import may finish first
        assert killed.status_code == 413 and "died" in killed.text, killed.text

    def step(attack: attacks.Attack) -> None:
        answer = target.client.post("/api/jobs", files={"file": ("many.svg", svg)}, timeout=120)
        attack.got(answer.status_code)

    uploads = attacks.Attack("degenerate svg", 1, step)
    run_beside(target, uploads)
    assert not uploads.errors, (uploads.errors, uploads.statuses)
    assert len(attacks.import_workers(target.proc.pid)) <= 2
    # later uploads work (on a loaded host none may have finished while the job ran)
    after = target.client.post("/api/jobs", files={"file": ("many.svg", svg)}, timeout=120)
    assert after.status_code == 201, after.text


def test_an_idle_websocket_outlives_every_deadline(target):
    """The socket opened before the first attack (a minute ago) still answers: the
    header deadline and the limits only ever cut the attackers."""
    assert attacks.ws_stop(target.idle_ws) < STOP_BOUND


@pytest.fixture
def limited(tmp_path) -> Iterator[LimitedServer]:
    """A server of four plotters under the usual 1,024 open-file limit."""
    server = LimitedServer(tmp_path / "data", ["--virtual", "4", "--sim-speed", "2"])
    server.start()
    try:
        yield server
    finally:
        server.close()


def start_all(server: ServerProcess) -> dict[str, str]:
    """Every plotter homed and plotting a long job; plotter name -> job id."""
    names = list(server.plotters())
    for name in names:
        server.wait_plotter(name, lambda m: m["connected"], 30)
        assert server.client.post(f"/api/plotters/{name}/machine/home").status_code == 200
    jobs = {}
    for name in names:
        server.wait_plotter(name, lambda m: m["state"] == "Idle", 60)
        answer = server.client.post("/api/jobs", params={"plotter": name, "start": "true"},
                                    files={"file": ("long.gcode", short_moves(12000))})
        assert answer.status_code == 201 and answer.json()["state"] == "running", answer.text
        jobs[name] = answer.json()["id"]
    for job_id in jobs.values():
        server.wait_progress(job_id, 10, 60)
    return jobs


def crowd_refused(url: str) -> bool:
    """Whether one more connection from one of the crowd's addresses gets a 503 (a
    newcomer's address would still get in: it holds less than its share)."""
    host, port = url.removeprefix("http://").split(":")
    with contextlib.suppress(OSError):
        sock = socket.socket()
        sock.bind((attacks.crowd_address(0), 0))
        sock.settimeout(10)
        sock.connect((host, int(port)))
        with sock:
            sock.sendall(b"GET /api/health HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")
            return sock.recv(64).startswith(b"HTTP/1.1 503")
    return False


def test_a_crowd_exhausting_connections_cannot_refuse_the_stop(limited):
    """40 addresses hold 1,200 connections (fewer each than the per-client cap),
    reopened as they close: the server is full, and a stop from a new connection
    still gets through and stops the running jobs, as does one on an open socket."""
    jobs = start_all(limited)
    url = limited.url.replace("http", "ws") + f"/api/ws?token={limited.token}"
    with connect(url) as ws:
        crowd = attacks.crowd(limited.url, addresses=40, sockets=1200).start()
        try:
            wait_until(lambda: crowd_refused(limited.url), bool, 30, "the server full")
            latencies = []
            for name in ("plotter1", "plotter2"):
                started = time.perf_counter()
                answer = httpx.post(f"{limited.url}/api/plotters/{name}/machine/estop",
                                    headers={"Authorization": f"Bearer {limited.token}"},
                                    timeout=30)  # fmt: skip
                latencies.append(time.perf_counter() - started)
                assert answer.status_code == 202, answer.text
            latencies.append(attacks.rest_stop(limited.url, limited.token))  # the first's again
            started = time.perf_counter()
            ws.send(json.dumps({"type": "estop", "plotter": "plotter3"}))
            while json.loads(ws.recv(30)) != {"type": "ack", "command": "estop"}:
                pass
            latencies.append(time.perf_counter() - started)
            everyone = httpx.post(f"{limited.url}/api/estop", timeout=30,
                                  headers={"Authorization": f"Bearer {limited.token}"})
            assert everyone.status_code == 202, everyone.text
            wait_until(lambda: crowd_refused(limited.url), bool, 30, "the server still full")
        finally:
            crowd.stop()
    assert crowd.statuses[503] > 0 and crowd.server_errors() == 0, crowd.statuses
    assert max(latencies) < CROWD_STOP_BOUND, [f"{t * 1000:.0f} ms" for t in latencies]
    for job_id in jobs.values():
        assert limited.wait_job(job_id, ("stopped",), 30)["state"] == "stopped"


def test_a_token_holding_flood_beside_four_streaming_plotters(limited):
    """60 addresses send 60 KB frames, console lines and invalid JSON as fast as they
    may, 200 WebSockets never read: the stops still answer within the bound."""
    jobs = start_all(limited)
    flood = attacks.authenticated_flood(limited.url, limited.token, addresses=60,
                                        silent=200).start()  # fmt: skip
    try:
        wait_until(lambda: flood.progress.value, lambda n: n >= 200, 90, "the flood's sockets")
        url = limited.url.replace("http", "ws") + f"/api/ws?token={limited.token}"
        with connect(url, max_size=None) as ws:
            ws_latency = attacks.ws_stop(ws)
        rest = [attacks.rest_stop(limited.url, limited.token) for _ in range(5)]
        running = [limited.job(jobs[name])["state"] for name in ("plotter2", "plotter3")]
    finally:
        flood.stop()
    assert flood.statuses[101] >= 200, (flood.statuses, flood.errors)
    assert ws_latency < STOP_BOUND, f"WebSocket stop took {ws_latency * 1000:.0f} ms"
    assert sorted(rest)[2] < STOP_BOUND, [f"{t * 1000:.0f} ms" for t in rest]
    assert running == ["running", "running"]  # the others plotted on through the flood
    assert limited.wait_job(jobs["plotter1"], ("stopped",), 30)["state"] == "stopped"


def test_huge_bodies_without_a_token_cost_the_stop_nothing(target):
    """100 MB no-token bodies streaming in beside the stops."""
    attack = attacks.huge_bodies(target.url, megabytes=100).start()
    try:
        time.sleep(0.5)
        latencies = [attacks.rest_stop(target.url, target.token) for _ in range(10)]
    finally:
        attack.stop()
    assert set(attack.statuses) <= {401, 413}, attack.statuses
    assert sorted(latencies)[5] < STOP_BOUND, [f"{t * 1000:.0f} ms" for t in latencies]
    assert target.client.post("/api/machine/unlock").status_code == 200


def test_concurrent_uploads_never_overshoot_the_quota(tmp_path):
    """Two uploads that each fit in what is left of the quota, but not both: one is
    stored, the other refused (507); the jobs stay within the quota."""
    data = tmp_path / "data"
    upload = moves(9000)
    with running_server(data, ["--virtual", "--sim-speed", "0"]) as server:
        first = server.client.post("/api/jobs", files={"file": ("a.gcode", upload)})
        assert first.status_code == 201, first.text
    job = sum(f.stat().st_size for f in (data / "jobs").rglob("*") if f.is_file())
    # room for one more job beside the first and the other upload's reservation, not two
    quota_mb = (2 * job + len(upload) + 3 * job) / 2 / 2**20
    with running_server(data, ["--virtual", "--sim-speed", "0"],
                        ["--total-quota-mb", f"{quota_mb:.4f}"]) as server:
        with ThreadPoolExecutor(2) as pool:
            answers = list(pool.map(
                lambda n: server.client.post("/api/jobs", files={"file": (f"{n}.gcode", upload)}),
                range(2)))  # fmt: skip
    codes = sorted(a.status_code for a in answers)
    assert codes == [201, 507], [a.text[:300] for a in answers]
    assert "MB quota" in next(a for a in answers if a.status_code == 507).text
    stored = sum(f.stat().st_size for f in (data / "jobs").rglob("*") if f.is_file())
    assert stored <= quota_mb * 2**20


def moves(lines: int) -> str:
    return "G21\nG90\n" + "".join(f"G1 X{i % 100}.5 Y{i % 37}.25 F3000\n" for i in range(lines))


def test_a_killed_idle_worker_is_replaced_before_the_next_upload(target):
    """Killed while it waited for work: the next upload is imported by a fresh worker."""
    warm = target.client.post("/api/jobs", files={"file": ("w.gcode", moves(50))})
    assert warm.status_code == 201, warm.text
    workers = attacks.import_workers(target.proc.pid)
    assert workers
    for pid in workers:
        os.kill(pid, signal.SIGKILL)
    wait_until(lambda: attacks.import_workers(target.proc.pid), lambda left: not left
               or not set(left) & set(workers), 10, "the workers gone")  # fmt: skip
    after = target.client.post("/api/jobs", files={"file": ("a.gcode", moves(50))})
    assert after.status_code == 201, after.text


@pytest.mark.parametrize("table, key", [
    ('board = "$(shell touch {marker})"', "board"),
    ("width = inf\nheight = 100", "width"),
    ("width = 100\nheight = nan", "height"),
])  # fmt: skip
def test_a_plotters_file_runs_no_command_and_takes_no_inf(tmp_path, table, key):
    """The server refuses to start, naming the file, the line and the key; the shell
    command in a board name never runs."""
    marker = tmp_path / "ran"
    data = tmp_path / "data"
    data.mkdir()
    (data / "plotters.toml").write_text(
        "[[plotter]]\nvirtual = true\n" + table.format(marker=marker) + "\n")
    server = ServerProcess(data, [])
    with pytest.raises(RuntimeError, match="exited") as info:
        server.start()
    server.close()
    line = 3 if key != "height" else 4
    assert f"plotters.toml:{line}: plotter 1: {key}: " in str(info.value)
    assert not marker.exists()
