"""What one address may make the server read of WebSockets: bytes per second.

Reading and parsing frames is what a token-holding flood costs the loop (60
addresses sending 60 KB frames took half its time, and the stop waited behind
it). So each client address has a byte bucket shared by its WebSockets; once it
is empty, their transports stop being read (the kernel's buffers fill and the
sender blocks) until it has refilled. Nothing is dropped and nobody is closed;
a page sends a few hundred bytes a second and never meets the limit. The
message rate (`ws.RateLimit`) still closes a client that sends too many.
docs/INTERNALS.md, "Hostile LAN".
"""

from __future__ import annotations

import time
from typing import Any

from uvicorn.protocols.websockets.websockets_sansio_impl import WebSocketsSansIOProtocol

BYTES_PER_S = 64 * 1024  # per client address, all its WebSockets together
BURST = 256 * 1024
KEPT = 4096  # addresses remembered; refilled ones are forgotten beyond this


class Buckets:
    """A byte bucket per address; `spend` says how long to wait before reading more."""

    def __init__(self, rate: float = BYTES_PER_S, burst: float = BURST) -> None:
        self.rate, self.burst = rate, burst
        self.level: dict[str, tuple[float, float]] = {}  # address -> (tokens, when)

    def spend(self, address: str, size: int, now: float | None = None) -> float:
        """Takes `size` bytes from the address's bucket (it may go below zero); the
        seconds until it is back above zero (0: read on)."""
        now = time.monotonic() if now is None else now
        tokens, at = self.level.get(address, (self.burst, now))
        tokens = min(self.burst, tokens + (now - at) * self.rate) - size
        if len(self.level) >= KEPT and address not in self.level:
            self._forget(now)
        self.level[address] = (tokens, now)
        return -tokens / self.rate if tokens < 0 else 0.0

    def _forget(self, now: float) -> None:
        for address, (tokens, at) in list(self.level.items()):
            if tokens + (now - at) * self.rate >= self.burst:
                del self.level[address]


BUCKETS = Buckets()


class MeteredWebSocket(WebSocketsSansIOProtocol):
    """uvicorn's WebSocket protocol whose reading waits for its address's bucket.

    uvicorn pauses reading after each message until the app asks for the next one;
    the meter's pause is a second reason, and reading resumes only when neither holds."""

    _throttled = False

    def data_received(self, data: bytes) -> None:
        address = self.client[0] if self.client else "?"
        wait = BUCKETS.spend(address, len(data))
        if wait > 0 and not self._throttled:
            self._throttled = True
            self.transport.pause_reading()
            self.loop.call_later(wait, self._refilled)
        super().data_received(data)

    def _refilled(self) -> None:
        self._throttled = False
        if not self.read_paused and not self.transport.is_closing():
            self.transport.resume_reading()

    async def receive(self) -> Any:
        message = await self.queue.get()
        if self.read_paused and self.queue.empty():
            self.read_paused = False
            if not self._throttled:
                self.transport.resume_reading()
        return message

