"""WebSocket hub: a client that falls behind is dropped without delaying the others."""

from __future__ import annotations

import asyncio
import json
from types import SimpleNamespace

from plotbridge.api import ws as ws_route
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


async def test_a_slow_client_gets_the_latest_state_and_every_transition():
    """States (machine reports, a job's progress) waiting for a client are replaced by
    newer ones: thousands of reports never fill its queue; transitions all arrive, in
    order, and a state made stale by a transition is not sent after it."""
    hub = Hub()
    slow = hub.add(ListSocket())
    job = {"id": "j", "state": "running"}
    for n in range(QUEUE_SIZE * 4):
        hub.broadcast({"type": "machine", "plotter": "p", "machine": {"n": n}})
        hub.broadcast({"type": "job", "job": {**job, "progress": n}})
    hub.broadcast({"type": "job", "job": {**job, "state": "stopped"},
                   "transition": {"from": "running", "to": "stopped", "cause": "estop"}})
    hub.broadcast({"type": "machine", "plotter": "p", "machine": {"n": "last"}})
    assert not slow.dropped
    slow.task = asyncio.create_task(slow.pump())
    await settle(lambda: slow.queue.empty() and len(slow.ws.sent) == 2)
    sent = [json.loads(text) for text in slow.ws.sent]
    assert [m["machine"]["n"] for m in sent if m["type"] == "machine"] == ["last"]
    jobs = [m for m in sent if m["type"] == "job"]  # the stale progress made way for the
    assert len(jobs) == 1 and jobs[0]["job"]["state"] == "stopped"  # transition
    slow.task.cancel()


def test_console_lines_that_only_ask_are_not_audited():
    """A `$$` changes nothing: no audit row (a client repeating it wrote one each time);
    a setting's change is audited."""
    rows: list[tuple] = []
    c = SimpleNamespace(access=SimpleNamespace(audit=lambda *row: rows.append(row)))
    for line in ("$$", " $g ", "$#", "?"):
        ws_route._audit(c, None, "command", {"line": line})
    assert rows == []
    ws_route._audit(c, None, "command", {"line": "$110=5000"})
    assert len(rows) == 1 and rows[0][1] == "WS command"
