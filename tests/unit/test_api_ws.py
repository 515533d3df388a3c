"""WebSocket hub: a client that falls behind is dropped without delaying the others."""

from __future__ import annotations

import asyncio

from plotbridge.guard.hosts import origin_allowed
from plotbridge.ws import QUEUE_SIZE, Hub

from tests.fixtures.waits import settle


class StuckSocket:
    """Never finishes a send, like a client whose TCP window stays closed."""

    async def send_text(self, text: str) -> None:
        await asyncio.Event().wait()


class ListSocket:
    def __init__(self) -> None:
        self.sent: list[str] = []

    async def send_text(self, text: str) -> None:
        self.sent.append(text)


async def test_slow_client_is_dropped_and_others_keep_receiving():
    hub = Hub()
    stuck, fast = hub.add(StuckSocket()), hub.add(ListSocket())
    stuck.task = asyncio.create_task(stuck.pump())
    fast.task = asyncio.create_task(fast.pump())
    for index in range(QUEUE_SIZE * 2):
        hub.broadcast({"type": "log", "n": index})  # never blocks
        if index % 32 == 0:
            await asyncio.sleep(0)
    await settle(lambda: stuck.task.done() and len(fast.ws.sent) == QUEUE_SIZE * 2)
    assert stuck.dropped and stuck not in hub.clients
    assert not fast.dropped
    fast.task.cancel()


def test_origin_check():
    assert origin_allowed(None, "plot.local:8000")
    assert origin_allowed("http://plot.local:8000", "plot.local:8000")
    assert origin_allowed("https://PLOT.local:8000/", "plot.local:8000")
    assert not origin_allowed("http://evil.example", "plot.local:8000")
    assert not origin_allowed("http://plot.local:8001", "plot.local:8000")
    assert not origin_allowed("null", "plot.local:8000")
    assert not origin_allowed("http://plot.local:8000", None)

