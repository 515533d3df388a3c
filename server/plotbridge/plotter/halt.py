"""Stopping what a board still holds after a job ended early (cancel, a board error):
hold, soft reset once the hold has stopped motion, then lift the pen (`$X` first if the
reset left an alarm)."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Callable

from plotbridge.plotter.link import Link

log = logging.getLogger("plotbridge.runner")


async def halt(link: Link) -> None:
    with contextlib.suppress(Exception):
        link.realtime(b"!")
    await wait_state(link, lambda s: s in ("Hold", "Idle", "Alarm", "Disconnected"), 5.0)
    await asyncio.sleep(0.3)  # let the deceleration complete
    link.estop()
    if await wait_state(link, lambda s: s in ("Idle", "Alarm"), 5.0) == "Alarm":
        await quiet_command(link, "$X")
    await quiet_command(link, "M5")


async def quiet_command(link: Link, line: str) -> None:
    try:
        await link.command(line)
    except Exception as exc:
        log.warning("%s after stopping a job failed: %s", line, exc)


async def wait_state(link: Link, predicate: Callable[[str], bool], limit: float) -> str:
    """Wait (at most `limit` s) for the machine state to satisfy `predicate`."""
    deadline = time.monotonic() + limit
    while True:
        status = link.status
        state = status.state if status.connected else "Disconnected"
        if predicate(state) or time.monotonic() > deadline:
            return state
        await asyncio.sleep(0.02)
