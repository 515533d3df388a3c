"""What one person is shown of a job: a submitter only their own jobs, and a job's
`actions` only what this person may do (plotbridge.access, JOB_ACTIONS)."""

from __future__ import annotations

from typing import Any

from plotbridge.access import Role, may_act
from plotbridge.people.access import Identity


def owns(identity: Identity, job: dict[str, Any]) -> bool:
    return job.get("owner") == identity.who


def job_view(identity: Identity, job: dict[str, Any]) -> dict[str, Any] | None:
    """The job as `identity` sees it, or None when it may not see it."""
    if identity.role == Role.admin:
        return job
    own = owns(identity, job)
    if identity.role == Role.submitter and not own:
        return None
    actions = job.get("actions")
    if actions is None:
        return job
    return {**job, "actions": [a for a in actions if may_act(identity.role, a, own)]}


def jobs_view(identity: Identity, jobs: list[dict[str, Any]]) -> list[dict[str, Any]]:
    return [shown for job in jobs if (shown := job_view(identity, job)) is not None]


def message_view(identity: Identity, message: dict[str, Any]) -> dict[str, Any] | None:
    """A WebSocket event as `identity` sees it (None: not sent to them)."""
    if identity.role == Role.admin or message.get("type") not in ("job", "jobs"):
        return message
    if message["type"] == "jobs":
        return {**message, "jobs": jobs_view(identity, message.get("jobs") or [])}
    shown = job_view(identity, message.get("job") or {})
    return None if shown is None else {**message, "job": shown}
