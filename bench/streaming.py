"""Streaming: lines per second end to end (plotbridge's Link -> pty -> the real firmware
in the virtual plotter, real time by default) for 0.5 mm and 0.2 mm segments, in the
readable program and in the compact wire format (program/wire.py, the job streaming
path), against the serial ceiling of each format (115200 baud / bytes per line); and
whether the board is ever starved (planner empty while lines are still to come).

    .venv/bin/python bench/streaming.py [--segments 1200] [--seg-mm 0.5,0.2]
        [--feed 18000] [--accel 3000] [--formats readable,compact]
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import math
import statistics
import sys
import tempfile
import time
from pathlib import Path

from plotbridge.plotter.link import Link, LinkEvent
from plotbridge.program.wire import compact
from plotbridge.virtual import VirtualPlotter

BAUD_BYTES_S = 115200 / 10   # 8N1


def circle(segments: int, seg_mm: float, feed: float) -> list[str]:
    r = segments * seg_mm / (2 * math.pi)
    cx, cy = 150.0, 110.0
    if r > 100:
        sys.exit(f"{segments} segments of {seg_mm} mm make a circle too big for the work area")
    if r < 2:
        sys.exit(f"{segments} segments of {seg_mm} mm: too few for a circle")
    pts = [(cx + r * math.cos(2 * math.pi * i / segments),
            cy + r * math.sin(2 * math.pi * i / segments)) for i in range(segments + 1)]
    lines = ["G21", "G90", "M5", f"G0 X{pts[0][0]:.3f} Y{pts[0][1]:.3f}", "M3"]
    lines += [f"G1 X{x:.3f} Y{y:.3f} F{feed:g}" for x, y in pts[1:]]
    return [*lines, "M5"]


async def wait(predicate, limit: float, what: str) -> None:
    deadline = time.monotonic() + limit
    while not predicate():
        if time.monotonic() > deadline:
            sys.exit(f"bench failed: {what} not within {limit} s")
        await asyncio.sleep(0.01)


def summary(values: list[int]) -> str:
    if not values:
        return "-"
    return f"min {min(values)}, median {statistics.median(values):g}, max {max(values)}"


async def run(args: argparse.Namespace, seg_mm: float, fmt: str) -> dict:
    data = Path(tempfile.mkdtemp(prefix="pb-stream-"))
    plotter = VirtualPlotter(data, speed=args.speed)
    await plotter.start()
    link = Link(str(plotter.port), poll_hz=args.poll_hz)
    task = asyncio.create_task(link.run())
    try:
        await wait(lambda: link.connected, 15, "connect")
        if link.status.state == "Alarm":
            await link.command("$X")
        for n in (120, 121):
            await link.command(f"${n}={args.accel:g}")
        for n in (110, 111):
            await link.command(f"${n}={max(args.feed, 6000):g}")
        await wait(lambda: link.status.state == "Idle" and link.status.planner_free, 5, "Idle")
        blocks = link.status.planner_free or 0
        program = circle(args.segments, seg_mm, args.feed)
        if fmt == "compact":
            program = [t for _, t in compact(enumerate(program, 1))]
        ack_times: dict[int, float] = {}
        first_motion = 6   # line number of the first G1
        samples: list[tuple[float, str, int, int, int]] = []
        acked = [0]

        def watch(event: LinkEvent) -> None:
            s = event.status
            if s is not None and s.rx_free is not None and s.planner_free is not None:
                samples.append((time.monotonic(), s.state, blocks - s.planner_free,
                                128 - s.rx_free, acked[0]))

        def on_ack(n: int) -> None:
            acked[0] = n
            ack_times[n] = time.monotonic()

        link.subscribe(watch)
        started = time.monotonic()
        await link.stream(iter(enumerate(program, 1)), on_ack)
        all_acked = time.monotonic()
        await wait(lambda: link.status.state == "Idle", 120, "Idle after the job")
        finished = time.monotonic()
        trace = await asyncio.to_thread(plotter.trace)
    finally:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task
        await plotter.stop()

    # The body: from the first acknowledged G1 while motion lines are still to be
    # acknowledged (after that the planner drains by design).
    last_motion = len(program) - 1
    body = [s for s in samples if first_motion <= s[4] < last_motion and s[0] <= all_acked]
    planner = [s[2] for s in body]
    rx = [s[3] for s in body]
    starved = [s for s in body if s[2] == 0 or s[1] not in ("Run", "Hold")]
    for t, state, fill, used, line in starved:
        print(f"starved: t={t - started:6.2f} s {state} planner {fill} rx {used} acked {line}")
    path_mm = args.segments * seg_mm
    body_lines = program[first_motion:last_motion]
    line_bytes = sum(len(t) + 1 for t in body_lines) / len(body_lines)
    rate = (last_motion - 1 - first_motion) / (ack_times[last_motion - 1] - ack_times[first_motion])
    result = {
        "format": fmt, "bytes_per_line": round(line_bytes, 1),
        "lines_per_s": round(rate, 1),
        "serial_ceiling_lines_per_s": round(BAUD_BYTES_S / line_bytes, 1),
        "segments": args.segments, "segment_mm": seg_mm, "feed_mm_min": args.feed,
        "sim_speed": args.speed, "planner_blocks": blocks,
        "wall_s": round(finished - started, 2),
        "ideal_s_at_feed": round(path_mm / (args.feed / 60), 2),
        "status_samples_in_body": len(body),
        "planner_fill": summary(planner),
        "rx_buffer_bytes_used": summary(rx),
        "starved_samples": len(starved),
        "draw_mm": trace.get("draw_mm"),
        "violations": trace.get("violations"),
    }
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--segments", type=int, default=1200)
    parser.add_argument("--seg-mm", default="0.5,0.2")
    parser.add_argument("--feed", type=float, default=18000)
    parser.add_argument("--accel", type=float, default=3000)
    parser.add_argument("--formats", default="readable,compact")
    parser.add_argument("--speed", type=float, default=1, help="simulation speed (1 = real time)")
    parser.add_argument("--poll-hz", type=float, default=20)
    args = parser.parse_args()
    results = []
    for seg_mm in (float(v) for v in args.seg_mm.split(",")):
        for fmt in args.formats.split(","):
            result = asyncio.run(run(args, seg_mm, fmt))
            results.append(result)
            for key, value in result.items():
                print(f"{key:28} {value}")
            print(json.dumps(result))
    print("summary (lines/s end to end; serial ceiling of the format):")
    for r in results:
        print(f"  {r['segment_mm']} mm {r['format']:8} {r['lines_per_s']:7.1f} lines/s; "
              f"ceiling {r['serial_ceiling_lines_per_s']:6.1f} ({r['bytes_per_line']} bytes/line); "
              f"starved samples {r['starved_samples']}")
    for seg_mm in sorted({r["segment_mm"] for r in results}):
        rates = {r["format"]: r["lines_per_s"] for r in results if r["segment_mm"] == seg_mm}
        if "readable" in rates and "compact" in rates:
            print(f"  {seg_mm} mm: compact {rates['compact'] / rates['readable']:.2f}x readable")


if __name__ == "__main__":
    main()
