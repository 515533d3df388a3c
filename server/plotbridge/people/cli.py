"""`plotbridge keys add|remove|list` and `plotbridge users add|list|remove|reset`: they write
the data directory's store directly, so they work while the server runs (it sees the
change within a moment and refuses a removed key at once, open WebSockets included)."""

from __future__ import annotations

import argparse
import io
import os
import socket
import sys
from pathlib import Path
from typing import Any

from plotbridge.access import ROLES, Role
from plotbridge.people.store import TOKEN_OWNER, PeopleStore

DB_FILE = "plotbridge.db"


def add_commands(commands: Any, data_dir_default: Path) -> None:
    keys = commands.add_parser("keys", help="API keys for scripts: add, remove, list")
    keys.add_argument("verb", choices=("add", "remove", "list"))
    keys.add_argument("name", nargs="?", help="the key's name")
    users = commands.add_parser("users", help="people: add, list, remove, reset (new login link)")
    users.add_argument("verb", choices=("add", "list", "remove", "reset"))
    users.add_argument("name", nargs="?", help="the person's name")
    for parser in (keys, users):
        parser.add_argument("--role", choices=ROLES, help="with add: what they may do")
        parser.add_argument("--data-dir", type=Path, default=data_dir_default,
                            help="the server's data directory")  # fmt: skip
    for flag, default in (("--host", os.environ.get("PLOTBRIDGE_HOST", "0.0.0.0")),
                          ("--port", os.environ.get("PLOTBRIDGE_PORT", "8000"))):  # fmt: skip
        users.add_argument(flag, default=default, help="the server's address in the link")


def link_url(host: str, port: int | str, code: str) -> str:
    if host in ("0.0.0.0", "::", ""):
        host = socket.gethostname()
    return f"http://{host}:{port}/login.html#{code}"


def print_link(url: str, who: str) -> None:
    """A one-time login link and its QR code (for a phone's camera)."""
    import segno

    qr = io.StringIO()
    segno.make(url, error="l").terminal(out=qr, compact=True)
    print(f"plotbridge: one-time login link for {who} (it becomes a session once opened):\n"
          f"{url}\n{qr.getvalue()}", flush=True)  # fmt: skip


def token_link(data_dir: Path, host: str, port: int | str) -> str:
    """A one-time login link for the token's admin."""
    store = open_store(data_dir)
    try:
        return link_url(host, port, store.new_link(TOKEN_OWNER, "token"))
    finally:
        store.close()


def open_store(data_dir: Path) -> PeopleStore:
    data_dir = data_dir.expanduser()
    os.umask(0o077)
    data_dir.mkdir(parents=True, exist_ok=True, mode=0o700)
    return PeopleStore(data_dir / DB_FILE)


def run(args: argparse.Namespace) -> int:
    try:
        if args.verb in ("add", "remove", "reset") and not args.name:
            raise ValueError(f"{args.command} {args.verb}: give a name")
        if args.verb == "add" and not args.role:
            raise ValueError(f"{args.command} add: give --role ({', '.join(ROLES)})")
        store = open_store(args.data_dir)
    except (ValueError, OSError) as exc:
        print(f"plotbridge {args.command}: {exc}", file=sys.stderr)
        return 2
    try:
        return (_keys if args.command == "keys" else _users)(store, args)
    except ValueError as exc:
        print(f"plotbridge {args.command} {args.verb}: {exc}", file=sys.stderr)
        return 1
    finally:
        store.close()


def _keys(store: PeopleStore, args: argparse.Namespace) -> int:
    if args.verb == "add":
        key = store.add_key(args.name, Role.parse(args.role))
        print(f"plotbridge: API key {args.name!r} ({args.role}) for server {store.server_id()}; "
              f"it is shown only now: {key}")  # fmt: skip
    elif args.verb == "remove":
        if not store.remove_key(args.name):
            raise ValueError(f"no key named {args.name!r}")
        print(f"plotbridge: key {args.name!r} removed; it is refused from now on")
    else:
        for key in store.keys():
            print(f"{key['name']}\t{key['role']}\t{key['id']}")
    return 0


def _users(store: PeopleStore, args: argparse.Namespace) -> int:
    if args.verb == "add":
        store.add_person(args.name, Role.parse(args.role))
        print_link(link_url(args.host, args.port, store.new_link(args.name, "person")), args.name)
    elif args.verb == "remove":
        if not store.remove_person(args.name):
            raise ValueError(f"no person named {args.name!r}")
        print(f"plotbridge: {args.name!r} removed; their sessions have ended")
    elif args.verb == "reset":
        if store.person_role(args.name) is None:
            raise ValueError(f"no person named {args.name!r}")
        store.end_sessions(args.name, "person")
        print_link(link_url(args.host, args.port, store.new_link(args.name, "person")), args.name)
    else:
        for person in store.people():
            print(f"{person['name']}\t{person['role']}")
    return 0
