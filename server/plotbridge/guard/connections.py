"""Connection limits below HTTP: per-client caps, a header deadline, the file limit.

`GuardedH11` is uvicorn's h11 protocol with two additions, decided when a
connection is accepted or while its request line and headers trickle in, long
before any app code runs:
- a client address holding `client_cap` connections (HTTP or WebSocket) gets a
  503 for the next one, and so does everyone once the server holds `total_cap`
  (kept below the open-file limit, so accept() never fails for lack of one);
- a request's headers must be complete within HEADER_TIMEOUT of the connection
  (or of the previous response): half-sent headers cannot hold a socket.
"""

from __future__ import annotations

import asyncio
import logging
import resource
from typing import Any

from uvicorn.protocols.http.h11_impl import H11Protocol

log = logging.getLogger("plotbridge.guard")

HEADER_TIMEOUT = 10.0  # s for a request line and headers to arrive
MAX_HEADER_BYTES = 16 * 1024  # h11's incomplete-event bound: bigger headers get 400
# Connections waiting to be accepted: the event loop accepts a whole burst before
# the refused ones are closed, so a long backlog could exhaust the descriptors.
BACKLOG = 128
FILES_RESERVED = 128  # descriptors kept free of connections (database, programs, serial, pipes)
_BUSY_BODY = b'{"detail": "too many open connections; try again shortly"}'
BUSY = (
    b"HTTP/1.1 503 Service Unavailable\r\ncontent-type: application/json\r\n"
    b"connection: close\r\nretry-after: 5\r\ncontent-length: %d\r\n\r\n%s"
    % (len(_BUSY_BODY), _BUSY_BODY)
)


def raise_file_limit() -> int:
    """Soft open-file limit raised to the hard one; returns the limit now in force."""
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if hard == resource.RLIM_INFINITY:
        hard = max(soft, 1 << 20)
    if soft < hard:
        try:
            resource.setrlimit(resource.RLIMIT_NOFILE, (hard, hard))
            soft = hard
        except (ValueError, OSError) as exc:
            log.warning("cannot raise the open-file limit from %d: %s", soft, exc)
    return soft


class Census:
    """Open transports per client address (a WebSocket's transport too: it stays
    counted after the upgrade hands it to another protocol, until it closes)."""

    def __init__(self, client_cap: int, total_cap: int) -> None:
        self.client_cap = client_cap
        self.total_cap = total_cap
        self.by_client: dict[str, set[Any]] = {}
        self.total = 0

    def admit(self, client: str, transport: Any) -> bool:
        held = self.by_client.setdefault(client, set())
        for old in [t for t in held if t.is_closing()]:
            held.discard(old)
            self.total -= 1
        if len(held) >= self.client_cap or self.total >= self.total_cap:
            return False
        held.add(transport)
        self.total += 1
        return True

    def release(self, client: str, transport: Any) -> None:
        held = self.by_client.get(client)
        if held is not None and transport in held:
            held.discard(transport)
            self.total -= 1
            if not held:
                del self.by_client[client]


CENSUS = Census(32, 1024 - FILES_RESERVED)


def configure(client_cap: int, file_limit: int) -> None:
    CENSUS.client_cap = client_cap
    CENSUS.total_cap = max(64, file_limit - FILES_RESERVED)


class GuardedH11(H11Protocol):
    _deadline: asyncio.TimerHandle | None = None
    _waiting_for: object = None
    _peer = "?"

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        super().connection_made(transport)
        self._peer = self.client[0] if self.client else "?"
        if not CENSUS.admit(self._peer, transport):
            log.warning("refused a connection from %s: too many open", self._peer)
            transport.write(BUSY)
            transport.close()
            return
        self._arm()

    def _arm(self) -> None:
        self._waiting_for = self.cycle
        self._deadline = self.loop.call_later(HEADER_TIMEOUT, self._headers_late)

    def _disarm(self) -> None:
        if self._deadline is not None:
            self._deadline.cancel()
            self._deadline = None

    def _headers_late(self) -> None:
        self._deadline = None
        if self.cycle is self._waiting_for and not self.transport.is_closing():
            self.transport.close()  # no request in time: drop it without an answer

    def data_received(self, data: bytes) -> None:
        super().data_received(data)
        if self._deadline is not None and self.cycle is not self._waiting_for:
            self._disarm()  # the request's headers are complete

    def handle_websocket_upgrade(self, event: Any) -> None:
        self._disarm()  # the headers are complete; the WebSocket protocol takes over
        super().handle_websocket_upgrade(event)

    def on_response_complete(self) -> None:
        super().on_response_complete()
        if not self.transport.is_closing():
            self._disarm()
            self._arm()  # the next request on this connection gets the same deadline

    def connection_lost(self, exc: Exception | None) -> None:
        self._disarm()
        CENSUS.release(self._peer, self.transport)
        super().connection_lost(exc)
