"""The people tables (SQLite, in the server's database file beside the jobs and pens).

People, API keys, sessions, one-time login links, the audit log and the access settings.
Secrets are never stored: a key, a session id or a login link's code is kept as its
SHA-256 digest (all are 192 random bits or more, so no slow hash is needed). The tables
are additive (created if missing): the jobs' `user_version` does not change.

`PeopleStore` is blocking (sqlite3). The command line (`plotbridge keys|users`) writes to
it while a server runs. Every write of what `Snapshot` mirrors replaces a stamp file beside
the database; the server stats it (`changed_mark()`, microseconds, no SQLite: the jobs
write the same file all the time) before it answers, reloads when it changed, and so
refuses a removed key at once.
"""

from __future__ import annotations

import json
import os
import re
import secrets
import tempfile
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from plotbridge.access import Role
from plotbridge.database import connect
from plotbridge.people.approval import MODES
from plotbridge.people.proof import KEY_PREFIX, digest

SCHEMA = (
    """CREATE TABLE IF NOT EXISTS people (
        name TEXT PRIMARY KEY COLLATE NOCASE, role TEXT NOT NULL, created REAL NOT NULL)""",
    """CREATE TABLE IF NOT EXISTS api_keys (
        name TEXT PRIMARY KEY COLLATE NOCASE, kid TEXT NOT NULL UNIQUE,
        digest TEXT NOT NULL UNIQUE, role TEXT NOT NULL, created REAL NOT NULL)""",
    """CREATE TABLE IF NOT EXISTS sessions (
        digest TEXT PRIMARY KEY, owner TEXT NOT NULL, kind TEXT NOT NULL,
        expires REAL NOT NULL)""",
    """CREATE TABLE IF NOT EXISTS login_links (
        digest TEXT PRIMARY KEY, owner TEXT NOT NULL, kind TEXT NOT NULL,
        expires REAL NOT NULL)""",
    """CREATE TABLE IF NOT EXISTS audit (
        id INTEGER PRIMARY KEY AUTOINCREMENT, at REAL NOT NULL, who TEXT NOT NULL,
        via TEXT NOT NULL, action TEXT NOT NULL, target TEXT, detail TEXT)""",
    """CREATE TABLE IF NOT EXISTS access_settings (
        name TEXT PRIMARY KEY, value TEXT NOT NULL)""",
)

TOKEN_OWNER = "token"  # the data directory's token: the first admin
NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._@-]{0,63}")
LINK_TTL = 7 * 24 * 3600.0  # s a one-time login link stays usable
AUDIT_KEPT = 10000  # entries; the oldest go past this
AUDIT_TRIM_EVERY = 100  # entries written between trims


def check_name(name: str, what: str) -> str:
    if not isinstance(name, str) or not NAME.fullmatch(name):
        raise ValueError(f"{what} name {name!r}: 1 to 64 letters, digits, '.', '_', '@' or "
                         "'-', starting with a letter or digit")  # fmt: skip
    if name.lower() == TOKEN_OWNER:
        raise ValueError(f"{what} name {name!r} is reserved for the server's token")
    return name


@dataclass(frozen=True)
class Snapshot:
    """What the server keeps in memory to check credentials without the disk."""

    people: dict[str, Role]  # lower-cased name -> role
    names: dict[str, str]  # lower-cased name -> name as written
    keys: dict[str, tuple[str, Role]]  # digest -> (name, role)
    kids: dict[str, str]  # key id -> digest
    sessions: dict[str, tuple[str, str, float]]  # digest -> (owner, kind, expiry)
    approval: str  # whose uploads wait for approval (people/approval.py)


class PeopleStore:
    def __init__(self, path: Path) -> None:
        self._lock = threading.Lock()
        self._stamp = path.with_name(path.name + "-people")
        self._db = connect(path, SCHEMA[0])
        self._db.execute("PRAGMA busy_timeout = 5000")  # the CLI and the server share it
        for statement in SCHEMA[1:]:
            self._db.execute(statement)
        self._written = 0

    def close(self) -> None:
        with self._lock:
            self._db.close()

    def _run(self, sql: str, args: tuple = ()) -> list[tuple]:
        with self._lock:
            return self._db.execute(sql, args).fetchall()

    def changed_mark(self) -> tuple[int, int, int] | None:
        """Changes with every write of what `Snapshot` mirrors, by any process."""
        try:
            stat = os.stat(self._stamp)
        except FileNotFoundError:
            return None
        return (stat.st_ino, stat.st_mtime_ns, stat.st_ctime_ns)

    def _mirrored(self, sql: str, args: tuple = ()) -> int:
        """A write of what `Snapshot` mirrors: its row count; the stamp is new after it."""
        with self._lock:
            count = self._db.execute(sql, args).rowcount
        self._changed()
        return count

    def _changed(self) -> None:
        """A new stamp file (a new inode: ownership and clock resolution do not matter)."""
        fd, temporary = tempfile.mkstemp(prefix=".people-", dir=self._stamp.parent)
        os.close(fd)
        os.replace(temporary, self._stamp)

    def snapshot(self) -> Snapshot:
        people = {name.lower(): Role.parse(role)
                  for name, role in self._run("SELECT name, role FROM people")}  # fmt: skip
        names = {name.lower(): name for (name,) in self._run("SELECT name FROM people")}
        keys, kids = {}, {}
        for name, kid, key_digest, role in self._run(
            "SELECT name, kid, digest, role FROM api_keys"
        ):
            keys[key_digest] = (name, Role.parse(role))
            kids[kid] = key_digest
        sessions = {row[0]: (row[1], row[2], float(row[3])) for row in self._run(
            "SELECT digest, owner, kind, expires FROM sessions WHERE expires > ?", (time.time(),)
        )}  # fmt: skip
        return Snapshot(people, names, keys, kids, sessions, self.setting("approval", MODES[0]))

    # ---- settings --------------------------------------------------------------------------

    def setting(self, name: str, default: str) -> str:
        rows = self._run("SELECT value FROM access_settings WHERE name = ?", (name,))
        return rows[0][0] if rows else default

    def set_setting(self, name: str, value: str) -> None:
        self._mirrored("INSERT OR REPLACE INTO access_settings (name, value) VALUES (?, ?)",
                       (name, value))  # fmt: skip

    def server_id(self) -> str:
        """This server's lasting identity (made once, kept in its database)."""
        self._run("INSERT OR IGNORE INTO access_settings (name, value) VALUES ('server_id', ?)",
                  (secrets.token_hex(8),))  # fmt: skip
        return self.setting("server_id", "")

    # ---- people and keys -------------------------------------------------------------------

    def add_person(self, name: str, role: Role) -> None:
        check_name(name, "a person's")
        if self._run("SELECT 1 FROM people WHERE name = ?", (name,)):
            raise ValueError(f"there is already a person named {name!r}")
        self._mirrored("INSERT INTO people (name, role, created) VALUES (?, ?, ?)",
                       (name, role.name, time.time()))  # fmt: skip

    def remove_person(self, name: str) -> bool:
        """Their sessions and links go too."""
        with self._lock:
            self._db.execute("BEGIN IMMEDIATE")
            found = self._db.execute("DELETE FROM people WHERE name = ?", (name,)).rowcount
            for table in ("sessions", "login_links"):
                self._db.execute(f"DELETE FROM {table} WHERE owner = ? COLLATE NOCASE "
                                 "AND kind = 'person'", (name,))  # fmt: skip
            self._db.execute("COMMIT")
        self._changed()
        return bool(found)

    def people(self) -> list[dict[str, Any]]:
        return [{"name": n, "role": r, "created": c}
                for n, r, c in self._run("SELECT name, role, created FROM people ORDER BY name")]

    def person_role(self, name: str) -> Role | None:
        rows = self._run("SELECT role FROM people WHERE name = ?", (name,))
        return Role.parse(rows[0][0]) if rows else None

    def add_key(self, name: str, role: Role) -> str:
        """A new API key (shown once: only its digest is kept)."""
        check_name(name, "a key's")
        if self._run("SELECT 1 FROM api_keys WHERE name = ?", (name,)):
            raise ValueError(f"there is already a key named {name!r}")
        kid = secrets.token_hex(4)
        key = f"{KEY_PREFIX}_{kid}_{secrets.token_urlsafe(32)}"
        self._mirrored("INSERT INTO api_keys (name, kid, digest, role, created) "
                       "VALUES (?, ?, ?, ?, ?)", (name, kid, digest(key), role.name, time.time()))
        return key

    def remove_key(self, name: str) -> bool:
        return bool(self._mirrored("DELETE FROM api_keys WHERE name = ?", (name,)))

    def keys(self) -> list[dict[str, Any]]:
        return [{"name": n, "role": r, "id": k, "created": c} for n, r, k, c in self._run(
            "SELECT name, role, kid, created FROM api_keys ORDER BY name")]  # fmt: skip

    def _delete(self, sql: str, args: tuple) -> int:
        with self._lock:
            return self._db.execute(sql, args).rowcount

    # ---- sessions and login links ----------------------------------------------------------

    def add_session(self, session_digest: str, owner: str, kind: str, expires: float) -> None:
        self._mirrored("INSERT OR REPLACE INTO sessions (digest, owner, kind, expires) "
                       "VALUES (?, ?, ?, ?)", (session_digest, owner, kind, expires))

    def end_session(self, session_digest: str) -> None:
        self._mirrored("DELETE FROM sessions WHERE digest = ?", (session_digest,))

    def end_sessions(self, owner: str, kind: str) -> int:
        return self._mirrored("DELETE FROM sessions WHERE owner = ? COLLATE NOCASE AND "
                              "kind = ?", (owner, kind))  # fmt: skip

    def new_link(self, owner: str, kind: str) -> str:
        """A one-time login code for `owner`; earlier unused ones are void."""
        code = secrets.token_urlsafe(24)
        with self._lock:
            self._db.execute("BEGIN IMMEDIATE")
            self._db.execute("DELETE FROM login_links WHERE (owner = ? COLLATE NOCASE AND "
                             "kind = ?) OR expires < ?", (owner, kind, time.time()))  # fmt: skip
            self._db.execute("INSERT INTO login_links (digest, owner, kind, expires) "
                             "VALUES (?, ?, ?, ?)",
                             (digest(code), owner, kind, time.time() + LINK_TTL))  # fmt: skip
            self._db.execute("COMMIT")
        return code

    def use_link(self, code: str) -> tuple[str, str] | None:
        """(owner, kind) of a valid one-time code, which is used up; else None."""
        with self._lock:
            row = self._db.execute(
                "DELETE FROM login_links WHERE digest = ? AND expires > ? RETURNING owner, kind",
                (digest(code), time.time()),
            ).fetchone()  # fmt: skip
        return (row[0], row[1]) if row else None

    # ---- audit -----------------------------------------------------------------------------

    def audit_add(self, at: float, who: str, via: str, action: str, target: str | None,
                  detail: dict[str, Any] | None) -> None:  # fmt: skip
        self._run("INSERT INTO audit (at, who, via, action, target, detail) VALUES (?,?,?,?,?,?)",
                  (at, who, via, action, target, json.dumps(detail) if detail else None))
        self._written += 1
        if self._written % AUDIT_TRIM_EVERY == 0:
            self._delete("DELETE FROM audit WHERE id <= (SELECT MAX(id) FROM audit) - ?",
                         (AUDIT_KEPT,))  # fmt: skip

    def audit(self, limit: int = 100, before: int | None = None) -> list[dict[str, Any]]:
        """Newest first."""
        rows = self._run(
            "SELECT id, at, who, via, action, target, detail FROM audit WHERE id < ? "
            "ORDER BY id DESC LIMIT ?", (before if before is not None else 2**62, limit),
        )  # fmt: skip
        return [_entry(row) for row in rows]

    def audit_all(self) -> Iterator[dict[str, Any]]:
        """Oldest first (the export)."""
        for row in self._run("SELECT id, at, who, via, action, target, detail FROM audit "
                             "ORDER BY id"):  # fmt: skip
            yield _entry(row)


def _entry(row: tuple) -> dict[str, Any]:
    entry_id, at, who, via, action, target, detail = row
    return {"id": entry_id, "at": at, "who": who, "via": via, "action": action,
            "target": target, "detail": json.loads(detail) if detail else None}  # fmt: skip
