"""One failure limit for every way of presenting a credential (login, Bearer, cookie,
WebSocket `?token=`, one-time link), counted per address, per credential tried, and in all.

A wrong credential's answer is held back: nothing for the first few failures, then a wait
that doubles per failure up to a bound. A right credential is never held, so guessers
behind a school's NAT or a proxy never lock out the people who know their key. Each held
answer keeps its connection open, and the guard bounds a client's open connections, so
the guesses one address can make per second are bounded; failures from every address
together hold all wrong answers too (many rotating addresses).
"""

from __future__ import annotations

import hashlib
import time

FREE = 5  # failures (per address or credential) answered at once
BASE_HOLD = 0.5  # s for the first held failure, doubling per failure
MAX_HOLD = 10.0  # s
ALL_FREE = 50  # failures from all addresses together within FORGET_AFTER
FORGET_AFTER = 900.0  # s without a failure: the count starts again
REMEMBERED = 10000  # addresses and credentials; the oldest half is forgotten past it


class Failures:
    def __init__(self) -> None:
        self._counts: dict[str, tuple[int, float]] = {}  # "a:ADDRESS" / "c:DIGEST" -> (n, last)
        self._all: tuple[int, float] = (0, 0.0)

    @staticmethod
    def _keys(address: str, credential: str) -> tuple[str, str]:
        tried = hashlib.sha256(credential.encode()).hexdigest()[:32]
        return f"a:{address}", f"c:{tried}"

    def _count(self, key: str, now: float) -> int:
        count, last = self._counts.get(key, (0, 0.0))
        return 0 if now - last > FORGET_AFTER else count

    def failed(self, address: str, credential: str) -> float:
        """Count a failure; the seconds its answer is to be held."""
        now = time.monotonic()
        held = []
        for key in self._keys(address, credential):
            count = self._count(key, now) + 1
            self._counts[key] = (count, now)
            held.append(count - FREE)
        total, last = self._all
        total = (0 if now - last > FORGET_AFTER else total) + 1
        self._all = (total, now)
        held.append((total - ALL_FREE) // 10)
        if len(self._counts) > REMEMBERED:
            keep = sorted(self._counts.items(), key=lambda kv: kv[1][1])[REMEMBERED // 2:]
            self._counts = dict(keep)
        worst = max(held)
        return 0.0 if worst <= 0 else min(MAX_HOLD, BASE_HOLD * 2 ** (worst - 1))
