"""WebSocket hub: fan-out with a bounded send queue per client.

A message is serialized once and put on every client's queue without waiting;
a client whose queue is full has fallen behind and is dropped, so a slow or dead
client never delays the others, the link or an emergency stop. The sends of one
event to hundreds of clients are spread over loop passes (`SendPace`): each pass
sends at most SENDS_PER_PASS, and what the selector reported in between (a stop's
request) runs before the rest. A state message (a plotter's machine report, a job's
progress, the fleet view) still waiting for a client is replaced by a newer one of the
same thing: a client that is slow but reading is sent the latest state, not every state
it missed, and never falls behind on them; a job's transition is never replaced.
"""

from __future__ import annotations

import asyncio
import json
import logging
import time
from collections.abc import Callable
from typing import Any

from starlette.websockets import WebSocket

log = logging.getLogger("plotbridge.ws")

QUEUE_SIZE = 256
MESSAGES_PER_S = 50  # from one client; the page sends a few per second at most (jogging)
MESSAGE_BURST = 100
SENDS_PER_PASS = 32  # WebSocket sends per event-loop pass (~40 us each)


class RateLimit:
    """Token bucket: `take()` is False once a client sends faster than the rate."""

    def __init__(self, rate: float = MESSAGES_PER_S, burst: float = MESSAGE_BURST) -> None:
        self.rate, self.burst = rate, burst
        self.tokens = burst
        self.at = time.monotonic()

    def take(self) -> bool:
        now = time.monotonic()
        self.tokens = min(self.burst, self.tokens + (now - self.at) * self.rate)
        self.at = now
        if self.tokens < 1:
            return False
        self.tokens -= 1
        return True


class SendPace:
    """How many sends this loop pass may still make. The first send of a pass schedules
    the count's reset, which runs at the start of the next pass, before the sends that
    waited for it and after nothing but what was already due."""

    def __init__(self, per_pass: int = SENDS_PER_PASS) -> None:
        self.per_pass = per_pass
        self.used = 0

    def take(self) -> bool:
        if self.used == 0:
            asyncio.get_running_loop().call_soon(self._reset)
        if self.used >= self.per_pass:
            return False
        self.used += 1
        return True

    def _reset(self) -> None:
        self.used = 0


View = Callable[[dict[str, Any]], dict[str, Any] | None]


def state_key(message: dict[str, Any]) -> tuple[str | None, bool]:
    """What `message` is the state of (None: an event of its own), and whether it is only
    the latest state of that (a newer one may replace it) rather than a transition."""
    kind = message.get("type")
    if kind == "machine":
        return f"machine:{message.get('plotter')}", True
    if kind == "job" and isinstance(message.get("job"), dict):
        return f"job:{message['job'].get('id')}", "transition" not in message
    if kind == "fleet":
        return "fleet", True
    return None, False


Queued = tuple[str | None, str | None]  # (key of a state in `latest`, None) or (None, text)


class Client:
    def __init__(self, ws: WebSocket, pace: SendPace, view: View | None = None) -> None:
        self.ws = ws
        self.pace = pace
        self.view = view  # what this client is shown of a message (None: all of it)
        self.identity: Any = None  # who is connected (people.Identity)
        self.queue: asyncio.Queue[Queued | None] = asyncio.Queue(QUEUE_SIZE)
        self.latest: dict[str, str] = {}  # states waiting to be sent, newest text by key
        self.dropped = False
        self.task: asyncio.Task[None] | None = None
        self.rate = RateLimit()

    def offer(self, text: str, key: str | None = None, latest: bool = False) -> bool:
        """Queue `text`; False when the queue is full. A `latest` state replaces the one of
        the same `key` still waiting (in its place); a transition of a key makes the state
        waiting for it stale (it is not sent) and goes at the end."""
        if key is not None and latest and key in self.latest:
            self.latest[key] = text
            return True
        if key is not None:
            self.latest.pop(key, None)
        try:
            if latest and key is not None:
                self.queue.put_nowait((key, None))
                self.latest[key] = text
            else:
                self.queue.put_nowait((None, text))
            return True
        except asyncio.QueueFull:
            return False

    async def pump(self) -> None:
        """Send queued messages until closed (None) or the socket fails."""
        while True:
            item = await self.queue.get()
            if item is None:
                return
            key, text = item
            if key is not None:
                text = self.latest.pop(key, None)
                if text is None:  # made stale by a transition since
                    continue
            while not self.pace.take():  # noqa: ASYNC110 (waits for the next pass, not an event)
                await asyncio.sleep(0)
            await self.ws.send_text(text)


class Hub:
    def __init__(self) -> None:
        self.clients: set[Client] = set()
        self.pace = SendPace()

    def add(self, ws: WebSocket, view: View | None = None) -> Client:
        client = Client(ws, self.pace, view)
        self.clients.add(client)
        return client

    def remove(self, client: Client) -> None:
        self.clients.discard(client)

    def broadcast(self, message: dict[str, Any]) -> None:
        if not self.clients:
            return
        text = json.dumps(message, separators=(",", ":"))
        key, latest = state_key(message)
        for client in list(self.clients):
            if client.view is not None:
                self.send(client, message, key, latest)
            elif not client.offer(text, key, latest):
                self._drop(client)

    def send(self, client: Client, message: dict[str, Any], key: str | None = None,
             latest: bool = False) -> None:  # fmt: skip
        shown = message if client.view is None else client.view(message)
        if shown is not None and not client.offer(json.dumps(shown, separators=(",", ":")),
                                                  key, latest):  # fmt: skip
            self._drop(client)

    def _drop(self, client: Client) -> None:
        log.warning("websocket client fell behind; dropped")
        client.dropped = True
        self.clients.discard(client)
        if client.task is not None:
            client.task.cancel()
