"""Session routes: health, the server's identity, login and logout, who am I, server facts."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, HTTPException, Query, Request
from fastapi.responses import RedirectResponse, Response

from plotbridge import __version__
from plotbridge.api.deps import Parts, Who
from plotbridge.auth import COOKIE, SESSION_TTL
from plotbridge.guard.middleware import client_address
from plotbridge.models import LoginBody

router = APIRouter()


def _set_cookie(response: Response, session: str) -> None:
    response.set_cookie(COOKIE, session, httponly=True, samesite="strict", path="/",
                        max_age=int(SESSION_TTL))  # fmt: skip


@router.get("/api/health")
async def health() -> dict[str, str]:
    return {"status": "ok"}


@router.get("/api/session")
async def session(request: Request, c: Parts) -> dict[str, bool]:
    """Whether this browser's session cookie is valid (no credential needed: the page asks
    before it shows the login form or the app; `GET /api/me` then says who and their role)."""
    cookie = request.cookies.get(COOKIE)
    return {"logged_in": bool(cookie) and c.access.by_session(cookie) is not None}


@router.get("/api/identity")
async def identity(
    c: Parts,
    key: Annotated[str, Query(max_length=64, description="the key's id, or 'token'")],
    nonce: Annotated[str, Query(min_length=16, max_length=128)],
) -> dict[str, Any]:
    """Proof that this server made key `key`, checked by a client before it sends the key
    (an HMAC of the nonce keyed by what only the real server holds)."""
    return {"server": c.access.server_id, "proof": c.access.proof(key, nonce)}


@router.post("/api/login", status_code=204)
async def login(body: LoginBody, c: Parts, request: Request) -> Response:
    """With the token (the first admin) or a one-time link's code (a person)."""
    session = None
    if body.token:
        session, who = c.access.login_token(body.token), "token (first admin)"
    elif body.link:
        made = await c.access.login_link(body.link)
        if made is not None:
            session, who = made
    tried = body.token or body.link
    if session is None:
        if tried:
            await c.access.failed(client_address(request.scope), tried)
        raise HTTPException(401, "wrong token, or a login link that is used up or expired")
    c.access.audit(None, "login", who, {"with": "token" if body.token else "link"})
    response = Response(status_code=204)
    _set_cookie(response, session)
    return response


@router.get("/login", include_in_schema=False)  # a browser link, answered with a redirect
async def login_link(c: Parts, request: Request, token: str = "") -> Response:
    """The token's login link as printed before one-time links (/login.html#CODE); a wrong
    one counts as a failed login and lands on the login page, which says why."""
    session = c.access.login_token(token) if token else None
    if session is None:
        if token:
            await c.access.failed(client_address(request.scope), token)
        return RedirectResponse("/?link=stale", status_code=303)
    c.access.audit(None, "login", "token (first admin)", {"with": "token link"})
    response = RedirectResponse("/", status_code=303)
    _set_cookie(response, session)
    return response


@router.post("/api/logout", status_code=204)
async def logout(c: Parts, who: Who) -> Response:
    """Ends this session; its WebSockets close."""
    c.access.end_session(who)
    response = Response(status_code=204)
    response.delete_cookie(COOKIE, path="/")
    return response


@router.post("/api/logout/everywhere", status_code=204)
async def logout_everywhere(c: Parts, who: Who) -> Response:
    """Ends every session of this person (or of the token); their WebSockets close."""
    assert who is not None
    c.access.end_everywhere(who)
    c.access.audit(who, "logout_everywhere")
    response = Response(status_code=204)
    response.delete_cookie(COOKIE, path="/")
    return response


@router.get("/api/me")
async def me(who: Who) -> dict[str, Any]:
    """Who is asking, and their role (the page hides what the role cannot do)."""
    assert who is not None
    return {**who.public(), "who": who.who}


@router.get("/api/server")
async def server_info(c: Parts) -> dict[str, Any]:
    config = c.config
    return {
        "version": __version__,
        "id": c.access.server_id,
        "virtual": config.virtual,
        "serial": config.serial,
        "data_dir": str(config.data_dir),
        "upload_limit": config.upload_limit,
        "auto_start": config.auto_start,
        "plotters": list(c.queue.plotters),
    }
