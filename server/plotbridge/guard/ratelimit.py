"""Failed-login lockout per client address."""

from __future__ import annotations

import time

FREE_FAILURES = 5  # failures before any wait
BASE_WAIT = 1.0  # s after the first failure past the free ones, doubling per failure
MAX_WAIT = 300.0  # s
FORGET_AFTER = 900.0  # s without a failure: the count starts again


class LoginLimiter:
    def __init__(self) -> None:
        self.failures: dict[str, tuple[int, float]] = {}  # client -> (count, last failure)

    def wait(self, client: str) -> float:
        """Seconds before `client` may try again (0: now)."""
        count, last = self.failures.get(client, (0, 0.0))
        now = time.monotonic()
        if now - last > FORGET_AFTER:
            return 0.0
        if count < FREE_FAILURES:
            return 0.0
        return max(0.0, last + min(MAX_WAIT, BASE_WAIT * 2 ** (count - FREE_FAILURES)) - now)

    def failed(self, client: str) -> None:
        now = time.monotonic()
        count, last = self.failures.get(client, (0, 0.0))
        if now - last > FORGET_AFTER:
            count = 0
        self.failures[client] = (count + 1, now)
        if len(self.failures) > 10000:  # forget the oldest half
            keep = sorted(self.failures.items(), key=lambda kv: kv[1][1])[5000:]
            self.failures = dict(keep)
