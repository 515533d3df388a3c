"""Per board profile: flash and RAM against the chip budget, the sustained
step rate (step/dir) or phase rate (four-wire) with no late step, and lines
per second of 0.5 mm segments. Figures in simulated time (plotsim).

- size: avr-size of `make BOARD=NAME` (text+data flash, data+bss RAM);
- rate: one long X move commanded at the target rate, acceleration high; the
  cruise is sampled from plotsim's trace in windows, and a window more than
  one step behind the commanded rate is a late step (a window's edges fall
  between steps, so one step is the resolution; the lowest window rate is
  printed as well);
- lines/s: 1000 G1 segments of 0.5 mm around a circle, streamed with GRBL
  character counting (128 bytes), between the first and last ok.

Run: .venv/bin/python bench/board_bench.py [BOARD ...]
"""

from __future__ import annotations

import itertools
import math
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from tests.fixtures.grbl import Grbl  # noqa: E402
from tests.fixtures.plotsim import FIRMWARE_DIR, PLOTSIM, Plotter  # noqa: E402

BOARDS = {  # name: (chip budget flash, RAM), steps/mm default, drive
    "uno-cnc-shield": ((30_720, 1_536), 80, "step/dir"),
    "uno-uln2003": ((30_720, 1_536), 32.6, "four-wire"),
    "mega-l298n": ((253_952, 7_168), 5, "four-wire"),
    "mega-stepdir": ((253_952, 7_168), 160, "step/dir"),
    "mega-ramps14": ((253_952, 7_168), 80, "step/dir"),
}
TARGET_HZ = {"step/dir": 40_000, "four-wire": 2_000}  # per axis; 28BYJ-48 tops out near 1,000
TARGET_LINES_S = 200  # 0.5 mm segments: 100 mm/s of drawing
WINDOWS = 8


def build(board: str) -> Path:
    subprocess.run(["make", "-s", "-C", str(FIRMWARE_DIR), f"BOARD={board}", "all"],
                   check=True, capture_output=True)
    d = "build" if board == "uno-cnc-shield" else f"build/{board}"
    return FIRMWARE_DIR / d / "plotbridge.elf"


def sizes(elf: Path) -> tuple[int, int]:
    out = subprocess.run(["avr-size", "-A", str(elf)], check=True, capture_output=True,
                         text=True).stdout
    sec = {m.group(1): int(m.group(2)) for m in re.finditer(r"^\.(\w+)\s+(\d+)", out, re.M)}
    return sec["text"] + sec["data"], sec["data"] + sec.get("bss", 0)


def start(board: str, elf: Path, tmp: Path, speed: float) -> tuple[Plotter, Grbl]:
    p = Plotter(PLOTSIM, elf, tmp / f"{board}-{speed:g}.ee", speed, (0, 0),
                ["--board", board, "--width", "100000", "--height", "100000",
                 "--max-step-rate", "1000000"]).start()
    g = Grbl(p.port)
    g.ser.write(b"\x18")
    g.wait_for(r"^Grbl 1\.1h", 30)
    for line in ("$X", "$20=0", "$21=0", "$130=100000", "$131=100000"):
        g.ok(line)
    return p, g


def step_rate(p: Plotter, g: Grbl, spm: float, hz: float) -> tuple[float, int]:
    """Lowest window rate during the cruise, and the windows that fell short."""
    feed = hz / spm * 60
    g.ok(f"$110={feed:.0f}")
    g.ok(f"$120={max(5000, feed / 60 * 20):.0f}")  # at full speed within 50 ms
    length = hz / spm * 3.0  # three seconds of cruise
    p.clear()
    g.ok(f"G1 X{length:.1f} F{feed:.0f}")
    # skip the ramp: wait until a quarter of the move is done
    samples = []
    while True:
        t = p.trace()
        if t["steps"]["x"] > length * spm * 0.25:
            samples.append((t["sim_time"], t["steps"]["x"]))
        if t["steps"]["x"] > length * spm * 0.9 or len(samples) > WINDOWS:
            break
        time.sleep(0.05)
    g.wait_state("Idle", 120)
    rates, short = [], 0
    for (ta, sa), (tb, sb) in itertools.pairwise(samples):
        if tb - ta < 0.01:
            continue
        r = (sb - sa) / (tb - ta)
        rates.append(r)
        if (sb - sa) < hz * (tb - ta) - 1:  # more than a step behind the command
            short += 1
    g.ok("G90 G0 X0")
    g.wait_state("Idle", 120)
    return (min(rates) if rates else 0.0), short


def lines_per_s(p: Plotter, g: Grbl, spm: float, max_feed: float) -> float:
    g.ok(f"$110={max_feed:.0f}")
    g.ok(f"$111={max_feed:.0f}")
    g.ok("$120=3000")
    g.ok("$121=3000")
    r, n = 50.0, 1000
    per_turn = int(2 * math.pi * r / 0.5)
    g.ok(f"G0 X{100 + r:.2f} Y100")
    g.ok("G4 P0")
    g.ok(f"G1 F{max_feed:.0f}")
    # short modal lines, as senders stream them
    lines = [f"X{100 + r * math.cos(2 * math.pi * k / per_turn):.2f}"
             f"Y{100 + r * math.sin(2 * math.pi * k / per_turn):.2f}"
             for k in range(1, n + 1)]
    inflight: list[int] = []
    t_first = t_last = None
    sent = 0
    acked = 0
    while acked < n:
        while sent < n and sum(inflight) + len(lines[sent]) + 1 <= 128:
            g.ser.write(lines[sent].encode() + b"\n")
            inflight.append(len(lines[sent]) + 1)
            sent += 1
        got = g.read_lines(0.5)
        for line in got:
            if line == "ok":
                inflight.pop(0)
                acked += 1
                if acked == 1:
                    t_first = p.trace()["sim_time"]
                if acked == n:
                    t_last = p.trace()["sim_time"]
            elif line.startswith("error"):
                raise SystemExit(f"error streaming: {line}")
    g.wait_state("Idle", 300)
    assert t_first is not None and t_last is not None
    return (n - 1) / (t_last - t_first)


def main() -> int:
    wanted = sys.argv[1:] or list(BOARDS)
    ok = True
    with tempfile.TemporaryDirectory() as d:
        for board in wanted:
            (flash_max, ram_max), spm, drive = BOARDS[board]
            elf = build(board)
            flash, ram = sizes(elf)
            hz = TARGET_HZ[drive]
            p, g = start(board, elf, Path(d), 0)  # unthrottled: only simulated time counts
            try:
                low, short = step_rate(p, g, spm, hz)
            finally:
                g.close()
                p.cleanup()
            # real time, so this script's own latency between lines costs the
            # firmware no simulated time; the drive's own limit sets the feed
            p, g = start(board, elf, Path(d), 1)
            try:
                lps = lines_per_s(p, g, spm, min(12000, 0.8 * hz / spm * 60))
            finally:
                g.close()
                p.cleanup()
            what = "step rate" if drive == "step/dir" else "phase rate"
            rows = [
                (f"flash <= {flash_max} B", f"{flash} B", flash <= flash_max),
                (f"RAM <= {ram_max} B", f"{ram} B", ram <= ram_max),
                (f"{what} {hz} Hz/axis, no late step", f"lowest window {low:.0f} Hz, "
                 f"{short} short windows", short == 0),
                (f"0.5 mm segments >= {TARGET_LINES_S} lines/s", f"{lps:.0f} lines/s",
                 lps >= TARGET_LINES_S),
            ]
            for target, got, met in rows:
                ok &= met
                print(f"{board:15s} {target:42s} {got:38s} {'MET' if met else 'NOT MET'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
