"""A job's life: its states, the one table of what moves it from state to state, and the
one place that changes a job's state (docs/INTERNALS.md, "The job lifecycle").

`TABLE[(state, cause)]` is the state a cause takes a job to; a cause is an action (what a
person or a script asks: `ACTIONS`) or an event (what the server sees happen: `EVENTS`).
An action with no row for the job's state is refused with 409, the state and the actions
allowed. `Lifecycle.move` is the only assignment of `job.state` in the server: it checks the
row, persists the job and publishes it once as a `job` message with the transition.
"""

from __future__ import annotations

import contextlib
import logging
import time
from collections.abc import AsyncIterator, Iterable
from enum import StrEnum
from typing import TYPE_CHECKING, Any

from plotbridge.errors import Refused

if TYPE_CHECKING:
    from plotbridge.events import EventHub
    from plotbridge.jobs.model import Job
    from plotbridge.jobs.store import JobStore

log = logging.getLogger("plotbridge.lifecycle")


class State(StrEnum):
    QUEUED = "queued"
    WAITING = "waiting"
    RUNNING = "running"
    PAUSED = "paused"
    PEN_CHANGE = "pen_change"
    DONE = "done"
    FAILED = "failed"
    CANCELLED = "cancelled"
    STOPPED = "stopped"
    INTERRUPTED = "interrupted"
    AWAITING_APPROVAL = "awaiting_approval"  # an upload an operator approves or declines


Q, W, R, P, C = State.QUEUED, State.WAITING, State.RUNNING, State.PAUSED, State.PEN_CHANGE
D, F, X, S, N = State.DONE, State.FAILED, State.CANCELLED, State.STOPPED, State.INTERRUPTED
AW = State.AWAITING_APPROVAL

ACTIVE: frozenset[State] = frozenset({R, P, C})
"""A plotter runs the job: it takes no other, and the job cannot be deleted."""
SETTLED: frozenset[State] = frozenset({D, F, X, S, N})
"""The job ran and ended (for now): nothing runs it."""
RESUMABLE: frozenset[State] = frozenset({S, N})
"""Ended where a resume picks it up exactly."""

ACTIONS: tuple[str, ...] = (
    "start", "hold", "continue", "stop", "resume", "home_then_resume", "resume_from",
    "restart", "cancel", "frame", "move", "edit", "delete", "approve", "decline",
)  # fmt: skip
"""What may be asked of a job, in the order the API lists them."""
EVENTS: tuple[str, ...] = (
    "wait", "dispatch", "pen_change", "held", "released", "done", "fail", "estop", "lost",
)  # fmt: skip
"""What the server sees happen to a job."""
GONE = None  # the row's target for delete: the job is no more

_SAME = object()


def _rows(cause: str, states: Iterable[State], to: State | object | None) -> dict:
    return {(state, cause): (state if to is _SAME else to) for state in states}


TABLE: dict[tuple[State, str], State | None] = {
    # actions
    **_rows("start", [Q], R),  # or `wait`, when no plotter can take it now
    **_rows("hold", [R], P),
    **_rows("continue", [P, C], R),
    **_rows("stop", ACTIVE, S),
    **_rows("resume", RESUMABLE, R),
    **_rows("home_then_resume", RESUMABLE, R),
    **_rows("resume_from", SETTLED, R),
    **_rows("restart", SETTLED, R),  # or `wait`
    **_rows("cancel", [AW, Q, W, *ACTIVE, *RESUMABLE], X),
    **_rows("frame", [Q, W, *SETTLED], _SAME),
    **_rows("move", [Q, W], _SAME),
    **_rows("edit", [Q], _SAME),
    **_rows("delete", [AW, Q, W, *SETTLED], GONE),
    **_rows("approve", [AW], Q),  # then started, if its sender asked to start it
    **_rows("decline", [AW], X),  # with the reason its sender sees
    # events
    **_rows("wait", [Q, W, *SETTLED], W),  # a start or restart no plotter can take now
    **_rows("dispatch", [Q, W], R),  # a free plotter took it
    **_rows("pen_change", [R], C),  # between layers, or to re-ink
    **_rows("held", [R], P),  # the board's hold button
    **_rows("released", [P, C], R),  # the board's resume button
    **_rows("done", [R], D),
    **_rows("fail", ACTIVE, F),
    **_rows("estop", ACTIVE, S),
    **_rows("lost", ACTIVE, N),  # the link lost, or the server restarted under it
}  # fmt: skip


def allowed(state: str, claimed: bool = False) -> list[str]:
    """The actions a job in `state` may be asked now (none while one is under way)."""
    if claimed:
        return []
    return [action for action in ACTIONS if (State(state), action) in TABLE]


def refusal(job: Job, action: str, why: str | None = None) -> Refused:
    """The 409 of an action the job's state does not allow."""
    message = why or f"job {job.id} is {job.state}: cannot {action.replace('_', ' ')} it"
    return Refused(409, {"message": message, "state": job.state, "actions": job.actions})


class Lifecycle:
    """Every job, in queue order, and the one place their states change."""

    def __init__(self, store: JobStore, events: EventHub) -> None:
        self.store = store
        self.events = events
        self.jobs: dict[str, Job] = {}  # in queue order

    def check(self, job: Job, action: str) -> None:
        """Refuse (409) `action` unless the job's state allows it now."""
        if action not in ACTIONS:
            raise Refused(404, f"no action {action!r}; the actions are: {', '.join(ACTIONS)}")
        if job.claim is not None:
            raise refusal(job, action, f"job {job.id}: a {job.claim.replace('_', ' ')} is "
                                       f"under way; cannot {action.replace('_', ' ')} it")
        if (State(job.state), action) not in TABLE:
            raise refusal(job, action)

    @contextlib.asynccontextmanager
    async def claim(self, job: Job, action: str) -> AsyncIterator[None]:
        """Hold the job for an action that awaits (homing, picking a point): every other
        action on it is refused meanwhile, so of two racing actions one wins."""
        self.check(job, action)
        job.claim = action
        self.publish(job, save=False)
        try:
            yield
        finally:
            job.claim = None
            self.publish(job, save=False)

    def move(self, job: Job, cause: str, **fields: Any) -> None:
        """Take `job` to the state `cause` leads to from its own (ValueError if the table
        has no such row: a bug), set `fields`, persist it and publish it."""
        before = State(job.state)
        key = (before, cause)
        if key not in TABLE:
            raise ValueError(f"job {job.id}: no transition from {before} on {cause!r}")
        after = TABLE[key]
        if after is None:
            raise ValueError(f"job {job.id}: {cause!r} removes the job; use forget()")
        for name, value in fields.items():
            setattr(job, name, value)
        self.publish(job, save=True, transition=self._set(job, after, cause))

    @staticmethod
    def _set(job: Job, after: State, cause: str) -> dict[str, str]:
        before = job.state
        job.state = after.value  # the one assignment of a job's state in the server
        if after in SETTLED and before not in SETTLED:
            job.finished_at = time.time()
        log.info("job %s: %s -> %s (%s)", job.id, before, after.value, cause)
        return {"from": before, "to": after.value, "cause": cause}

    def publish(self, job: Job, save: bool = True,
                transition: dict[str, str] | None = None) -> None:  # fmt: skip
        """The job's one event (state change or progress): stored when `save`, sent to
        every subscriber of the hub."""
        if save and job.id in self.jobs:
            self.store.save(job, list(self.jobs).index(job.id))
        message: dict[str, Any] = {"type": "job", "job": job.public()}
        if transition is not None:
            message["transition"] = transition
        self.events.publish(message)

    def forget(self, job: Job) -> None:
        """A deleted job (its `delete` row checked by the caller) leaves the registry."""
        self.jobs.pop(job.id, None)
        self.events.publish({"type": "job_deleted", "id": job.id})

    def restarted(self, job: Job) -> None:
        """At load: a job that was active when the server died is interrupted (nothing is
        subscribed yet; it is written at once)."""
        after = TABLE[(State(job.state), "lost")]
        assert after is not None
        self._set(job, after, "lost")
        self.store.write(job.record(), len(self.jobs))
