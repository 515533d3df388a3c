"""Session routes: health, login and logout, server facts."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, HTTPException, Request
from fastapi.responses import RedirectResponse, Response

from plotbridge import __version__
from plotbridge.api.deps import GUARD, Parts
from plotbridge.auth import COOKIE, SESSION_TTL
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
    """Whether this browser's session cookie is valid (no authentication: the page asks
    before it shows the login form or the app)."""
    return {"logged_in": c.auth.check_session(request.cookies.get(COOKIE))}


@router.post("/api/login", status_code=204)
async def login(body: LoginBody, c: Parts) -> Response:
    if not c.auth.check_token(body.token):
        raise HTTPException(401, "wrong token")
    response = Response(status_code=204)
    _set_cookie(response, c.auth.new_session())
    return response


@router.get("/login", include_in_schema=False)  # a browser link, answered with a redirect
async def login_link(c: Parts, token: str = "") -> Response:
    if not c.auth.check_token(token):  # a stale link: the login page says so
        return RedirectResponse("/?link=stale", status_code=303)
    response = RedirectResponse("/", status_code=303)
    _set_cookie(response, c.auth.new_session())
    return response


@router.post("/api/logout", status_code=204)
async def logout(request: Request, c: Parts) -> Response:
    c.auth.end_session(request.cookies.get(COOKIE))
    response = Response(status_code=204)
    response.delete_cookie(COOKIE, path="/")
    return response


@router.get("/api/server", dependencies=GUARD)
async def server_info(c: Parts) -> dict[str, Any]:
    config = c.config
    return {
        "version": __version__,
        "virtual": config.virtual,
        "serial": config.serial,
        "data_dir": str(config.data_dir),
        "upload_limit": config.upload_limit,
        "auto_start": config.auto_start,
        "plotters": list(c.queue.plotters),
    }
