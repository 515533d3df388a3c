"""Each plotter's state for the broker, followed from the event hub.

One JSON object per plotter (the retained `state` topic) holds what the Home Assistant
entities and the fleet view read. It is sent when it changes, at most every
MIN_INTERVAL s per plotter (machine reports come 10 times a second while moving).
"""

from __future__ import annotations

import asyncio
import json
import time
from collections.abc import Callable
from typing import Any

MIN_INTERVAL = 0.5  # s between two state messages of one plotter
PROMPT_CHARS = 250  # a Home Assistant sensor's state holds 255


class Telemetry:
    def __init__(self, plotters: list[str], send_state: Callable[[str, str], None],
                 send_event: Callable[[str, str], None]) -> None:  # fmt: skip
        self.plotters = {name: self._blank() for name in plotters}
        self.jobs: dict[str, dict[str, Any]] = {}  # plotter -> its current (or last) job
        self.send_state = send_state
        self.send_event = send_event
        self._sent: dict[str, str] = {}
        self._sent_at: dict[str, float] = {}
        self._timers: dict[str, asyncio.TimerHandle] = {}

    @staticmethod
    def _blank() -> dict[str, Any]:
        return {"state": "Disconnected", "connected": False, "job": "", "job_id": None,
                "job_state": "", "progress": 0, "time_left": None, "drawn_m": 0,
                "pen_prompt": "", "actions": []}  # fmt: skip

    # ---- from the hub -------------------------------------------------------------------

    def on_event(self, message: dict[str, Any]) -> None:
        kind = message.get("type")
        if kind == "machine" and message.get("plotter") in self.plotters:
            machine = message["machine"]
            self._update(message["plotter"], state=machine.get("state", "Disconnected"),
                         connected=bool(machine.get("connected")))  # fmt: skip
        elif kind == "job":
            self._job(message["job"])
        elif kind == "jobs":
            for job in message.get("jobs", []):
                self._job(job)

    def _job(self, job: dict[str, Any]) -> None:
        plotter = job.get("plotter")
        if plotter not in self.plotters or job.get("state") == "queued":
            return
        current = self.jobs.get(plotter)
        if current is not None and current["id"] != job["id"] and job.get("state") in (
                "done", "failed", "cancelled", "stopped", "interrupted") and current.get(
                "state") not in ("done", "failed", "cancelled", "stopped", "interrupted"):
            return  # an old job's news while another runs
        entering_pen_change = job.get("state") == "pen_change" and (
            current is None or current.get("state") != "pen_change" or current["id"] != job["id"])
        self.jobs[plotter] = job
        prompt = ""
        if job.get("state") == "pen_change" and job.get("pen_change"):
            prompt = str(job["pen_change"].get("message") or "change the pen")[:PROMPT_CHARS]
        eta = job.get("eta_s")
        self._update(plotter, job=str(job.get("name", ""))[:PROMPT_CHARS], job_id=job["id"],
                     job_state=job.get("state", ""),
                     progress=round(100 * float(job.get("progress") or 0), 1),
                     time_left=round(eta) if isinstance(eta, int | float) else None,
                     drawn_m=round(drawn_mm(job) / 1000, 3), pen_prompt=prompt,
                     actions=list(job.get("actions") or []))  # fmt: skip
        if entering_pen_change:
            self.send_event(plotter, json.dumps({
                "event_type": "pen_change", "message": prompt, "job": job.get("name"),
                "layer": (job.get("pen_change") or {}).get("layer"),
                "colour": (job.get("pen_change") or {}).get("colour"),
            }))  # fmt: skip

    # ---- out ---------------------------------------------------------------------------

    def _update(self, plotter: str, **fields: Any) -> None:
        self.plotters[plotter].update(fields)
        if plotter in self._timers:
            return
        wait = self._sent_at.get(plotter, 0.0) + MIN_INTERVAL - time.monotonic()
        if wait <= 0:
            self.flush(plotter)
        else:
            self._timers[plotter] = asyncio.get_running_loop().call_later(
                wait, self.flush, plotter)

    def flush(self, plotter: str) -> None:
        self._timers.pop(plotter, None)
        payload = json.dumps(self.plotters[plotter], sort_keys=True)
        if payload != self._sent.get(plotter):
            self._sent[plotter] = payload
            self._sent_at[plotter] = time.monotonic()
            self.send_state(plotter, payload)

    def resend(self) -> None:
        """Every state again (after a reconnect)."""
        self._sent.clear()
        for plotter in self.plotters:
            self.flush(plotter)

    def close(self) -> None:
        for timer in self._timers.values():
            timer.cancel()
        self._timers.clear()


def drawn_mm(job: dict[str, Any]) -> float:
    """The job's pen-down distance drawn: its own `drawn_mm` where the job tells it, else
    each layer's pen-down length times its share done."""
    if isinstance(job.get("drawn_mm"), int | float):
        return float(job["drawn_mm"])
    return sum(float(layer.get("pen_down_mm") or 0) * float(layer.get("progress") or 0)
               for layer in job.get("layers") or [])  # fmt: skip
