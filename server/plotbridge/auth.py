"""Token rules and the token file. The token is the first admin's credential; checking
it, sessions and everyone else's credentials are `plotbridge.people` (a rotated token
file ends the token's sessions: the server notices within a second)."""

from __future__ import annotations

import os
import secrets
from pathlib import Path

COOKIE = "plotbridge_session"
MIN_TOKEN_LENGTH = 16
SESSION_TTL = 30 * 24 * 3600.0  # s


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
