"""An unfriendly device on the LAN (127.0.0.2) attacks a real server while a job
plots: the job finishes with its trace intact, the emergency stop (REST and
WebSocket) still answers quickly, nothing answers 5xx, memory stays bounded.

Scaled down to run in a minute or two; bench/hostile.py runs the full sizes
and measures the 20 ms goal. STOP_BOUND is far inside the 10 s the unguarded
server took, and holds on a loaded machine.
"""

from __future__ import annotations

import json
import os
import signal
import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor

import pytest
from websockets.sync.client import connect

from tests.fixtures import attacks
from tests.fixtures.drawings import drawing
from tests.fixtures.server import ServerProcess, running_server
from tests.fixtures.trace import assert_same_drawing

pytestmark = pytest.mark.e2e

STOP_BOUND = 0.25  # s
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
