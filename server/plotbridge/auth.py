"""Bearer token and session cookie."""

from __future__ import annotations

import hashlib
import hmac
import secrets
from pathlib import Path

COOKIE = "plotbridge_session"


def load_or_create_token(data_dir: Path) -> str:
    """The token kept in `<data_dir>/token`, generated (mode 0600) on first start."""
    path = data_dir / "token"
    if path.exists():
        token = path.read_text().strip()
        if token:
            return token
    token = secrets.token_urlsafe(24)
    path.touch(mode=0o600)
    path.write_text(token + "\n")
    return token


class Auth:
    def __init__(self, token: str) -> None:
        self.token = token
        # The cookie value is derived from the token: it survives restarts and dies with it.
        self.session = hmac.new(token.encode(), b"plotbridge-session", hashlib.sha256).hexdigest()

    def check_token(self, candidate: str | None) -> bool:
        return candidate is not None and hmac.compare_digest(
            candidate.encode(), self.token.encode()
        )

    def check_session(self, candidate: str | None) -> bool:
        return candidate is not None and hmac.compare_digest(
            candidate.encode(), self.session.encode()
        )

    def check_header(self, authorization: str | None) -> bool:
        if not authorization:
            return False
        scheme, _, value = authorization.partition(" ")
        return scheme.lower() == "bearer" and self.check_token(value.strip())


def origin_allowed(origin: str | None, host: str | None) -> bool:
    """WebSocket Origin check: absent (scripts) or the same host:port as the request."""
    if origin is None:
        return True
    if not host:
        return False
    _, sep, rest = origin.partition("://")
    return bool(sep) and rest.rstrip("/").lower() == host.lower()
