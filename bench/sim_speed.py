"""How fast plotsim runs unthrottled: simulated seconds per wall second.

Two workloads, each measured over a few wall seconds with `--speed 0`:
  - probe: the probe test firmware stepping X at 30 kHz from a timer interrupt;
  - firmware: the real firmware idle, running long fast G1 moves (~30 kHz
    steps), and at a typical drawing feed, when firmware/build/plotbridge.elf
    exists. The trace's violation counters are printed with each figure.
Run from the repository root: `.venv/bin/python bench/sim_speed.py [--seconds S]`.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import serial

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from tests.fixtures.plotsim import FIRMWARE_ELF, PLOTSIM, PROBE_ELF, Plotter  # noqa: E402

# 30 kHz at the default 80 steps/mm is 375 mm/s = 22500 mm/min
FAST_FEED = 22500
FIRMWARE_SETUP = [
    "$22=0",  # no homing cycle needed to move
    "$20=0",
    "$21=0",
    f"$110={FAST_FEED}",
    f"$111={FAST_FEED}",
    "$120=20000",
    "$121=20000",
    "$X",
    "G21 G90",
]


def measure(p: Plotter, seconds: float) -> dict[str, float]:
    first: dict[str, Any] = p.trace()
    w0 = time.monotonic()
    time.sleep(seconds)
    last: dict[str, Any] = p.trace()
    wall = time.monotonic() - w0
    sim = last["sim_time"] - first["sim_time"]
    pulses = sum(last["pulses"][a] - first["pulses"][a] for a in "xy")
    return {
        "sim_per_wall": sim / wall,
        "sim_s": sim,
        "step_rate_sim": pulses / sim if sim else 0.0,
        "max_step_rate": max(last["max_step_rate"].values()),
        "violations": sum(last["violations"].values()),
    }


def report(name: str, r: dict[str, float]) -> None:
    print(
        f"{name:<34} {r['sim_per_wall']:6.2f} sim s / wall s   "
        f"steps {r['step_rate_sim'] / 1000:6.1f} kHz (simulated)   "
        f"max {r['max_step_rate'] / 1000:5.1f} kHz   violations {r['violations']:.0f}"
    )


def bench_probe(seconds: float, workdir: Path) -> None:
    p = Plotter(PLOTSIM, PROBE_ELF, workdir / "probe.eeprom", start=(150, 110)).start()
    try:
        with serial.Serial(p.port, 115200, timeout=5) as port:
            time.sleep(0.3)  # power-up drawing
            report("probe, idle (UART polling loop)", measure(p, seconds))
            port.write(b"F")
            time.sleep(0.2)
            report("probe, 30 kHz X steps", measure(p, seconds))
    finally:
        p.cleanup()


def send(port: serial.Serial, line: str) -> str:
    port.write(line.encode() + b"\n")
    while True:
        answer = port.readline().decode(errors="replace").strip()
        if not answer:
            raise RuntimeError(f"no answer to {line!r}")
        if answer == "ok" or answer.startswith(("error", "ALARM")):
            return answer


def feed_moves(port: serial.Serial, stop: threading.Event, feed: int, diagonal: bool) -> None:
    """Keeps the planner full of long moves (X only, or diagonal) until told to stop."""
    x = 200
    while not stop.is_set():
        send(port, f"G1 X{x} Y{x if diagonal else 0} F{feed}")
        x = 210 - x


def measure_moving(p: Plotter, port: serial.Serial, seconds: float, feed: int,
                   diagonal: bool) -> None:
    stop = threading.Event()
    feeder = threading.Thread(target=feed_moves, args=(port, stop, feed, diagonal))
    feeder.start()
    try:
        time.sleep(0.5)  # planner filled, moving
        p.clear()
        name = f"firmware, G1 {'XY' if diagonal else 'X'} moves at {feed} mm/min"
        report(name, measure(p, seconds))
        print(f"  violations: {p.trace()['violations']}")
    finally:
        stop.set()
        feeder.join(timeout=30)
    port.write(b"\x18")  # soft reset: drop the queued moves before the next figure
    time.sleep(0.3)
    port.reset_input_buffer()
    send(port, "$X")


def bench_firmware(seconds: float, workdir: Path) -> None:
    if not FIRMWARE_ELF.exists():
        print(f"firmware: {FIRMWARE_ELF.relative_to(REPO)} not built, not measured")
        return
    p = Plotter(PLOTSIM, FIRMWARE_ELF, workdir / "fw.eeprom", start=(0, 0)).start()
    try:
        with serial.Serial(p.port, 115200, timeout=5) as port:
            port.write(b"\x18")
            time.sleep(0.5)
            port.reset_input_buffer()
            for line in FIRMWARE_SETUP:
                answer = send(port, line)
                if answer != "ok":
                    print(f"firmware: {line!r} answered {answer!r}")
            report("firmware, idle", measure(p, min(seconds, 1.0)))
            measure_moving(p, port, seconds, FAST_FEED, diagonal=False)
            measure_moving(p, port, seconds, 3000, diagonal=True)
    finally:
        p.cleanup()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=3.0, help="wall seconds per figure")
    args = parser.parse_args()
    subprocess.run(["make", "-s", "-C", str(REPO / "firmware" / "sim")], check=True)
    with tempfile.TemporaryDirectory(prefix="sim-speed-") as tmp:
        bench_probe(args.seconds, Path(tmp))
        bench_firmware(args.seconds, Path(tmp))
    return 0


if __name__ == "__main__":
    sys.exit(main())
