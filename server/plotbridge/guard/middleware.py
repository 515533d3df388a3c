"""The guard middleware (pure ASGI, so nothing is buffered or parsed on its way).

Order for an HTTP request, each step before the app reads the body:
Host allow-list -> declared body size -> authentication (routes other than health
and login; a wrong credential's answer is held: people/failures.py) -> CSRF
(cookie-authenticated changes); then the body
is counted while the app reads it (413 past the route's bound, 408 if it stalls)
and every response gets the security headers.
"""

from __future__ import annotations

import asyncio
import json
import logging
from collections.abc import Awaitable, Callable, MutableMapping
from typing import Any
from urllib.parse import parse_qs

from starlette.requests import ClientDisconnect

from plotbridge.access import PUBLIC_PATHS
from plotbridge.guard.headers import security_headers
from plotbridge.guard.hosts import host_allowed, origin_allowed, own_names
from plotbridge.guard.limits import body_limit
from plotbridge.guard.logs import escape

log = logging.getLogger("plotbridge.guard")

Scope = MutableMapping[str, Any]
Message = MutableMapping[str, Any]
Receive = Callable[[], Awaitable[Message]]
Send = Callable[[Message], Awaitable[None]]
ASGIApp = Callable[[Scope, Receive, Send], Awaitable[None]]

BODY_IDLE_TIMEOUT = 10.0  # s without a byte of a body that has not all arrived: 408
CSRF_HEADER = b"x-plotbridge"  # the page adds it; a form or no-cors fetch cannot
UNSAFE = ("POST", "PUT", "PATCH", "DELETE")
WS_PER_CLIENT = 8  # open WebSockets per client address (the page needs one)
COOKIE = "plotbridge_session"


def _headers(scope: Scope) -> dict[bytes, bytes]:
    return {k.lower(): v for k, v in scope.get("headers", ())}


def _cookie(headers: dict[bytes, bytes], name: str) -> str | None:
    for part in headers.get(b"cookie", b"").decode("latin-1").split(";"):
        key, _, value = part.strip().partition("=")
        if key == name:
            return value
    return None


def client_address(scope: Scope) -> str:
    client = scope.get("client")
    return str(client[0]) if client else "?"


async def _answer(send: Send, status: int, detail: str, extra: list | None = None) -> None:
    body = json.dumps({"detail": detail}).encode()
    headers = [
        (b"content-type", b"application/json"),
        (b"content-length", str(len(body)).encode()),
        (b"connection", b"close"),
        *security_headers(""),
        *(extra or []),
    ]
    await send({"type": "http.response.start", "status": status, "headers": headers})
    await send({"type": "http.response.body", "body": body})


def _credentials(headers: dict[bytes, bytes], query_token: str | None) -> dict[str, str | None]:
    scheme, _, value = headers.get(b"authorization", b"").decode("latin-1").partition(" ")
    return {"bearer": value.strip() if scheme.lower() == "bearer" else None,
            "cookie": _cookie(headers, COOKIE), "query": query_token}  # fmt: skip


class Checks:
    """The questions asked of every request's headers: the guard's, and the stop
    lane's (guard/stoplane.py), which asks them before the app sees the request.
    Who is asking is people/access.py's answer (`access`: its `Access`)."""

    def __init__(self, access: Any, allowed_hosts: tuple[str, ...] = ()) -> None:
        self.access = access
        self.names = own_names(allowed_hosts)

    def host_ok(self, headers: dict[bytes, bytes]) -> bool:
        return host_allowed(headers.get(b"host", b"").decode("latin-1"), self.names)

    async def identify(self, scope: Scope, headers: dict[bytes, bytes],
                       query_token: str | None) -> Any:  # fmt: skip
        """Who is asking (an `Identity`), kept in the scope for the app; None if nobody.
        A wrong credential counts as a failure and its answer is held (people/failures.py)."""
        identity = await self.access.identify(
            **_credentials(headers, query_token), address=client_address(scope))
        scope.setdefault("state", {})["identity"] = identity
        return identity

    def known(self, headers: dict[bytes, bytes]) -> Any:
        """Who is asking, from what the server holds in memory: no wait, no disk, no
        failure counted (a wrong credential goes on to the guard, which counts it)."""
        return self.access.lookup(**_credentials(headers, None))

    def own_origin(self, headers: dict[bytes, bytes]) -> bool | None:
        """True/False: the Origin is/is not this server's; None: no Origin sent."""
        origin = headers.get(b"origin")
        if origin is None:
            return None
        return origin_allowed(origin.decode("latin-1"), headers.get(b"host", b"").decode("latin-1"))

    def cross_site(self, method: str, headers: dict[bytes, bytes], via: str | None) -> bool:
        """A change not authenticated by a bearer token that another site's page may
        have sent: a foreign Origin, or a cookie without Origin nor our page's header."""
        if method not in UNSAFE or via == "bearer":
            return False
        origin = self.own_origin(headers)
        unmarked = origin is None and CSRF_HEADER not in headers
        return origin is False or (via == "cookie" and unmarked)


class Guard:
    def __init__(self, app: ASGIApp, *, checks: Checks, upload_limit: int) -> None:
        self.app = app
        self.checks = checks
        self.upload_limit = upload_limit
        self.websockets: dict[str, int] = {}

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] == "http":
            await self._http(scope, receive, send)
        elif scope["type"] == "websocket":
            await self._websocket(scope, receive, send)
        else:
            await self.app(scope, receive, send)

    # ---- HTTP ------------------------------------------------------------------

    async def _http(self, scope: Scope, receive: Receive, send: Send) -> None:
        headers = _headers(scope)
        method, path = scope["method"], scope["path"]
        client = client_address(scope)
        if not self.checks.host_ok(headers):
            return await _answer(send, 400, "the Host header names no address of this server")
        limit = body_limit(method, path, self.upload_limit)
        length = headers.get(b"content-length", b"")
        if length and (not length.isdigit() or int(length) > limit):
            return await _answer(send, 413, f"request body larger than {limit} bytes")
        api = path.startswith("/api/")
        identity = await self.checks.identify(scope, headers, None)
        via = identity.via if identity is not None else None
        if api and path not in PUBLIC_PATHS and via is None:
            return await _answer(
                send, 401, "missing or wrong token: send 'Authorization: Bearer TOKEN' or log in",
                [(b"www-authenticate", b"Bearer")],
            )  # fmt: skip
        if self.checks.cross_site(method, headers, via):
            log.warning("refused cross-site %s %s from %s", method, escape(path), client)
            return await _answer(send, 403, "cross-site request refused (Origin)")
        await self._run(scope, receive, send, limit, path, client)

    async def _run(
        self, scope: Scope, receive: Receive, send: Send,
        limit: int, path: str, client: str,
    ) -> None:  # fmt: skip
        received = 0
        started = False
        refused = False  # the guard answered: the app is told the client left
        extra = security_headers(path)

        async def counted_receive() -> Message:
            nonlocal received, refused
            if refused:
                return {"type": "http.disconnect"}
            try:
                message = await asyncio.wait_for(receive(), BODY_IDLE_TIMEOUT)
            except TimeoutError:
                message = None
            if message is not None and message["type"] == "http.request":
                received += len(message.get("body", b""))
                if received <= limit:
                    return message
            elif message is not None:
                return message
            if not started:  # answer now; the app sees a disconnect and gives up
                refused = True
                if message is None:
                    await _answer(send, 408, "the request body stopped arriving")
                else:
                    await _answer(send, 413, f"request body larger than {limit} bytes")
            return {"type": "http.disconnect"}

        async def guarded_send(message: Message) -> None:
            nonlocal started
            if refused:
                return
            if message["type"] == "http.response.start":
                started = True
                own = message.get("headers", ())
                named = {name.lower() for name, _ in own}  # a page's own policy wins
                message = {**message, "headers": [*own, *(h for h in extra if h[0] not in named)]}
            await send(message)

        try:
            await self.app(scope, counted_receive, guarded_send)
        except ClientDisconnect:
            if not refused:
                log.info("client %s went away during %s", client, escape(path))

    # ---- WebSocket ---------------------------------------------------------------

    async def _websocket(self, scope: Scope, receive: Receive, send: Send) -> None:
        """Refusals are sent as close codes after accepting (a browser sees no code
        for an HTTP refusal): 4401 not logged in, 4403 foreign origin, 1013 too many."""
        headers = _headers(scope)
        client = client_address(scope)
        if not self.checks.host_ok(headers):
            return await self._ws_refuse(receive, send, 4403, "host not allowed")
        query = parse_qs(scope.get("query_string", b"").decode("latin-1"))
        token = query.get("token", [None])[0]
        if await self.checks.identify(scope, headers, token) is None:
            return await self._ws_refuse(receive, send, 4401, "missing or wrong token")
        if self.checks.own_origin(headers) is False:
            return await self._ws_refuse(receive, send, 4403, "origin not allowed")
        if self.websockets.get(client, 0) >= WS_PER_CLIENT:
            log.warning("refused a WebSocket from %s: %d open", client, WS_PER_CLIENT)
            return await self._ws_refuse(receive, send, 1013, "too many connections")
        self.websockets[client] = self.websockets.get(client, 0) + 1
        try:
            await self.app(scope, receive, send)
        finally:
            self.websockets[client] -= 1
            if not self.websockets[client]:
                del self.websockets[client]

    async def _ws_refuse(self, receive: Receive, send: Send, code: int, reason: str) -> None:
        message = await receive()
        if message["type"] != "websocket.connect":
            return
        await send({"type": "websocket.accept"})
        await send({"type": "websocket.close", "code": code, "reason": reason})
