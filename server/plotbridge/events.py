"""The event hub: components publish messages, subscribers (WebSocket clients) receive them.

A message is a JSON-able dict with a `type` (docs/INTERNALS.md, "WebSocket
messages"). Publishing is synchronous and never waits: each subscriber must
take a message at once (the WebSocket fan-out queues it per client).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

log = logging.getLogger("plotbridge.events")

Message = dict[str, Any]
Subscriber = Callable[[Message], None]


class EventHub:
    def __init__(self) -> None:
        self._subscribers: list[Subscriber] = []

    def subscribe(self, subscriber: Subscriber) -> Callable[[], None]:
        self._subscribers.append(subscriber)

        def unsubscribe() -> None:
            if subscriber in self._subscribers:
                self._subscribers.remove(subscriber)

        return unsubscribe

    def publish(self, message: Message) -> None:
        for subscriber in list(self._subscribers):
            try:
                subscriber(message)
            except Exception:
                log.exception("event subscriber failed on a %s message", message.get("type"))
