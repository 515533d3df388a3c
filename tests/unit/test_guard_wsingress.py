"""What one address may make the server read of WebSockets (guard/wsingress.py)."""

from __future__ import annotations

from plotbridge.guard import wsingress
from plotbridge.guard.wsingress import Buckets


def test_an_address_reads_its_burst_then_waits_for_the_rate():
    buckets = Buckets(rate=1000, burst=4000)
    assert buckets.spend("a", 4000, now=0.0) == 0.0
    assert buckets.spend("a", 500, now=0.0) == 0.5  # 500 bytes owed at 1000 B/s
    assert buckets.spend("b", 3000, now=0.0) == 0.0  # another address has its own
    assert buckets.spend("a", 0, now=0.5) == 0.0  # paid back
    assert buckets.spend("a", 2000, now=2.5) == 0.0  # refilled by 2000, not past the burst


def test_many_addresses_are_forgotten_once_refilled(monkeypatch):
    monkeypatch.setattr(wsingress, "KEPT", 3)
    buckets = Buckets(rate=1000, burst=1000)
    for n, address in enumerate("abc"):
        buckets.spend(address, 1000 if address == "c" else 10, now=float(n) / 100)
    buckets.spend("d", 10, now=0.5)  # a and b have refilled; c has not
    assert set(buckets.level) == {"c", "d"}
