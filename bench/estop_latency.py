"""Emergency-stop latency through the whole server, with 50 WebSocket clients watching.

Starts `plotbridge serve --virtual` (real firmware in the simulator, real time
by default), connects 50 WebSocket clients that read everything, then 50
times: upload and start a job, let it plot, send an emergency stop (REST and
WebSocket alternately) and take the simulator's `last_step_monotonic` (the
same clock as time.monotonic()) minus the moment the request was sent.
Also samples the server's CPU and resident memory while a job plots.

    .venv/bin/python bench/estop_latency.py [--runs 50] [--clients 50] [--sim-speed 1]
                                            [--cpu-hogs N]
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import multiprocessing
import os
import random
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import httpx
import websockets

TOKEN = "bench-token-0123456789"


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def zigzag(rows: int = 100) -> str:
    lines = ["G21", "G90", "M5", "G0 X20 Y20", "M3"]
    for i in range(rows):
        x = 280 if i % 2 == 0 else 20
        lines.append(f"G1 X{x} Y{20 + (i * 1.5) % 180:.3f} F3000")
    return "\n".join([*lines, "M5"]) + "\n"


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def rss_mb(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


class Bench:
    def __init__(self, args: argparse.Namespace) -> None:
        self.args = args
        self.data = Path(tempfile.mkdtemp(prefix="pb-estop-"))
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.http = httpx.AsyncClient(base_url=self.url, timeout=30,
                                      headers={"Authorization": f"Bearer {TOKEN}"})
        self.proc: subprocess.Popen[bytes] | None = None
        self.received = 0

    def spawn_server(self) -> None:
        with (self.data / "server.log").open("wb") as log:
            self.proc = subprocess.Popen(
                [sys.executable, "-m", "plotbridge", "serve", "--host", "127.0.0.1",
                 "--port", str(self.port), "--data-dir", str(self.data / "data"),
                 "--token", TOKEN, "--virtual", "--sim-speed", f"{self.args.sim_speed:g}"],
                stdout=log, stderr=subprocess.STDOUT, start_new_session=True)

    def stop_server(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(15)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()

    async def start_server(self) -> None:
        await asyncio.to_thread(self.spawn_server)
        await self.until(self.healthy, 180, "server health")
        await self.until(self.connected, 30, "board connected")

    async def healthy(self) -> bool:
        with contextlib.suppress(httpx.HTTPError):
            return (await self.http.get("/api/health", timeout=1)).status_code == 200
        return False

    async def machine(self) -> dict:
        return (await self.http.get("/api/machine")).json()

    async def connected(self) -> bool:
        return bool((await self.machine()).get("connected"))

    async def until(self, predicate, limit: float, what: str) -> None:
        deadline = time.monotonic() + limit
        while not await predicate():
            if self.proc is not None and self.proc.poll() is not None:
                raise RuntimeError(f"server exited; see {self.data / 'server.log'}")
            if time.monotonic() > deadline:
                raise RuntimeError(f"{what}: not within {limit} s")
            await asyncio.sleep(0.05)


    async def trace(self) -> dict:
        return (await self.http.get("/api/sim/trace")).json()

    async def start_job(self) -> str:
        await self.ready_machine()
        answer = await self.http.post("/api/jobs", params={"name": "bench.gcode", "start": "true"},
                                      content=zigzag().encode())
        job = answer.json()
        if answer.status_code != 201 or job.get("state") != "running":
            raise RuntimeError(f"job did not start: {answer.status_code} {job}")
        return job["id"]

    async def ready_machine(self) -> None:
        if (await self.machine())["state"] == "Alarm":
            answer = await self.http.post("/api/machine/unlock")
            if answer.status_code != 200:
                raise RuntimeError(f"unlock failed: {answer.text}")

        async def idle() -> bool:
            return (await self.machine())["state"] == "Idle"

        await self.until(idle, 10, "Idle")

    async def moving(self) -> bool:
        """Drawing: pen down and steps advancing (not travelling or settling the pen)."""
        first = await self.trace()
        await asyncio.sleep(0.05)
        second = await self.trace()
        return first["pen"] == second["pen"] == "down" and second["steps"] != first["steps"]

    async def job_state(self, job_id: str) -> str:
        return (await self.http.get(f"/api/jobs/{job_id}")).json()["state"]

    async def load_sample(self) -> dict:
        """Server CPU and memory over a few seconds of plotting."""
        assert self.proc is not None
        job = await self.start_job()
        await self.until(self.moving, 20, "motion")
        c0, t0 = cpu_seconds(self.proc.pid), time.monotonic()
        await asyncio.sleep(self.args.load_seconds)
        c1, t1 = cpu_seconds(self.proc.pid), time.monotonic()
        rss = rss_mb(self.proc.pid)
        await self.http.post(f"/api/jobs/{job}/cancel")
        await asyncio.sleep(1.0)
        return {"cpu_percent_of_one_core": round(100 * (c1 - c0) / (t1 - t0), 1),
                "rss_mb": round(rss, 1)}

    async def one_stop(self, run: int, ws: websockets.ClientConnection) -> float:
        job = await self.start_job()
        await self.until(self.moving, 20, "motion")
        await asyncio.sleep(random.uniform(0.1, 0.6))
        via = "websocket" if run % 2 else "rest"
        if via == "rest":
            # A ready connection and request bytes: "sent" is when they hit the socket,
            # so the client's own HTTP work does not count.
            reader, writer = await asyncio.open_connection("127.0.0.1", self.port)
            request = (f"POST /api/machine/estop HTTP/1.1\r\nHost: 127.0.0.1:{self.port}\r\n"
                       f"Authorization: Bearer {TOKEN}\r\nContent-Length: 0\r\n"
                       "Connection: close\r\n\r\n").encode()
            sent = time.monotonic()
            writer.write(request)
            status_line = await reader.readline()
            writer.close()
            if b" 202 " not in status_line:
                raise RuntimeError(f"estop answered {status_line!r}")
        else:
            message = json.dumps({"type": "estop"})
            sent = time.monotonic()
            await ws.send(message)
        await asyncio.sleep(0.4)
        before = await self.trace()
        await asyncio.sleep(0.2)
        after = await self.trace()
        if before["steps"] != after["steps"]:
            raise RuntimeError(f"run {run}: still stepping 0.4 s after the stop")

        async def stopped() -> bool:
            return await self.job_state(job) == "stopped"

        await self.until(stopped, 5, "job stopped")
        return after["last_step_monotonic"] - sent

    async def run(self) -> dict:
        load_before = os.getloadavg()[0]
        await self.start_server()
        # The watching clients live in another process, so their traffic does
        # not delay this one's stop requests (only the server's, as it should).
        ctx = multiprocessing.get_context("spawn")
        connected, received = ctx.Value("i", 0), ctx.Value("i", 0)
        watchers = ctx.Process(
            target=run_watchers, args=(self.port, self.args.clients, connected, received),
            daemon=True)
        watchers.start()

        async def all_connected() -> bool:
            return connected.value == self.args.clients

        await self.until(all_connected, 30, "WebSocket clients connected")
        load = await self.load_sample()
        uri = f"ws://127.0.0.1:{self.port}/api/ws?token={TOKEN}"
        latencies: list[tuple[str, float]] = []
        async with websockets.connect(uri, max_size=None) as control:
            drain = asyncio.create_task(self.drain(control))
            for run in range(self.args.runs):
                latency = await self.one_stop(run, control)
                latencies.append(("websocket" if run % 2 else "rest", latency))
                print(f"run {run + 1:2}: {latencies[-1][0]:9} {latency * 1000:7.2f} ms",
                      flush=True)
            drain.cancel()
        self.received = received.value
        watchers.terminate()
        ms = [v * 1000 for _, v in latencies]
        return {
            "runs": len(ms), "clients": self.args.clients, "sim_speed": self.args.sim_speed,
            "median_ms": round(statistics.median(ms), 2), "worst_ms": round(max(ms), 2),
            "best_ms": round(min(ms), 2),
            "rest_worst_ms": round(max(v * 1000 for k, v in latencies if k == "rest"), 2),
            "ws_worst_ms": round(max((v * 1000 for k, v in latencies if k == "websocket"),
                                     default=float("nan")), 2),
            "ws_messages_received": self.received, **load,
            # other processes on the machine skew the worst case: say how busy it was
            "load_avg_1min_before_after": [round(load_before, 2), round(os.getloadavg()[0], 2)],
            "cpus": os.cpu_count(),
        }

    async def drain(self, ws: websockets.ClientConnection) -> None:
        async for _ in ws:
            pass

    async def close(self) -> None:
        await self.http.aclose()
        await asyncio.to_thread(self.stop_server)


async def watch(port: int, connected: Any, received: Any) -> None:
    uri = f"ws://127.0.0.1:{port}/api/ws?token={TOKEN}"
    async with websockets.connect(uri, max_size=None) as ws:
        with connected.get_lock():
            connected.value += 1
        async for _ in ws:
            with received.get_lock():
                received.value += 1


def run_watchers(port: int, count: int, connected: Any, received: Any) -> None:
    async def main() -> None:
        await asyncio.gather(*(watch(port, connected, received) for _ in range(count)))

    asyncio.run(main())


def spin() -> None:
    while True:
        pass


async def main_async(args: argparse.Namespace) -> dict:
    bench = Bench(args)
    # Busy processes stand in for a machine loaded by other work (test runs, builds).
    hogs = [multiprocessing.get_context("spawn").Process(target=spin, daemon=True)
            for _ in range(args.cpu_hogs)]
    for hog in hogs:
        hog.start()
    try:
        return {**await bench.run(), "cpu_hogs": args.cpu_hogs}
    finally:
        for hog in hogs:
            hog.terminate()
        await bench.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=50)
    parser.add_argument("--clients", type=int, default=50)
    parser.add_argument("--sim-speed", type=float, default=1)
    parser.add_argument("--load-seconds", type=float, default=5)
    parser.add_argument("--cpu-hogs", type=int, default=0,
                        help="busy-looping processes to run meanwhile (a loaded machine)")
    args = parser.parse_args()
    result = asyncio.run(main_async(args))
    for key, value in result.items():
        print(f"{key:24} {value}")
    print(json.dumps(result))
    sys.exit(0 if result["worst_ms"] < 20 else 1)


if __name__ == "__main__":
    main()
