"""WebSocket hub: a client that falls behind is dropped without delaying the others."""

from __future__ import annotations

import asyncio

from plotbridge.guard.hosts import origin_allowed
from plotbridge.ws import QUEUE_SIZE, SENDS_PER_PASS, Hub

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



async def test_one_event_to_many_clients_is_sent_over_several_loop_passes():
    """A loop pass sends at most SENDS_PER_PASS: a stop read meanwhile waits for no more."""
    hub = Hub()
    clients = [hub.add(ListSocket()) for _ in range(SENDS_PER_PASS * 3)]
    for client in clients:
        client.task = asyncio.create_task(client.pump())
    hub.broadcast({"type": "machine"})
    passes = 0
    while sum(len(c.ws.sent) for c in clients) < len(clients):
        before = sum(len(c.ws.sent) for c in clients)
        await asyncio.sleep(0)
        passes += 1
        assert sum(len(c.ws.sent) for c in clients) - before <= SENDS_PER_PASS
        assert passes < 100
    assert passes >= 3
    for client in clients:
        client.task.cancel()
