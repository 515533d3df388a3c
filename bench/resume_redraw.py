"""Exact resume: the pen-down length drawn twice when a job is resumed.

For each drawing (long strokes; 0.5 mm segments) and each interruption (an
emergency stop; the link lost: the simulator stopped mid-stroke and started
again where its pen was; the server killed with SIGKILL and started again), it
plots the drawing once without a stop (the reference trace length), then again
with the interruption once 40 % of the ink is down, resumes the job and
compares the traced pen-down length with the reference. The real firmware in
plotsim at real time, a real `plotbridge serve`.

Targets (issue 12): an emergency stop redraws at most one step; a lost link at
most one status report interval of travel (the feed times 1 / JOB_POLL_HZ). A
server killed mid-stroke leaves the board running what it holds: it is measured
against the same interval (the issue's "against today's many strokes").

    .venv/bin/python bench/resume_redraw.py [--sim-speed 1]
"""

from __future__ import annotations

import argparse
import contextlib
import os
import shutil
import signal
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from plotbridge.plotter.runner import JOB_POLL_HZ  # noqa: E402

from tests.fixtures.plotsim import FIRMWARE_ELF, PLOTSIM, Plotter  # noqa: E402
from tests.fixtures.server import ServerProcess  # noqa: E402

FEED = 3000  # mm/min
STEP_MM = 1 / 80
TARGETS = {"estop": STEP_MM, "link drop": FEED / 60 / JOB_POLL_HZ,
           "server kill -9": FEED / 60 / JOB_POLL_HZ}  # fmt: skip


def long_strokes() -> str:
    lines = ["G21", "G90", "M5"]
    for row in range(6):
        y = 20 + 10 * row
        lines += [f"G0 X20 Y{y}", "M3", f"G1 X170 Y{y} F{FEED}", "M5"]
    return "\n".join(lines) + "\n"


def short_segments(segment: float = 0.5) -> str:
    lines = ["G21", "G90", "M5", "G0 X20 Y20", "M3"]
    x = 20.0
    for row in range(4):
        for _ in range(200):
            x += segment if row % 2 == 0 else -segment
            lines.append(f"G1 X{x:.3f} Y{20 + 2 * row} F{FEED}")
        lines.append(f"G1 X{x:.3f} Y{22 + 2 * row} F{FEED}")
    lines.append("M5")
    return "\n".join(lines) + "\n"


def submit(server: ServerProcess, gcode: str) -> str:
    response = server.client.post("/api/jobs", files={"file": ("bench.gcode", gcode)})
    response.raise_for_status()
    job_id = response.json()["id"]
    server.client.post(f"/api/jobs/{job_id}/start").raise_for_status()
    return job_id


def wait(predicate: Callable[[], bool], limit: float, what: str) -> None:
    deadline = time.monotonic() + limit
    while not predicate():
        if time.monotonic() > deadline:
            raise RuntimeError(f"timed out waiting for {what}")
        time.sleep(0.01)


def settled(plotter: Plotter) -> bool:
    steps = plotter.trace()["steps"]
    time.sleep(0.5)
    return plotter.trace()["steps"] == steps


def run(kind: str, gcode: str, speed: float, work: Path) -> float:
    """The pen-down mm drawn twice for one drawing and one interruption."""
    plotter = Plotter(PLOTSIM, FIRMWARE_ELF, work / "eeprom.bin", speed).start()
    server = ServerProcess(work / "data", ["--serial", plotter.port])
    try:
        server.start()
        server.home()
        plotter.clear()
        reference = submit(server, gcode)
        server.wait_job(reference, "done", 300)
        once = plotter.trace()["draw_mm"]
        plotter.clear()
        job = submit(server, gcode)
        wait(lambda: plotter.trace()["draw_mm"] >= 0.4 * once, 300, "40 % of the ink")
        drawn_before = 0.0
        if kind == "estop":
            server.client.post("/api/machine/estop").raise_for_status()
            server.wait_job(job, "stopped", 10)
        elif kind == "link drop":
            plotter.stop()
            server.wait_job(job, "interrupted", 10)
            before = plotter.trace()
            drawn_before = before["draw_mm"]
            plotter.restart(start=(before["position"]["x"], before["position"]["y"]))
        else:
            killed = server.proc.pid if server.proc else None
            server.kill()
            if killed is not None:  # its import workers (own process group) go too
                with contextlib.suppress(ProcessLookupError, PermissionError):
                    os.killpg(killed, signal.SIGKILL)
            wait(lambda: settled(plotter), 60, "the board to run out of moves")
            server.start()
            server.wait_job(job, "interrupted", 10)
        server.wait_machine(lambda m: m["connected"] and m["state"] in ("Idle", "Alarm"), 30)
        if server.machine()["state"] == "Alarm":
            server.home()
        server.client.post(f"/api/jobs/{job}/resume").raise_for_status()
        final = server.wait_job(job, ("done", "failed", "stopped", "interrupted"), 300)
        if final["state"] != "done":
            raise RuntimeError(f"the resumed job ended {final['state']}: {final.get('error')}")
        return drawn_before + plotter.trace()["draw_mm"] - once
    finally:
        server.close()
        plotter.cleanup()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sim-speed", type=float, default=1.0)
    args = parser.parse_args()
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))  # the servers' finally blocks run
    failed = False
    for name, gcode in (("long strokes", long_strokes()), ("0.5 mm segments", short_segments())):
        for kind, target in TARGETS.items():
            work = Path(tempfile.mkdtemp(prefix="resume-bench-"))
            try:
                redrawn = run(kind, gcode, args.sim_speed, work)
            finally:
                shutil.rmtree(work, ignore_errors=True)
            met = redrawn <= target
            failed |= not met
            print(f"{name:16} {kind:15} redrawn {redrawn:8.3f} mm  target <= {target:.4f} mm  "
                  f"{'MET' if met else 'NOT MET'}", flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
