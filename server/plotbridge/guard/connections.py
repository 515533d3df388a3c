"""Connection limits below HTTP: per-client caps, a header deadline, the file limit.

`GuardedServer` is uvicorn's server whose listening sockets are served by the
`Acceptor` (guard/acceptor.py): a connection the census has room for goes to
`GuardedH11`, any other may carry only a stop. `GuardedH11` is uvicorn's h11
protocol with two additions, decided long before any app code runs:
- each request's head (request line and headers) is collected before h11 sees
  it and offered to the stop lane (guard/stoplane.py), which acts on an allowed
  emergency stop at once and answers it;
- a request's headers must be complete within HEADER_TIMEOUT of the connection
  (or of the previous response): half-sent headers cannot hold a socket.
The census counts connections per client address (`client_cap`) and in all
(`total_cap`, kept KEPT_FREE below the open-file limit). docs/INTERNALS.md,
"The stop lane".
"""

from __future__ import annotations

import asyncio
import logging
import os
import resource
import socket
from typing import Any

import h11
import uvicorn
from uvicorn.protocols.http.h11_impl import H11Protocol

from plotbridge.guard.acceptor import PROBATION, Acceptor, may_be_stop
from plotbridge.guard.stoplane import BODY_MAX, HEAD_MAX, LANE, NEED_MORE

log = logging.getLogger("plotbridge.guard")

HEADER_TIMEOUT = 10.0  # s for a request line and headers to arrive
MAX_HEADER_BYTES = HEAD_MAX  # h11's incomplete-event bound: bigger headers get 400
BACKLOG = 128  # asyncio's accept burst (unused: the Acceptor accepts) and first listen queue
LISTEN_QUEUE = 4096  # the kernel's queue of connections not yet accepted (somaxconn caps it)
FILES_RESERVED = 128  # descriptors kept free of connections (database, programs, serial, pipes)
HANDOVER_SLACK = 64  # connections admitted whose protocol has not started yet
KEPT_FREE = FILES_RESERVED + PROBATION + HANDOVER_SLACK


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
    counted after the upgrade hands it to another protocol, until it closes), and
    connections admitted whose transport is still being made."""

    def __init__(self, client_cap: int, total_cap: int) -> None:
        self.client_cap = client_cap
        self.total_cap = total_cap
        self.by_client: dict[str, set[Any]] = {}
        self.pending: dict[str, int] = {}
        self.total = 0  # transports and pending ones

    def reserve(self, client: str) -> bool:
        """Whether a new connection from `client` fits; if so it is counted."""
        held = self.by_client.setdefault(client, set())
        for old in [t for t in held if t.is_closing()]:
            held.discard(old)
            self.total -= 1
        pending = self.pending.get(client, 0)
        mine = len(held) + pending
        full = self.total >= self.total_cap
        if mine >= self.client_cap or (full and not self._displace(client, mine)):
            if not held:
                del self.by_client[client]
            return False
        self.pending[client] = pending + 1
        self.total += 1
        return True

    def _displace(self, client: str, mine: int) -> bool:
        """When full, an address holding less than its share (the cap over the addresses
        holding connections) gets a connection of the address holding the most, which
        is closed: a crowd cannot keep a newcomer (the page that would stop) out."""
        share = self.total_cap // max(1, len(self.by_client))
        biggest = max(self.by_client, key=lambda c: len(self.by_client[c]))
        if mine >= share or len(self.by_client[biggest]) <= mine + 1:
            return False
        victim = self.by_client[biggest].pop()
        self.total -= 1
        if not self.by_client[biggest]:
            del self.by_client[biggest]
        log.warning("server full: closed a connection of %s for one of %s", biggest, client)
        victim.close()
        return True

    def arrived(self, client: str, transport: Any) -> None:
        """A reserved connection's transport (counted since `reserve`)."""
        if self._unpend(client):
            self.by_client.setdefault(client, set()).add(transport)

    def abandon(self, client: str) -> None:
        """A reserved connection that never got its transport."""
        if self._unpend(client):
            self.total -= 1

    def _unpend(self, client: str) -> bool:
        pending = self.pending.get(client, 0)
        if not pending:
            return False
        if pending == 1:
            del self.pending[client]
        else:
            self.pending[client] = pending - 1
        return True

    def release(self, client: str, transport: Any) -> None:
        held = self.by_client.get(client)
        if held is not None and transport in held:
            held.discard(transport)
            self.total -= 1
            if not held:
                del self.by_client[client]


CENSUS = Census(32, 1024 - KEPT_FREE)


def configure(client_cap: int, file_limit: int) -> None:
    CENSUS.client_cap = client_cap
    CENSUS.total_cap = max(64, file_limit - KEPT_FREE)


class GuardedServer(uvicorn.Server):
    acceptors: list[Acceptor]

    async def startup(self, sockets: list[socket.socket] | None = None) -> None:
        """Once uvicorn listens, its sockets are served by Acceptors instead of asyncio's
        accept loop, with a kernel queue of LISTEN_QUEUE (asyncio's listen() gave it
        its accept burst's size): a stop's connection is not dropped (and retried a
        second later) while a crowd fills the queue."""
        await super().startup(sockets)
        loop = asyncio.get_running_loop()
        self.acceptors = []
        for server in getattr(self, "servers", ()):
            for wrapped in server.sockets:
                loop.remove_reader(wrapped.fileno())
                listener = socket.socket(fileno=os.dup(wrapped.fileno()))
                listener.setblocking(False)
                listener.listen(LISTEN_QUEUE)
                self.acceptors.append(Acceptor(listener, CENSUS.reserve, self._hand_over,
                                               CENSUS.abandon))

    def _hand_over(self, sock: socket.socket, peer: str) -> None:
        loop = asyncio.get_running_loop()
        protocol = GuardedH11(config=self.config, server_state=self.server_state,
                              app_state=self.lifespan.state)  # fmt: skip
        task = loop.create_task(loop.connect_accepted_socket(lambda: protocol, sock))

        def made(task: asyncio.Task[Any]) -> None:
            if task.cancelled() or task.exception() is not None:
                CENSUS.abandon(peer)
                sock.close()

        task.add_done_callback(made)

    async def shutdown(self, sockets: list[socket.socket] | None = None) -> None:
        for acceptor in getattr(self, "acceptors", ()):
            acceptor.close()
        await super().shutdown(sockets)


class GuardedH11(H11Protocol):
    _deadline: asyncio.TimerHandle | None = None
    _waiting_for: object = None
    _peer = "?"
    _head: bytearray | None = None  # the request head so far; None: h11 reads the data

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        super().connection_made(transport)
        self._peer = self.client[0] if self.client else "?"
        CENSUS.arrived(self._peer, transport)
        self._head = bytearray()
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
        if self._head is not None:
            data = self._collect(data)
            if not data:
                return
        super().data_received(data)
        if self._deadline is not None and self.cycle is not self._waiting_for:
            self._disarm()  # the request's headers are complete

    def _collect(self, data: bytes) -> bytes:
        """Keeps a request's head until it is complete, then offers a stop's to the
        lane; returns what h11 is to read now (nothing while the head is incomplete,
        or when the lane answered)."""
        assert self._head is not None
        self._unset_keepalive_if_required()  # data arrived: no keep-alive close meanwhile
        head = self._head
        head += data
        complete = head.find(b"\r\n\r\n", max(0, len(head) - len(data) - 3)) >= 0
        if not complete and len(head) <= MAX_HEADER_BYTES:
            return b""  # the header deadline holds meanwhile
        answer = None
        if complete and may_be_stop(bytes(head[:256])):
            answer = LANE.answer(bytes(head))
            if answer == NEED_MORE and len(head) <= MAX_HEADER_BYTES + BODY_MAX:
                return b""
        self._head = None
        if answer:
            self._disarm()
            self.transport.write(answer)
            self.transport.close()
            return b""
        return bytes(head)

    def handle_websocket_upgrade(self, event: Any) -> None:
        self._disarm()  # the headers are complete; the WebSocket protocol takes over
        super().handle_websocket_upgrade(event)

    def on_response_complete(self) -> None:
        super().on_response_complete()
        if not self.transport.is_closing():
            self._disarm()
            self._arm()  # the next request on this connection gets the same deadline
            idle = self.conn.their_state is h11.IDLE and not self.conn.trailing_data[0]
            self._head = bytearray() if idle else None  # not mid-way through pipelined data

    def connection_lost(self, exc: Exception | None) -> None:
        self._disarm()
        CENSUS.release(self._peer, self.transport)
        super().connection_lost(exc)
