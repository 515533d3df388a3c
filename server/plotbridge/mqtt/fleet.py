"""The fleet as the broker shows it: every bridge's status, info and plotters' states.

Whatever arrives on these topics is checked before it is kept: anything else is dropped,
and said once (a flood of retained garbage costs a log line, not a log line per message).
"""

from __future__ import annotations

import json
import time
from typing import Any

from plotbridge.mqtt.connection import Once

MAX_PAYLOAD = 16384  # bytes of one status, info or state message
MAX_BRIDGES = 64
MAX_PLOTTERS = 64  # per bridge


class FleetView:
    def __init__(self, problems: Once) -> None:
        self.bridges: dict[str, dict[str, Any]] = {}
        self.problems = problems

    def _bridge(self, name: str) -> dict[str, Any] | None:
        if name not in self.bridges:
            if len(self.bridges) >= MAX_BRIDGES:
                self.problems.warn("fleet-size", "MQTT: more than %d bridges in the fleet; "
                                   "ignoring the others", MAX_BRIDGES)  # fmt: skip
                return None
            self.bridges[name] = {"online": False, "url": "", "plotters": {}, "seen": 0.0}
        return self.bridges[name]

    def _garbage(self, topic: str, why: str) -> None:
        self.problems.warn("fleet-garbage", "MQTT: ignoring a malformed message on %s (%s); "
                           "further ones are not logged", topic, why)  # fmt: skip

    def status(self, bridge: str, payload: bytes) -> None:
        if payload == b"":
            self.bridges.pop(bridge, None)
            return
        if payload not in (b"online", b"offline"):
            return self._garbage(f"{bridge}/status", "not online or offline")
        entry = self._bridge(bridge)
        if entry is not None:
            entry["online"] = payload == b"online"
            entry["seen"] = time.time()

    def info(self, bridge: str, payload: bytes) -> None:
        data = self._json(f"{bridge}/info", payload)
        if data is None:
            return
        url = data.get("url")
        plotters = data.get("plotters")
        if not isinstance(url, str) or not isinstance(plotters, list) or not all(
                isinstance(p, str) for p in plotters):
            return self._garbage(f"{bridge}/info", "needs url and plotters")
        entry = self._bridge(bridge)
        if entry is None:
            return
        entry["url"] = url[:500]
        for gone in set(entry["plotters"]) - set(plotters):
            del entry["plotters"][gone]

    def state(self, bridge: str, plotter: str, payload: bytes) -> None:
        if payload == b"":
            entry = self.bridges.get(bridge)
            if entry is not None:
                entry["plotters"].pop(plotter, None)
            return
        data = self._json(f"{bridge}/plotter/{plotter}/state", payload)
        if data is None:
            return
        if not isinstance(data.get("state"), str) or not isinstance(data.get("progress"),
                                                                     int | float):  # fmt: skip
            return self._garbage(f"{bridge}/plotter/{plotter}/state", "needs state, progress")
        entry = self._bridge(bridge)
        if entry is None:
            return
        if plotter not in entry["plotters"] and len(entry["plotters"]) >= MAX_PLOTTERS:
            return self._garbage(f"{bridge}/plotter/{plotter}/state", "too many plotters")
        keep = ("state", "connected", "job", "job_state", "progress", "time_left", "drawn_m",
                "pen_prompt")
        entry["plotters"][plotter] = {k: data.get(k) for k in keep}

    def _json(self, where: str, payload: bytes) -> dict[str, Any] | None:
        if len(payload) > MAX_PAYLOAD:
            self._garbage(where, f"{len(payload)} bytes")
            return None
        try:
            data = json.loads(payload)
        except (ValueError, UnicodeDecodeError):
            self._garbage(where, "not JSON")
            return None
        if not isinstance(data, dict):
            self._garbage(where, "not a JSON object")
            return None
        return data

    def describe(self) -> list[dict[str, Any]]:
        return [{"bridge": name, "online": b["online"], "url": b["url"],
                 "plotters": [{"name": p, **state} for p, state in sorted(b["plotters"].items())]}
                for name, b in sorted(self.bridges.items())]  # fmt: skip
