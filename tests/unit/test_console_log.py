"""A plotter's console lines published together (plotter/consolelog.py)."""

from __future__ import annotations

from plotbridge.plotter import consolelog
from plotbridge.plotter.consolelog import ConsoleLog

from tests.fixtures.waits import settle


async def test_lines_of_one_interval_are_one_event():
    events: list[dict] = []
    log = ConsoleLog("left", events.append)
    log.add("tx", "$$")
    for n in range(35):
        log.add("rx", f"${n}=1")
    assert events == []  # gathered for LOG_INTERVAL
    await settle(lambda: events, what="the console event")
    assert len(events) == 1 and events[0]["plotter"] == "left"
    assert events[0]["lines"][0] == {"direction": "tx", "line": "$$"}
    assert len(events[0]["lines"]) == 36
    log.add("rx", "ok")
    await settle(lambda: len(events) == 2, what="the next interval's event")


async def test_a_flood_of_lines_is_counted_not_sent(monkeypatch):
    monkeypatch.setattr(consolelog, "LOG_LINES", 4)
    events: list[dict] = []
    log = ConsoleLog("left", events.append)
    for n in range(10):
        log.add("rx", str(n))
    log.flush()
    lines = [entry["line"] for entry in events[0]["lines"]]
    assert lines[:4] == ["0", "1", "2", "3"]
    assert lines[4].startswith("(6 console lines not shown")
