"""The server's one authority on who is asking: credentials in, an `Identity` out.

Credentials: the data directory's token (the first admin, as before there were people),
API keys (`plotbridge keys add`), and sessions (a login with the token or a one-time
link). What the store holds is mirrored in memory and reloaded when another process
(the command line) writes it, so checking a credential never waits on the disk and a
removed key is refused at once. Open WebSockets are tracked with their identity: a
logout, a token rotation, a removed key or person closes theirs (`revalidate`).
Writes (sessions, the audit log) go to one writer thread.
"""

from __future__ import annotations

import asyncio
import contextlib
import hmac
import logging
import secrets
import threading
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from plotbridge.access import Role
from plotbridge.auth import SESSION_TTL, TokenRefused, read_token_file
from plotbridge.people.failures import Failures
from plotbridge.people.proof import digest, server_proof
from plotbridge.people.store import TOKEN_OWNER, PeopleStore, Snapshot

log = logging.getLogger("plotbridge.people")

WATCH_INTERVAL = 0.25  # s between looks for a change by another process (or the token file)
MAX_SESSIONS = 1000  # the oldest goes when a login would add one more


@dataclass(frozen=True)
class Identity:
    """Who a request is: `kind` token, key or person; `via` bearer, cookie or query."""

    name: str
    kind: str
    role: Role
    via: str
    secret: str  # the digest of the credential shown (session id, key or token)

    @property
    def who(self) -> str:
        return {"token": "token (first admin)", "key": f"key {self.name}",
                "bridge": "MQTT (this bridge's operator)"}.get(self.kind, self.name)  # fmt: skip

    def public(self) -> dict[str, Any]:
        return {"name": self.name, "kind": self.kind, "role": self.role.name}


MQTT = Identity("mqtt", "bridge", Role.operator, "mqtt", "")
"""Who MQTT commands act as (mqtt/verbs.py): this bridge's own operator, asked of the role
table like anyone (it may stop, hold, continue, home and start; not settings nor deletes of
jobs it does not own) and named in the audit log."""


class Access:
    def __init__(self, store: PeopleStore, token: str, token_file: Path | None = None) -> None:
        self.store = store
        self.token = token
        self.token_file = token_file
        self._token_stamp = self._stamp()
        self._mark = store.changed_mark()
        self.known: Snapshot = store.snapshot()
        self.failures = Failures()
        self.server_id = store.server_id()
        self._writer = ThreadPoolExecutor(1, thread_name_prefix="plotbridge-people")
        self._unwritten = 0  # session writes queued on the writer thread
        self._count_lock = threading.Lock()
        self._watched: dict[int, tuple[Identity, Callable[[], None]]] = {}
        self._watcher: asyncio.Task[None] | None = None
        self._next_token_look = 0.0

    # ---- life ------------------------------------------------------------------------------

    def start(self) -> None:
        self._watcher = asyncio.create_task(self._watch())

    async def close(self) -> None:
        if self._watcher is not None:
            self._watcher.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._watcher
        self._writer.shutdown(wait=True)
        self.store.close()

    async def _watch(self) -> None:
        while True:
            await asyncio.sleep(WATCH_INTERVAL)
            try:
                self.refresh()
            except Exception:  # a locked or busy file: look again next time
                log.exception("people: cannot reload")

    def refresh(self) -> None:
        """Take another process's changes and a rotated token; close what they revoked."""
        changed = self._reload_token()
        if self._reload_store() or changed:
            self.revalidate()

    def _reload_store(self) -> bool:
        """Take the store's state when a people write (this process's or another's) came
        since: a stat of the store's stamp, no SQLite. Not while this process's own session
        writes are queued: the store does not hold them yet (a later look will)."""
        if self._unwritten:
            return False
        mark = self.store.changed_mark()
        if mark == self._mark:
            return False
        self._mark = mark
        self.known = self.store.snapshot()
        return True

    def _stamp(self) -> tuple[int, int] | None:
        try:
            stat = self.token_file.stat() if self.token_file else None
        except OSError:
            return None
        return (stat.st_mtime_ns, stat.st_size) if stat else None

    def _reload_token(self) -> bool:
        stamp = self._stamp()
        if stamp is None or stamp == self._token_stamp or self.token_file is None:
            return False
        try:
            token = read_token_file(self.token_file)
        except (OSError, TokenRefused):
            return False  # half-written or unusable: keep the old one, look again
        self._token_stamp = stamp
        if token == self.token:
            return False
        self.token = token
        log.info("the token changed: every session of the token ends")
        self.store.end_sessions(TOKEN_OWNER, "token")
        self._mark = self.store.changed_mark()
        self.known = self.store.snapshot()
        return True

    def _look_at_token(self) -> None:
        now = time.monotonic()
        if now >= self._next_token_look:
            self._next_token_look = now + 1.0
            if self._reload_token():
                self.revalidate()

    # ---- credentials -----------------------------------------------------------------------

    def _current(self) -> None:
        """Reload before answering if another process wrote."""
        if self._reload_store():
            self.revalidate()

    def by_secret(self, secret: str, via: str) -> Identity | None:
        """The identity of a token or API key as sent (Bearer, `?token=`)."""
        self._look_at_token()
        self._current()
        return self._secret(secret, via)

    def _secret(self, secret: str, via: str) -> Identity | None:
        if hmac.compare_digest(secret.encode(), self.token.encode()):
            return Identity("admin", "token", Role.admin, via, digest(secret))
        hashed = digest(secret)
        found = self.known.keys.get(hashed)
        return Identity(found[0], "key", found[1], via, hashed) if found else None

    def by_session(self, session: str) -> Identity | None:
        self._look_at_token()
        self._current()
        return self._session(session)

    def _session(self, session: str) -> Identity | None:
        hashed = digest(session)
        found = self.known.sessions.get(hashed)
        if found is None or found[2] <= time.time():
            return None
        owner, kind, _ = found
        if kind == "token":
            return Identity("admin", "token", Role.admin, "cookie", hashed)
        role = self.known.people.get(owner.lower())
        if role is None:
            return None
        return Identity(self.known.names[owner.lower()], "person", role, "cookie", hashed)

    async def identify(self, *, bearer: str | None, cookie: str | None, query: str | None,
                       address: str) -> Identity | None:  # fmt: skip
        """The first valid credential sent; None when none was sent or all were wrong
        (a wrong one counts as a failure and its answer is held: people/failures.py)."""
        tried = []
        for value, check in ((bearer, lambda v: self.by_secret(v, "bearer")),
                             (cookie, self.by_session),
                             (query, lambda v: self.by_secret(v, "query"))):  # fmt: skip
            if value:
                identity = check(value)
                if identity is not None:
                    return identity
                tried.append(value)
        for value in tried:
            await self.failed(address, value)
        return None

    def lookup(self, *, bearer: str | None, cookie: str | None,
               query: str | None) -> Identity | None:  # fmt: skip
        """`identify` from memory only, synchronously: no disk, no failure counted, no wait
        (the stop lane's check, in the callback that read the request; the watcher keeps
        memory within WATCH_INTERVAL of another process's change). None: ask `identify`."""
        for value, check in ((bearer, lambda v: self._secret(v, "bearer")),
                             (cookie, self._session),
                             (query, lambda v: self._secret(v, "query"))):  # fmt: skip
            if value and (identity := check(value)) is not None:
                return identity
        return None

    async def failed(self, address: str, credential: str) -> None:
        hold = self.failures.failed(address, credential)
        self.audit(None, "login_failed", None, {"address": address})
        if hold > 0:
            await asyncio.sleep(hold)

    def proof(self, kid: str, nonce: str) -> str | None:
        """That this server holds key `kid` (or the token, kid "token"): an HMAC of the
        nonce and the server id keyed by the key's digest, which only the server that
        made the key knows. A client checks it before sending the key (client.py)."""
        self._look_at_token()
        self._current()
        key = digest(self.token) if kid == TOKEN_OWNER else self.known.kids.get(kid)
        if key is None:
            return None
        return server_proof(key, nonce, self.server_id)

    @property
    def approval_mode(self) -> str:
        return self.known.approval

    # ---- sessions --------------------------------------------------------------------------

    def new_session(self, owner: str, kind: str) -> str:
        session = secrets.token_urlsafe(32)
        hashed, expires = digest(session), time.time() + SESSION_TTL
        sessions = self.known.sessions
        while len(sessions) >= MAX_SESSIONS:
            oldest = min(sessions, key=lambda k: sessions[k][2])
            del sessions[oldest]
            self._write_known(self.store.end_session, oldest)
        sessions[hashed] = (owner, kind, expires)
        self._write_known(self.store.add_session, hashed, owner, kind, expires)
        return session

    def login_token(self, token: str) -> str | None:
        self._look_at_token()
        if not hmac.compare_digest(token.encode(), self.token.encode()):
            return None
        return self.new_session(TOKEN_OWNER, "token")

    async def login_link(self, code: str) -> tuple[str, str] | None:
        """A one-time code used up: (session, the person's name); None if not valid."""
        loop = asyncio.get_running_loop()
        used = await loop.run_in_executor(self._writer, self.store.use_link, code)
        if used is None:
            return None
        owner, kind = used
        if kind == "person" and owner.lower() not in self.known.people:
            self._current()
            if owner.lower() not in self.known.people:
                return None
        return self.new_session(owner, kind), owner

    def end_session(self, identity: Identity | None) -> None:
        if identity is None or identity.via != "cookie":
            return
        self.known.sessions.pop(identity.secret, None)
        self._write_known(self.store.end_session, identity.secret)
        self.revalidate()

    def end_everywhere(self, identity: Identity) -> None:
        """Every session of this person (or of the token)."""
        owner = TOKEN_OWNER if identity.kind == "token" else identity.name
        kind = "token" if identity.kind == "token" else "person"
        for hashed, (who, how, _) in list(self.known.sessions.items()):
            if how == kind and who.lower() == owner.lower():
                del self.known.sessions[hashed]
        self._write_known(self.store.end_sessions, owner, kind)
        self.revalidate()

    # ---- changes made through the API ------------------------------------------------------

    async def change(self, fn: Callable[..., Any], *args: Any) -> Any:
        """Run a store change on the writer thread, then reload and revalidate."""
        loop = asyncio.get_running_loop()
        result = await loop.run_in_executor(self._writer, fn, *args)
        self.known = await loop.run_in_executor(self._writer, self.store.snapshot)
        self._mark = self.store.changed_mark()
        self.revalidate()
        return result

    async def read(self, fn: Callable[..., Any], *args: Any) -> Any:
        """A store read on the writer thread (after the writes before it)."""
        return await asyncio.get_running_loop().run_in_executor(self._writer, fn, *args)

    # ---- open WebSockets -------------------------------------------------------------------

    def track(self, identity: Identity, close: Callable[[], None]) -> Callable[[], None]:
        """Call `close` when `identity` is no longer valid; returns the untrack call."""
        token = id(close)
        self._watched[token] = (identity, close)

        def untrack() -> None:
            self._watched.pop(token, None)

        return untrack

    def still(self, identity: Identity) -> bool:
        if identity.kind == "token" and identity.via != "cookie":
            return identity.secret == digest(self.token)
        if identity.via == "cookie":
            again = self.by_session_digest(identity.secret)
        else:
            found = self.known.keys.get(identity.secret)
            again = found is not None and found[1] == identity.role
        return bool(again)

    def by_session_digest(self, hashed: str) -> bool:
        found = self.known.sessions.get(hashed)
        if found is None or found[2] <= time.time():
            return False
        return found[1] == "token" or found[0].lower() in self.known.people

    def revalidate(self) -> None:
        for token, (identity, close) in list(self._watched.items()):
            if not self.still(identity):
                log.info("closing the WebSockets of %s: signed out or revoked", identity.who)
                self._watched.pop(token, None)
                close()

    # ---- audit -----------------------------------------------------------------------------

    def audit(self, identity: Identity | None, action: str, target: str | None = None,
              detail: dict[str, Any] | None = None) -> None:  # fmt: skip
        """One entry, written by the writer thread (never waits)."""
        who = identity.who if identity else "nobody"
        via = identity.via if identity else "-"
        self._write(self.store.audit_add, time.time(), who, via, action, target, detail)

    def _write(self, fn: Callable[..., Any], *args: Any) -> None:
        future = self._writer.submit(fn, *args)
        future.add_done_callback(_log_failure)

    def _write_known(self, fn: Callable[..., Any], *args: Any) -> None:
        """A write of what `known` mirrors (sessions): no reload until it is in the store."""
        with self._count_lock:
            self._unwritten += 1
        future = self._writer.submit(fn, *args)
        future.add_done_callback(self._written)

    def _written(self, future: Any) -> None:
        with self._count_lock:
            self._unwritten -= 1
        _log_failure(future)


def _log_failure(future: Any) -> None:
    if future.exception() is not None:
        log.error("people store: %s", future.exception())

