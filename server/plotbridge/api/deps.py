"""What every router needs: the components, the access check, error answers."""

from __future__ import annotations

import re
from collections.abc import AsyncIterator
from dataclasses import dataclass
from typing import Annotated, Any

from fastapi import Depends, HTTPException, Request, WebSocketException
from fastapi.responses import JSONResponse
from starlette.requests import HTTPConnection

from plotbridge.access import Role, may, rule
from plotbridge.config import Config
from plotbridge.events import EventHub
from plotbridge.jobs.actions import JobActions
from plotbridge.notify import Webhooks
from plotbridge.pens import PenLibrary
from plotbridge.people import Access, Identity
from plotbridge.people.actor import ACTOR
from plotbridge.queue import JobQueue
from plotbridge.ws import Hub


@dataclass
class Components:
    config: Config
    access: Access  # who is asking, people, keys, sessions, the audit log
    events: EventHub
    queue: JobQueue
    actions: JobActions  # the job verbs (jobs/actions.py)
    clients: Hub  # the WebSocket fan-out
    pens: PenLibrary
    webhooks: Webhooks


def components(request: Request) -> Components:
    return request.app.state.components


def components_of(conn: HTTPConnection) -> Components:
    return conn.app.state.components


async def authorize(conn: HTTPConnection) -> AsyncIterator[Identity | None]:
    """The one access check of every route and the WebSocket: the matched route's rule in
    `plotbridge.access.ROUTES` against who is asking (the guard identified them). Every
    change (POST, PUT, PATCH, DELETE) by a logged-in caller is audited with its outcome; a
    route may add to the entry in `request.state.audit` (a dict)."""
    websocket = conn.scope["type"] == "websocket"
    method = "WS" if websocket else conn.scope["method"].replace("HEAD", "GET")
    template = getattr(conn.scope.get("route"), "path", conn.scope["path"])
    need, owner_rule = rule(method, template, conn.path_params.get("action"))
    identity: Identity | None = conn.scope.get("state", {}).get("identity")
    if need is None:
        yield identity
        return
    if identity is None:
        if websocket:
            raise WebSocketException(4401, "missing or wrong token")
        raise HTTPException(
            401, "missing or wrong token: send 'Authorization: Bearer TOKEN' or log in",
            headers={"WWW-Authenticate": "Bearer"},
        )  # fmt: skip
    own = False
    if owner_rule and identity.role == Role.submitter:
        job = components_of(conn).queue.get(conn.path_params.get("job_id", ""))
        own = job.owner == identity.who
    if not may(identity.role, need, own, owner_rule):
        whose = " on their own jobs" if owner_rule and identity.role >= need else ""
        raise HTTPException(403, f"{identity.who} is a {identity.role.name}: {method} "
                                 f"{template} needs {need.name}{whose}")  # fmt: skip
    ACTOR.set(identity.who)
    if method in ("GET", "WS"):
        yield identity
        return
    access = components_of(conn).access
    detail: dict[str, Any] = {"page": page_id(conn.headers.get(PAGE_HEADER))}
    params = dict(conn.path_params)
    action = params.pop("action", None)  # the job action route: named by its action
    what = f"{method} {template.replace('{action}', str(action))}"
    target = "/".join(str(v) for v in params.values()) or None
    try:
        yield identity
    except Exception as exc:
        detail["refused"] = getattr(exc, "status", getattr(exc, "status_code", 500))
        raise
    finally:
        detail.update(getattr(conn.state, "audit", None) or {})
        access.audit(identity, what, target,
                     {k: v for k, v in detail.items() if v is not None})


GUARD = [Depends(authorize)]  # also app-wide (app.py); FastAPI runs it once per request

PAGE_HEADER = "X-Plotbridge-Page"  # the stopping page's id (REST); the WebSocket's "page"
_PAGE_ID = re.compile(r"[A-Za-z0-9_-]{1,64}")


def page_id(value: object) -> str | None:
    """A page's self-chosen random id as given, or None when absent or malformed: it
    is echoed to every client, so nothing else (no session, no token) goes out."""
    return value if isinstance(value, str) and _PAGE_ID.fullmatch(value) else None


def error(status: int, detail: Any) -> JSONResponse:
    return JSONResponse({"detail": detail}, status_code=status)


def upload_error(status: int, message: str) -> JSONResponse:
    return error(status, {"errors": [{"line": None, "message": message}]})


Parts = Annotated[Components, Depends(components)]
"""A route's parameter for the components."""
Who = Annotated[Identity | None, Depends(authorize)]
"""A route's parameter for who is asking (None only on public routes)."""
