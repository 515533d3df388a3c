"""What is worth telling someone away from the plotter, read off the event hub.

The hub carries every job change and machine report (docs/INTERNALS.md,
"WebSocket messages"). `NoticeWatcher.feed` turns the transitions among them
into notices: a job started, a pen change is due, a job done, failed or
stopped, a plotter's alarm, a plotter's link lost. Pure and synchronous: it
runs inside `EventHub.publish`, also on the emergency stop's path.
"""

from __future__ import annotations

import itertools
import time
import uuid
from dataclasses import dataclass, field
from datetime import UTC, datetime
from typing import Any

from plotbridge.grbl import alarm_message
from plotbridge.jobs.lifecycle import ACTIVE, RESUMABLE, State

EVENTS: tuple[str, ...] = (
    "job_started", "pen_change", "job_done", "job_failed", "job_stopped", "alarm", "link_lost",
)  # fmt: skip
ENDED_RECENTLY_S = 5.0  # a link lost this soon after its job was interrupted names that job
STOPPED = RESUMABLE | {State.CANCELLED}  # ended early (the lifecycle's states)
SAID = ("progress", "drawn_mm", "eta_s", "summary", "actions")  # copied from the job


@dataclass(frozen=True)
class JobRef:
    id: str
    name: str
    state: str
    at: float  # time.monotonic() of the last state change


@dataclass(frozen=True)
class Notice:
    """One event as a webhook receiver gets it (`body()`)."""

    event: str
    plotter: str | None
    job: JobRef | None
    message: str
    details: dict[str, Any] = field(default_factory=dict)
    at: float = field(default_factory=time.time)
    id: str = ""

    def body(self) -> dict[str, Any]:
        return {
            "event": self.event,
            "id": self.id,
            "time": datetime.fromtimestamp(self.at, UTC).isoformat(timespec="milliseconds"),
            "timestamp": round(self.at, 3),
            "plotter": self.plotter,
            "job": ({"id": self.job.id, "name": self.job.name, "state": self.job.state}
                    if self.job else None),
            "message": self.message,
            "details": self.details,
        }


class NoticeWatcher:
    """Follows job states and machine reports; `feed` answers the notices a message makes."""

    def __init__(self) -> None:
        self._jobs: dict[str, str] = {}  # job id -> last state seen
        self._last_job: dict[str, JobRef] = {}  # plotter -> its latest job
        self._machines: dict[str, tuple[bool, str]] = {}  # plotter -> (connected, state)
        self._prefix = uuid.uuid4().hex[:8]  # ids stay unique across server restarts
        self._serial = itertools.count(1)

    def feed(self, message: dict[str, Any]) -> list[Notice]:
        kind = message.get("type")
        if kind == "job" and isinstance(message.get("job"), dict):
            notices = self._job(message["job"])
        elif kind == "machine" and isinstance(message.get("machine"), dict):
            notices = self._machine(message.get("plotter"), message["machine"])
        elif kind == "job_deleted":
            self._jobs.pop(str(message.get("id")), None)
            notices = []
        else:
            notices = []
        return [self._numbered(notice) for notice in notices]

    def _numbered(self, notice: Notice) -> Notice:
        return Notice(notice.event, notice.plotter, notice.job, notice.message, notice.details,
                      notice.at, f"{self._prefix}-{next(self._serial)}")  # fmt: skip

    def _job(self, job: dict[str, Any]) -> list[Notice]:
        job_id, state = str(job.get("id")), str(job.get("state"))
        before = self._jobs.get(job_id)
        self._jobs[job_id] = state
        if before == state:
            return []  # progress
        plotter = job.get("plotter")
        ref = JobRef(job_id, str(job.get("name")), state, time.monotonic())
        if plotter and (state in ACTIVE or before in ACTIVE):
            self._last_job[plotter] = ref
        where = f" on {plotter}" if plotter else ""
        name = f"Job '{ref.name}'"
        said = {key: job.get(key) for key in SAID}  # the server's own numbers and words
        if state == "running" and before not in ACTIVE:
            how = "resumed" if before in STOPPED else "started"
            return [Notice("job_started", plotter, ref, f"{name} {how}{where}",
                           {"lines_total": job.get("lines_total"),
                            "estimate_s": job.get("estimate_s"), **said})]  # fmt: skip
        if state == "pen_change":
            change = job.get("pen_change") or {}
            text = change.get("message") or "load the next pen, then continue"
            return [Notice("pen_change", plotter, ref, f"{name}{where}: {text}",
                           {**change, **said})]  # fmt: skip
        if state == "done":
            return [Notice("job_done", plotter, ref, f"{name} done{where}", said)]
        if state == "failed":
            error = job.get("error") or "no reason given"
            return [Notice("job_failed", plotter, ref, f"{name} failed{where}: {error}",
                           {"error": job.get("error"), "lines_done": job.get("lines_done"),
                            **said})]  # fmt: skip
        if state in STOPPED and before in ACTIVE:
            why = f": {job['error']}" if job.get("error") else ""
            return [Notice("job_stopped", plotter, ref, f"{name} {state}{where}{why}",
                           {"error": job.get("error"), "lines_done": job.get("lines_done"),
                            "resume_line": job.get("resume_line"), **said})]  # fmt: skip
        return []

    def _machine(self, plotter: str | None, machine: dict[str, Any]) -> list[Notice]:
        name = plotter or "the plotter"
        connected, state = bool(machine.get("connected")), str(machine.get("state"))
        before = self._machines.get(name)
        self._machines[name] = (connected, state)
        if before is None or not before[0]:
            return []  # first report, or the board came (back) up: its start-up Alarm is no news
        if not connected:
            return [Notice("link_lost", plotter, self._job_on(name),
                           f"{name}: the link to the plotter was lost")]  # fmt: skip
        if state == "Alarm" and before[1] != "Alarm":
            code = machine.get("alarm")
            text = f"ALARM:{code}: {alarm_message(code)}" if code is not None else "an alarm"
            return [Notice("alarm", plotter, self._job_on(name), f"{name} raised {text}",
                           {"code": code})]  # fmt: skip
        return []

    def _job_on(self, plotter: str) -> JobRef | None:
        """The plotter's job when something happens to the plotter: the active one, or one
        that just ended (a lost link interrupts its job before the report says so)."""
        ref = self._last_job.get(plotter)
        if ref is None:
            return None
        current = self._jobs.get(ref.id)
        if current in ACTIVE:
            return JobRef(ref.id, ref.name, current, ref.at)
        if current is not None and time.monotonic() - ref.at < ENDED_RECENTLY_S:
            return JobRef(ref.id, ref.name, current, ref.at)
        return None
