"""Several plotters on one server: 4 virtual plotters plotting at once.

Starts `plotbridge serve --virtual 4` (the real firmware in 4 simulators, real
time by default), homes them, and then, `--rounds` times: starts a long job on
every plotter, lets them all plot, and stops each plotter on its own
(`POST /api/plotters/NAME/machine/estop`) while the others go on; the latency
of a stop is the simulator's `last_step_monotonic` (the same clock as
time.monotonic()) minus the moment the request was sent. Meanwhile it samples
the CPU time and resident memory of the server process and, separately, of the
simulators; and a WebSocket client records every machine report (`Bf:` free
planner blocks) to check that no plotter's planner runs empty mid-job.

    .venv/bin/python bench/plotters.py [--plotters 4] [--rounds 50] [--sim-speed 1]
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import httpx
import websockets

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from tests.fixtures.server import ServerProcess  # noqa: E402

TICK = 100  # /proc/PID/stat clock ticks per second on Linux
TARGET_ESTOP_MS = 100.0
TARGET_SERVER_CPU = 25.0  # % of one core for 4 plotters (the issue: "a few percent per plotter")
TARGET_SERVER_RSS_MB = 120.0


def zigzag(rows: int = 60, segment: float = 0.5, feed: int = 3000) -> str:
    """One pen-down line of 0.5 mm moves: no pen lift, so the planner never drains by design."""
    lines = ["G21", "G90", "M5", "G0 X10 Y10", "M3"]
    x, y = 10.0, 10.0
    for row in range(rows):
        for _ in range(160):
            x += segment if row % 2 == 0 else -segment
            lines.append(f"G1 X{x:.3f} Y{y:.3f} F{feed}")
        y += 1.0
        lines.append(f"G1 X{x:.3f} Y{y:.3f} F{feed}")
    lines.append("M5")
    return "\n".join(lines) + "\n"


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICK


def rss_mb(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return 0.0


def children(pid: int) -> list[int]:
    found = []
    for task in Path(f"/proc/{pid}/task").iterdir():
        with contextlib.suppress(OSError):
            found += [int(c) for c in (task / "children").read_text().split()]
    return found


def simulators(server_pid: int) -> list[int]:
    return [p for p in children(server_pid)
            if b"plotsim" in Path(f"/proc/{p}/cmdline").read_bytes()]  # fmt: skip


class Watch:
    """Machine reports and job progress from the WebSocket."""

    def __init__(self) -> None:
        self.planner: dict[str, int] = {}  # planner depth per plotter (the most free seen)
        self.samples: list[tuple[str, str, int]] = []  # plotter, state, free blocks
        self.jobs: dict[str, dict[str, Any]] = {}
        self.starved: list[tuple[str, str, int]] = []
        self.began_at: dict[str, int] = {}  # lines done when the job (re)started there

    async def run(self, url: str, token: str) -> None:
        async with websockets.connect(f"{url.replace('http', 'ws')}/api/ws?token={token}") as ws:
            async for text in ws:
                self.on(json.loads(text))

    def on(self, message: dict[str, Any]) -> None:
        if message.get("type") == "job":
            job = message["job"]
            name = job["plotter"] or ""
            before = self.jobs.get(name)
            if job["state"] == "running" and (before is None or before["state"] != "running"):
                self.began_at[name] = job["lines_done"]  # a resume's preamble lifts the pen
            self.jobs[name] = job
        elif message.get("type") == "machine":
            name, machine = message["plotter"], message["machine"]
            free = machine.get("planner_free")
            if free is None:
                return
            depth = self.planner[name] = max(self.planner.get(name, 0), free)
            job = self.jobs.get(name)
            mid_job = (job is not None and job["state"] == "running"
                       and self.began_at.get(name, 0) + 50 < job["lines_done"]
                       < job["lines_total"] - depth - 10)
            if mid_job:
                self.samples.append((name, machine["state"], free))
                if free >= depth:
                    self.starved.append((name, machine["state"], job["lines_done"]))


async def bench(args: argparse.Namespace) -> int:
    data = Path(tempfile.mkdtemp(prefix="bench-plotters-"))
    link = ["--virtual", str(args.plotters), "--sim-speed", str(args.sim_speed)]
    server = ServerProcess(data, link, ["--log-level", "warning"])
    await asyncio.to_thread(server.start)
    names = [f"plotter{n}" for n in range(1, args.plotters + 1)]
    watch = Watch()
    http = httpx.AsyncClient(base_url=server.url, timeout=130,
                             headers={"Authorization": f"Bearer {server.token}"})  # fmt: skip
    watcher = asyncio.create_task(watch.run(server.url, server.token))
    latencies: dict[str, list[float]] = {name: [] for name in names}
    cpu = {"server": 0.0, "sims": 0.0}
    plotting_s = 0.0
    rss: list[float] = []
    try:
        await asyncio.gather(*(home(http, name) for name in names))
        uploads = [await upload(http, zigzag()) for _ in names]
        assert server.proc is not None
        sims = simulators(server.proc.pid)
        for round_ in range(args.rounds):
            pairs = zip(uploads, names, strict=True)
            await asyncio.gather(*(begin(http, job, name) for job, name in pairs))
            began = time.monotonic()
            server_cpu, sims_cpu = cpu_seconds(server.proc.pid), sum(map(cpu_seconds, sims))
            await asyncio.sleep(args.plot_s)
            cpu["server"] += cpu_seconds(server.proc.pid) - server_cpu
            cpu["sims"] += sum(map(cpu_seconds, sims)) - sims_cpu
            plotting_s += time.monotonic() - began
            rss.append(rss_mb(server.proc.pid))
            for name in names:  # one at a time, the others still plotting
                sent = time.monotonic()
                answer = await http.post(f"/api/plotters/{name}/machine/estop")
                assert answer.status_code == 202, answer.text
                await asyncio.sleep(0.3)
                trace = (await http.get(f"/api/plotters/{name}/sim/trace")).json()
                latencies[name].append((trace["last_step_monotonic"] - sent) * 1000)
            print(f"round {round_ + 1}/{args.rounds}: worst "
                  f"{max(lat[-1] for lat in latencies.values()):.1f} ms", flush=True)
    finally:
        watcher.cancel()
        await http.aclose()
        await asyncio.to_thread(server.close)
    report(args, latencies, cpu, plotting_s, rss, watch)
    return 0


async def home(http: httpx.AsyncClient, name: str) -> None:
    for _ in range(300):
        machine = (await http.get(f"/api/plotters/{name}/machine")).json()
        if machine["connected"]:
            break
        await asyncio.sleep(0.1)
    answer = await http.post(f"/api/plotters/{name}/machine/home")
    assert answer.status_code == 200, answer.text


async def upload(http: httpx.AsyncClient, gcode: str) -> str:
    answer = await http.post("/api/jobs", files={"file": ("zigzag.gcode", gcode)})
    assert answer.status_code == 201, answer.text
    return answer.json()["id"]


async def begin(http: httpx.AsyncClient, job_id: str, name: str) -> None:
    """Unlock after the last stop (a reset mid-move leaves an alarm), then start the job."""
    for _ in range(100):
        machine = (await http.get(f"/api/plotters/{name}/machine")).json()
        if machine["state"] == "Idle":
            break
        if machine["state"] == "Alarm":
            await http.post(f"/api/plotters/{name}/machine/unlock")
        await asyncio.sleep(0.1)
    answer = await http.post(f"/api/jobs/{job_id}/start", params={"plotter": name})
    assert answer.status_code == 200, answer.text


def report(args: argparse.Namespace, latencies: dict[str, list[float]], cpu: dict[str, float],
           plotting_s: float, rss: list[float], watch: Watch) -> None:  # fmt: skip
    def line(target: str, figure: str, met: bool) -> None:
        print(f"{target:<58} {figure:>22}  {'MET' if met else 'NOT MET'}")

    print(f"\n{args.plotters} virtual plotters at {args.sim_speed:g}x real time, "
          f"{args.rounds} rounds, {plotting_s:.0f} s of all plotting at once")
    server_cpu = 100 * cpu["server"] / max(plotting_s, 1e-9)
    sims_cpu = 100 * cpu["sims"] / max(plotting_s, 1e-9)
    line(f"server CPU while all plot (<= {TARGET_SERVER_CPU:g}% of a core)",
         f"{server_cpu:.1f}%", server_cpu <= TARGET_SERVER_CPU)
    print(f"{'  (simulators, not the server: ' + f'{sims_cpu:.0f}% of a core in all)':<58}")
    worst_rss = max(rss, default=0.0)
    line(f"server RSS (<= {TARGET_SERVER_RSS_MB:g} MB)", f"{worst_rss:.1f} MB",
         worst_rss <= TARGET_SERVER_RSS_MB)
    for name, values in latencies.items():
        worst = max(values, default=float("inf"))
        line(f"estop latency {name}, worst of {len(values)} (< {TARGET_ESTOP_MS:g} ms)",
             f"{worst:.1f} ms (median {sorted(values)[len(values) // 2]:.1f})",
             worst < TARGET_ESTOP_MS)
    line("planner never empty mid-job (machine reports)",
         f"{len(watch.starved)} of {len(watch.samples)} empty", not watch.starved
         and bool(watch.samples))
    for name, state, at in watch.starved[:10]:
        print(f"  empty: {name} {state} at line {at}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plotters", type=int, default=4)
    parser.add_argument("--rounds", type=int, default=50)
    parser.add_argument("--plot-s", type=float, default=1.5, help="plotting time per round")
    parser.add_argument("--sim-speed", type=float, default=1.0)
    return asyncio.run(bench(parser.parse_args()))


if __name__ == "__main__":
    sys.exit(main())
