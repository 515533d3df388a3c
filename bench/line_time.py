"""The firmware's time per line as the estimate models it (motion/timing.py, LINE_S):
from a line's last byte into the UART to the end of its `ok`, when the line meets an
idle main loop and the planner has room.

The real firmware of each board profile runs in the firmware benchmark's libsimavr
harness (firmware/test/bench/harness.c, built by bench/firmware_bench.py), which
streams compact wire lines with N words (what the server sends to our firmware) slower
than the firmware takes them (HARNESS_BYTE_BITS: a byte every that many bit times),
and reports when each line's last byte went in and when its `ok` came out, in
simulated cycles (exact and repeatable). Prints the median and spread per board and
drawing speed, and whether the figure in timing.py is within 5% of the Uno's at F6000
(the figure it stands for) as MET / NOT MET.

Run: .venv/bin/python bench/line_time.py [--board NAME ...]
"""

from __future__ import annotations

import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "bench"))

import firmware_bench as fb  # noqa: E402
from plotbridge.motion.timing import LINE_S  # noqa: E402
from plotbridge.program.wire import compact, numbered  # noqa: E402

# (segment mm, feed mm/min, bit times a byte): slow enough a byte rate that each line
# arrives after the one before is acknowledged (and executed, most of it)
RUNS = [(0.2, 1500, 60), (1.0, 3000, 200), (0.2, 6000, 40), (0.5, 6000, 60), (0.5, 12000, 30)]
REFERENCE = ("uno-cnc-shield", 0.5, 6000)
LINES = 1200
SKIP = 5    # the first lines queue behind the rapid to the start


def program(segment: float, feed: float) -> tuple[list[str], list[str]]:
    """A circle of `segment` mm lines, as the server sends them to our firmware."""
    r = 50.0
    pre = ["$X", "G0 X150 Y110", "G4 P0"]
    lines = [f"G1 X{100 + r * math.cos(segment * k / r):.3f} "
             f"Y{110 + r * math.sin(segment * k / r):.3f} F{feed:g}" for k in range(1, LINES + 1)]
    wire = compact(enumerate(lines, len(pre) + 1), (80.0, 80.0))
    return pre, [numbered(n, text) for n, text in wire]


def latencies(board: fb.Board, harness: Path, elf: Path, tmp: Path, segment: float,
              feed: float, bits: int) -> list[float]:
    """Seconds from each line's last byte to its ok."""
    pre, body = program(segment, feed)
    gcode = tmp / "in.gcode"
    gcode.write_text("\n".join(pre + body) + "\n")
    env = {**os.environ, **board.pins, "HARNESS_MCU": board.mcu, "HARNESS_BYTE_BITS": str(bits)}
    out = subprocess.run([str(harness), str(elf), str(gcode), "300"], env=env, check=True,
                         capture_output=True, text=True).stdout
    r = json.loads(out[out.index("{"):])
    if r["errors"] or r["alarm"] or r["acked"] != r["lines"]:
        raise SystemExit(f"simulation went wrong: { {k: r[k] for k in ('lines', 'acked')} }")
    first = len(pre) + SKIP
    return [(a - b) / fb.F_CPU for a, b in zip(r["ack_cycles"][first:],
                                               r["last_byte_cycles"][first:], strict=True)]


def main() -> int:
    args = sys.argv[1:]
    names = [args[k + 1] for k, a in enumerate(args[:-1]) if a == "--board"] or list(fb.BOARDS)
    reference = None
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        for name in names:
            board = fb.BOARDS[name]
            _, harness = fb.build(board, tmp)
            elf = fb.FW / board.build_dir / "plotbridge.elf"    # the real build
            for segment, feed, bits in RUNS:
                lat = latencies(board, harness, elf, tmp, segment, feed, bits)
                q = statistics.quantiles(lat, n=20)
                median = statistics.median(lat)
                print(f"{name}: {segment} mm lines at F{feed}: line time median "
                      f"{median * 1000:.3f} ms (5% {q[0] * 1000:.3f}, 95% {q[-1] * 1000:.3f}; "
                      f"{len(lat)} lines, a byte every {bits} bit times)")
                if (name, segment, feed) == REFERENCE:
                    reference = median
    if reference is not None:
        ok = abs(LINE_S - reference) <= 0.05 * reference
        print(f"{'MET' if ok else 'NOT MET':8} timing.LINE_S {LINE_S * 1000:.2f} ms within 5% of "
              f"the Uno's at F6000 ({reference * 1000:.3f} ms)")
    return 0


if __name__ == "__main__":
    sys.stdout.reconfigure(line_buffering=True)
    sys.exit(main())
