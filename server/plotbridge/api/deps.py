"""What every router needs: the components, the authentication guard, error answers."""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Annotated, Any

from fastapi import Depends, HTTPException, Request
from fastapi.responses import JSONResponse

from plotbridge.auth import COOKIE, Auth
from plotbridge.config import Config
from plotbridge.events import EventHub
from plotbridge.jobs.actions import JobActions
from plotbridge.notify import Webhooks
from plotbridge.pens import PenLibrary
from plotbridge.queue import JobQueue
from plotbridge.ws import Hub


@dataclass
class Components:
    config: Config
    auth: Auth
    events: EventHub
    queue: JobQueue
    actions: JobActions  # the job verbs (jobs/actions.py)
    clients: Hub  # the WebSocket fan-out
    pens: PenLibrary
    webhooks: Webhooks


def components(request: Request) -> Components:
    return request.app.state.components


async def authenticated(request: Request) -> None:  # async: no thread-pool hop
    auth = components(request).auth
    if auth.check_header(request.headers.get("authorization")):
        return
    if auth.check_session(request.cookies.get(COOKIE)):
        return
    raise HTTPException(
        401, "missing or wrong token: send 'Authorization: Bearer TOKEN' or log in",
        headers={"WWW-Authenticate": "Bearer"},
    )  # fmt: skip


GUARD = [Depends(authenticated)]

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
