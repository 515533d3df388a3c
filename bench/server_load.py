"""Server CPU and memory while plotting with 50 WebSocket clients watching.

Starts a real `plotbridge serve` (virtual plotter at real time by default, or
`--serial DEVICE`), homes, plots a drawing of 0.5 mm segments and, while it
streams, keeps N WebSocket clients connected. Reports the server process's CPU
(share of one core, from /proc) and resident memory (VmHWM / VmRSS).
Targets: < 10 % of one core, < 80 MB.

    .venv/bin/python bench/server_load.py [--clients 50] [--seconds 20] [--serial DEV]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import math
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from websockets.asyncio.client import connect

from tests.fixtures.server import ServerProcess

TICKS = os.sysconf("SC_CLK_TCK")


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICKS  # utime + stime


def memory_kb(pid: int) -> dict[str, int]:
    values = {}
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        key, _, rest = line.partition(":")
        if key in ("VmRSS", "VmHWM"):
            values[key] = int(rest.split()[0])
    return values


def spiral(segment_mm: float = 0.5, turns: int = 40, feed: int = 3000) -> str:
    """One long pen-down spiral of `segment_mm` segments: a dense stream of short lines."""
    lines = ["G21", "G90", "M5", "G0 X150 Y110", "M3"]
    angle, radius = 0.0, 2.0
    while angle < turns * 2 * math.pi:
        radius = 2.0 + 2.0 * angle / (2 * math.pi)
        angle += segment_mm / radius
        x, y = 150 + radius * math.cos(angle), 110 + radius * math.sin(angle)
        lines.append(f"G1 X{x:.3f} Y{y:.3f} F{feed}")
    lines.append("M5")
    return "\n".join(lines) + "\n"


def hatch(segments: int, segment_mm: float = 0.5, feed: int = 3000) -> str:
    """`segments` pen-down moves of `segment_mm` in rows 0.1 mm apart: a long program
    (one million segments is about 30 MB) to see what streaming it costs in memory."""
    per_row = int(280 / segment_mm)
    lines = ["G21", "G90", "M5", "G0 X10 Y10", "M3"]
    for n in range(segments):
        row, step = divmod(n, per_row)
        x = 10 + (step + 1) * segment_mm if row % 2 == 0 else 290 - (step + 1) * segment_mm
        lines.append(f"G1 X{x:.3f} Y{10 + (row * 0.1) % 200:.3f} F{feed}")
    lines.append("M5")
    return "\n".join(lines) + "\n"


async def watch(url: str, counts: list[int], index: int, stop: asyncio.Event) -> None:
    async with connect(url, max_queue=None) as ws:
        while not stop.is_set():
            try:
                await asyncio.wait_for(ws.recv(), 0.5)
                counts[index] += 1
            except TimeoutError:
                continue


async def measure(server: ServerProcess, clients: int, seconds: float) -> dict:
    url = server.url.replace("http", "ws") + f"/api/ws?token={server.token}"
    counts = [0] * clients
    stop = asyncio.Event()
    tasks = [asyncio.create_task(watch(url, counts, i, stop)) for i in range(clients)]
    await asyncio.sleep(2.0)  # connect and receive the snapshots
    pid = server.proc.pid
    cpu0, wall0, msgs0 = cpu_seconds(pid), time.monotonic(), sum(counts)
    job0 = await asyncio.to_thread(server.job, server.bench_job)
    await asyncio.sleep(seconds)
    cpu1, wall1, msgs1 = cpu_seconds(pid), time.monotonic(), sum(counts)
    job1 = await asyncio.to_thread(server.job, server.bench_job)
    stop.set()
    await asyncio.gather(*tasks, return_exceptions=True)
    wall = wall1 - wall0
    return {
        "clients": clients,
        "seconds": round(wall, 1),
        "cpu_percent_of_one_core": round(100 * (cpu1 - cpu0) / wall, 1),
        "rss_mb": round(memory_kb(pid)["VmRSS"] / 1024, 1),
        "peak_rss_mb": round(memory_kb(pid)["VmHWM"] / 1024, 1),
        "ws_messages_per_client_per_s": round((msgs1 - msgs0) / clients / wall, 1),
        "lines_acked_per_s": round((job1["lines_done"] - job0["lines_done"]) / wall, 1),
        "job_state_at_end": job1["state"],
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clients", type=int, default=50)
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--serial", help="a board or plotsim pty (default: --virtual)")
    parser.add_argument("--sim-speed", type=float, default=1.0)
    parser.add_argument("--segments", type=int, default=0,
                        help="plot a hatch of this many 0.5 mm moves instead of the spiral")
    args = parser.parse_args()
    link = ["--serial", args.serial] if args.serial else ["--virtual", "--sim-speed", f"{args.sim_speed:g}"]  # noqa: E501
    with tempfile.TemporaryDirectory() as tmp:
        server = ServerProcess(Path(tmp) / "data", link)
        server.start()
        try:
            server.wait_machine(lambda m: m["connected"], 30)
            if server.machine()["state"] == "Alarm":
                home = server.client.post("/api/machine/home")
                assert home.status_code == 200, home.text
            server.wait_machine(lambda m: m["state"] == "Idle", 30)
            drawing = hatch(args.segments) if args.segments else spiral()
            upload = server.client.post("/api/jobs", files={"file": ("bench.gcode", drawing)},
                                        timeout=600)
            assert upload.status_code == 201, upload.text
            server.bench_job = upload.json()["id"]
            start = server.client.post(f"/api/jobs/{server.bench_job}/start")
            assert start.status_code == 200, start.text
            result = asyncio.run(measure(server, args.clients, args.seconds))
        finally:
            server.close()
    result["target"] = "cpu < 10 % of one core, rss < 80 MB"
    print(json.dumps(result, indent=2))
    ok = result["cpu_percent_of_one_core"] < 10 and result["peak_rss_mb"] < 80
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
