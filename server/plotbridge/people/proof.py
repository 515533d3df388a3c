"""The server's proof that it holds a key: what a client checks before it sends the key to
a server (zeroconf only proposes servers; an impostor announcing `_plotbridge._tcp` holds
no key's digest, so it cannot answer)."""

from __future__ import annotations

import hashlib
import hmac

KEY_PREFIX = "pbk"
TOKEN_ID = "token"  # the id a client asks about for the data directory's token


def key_id(key: str) -> str:
    """The public id inside an API key (`pbk_ID_SECRET`); "token" for the token."""
    parts = key.split("_", 2)
    return parts[1] if len(parts) == 3 and parts[0] == KEY_PREFIX else TOKEN_ID


def digest(secret: str) -> str:
    return hashlib.sha256(secret.encode()).hexdigest()


def server_proof(key_digest: str, nonce: str, server_id: str) -> str:
    """An HMAC of the nonce and the server's id, keyed by the key's SHA-256 digest."""
    return hmac.new(bytes.fromhex(key_digest), f"{nonce}:{server_id}".encode(),
                    hashlib.sha256).hexdigest()  # fmt: skip
