"""One webhook URL's ordered, bounded queue and the task that posts it.

`put` never waits (it runs inside the event hub's publish, also on the
emergency stop's path): it appends the event's JSON to the queue and to the
outbox (outbox.py: kept on disk until it leaves the queue, so a restart
delivers it), dropping the oldest one with a log line when the receiver has
been down so long that `limit` events wait. A queue starts with the events a
previous run left waiting (the oldest dropped the same way beyond `limit`).
The task posts the events one at a time in order; each event leaves the queue
once its receiver answered 2xx (or refused it for good), so it is delivered
once, in order. A receiver that errs (5xx, 408, 429, connection refused,
timeout) gets the same event again after a delay doubling from `first_delay`
to `max_delay`. A timed-out request may have arrived: every
event carries an `id` for the receiver to recognise a repeat.
"""

from __future__ import annotations

import asyncio
import json
import logging
from collections import deque
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import Any

from plotbridge.notify.outbox import Outbox, Pending

log = logging.getLogger("plotbridge.notify")

Post = Callable[[str, bytes, dict[str, str]], Awaitable[int]]
"""Posts a body to a URL with headers; answers the HTTP status. Raises `OSError` or
`httpx.TransportError` (refused, timed out, reset) when there is no answer."""

RETRY_STATUS = frozenset({408, 425, 429})  # and every 5xx


@dataclass
class Figures:
    """What the settings API shows per URL."""

    delivered: int = 0
    retries: int = 0
    dropped: int = 0
    refused: int = 0
    last_error: str | None = None


class Delivery:
    def __init__(self, url: str, post: Post, outbox: Outbox, waiting: list[Pending] | None = None,
                 *, limit: int = 100, first_delay: float = 0.5,
                 max_delay: float = 60.0) -> None:  # fmt: skip
        self.url = url
        self._post = post
        self._outbox = outbox
        self.limit = limit
        self.first_delay = first_delay
        self.max_delay = max_delay
        self.figures = Figures()
        self._queue: deque[Pending] = deque()
        self._wake = asyncio.Event()
        self._task: asyncio.Task[None] | None = None
        if waiting:
            log.info("webhook %s: %d events from before the restart to deliver", url,
                     len(waiting))  # fmt: skip
            for pending in waiting:
                self._append(pending)

    @property
    def queued(self) -> int:
        return len(self._queue)

    def start(self) -> None:
        self._task = asyncio.get_running_loop().create_task(self._run(), name="webhook")

    async def close(self) -> None:
        """Ends the delivery task; cancelled again should an await inside it have swallowed
        the cancel (asyncio.wait_for in 3.11 can)."""
        task, self._task = self._task, None
        while task is not None and not task.done():
            task.cancel()
            await asyncio.wait({task}, timeout=1.0)

    def put(self, event: str, body: dict[str, Any]) -> None:
        """Queue one event (never waits)."""
        self._append(self._outbox.add(self.url, event, json.dumps(body).encode()))

    def _append(self, pending: Pending) -> None:
        if len(self._queue) >= self.limit:
            lost = self._queue.popleft()
            self._outbox.remove(lost)
            self.figures.dropped += 1
            log.warning("webhook %s: %d events wait (receiver down?); dropped the oldest, "
                        "a %s", self.url, self.limit, lost.event)  # fmt: skip
        self._queue.append(pending)
        self._wake.set()

    async def _run(self) -> None:
        while True:
            while not self._queue:
                self._wake.clear()
                await self._wake.wait()
            pending = self._queue[0]
            await self._deliver(pending)
            if self._queue and self._queue[0] is pending:  # not dropped meanwhile
                self._queue.popleft()
                self._outbox.remove(pending)

    async def _deliver(self, pending: Pending) -> None:
        """Post until the receiver takes it, refuses it for good, or the queue drops it."""
        delay = self.first_delay
        headers = {"Content-Type": "application/json", "X-Plotbridge-Event": pending.event}
        while True:
            try:
                status = await self._post(self.url, pending.body, headers)
                problem = None if status < 300 else f"answered HTTP {status}"
            except asyncio.CancelledError:
                raise
            except Exception as exc:  # refused, timed out, reset, bad name: the receiver's side
                status, problem = 0, f"{type(exc).__name__}: {exc}".rstrip(": ")
            if problem is None:
                self.figures.delivered += 1
                self.figures.last_error = None
                return
            self.figures.last_error = problem
            if status and status not in RETRY_STATUS and status < 500:
                self.figures.refused += 1
                log.warning("webhook %s %s to a %s; not sent again", self.url, problem,
                            pending.event)  # fmt: skip
                return
            self.figures.retries += 1
            log.warning("webhook %s %s to a %s; again in %.1f s", self.url, problem,
                        pending.event, delay)  # fmt: skip
            await asyncio.sleep(delay)
            delay = min(delay * 2, self.max_delay)
            if not self._queue or self._queue[0] is not pending:
                return  # dropped while waiting (the queue overflowed)
