"""The stop lane: an emergency stop acted on in the callback that read its request.

The connection protocol (`connections.GuardedH11`) hands the lane each request's
head (request line and headers) as soon as it is complete, before h11, the
ASGI task, the middleware, FastAPI's dependencies or any worker thread see it.
A stop route (`POST /api/estop`, `/api/machine/estop`,
`/api/plotters/NAME/machine/estop`) that passes the guard's own checks (Host;
who is asking, from people.Access's memory, with a role the table in access.py lets
stop, which is every role; Origin) is acted on there and audited: the reset bytes
are written and the answer goes out in the same loop callback, then the connection
closes. Anything
else goes on to the app as before. A connection over the connection caps may
send only this (docs/INTERNALS.md, "The stop lane").
"""

from __future__ import annotations

import json
import logging
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any
from urllib.parse import unquote

from plotbridge.access import may, rule
from plotbridge.errors import Refused
from plotbridge.guard.headers import security_headers

log = logging.getLogger("plotbridge.guard")

HEAD_MAX = 16 * 1024  # bytes of a request's head; h11 is given the same bound
BODY_MAX = 1024  # a stop's body is not read: a larger declared one goes the usual way
PAGE_HEADER = b"x-plotbridge-page"
_PAGE_ID = re.compile(r"[A-Za-z0-9_-]{1,64}")
_ROUTE = re.compile(r"/api/(?:(estop)|machine/estop|plotters/([A-Za-z0-9_-]{1,64})/machine/estop)")
ESTOP = "/api/estop"  # the role table's rows of the three routes
MACHINE_ESTOP = "/api/machine/estop"
PLOTTER_ESTOP = "/api/plotters/{name}/machine/estop"

# (plotter or None for the first, every plotter, source, page id) -> the answer's body
StopVerb = Callable[[str | None, bool, str, str | None], dict[str, Any]]


NEED_MORE = b""  # answer(): the stop's small body has not all arrived yet


@dataclass(frozen=True)
class Head:
    method: str
    path: str
    headers: dict[bytes, bytes]
    size: int  # bytes of the head, its blank line included


def parse_head(data: bytes) -> Head | None:
    """The request line and headers of `data` (which holds the whole head), or None
    when they are not a plain HTTP/1.1 request head."""
    head, _, _ = data.partition(b"\r\n\r\n")
    size = len(head) + 4
    lines = head.split(b"\r\n")
    parts = lines[0].split(b" ")
    if len(parts) != 3 or not parts[2].startswith(b"HTTP/1."):
        return None
    headers: dict[bytes, bytes] = {}
    for line in lines[1:]:
        name, colon, value = line.partition(b":")
        if not colon or not name or name != name.strip():
            return None
        name = name.lower()
        if name in headers:  # a repeated header: leave it to h11 and the app
            return None
        headers[name] = value.strip()
    try:
        return Head(parts[0].decode("ascii"), unquote(parts[1].decode("ascii")), headers, size)
    except UnicodeDecodeError:
        return None


def response(status: int, body: dict[str, Any]) -> bytes:
    text = json.dumps(body).encode()
    reason = {202: "Accepted", 404: "Not Found"}.get(status, "Error")
    lines = [f"HTTP/1.1 {status} {reason}", "content-type: application/json",
             f"content-length: {len(text)}", "connection: close"]  # fmt: skip
    lines += [f"{name.decode()}: {value.decode()}" for name, value in security_headers("")]
    return ("\r\n".join(lines) + "\r\n\r\n").encode() + text


class StopLane:
    def __init__(self) -> None:
        self.checks: Any = None  # middleware.Checks, bound by the app
        self.stop: StopVerb | None = None

    def bind(self, checks: Any, stop: StopVerb) -> None:
        self.checks, self.stop = checks, stop

    def answer(self, data: bytes) -> bytes | None:
        """The whole answer to a request head that is an allowed stop, sent after the
        stop is done; None for any other request (it goes on to the app); NEED_MORE
        while the stop's declared body is still arriving (it is read, never parsed:
        closing a socket with unread bytes would reset it, losing the answer)."""
        if self.stop is None or not data.startswith(b"POST "):
            return None
        head = parse_head(data)
        if head is None or head.method != "POST":
            return None
        route = _ROUTE.fullmatch(head.path.partition("?")[0])
        if route is None:
            return None
        template = ESTOP if route[1] else PLOTTER_ESTOP if route[2] else MACHINE_ESTOP
        identity = self._allowed(head.headers, template)
        if identity is None:
            return None
        if len(data) < head.size + int(head.headers.get(b"content-length", b"0")):
            return NEED_MORE
        page = head.headers.get(PAGE_HEADER, b"").decode("latin-1")
        origin = page if _PAGE_ID.fullmatch(page) else None
        try:
            body = self.stop(route[2], route[1] is not None, "REST", origin)
        except Refused as exc:  # no plotter of that name
            status, body = exc.status, {"detail": exc.detail}
        else:
            status = 202
        detail = {"page": origin, "refused": status if status >= 400 else None}
        self.checks.access.audit(identity, f"POST {template}", route[2],
                                 {k: v for k, v in detail.items() if v is not None})  # fmt: skip
        return response(status, body)

    def _allowed(self, headers: dict[bytes, bytes], template: str) -> Any:
        """Who is stopping (an `Identity`), when the guard's answer would be the route's:
        Host, an identity the role table lets stop, Origin, no body to read (none, or a
        small one declared by its length); else None (the request goes on to the app)."""
        if b"transfer-encoding" in headers:
            return None
        length = headers.get(b"content-length", b"0")
        if not length.isdigit() or int(length) > BODY_MAX:
            return None
        checks = self.checks
        if not checks.host_ok(headers):
            return None
        identity = checks.known(headers)
        need, owner_rule = rule("POST", template)
        if identity is None or not may(identity.role, need, False, owner_rule):
            return None
        return None if checks.cross_site("POST", headers, identity.via) else identity


LANE = StopLane()
