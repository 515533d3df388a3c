"""The listener's accept path: every waiting connection is taken off the kernel's
queue at once, and one over the connection caps may still carry a stop.

Replaces asyncio's own accept loop on uvicorn's listening sockets. asyncio accepts
a burst, makes each connection a task, a transport and a protocol, and when
accept() fails for want of a descriptor it stops listening for a second. Here:
- a connection the census has room for is handed to uvicorn's protocol as before,
  unless what it sent with its connection is a whole stop: that is acted on and
  answered at once;
- any other is never given a transport: what it has sent is read at once (a
  stop's request is normally there already) and offered to the stop lane; a stop
  is acted on and answered in this same callback, anything else gets 503 and is
  closed; one that has sent only the start of what may be a stop's head waits,
  at most PROBATION of them for PROBATION_TIMEOUT, the silent ones displaced first;
- when the process is out of descriptors anyway, a spare one is given up to
  accept, answer and close the next connection the same way, then taken again.
So accept() never stalls, and the queue drains as fast as refusals cost (a few
system calls each), so a stop waits behind no crowd. docs/INTERNALS.md, "The stop lane".
"""

from __future__ import annotations

import asyncio
import contextlib
import errno
import logging
import os
import socket
from collections.abc import Callable
from typing import Any

from plotbridge.guard.stoplane import BODY_MAX, HEAD_MAX, LANE, NEED_MORE

log = logging.getLogger("plotbridge.guard")

PROBATION = 64  # connections over the caps waiting to show whether they are a stop
PROBATION_TIMEOUT = 2.0  # s such a connection has to send its stop
PER_WAKE = 64  # connections accepted per call, so the loop's other work goes on between
_STOP_PREFIX = b"POST /api/"
_BUSY_BODY = b'{"detail": "too many open connections; try again shortly"}'
BUSY = (
    b"HTTP/1.1 503 Service Unavailable\r\ncontent-type: application/json\r\n"
    b"connection: close\r\nretry-after: 5\r\ncontent-length: %d\r\n\r\n%s"
    % (len(_BUSY_BODY), _BUSY_BODY)
)
_OUT_OF_FILES = (errno.EMFILE, errno.ENFILE, errno.ENOBUFS, errno.ENOMEM)


def may_be_stop(head: bytes) -> bool:
    """Whether the start of a request head could still be a stop's."""
    if not (head.startswith(_STOP_PREFIX) or _STOP_PREFIX.startswith(head)):
        return False
    line, newline, _ = head.partition(b"\r\n")
    return not newline or b"estop " in line


class _Waiting:
    """A connection over the caps whose head is still arriving."""

    def __init__(self, sock: socket.socket, peer: str, head: bytes) -> None:
        self.sock, self.peer, self.head = sock, peer, head
        self.deadline: asyncio.TimerHandle | None = None


class Acceptor:
    def __init__(self, listener: socket.socket, admit: Callable[[str], bool],
                 hand_over: Callable[[socket.socket, str], Any],
                 abandon: Callable[[str], None]) -> None:  # fmt: skip
        """`listener`: a listening socket (non-blocking); `admit(peer)`: whether the
        caps leave room for a connection from `peer` (counting it); `hand_over(sock,
        peer)`: give an admitted connection to the HTTP protocol; `abandon(peer)`: an
        admitted one closed before that."""
        self.listener = listener
        self.admit = admit
        self.hand_over = hand_over
        self.abandon = abandon
        self.loop = asyncio.get_running_loop()
        self.waiting: dict[int, _Waiting] = {}  # by descriptor, oldest first
        self.refused = 0
        self._spare: int | None = os.open(os.devnull, os.O_RDONLY)
        self.loop.add_reader(listener.fileno(), self._accept)

    def close(self) -> None:
        self.loop.remove_reader(self.listener.fileno())
        self.listener.close()
        for entry in list(self.waiting.values()):
            self._drop(entry)
        if self._spare is not None:
            os.close(self._spare)
            self._spare = None

    def _accept(self) -> None:
        for _ in range(PER_WAKE):
            try:
                sock, address = self.listener.accept()
            except (BlockingIOError, InterruptedError):
                return
            except OSError as exc:
                if exc.errno in _OUT_OF_FILES and self._spare is not None:
                    self._accept_with_spare()
                    continue
                log.error("accept failed: %s", exc)
                return
            sock.setblocking(False)
            peer = str(address[0])
            if self.admit(peer):
                if self._stopped_at_once(sock):
                    self.abandon(peer)
                else:
                    self.hand_over(sock, peer)
            else:
                self._over_caps(sock, peer)

    def _stopped_at_once(self, sock: socket.socket) -> bool:
        """A stop whose whole request came with its connection (a client sends it as it
        connects) is acted on and answered here, one loop pass before a transport
        could read it; anything else is left unread for the HTTP protocol."""
        try:
            data = sock.recv(HEAD_MAX + BODY_MAX, socket.MSG_PEEK)
        except OSError:
            return False
        if not may_be_stop(data[:256]) or b"\r\n\r\n" not in data:
            return False
        answer = LANE.answer(data)
        if not answer:  # not a stop, not allowed, or its body is still on its way
            return False
        with contextlib.suppress(OSError):
            sock.recv(len(data))  # read, so that closing sends the answer, not a reset
            sock.send(answer)
        sock.close()
        return True

    def _accept_with_spare(self) -> None:
        """Out of descriptors: the spare one lets the next connection be answered."""
        assert self._spare is not None
        os.close(self._spare)
        self._spare = None
        try:
            sock, address = self.listener.accept()
        except OSError:
            sock = None
        if sock is not None:
            sock.setblocking(False)
            log.warning("out of file descriptors: a connection from %s answered with the "
                        "spare one", address[0])  # fmt: skip
            self._over_caps(sock, str(address[0]), keep=False)
        with contextlib.suppress(OSError):
            self._spare = os.open(os.devnull, os.O_RDONLY)

    def _over_caps(self, sock: socket.socket, peer: str, keep: bool = True) -> None:
        head = _receive(sock, b"")
        if head is None:  # closed already
            sock.close()
            return
        entry = _Waiting(sock, peer, head)
        if not self._decide(entry) and keep:
            self._wait(entry)
        elif entry.sock.fileno() >= 0:
            self._refuse(entry)

    def _decide(self, entry: _Waiting) -> bool:
        """Answers a complete stop, refuses what cannot be one; False: wait for more."""
        head = entry.head
        if not head or (may_be_stop(head) and b"\r\n\r\n" not in head):
            return len(head) > HEAD_MAX and self._refuse(entry)
        answer = LANE.answer(head) if head.startswith(_STOP_PREFIX) else None
        if answer == NEED_MORE and len(head) <= HEAD_MAX + BODY_MAX:
            return False
        if not answer:
            return self._refuse(entry)
        with contextlib.suppress(OSError):  # a fresh socket's buffer takes the whole answer
            entry.sock.send(answer)
        self._drop(entry)
        return True

    def _wait(self, entry: _Waiting) -> None:
        if len(self.waiting) >= PROBATION:
            silent = (e for e in self.waiting.values() if not e.head)
            self._refuse(next(silent, None) or next(iter(self.waiting.values())))
        fd = entry.sock.fileno()
        self.waiting[fd] = entry
        entry.deadline = self.loop.call_later(PROBATION_TIMEOUT, self._refuse, entry)
        self.loop.add_reader(fd, self._more, entry)

    def _more(self, entry: _Waiting) -> None:
        head = _receive(entry.sock, entry.head)
        if head is None:
            self._drop(entry)
            return
        entry.head = head
        self._decide(entry)

    def _refuse(self, entry: _Waiting) -> bool:
        self.refused += 1
        if self.refused % 1000 == 1:
            log.warning("refused a connection from %s: too many open (%d refused so far)",
                        entry.peer, self.refused)  # fmt: skip
        with contextlib.suppress(OSError):
            entry.sock.send(BUSY)
        self._drop(entry)
        return True

    def _drop(self, entry: _Waiting) -> None:
        fd = entry.sock.fileno()
        if fd >= 0 and self.waiting.pop(fd, None) is not None:
            self.loop.remove_reader(fd)
        if entry.deadline is not None:
            entry.deadline.cancel()
        entry.sock.close()


def _receive(sock: socket.socket, head: bytes) -> bytes | None:
    """`head` and what has arrived since; None when the peer closed."""
    try:
        data = sock.recv(HEAD_MAX + BODY_MAX)
    except (BlockingIOError, InterruptedError):
        return head
    except OSError:
        return None
    return head + data if data else None
