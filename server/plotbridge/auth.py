"""Token rules, the token file, and real login sessions.

A session is a random id handed out at each login, valid for SESSION_TTL,
ended by logout, and ended for everyone when the token changes
(`plotbridge token --rotate` rewrites the token file; the server notices within
a second). Sessions outlive a server restart: their ids' SHA-256 digests and
expiry times are kept in the data directory (0600), never the ids themselves.
"""

from __future__ import annotations

import hashlib
import hmac
import json
import logging
import os
import secrets
import time
from pathlib import Path

log = logging.getLogger("plotbridge.auth")

COOKIE = "plotbridge_session"
MIN_TOKEN_LENGTH = 16
SESSION_TTL = 30 * 24 * 3600.0  # s
MAX_SESSIONS = 1000  # the oldest goes when a login would add one more
RELOAD_INTERVAL = 1.0  # s between looks at the token file


class TokenRefused(ValueError):
    pass


def check_token_rules(token: str) -> str:
    token = token.strip()
    if len(token) < MIN_TOKEN_LENGTH:
        raise TokenRefused(
            f"the token must be at least {MIN_TOKEN_LENGTH} characters (got {len(token)})"
        )
    return token


def write_private(path: Path, text: str) -> None:
    """Write `text` to a file only its owner can read (0600 from the first byte)."""
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w") as handle:
        handle.write(text)
    os.chmod(path, 0o600)


def read_token_file(path: Path) -> str:
    return check_token_rules(path.read_text())


def load_or_create_token(path: Path) -> tuple[str, bool]:
    """The token kept in `path`, generated on first start; (token, newly made)."""
    if path.exists() and path.read_text().strip():
        return read_token_file(path), False
    token = new_token()
    write_private(path, token + "\n")
    return token, True


def new_token() -> str:
    return secrets.token_urlsafe(24)


class Auth:
    def __init__(self, token: str, token_file: Path | None = None,
                 sessions_file: Path | None = None) -> None:  # fmt: skip
        self.token = check_token_rules(token)
        self.token_file = token_file
        self._file_stamp = self._stamp()
        self._next_look = 0.0
        self.sessions_file = sessions_file
        self.sessions: dict[str, float] = self._load_sessions()  # id digest -> expiry (wall)

    # ---- token ---------------------------------------------------------------

    def _stamp(self) -> tuple[int, int] | None:
        if self.token_file is None:
            return None
        try:
            stat = self.token_file.stat()
        except OSError:
            return None
        return stat.st_mtime_ns, stat.st_size

    def _reload(self) -> None:
        """A rotated token file: take the new token, end every session."""
        now = time.monotonic()
        if self.token_file is None or now < self._next_look:
            return
        self._next_look = now + RELOAD_INTERVAL
        stamp = self._stamp()
        if stamp == self._file_stamp or stamp is None:
            return
        try:
            token = read_token_file(self.token_file)
        except (OSError, TokenRefused):
            return  # half-written or unusable: keep the old token, look again later
        self._file_stamp = stamp
        if token != self.token:
            self.token = token
            self.sessions.clear()
            self._save_sessions()

    def check_token(self, candidate: str | None) -> bool:
        self._reload()
        return candidate is not None and hmac.compare_digest(
            candidate.encode(), self.token.encode()
        )

    def check_header(self, authorization: str | None) -> bool:
        if not authorization:
            return False
        scheme, _, value = authorization.partition(" ")
        return scheme.lower() == "bearer" and self.check_token(value.strip())

    # ---- sessions ------------------------------------------------------------

    def _load_sessions(self) -> dict[str, float]:
        if self.sessions_file is None:
            return {}
        try:
            kept = json.loads(self.sessions_file.read_text())
        except (OSError, ValueError):
            return {}  # none yet, or unreadable: everyone logs in again
        now = time.time()
        if not isinstance(kept, dict):
            return {}
        return {k: float(v) for k, v in kept.items()
                if isinstance(k, str) and isinstance(v, (int, float)) and v > now}  # fmt: skip

    def _save_sessions(self) -> None:
        if self.sessions_file is None:
            return
        try:  # a few hundred bytes, only at login and logout
            write_private(self.sessions_file, json.dumps(self.sessions))
        except OSError as exc:  # sessions still work; they end with the server
            log.warning("sessions not kept across restarts: %s", exc)

    @staticmethod
    def _digest(session: str) -> str:
        return hashlib.sha256(session.encode()).hexdigest()

    def new_session(self) -> str:
        now = time.time()
        self.sessions = {k: v for k, v in self.sessions.items() if v > now}
        while len(self.sessions) >= MAX_SESSIONS:
            del self.sessions[next(iter(self.sessions))]
        session = secrets.token_urlsafe(32)
        self.sessions[self._digest(session)] = now + SESSION_TTL
        self._save_sessions()
        return session

    def check_session(self, candidate: str | None) -> bool:
        self._reload()
        if not candidate:
            return False
        key = self._digest(candidate)
        expiry = self.sessions.get(key)
        if expiry is None:
            return False
        if expiry <= time.time():
            del self.sessions[key]
            return False
        return True

    def end_session(self, candidate: str | None) -> None:
        if candidate and self.sessions.pop(self._digest(candidate), None) is not None:
            self._save_sessions()
