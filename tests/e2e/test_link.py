"""The serial link against the real firmware in the simulator (plotsim)."""

from __future__ import annotations

import asyncio
import contextlib
import math
from collections.abc import AsyncIterator

import pytest
from plotbridge.plotter.link import Link, LinkEvent, StreamAborted

from tests.fixtures.waits import settle

pytestmark = pytest.mark.e2e


@contextlib.asynccontextmanager
async def link_to(port: str) -> AsyncIterator[Link]:
    link = Link(port)
    task = asyncio.create_task(link.run())
    try:
        await settle(lambda: link.connected, 10, "connected")
        yield link
    finally:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task


async def unlocked(link: Link) -> None:
    """Clear the power-up alarm (homing is enabled by default) and wait for Idle."""
    if link.status.state == "Alarm":
        await link.command("$X")
    await settle(lambda: link.status.state == "Idle", 5, "Idle")


def circle_program(cx: float, cy: float, r: float, segments: int) -> list[str]:
    pts = [(cx + r * math.cos(2 * math.pi * i / segments),
            cy + r * math.sin(2 * math.pi * i / segments)) for i in range(segments + 1)]
    lines = ["G21", "G90", "M5", f"G0 X{pts[0][0]:.3f} Y{pts[0][1]:.3f}", "M3"]
    lines += [f"G1 X{x:.3f} Y{y:.3f} F3000" for x, y in pts[1:]]
    lines += ["M5"]
    return lines


async def trace(plotter) -> dict:
    return await asyncio.to_thread(plotter.trace)


async def test_connect_reads_settings_and_status(plotter):
    async with link_to(plotter.port) as link:
        assert link.status.firmware and link.status.firmware.startswith("1.1")
        assert link.settings[130] == 300 and link.settings[131] == 220
        assert link.settings[100] == 80 and 60 in link.settings and 63 in link.settings
        assert link.status.state in ("Idle", "Alarm")
        before = link.status.updated_at
        await settle(lambda: link.status.updated_at > before, what="the next poll's report")


async def test_stream_few_hundred_segments_and_trace_completes(plotter):
    async with link_to(plotter.port) as link:
        await unlocked(link)
        program = circle_program(100, 100, 40, 400)   # 0.63 mm segments
        fills: list[tuple[int | None, int | None]] = []

        def watch(event: LinkEvent) -> None:
            if event.kind == "status" and event.status.state == "Run":
                fills.append((event.status.rx_free, event.status.planner_free))

        link.subscribe(watch)
        acked: list[int] = []
        await link.stream(iter(enumerate(program, 1)), acked.append)
        assert acked == list(range(1, len(program) + 1))
        await settle(lambda: link.status.state == "Idle", 20, "Idle after the stream")
        t = await trace(plotter)
        assert t["pen"] == "up"
        assert (round(t["position"]["x"], 1), round(t["position"]["y"], 1)) == (140.0, 100.0)
        drawn = [p for stroke in t["strokes"] for p in stroke]
        assert len(t["strokes"]) == 1, t["strokes"]
        assert all(abs(math.hypot(x - 100, y - 100) - 40) < 0.1 for x, y, *_ in drawn)
        assert abs(t["draw_mm"] - 2 * math.pi * 40) < 1.0
        assert not any(t["violations"].values()), t["violations"]
        # Character counting kept the receive buffer in use while running.
        assert fills, "no status report while running"
        assert min(rx for rx, _ in fills if rx is not None) < 128 - 40


async def test_estop_mid_stream_stops_motion(plotter):
    async with link_to(plotter.port) as link:
        await unlocked(link)
        program = ["G21", "G90", "M3"] + [
            f"G1 X{10 + (i % 2) * 200} Y{10 + i} F3000" for i in range(60)]
        acked: list[int] = []
        stream = asyncio.create_task(link.stream(iter(enumerate(program, 1)), acked.append))
        await settle(lambda: link.status.state == "Run" and len(acked) > 5, 10, "running")
        link.estop()
        with pytest.raises(StreamAborted) as info:
            await asyncio.wait_for(stream, 5)
        assert info.value.reason == "estop" and info.value.last_acked < len(program)
        await settle(lambda: link.status.state == "Alarm", 5, "Alarm after estop")
        first = await trace(plotter)
        await asyncio.sleep(0.5)
        second = await trace(plotter)
        assert first["steps"] == second["steps"], "the steppers kept moving after estop"
        # Unlock works and the link is in step again.
        assert await link.command("$X") is not None
        await settle(lambda: link.status.state == "Idle", 5, "Idle after unlock")


async def test_link_loss_and_reconnect(plotter):
    async with link_to(plotter.port) as link:
        events: list[str] = []
        link.subscribe(lambda e: events.append(e.kind))
        plotter.kill()
        # the closed port tells at once: well before the silence limit could
        await settle(lambda: not link.connected, link.silence_timeout - 1, "loss noticed")
        assert link.status.state == "Disconnected" and "disconnected" in events
        await asyncio.to_thread(plotter.restart)
        await settle(lambda: link.connected, 10, "reconnected")
        assert events.count("connected") == 1
        assert link.settings[130] == 300
        await unlocked(link)
        assert await link.command("G0 X5 Y5") == []
