"""Who may do what: the one table of every route's and WebSocket message's required role.

Roles are ordered: viewer < submitter < operator < admin; a role may do what the roles
below it may. `PUBLIC` needs no credential. A rule's second part marks a job route a
submitter may use on their own jobs only (a viewer sees every job; operators and admins
act on any). STOP needs only a login, whatever
the role: safety beats permissions. The one dependency that enforces this table is
`api.deps.authorize`; tests/unit/test_access_matrix.py calls every route and message as
each role and as nobody, and fails on a route missing here.
"""

from __future__ import annotations

from enum import IntEnum


class Role(IntEnum):
    viewer = 1  # sees plotters, jobs and previews; may STOP
    submitter = 2  # also uploads (the upload waits for approval); cancels their own jobs
    operator = 3  # runs jobs, approves, holds, resumes, homes, jogs, changes pens
    admin = 4  # also machine settings, console, people and keys, webhooks, the audit log

    @classmethod
    def parse(cls, text: str) -> Role:
        try:
            return cls[text.strip().lower()]
        except KeyError:
            raise ValueError(f"no role {text!r}; the roles are: {', '.join(ROLES)}") from None


ROLES: tuple[str, ...] = tuple(role.name for role in Role)
PUBLIC = None  # no credential needed

V, S, O, A = Role.viewer, Role.submitter, Role.operator, Role.admin  # noqa: E741
_MACHINE: dict[tuple[str, str], Role] = {
    ("GET", "/machine"): V,
    ("POST", "/machine/estop"): V,
    ("POST", "/machine/hold"): O,
    ("POST", "/machine/continue"): O,
    ("POST", "/machine/unlock"): O,
    ("POST", "/machine/home"): O,
    ("POST", "/machine/pen"): O,
    ("POST", "/machine/jog"): O,
    ("POST", "/machine/motors"): O,
    ("POST", "/machine/command"): A,
    ("GET", "/machine/settings"): O,
    ("PUT", "/machine/settings"): A,
    ("GET", "/sim/trace"): V,
}

Need = Role | None
Rule = tuple[Need, bool]  # (least role, or PUBLIC; a submitter only on their own job)
BY_ACTION: Rule = (A, False)  # a marker: the rule of the path's {action} in JOB_ACTIONS

ROUTES: dict[tuple[str, str], Rule] = {
    # session, server, the API docs
    ("GET", "/docs"): (PUBLIC, False),
    ("GET", "/docs/oauth2-redirect"): (PUBLIC, False),
    ("GET", "/redoc"): (PUBLIC, False),
    ("GET", "/openapi.json"): (PUBLIC, False),
    ("GET", "/api/health"): (PUBLIC, False),
    ("GET", "/api/session"): (PUBLIC, False),  # whether this browser is logged in
    ("GET", "/api/identity"): (PUBLIC, False),
    ("POST", "/api/login"): (PUBLIC, False),
    ("GET", "/login"): (PUBLIC, False),
    ("POST", "/api/logout"): (PUBLIC, False),
    ("POST", "/api/logout/everywhere"): (V, False),
    ("GET", "/api/me"): (V, False),
    ("GET", "/api/server"): (V, False),
    # plotters
    ("GET", "/api/plotters"): (V, False),
    ("POST", "/api/estop"): (V, False),
    **{(m, "/api" + p): (r, False) for (m, p), r in _MACHINE.items()},
    **{(m, "/api/plotters/{name}" + p): (r, False) for (m, p), r in _MACHINE.items()},
    # the MQTT fleet (mqtt/api.py): its stops are STOP, everyone's
    ("GET", "/api/fleet"): (V, False),
    ("POST", "/api/fleet/stop"): (V, False),
    ("POST", "/api/fleet/estop"): (V, False),
    # jobs
    ("GET", "/api/jobs"): (V, False),
    ("POST", "/api/jobs"): (S, False),
    ("GET", "/api/jobs/{job_id}"): (V, True),
    ("PATCH", "/api/jobs/{job_id}"): (S, True),
    ("DELETE", "/api/jobs/{job_id}"): (A, False),
    ("GET", "/api/jobs/{job_id}/preview"): (V, True),
    ("POST", "/api/jobs/{job_id}/{action}"): BY_ACTION,  # the action's rule: JOB_ACTIONS
    ("POST", "/api/jobs/{job_id}/pause"): (O, False),
    ("POST", "/api/jobs/{job_id}/resume"): (O, False),
    ("POST", "/api/jobs/{job_id}/move"): (O, False),
    ("GET", "/api/patterns"): (V, False),
    # pens
    ("GET", "/api/pens"): (V, False),
    ("POST", "/api/pens"): (O, False),
    ("GET", "/api/pens/{pen}"): (V, False),
    ("PATCH", "/api/pens/{pen}"): (O, False),
    ("DELETE", "/api/pens/{pen}"): (O, False),
    ("POST", "/api/pens/{pen}/reset"): (O, False),
    ("POST", "/api/pens/{pen}/try"): (O, False),
    # settings, people, keys, audit
    ("GET", "/api/settings/webhooks"): (A, False),
    ("PUT", "/api/settings/webhooks"): (A, False),
    ("GET", "/api/settings/approval"): (V, False),
    ("PUT", "/api/settings/approval"): (A, False),
    ("GET", "/api/people"): (A, False),
    ("POST", "/api/people"): (A, False),
    ("DELETE", "/api/people/{name}"): (A, False),
    ("POST", "/api/people/{name}/reset"): (A, False),
    ("GET", "/api/keys"): (A, False),
    ("POST", "/api/keys"): (A, False),
    ("DELETE", "/api/keys/{name}"): (A, False),
    ("GET", "/api/audit"): (A, False),
    ("GET", "/api/audit/export"): (A, False),
    # events
    ("WS", "/api/ws"): (V, False),
}  # fmt: skip

PUBLIC_PATHS = frozenset(path for (_, path), (need, _) in ROUTES.items() if need is PUBLIC)
"""The paths that need no credential (the guard lets them through, the API docs say so)."""

WS_MESSAGES: dict[str, Role] = {
    "estop": V,  # handled first, before any other check
    "pause": O,
    "resume": O,
    "jog": O,
    "command": A,
    "job_action": V,  # the action's own role below decides
}

JOB_ACTIONS: dict[str, Rule] = {
    # what a job's `actions` may list for a role; `stop` is STOP: everyone's
    "stop": (V, False),
    "cancel": (S, True),
    "delete": (A, False),
    "edit": (S, True),
    "start": (O, False),
    "hold": (O, False),
    "continue": (O, False),
    "resume": (O, False),
    "home_then_resume": (O, False),
    "resume_from": (O, False),
    "restart": (O, False),
    "frame": (O, False),
    "move": (O, False),
    "approve": (O, False),
    "decline": (O, False),
}  # fmt: skip

def rule(method: str, template: str, action: str | None = None) -> Rule:
    """The rule of a matched route (`action`: its {action} path part); an unlisted route
    or action needs admin (and fails the tests)."""
    found = ROUTES.get((method, template), (A, False))
    if found is BY_ACTION:
        return JOB_ACTIONS.get(action or "", (A, False))
    return found


def may(role: Role, need: Need, own: bool, owner_rule: bool) -> bool:
    """May `role` use something needing `need`? `owner_rule`: a submitter only on what
    they own (`own`)."""
    if need is None:
        return True
    if role < need:
        return False
    return not (owner_rule and role == Role.submitter and not own)


def may_act(role: Role, action: str, own: bool) -> bool:
    need, owner_rule = JOB_ACTIONS.get(action, (A, False))
    return may(role, need, own, owner_rule)
