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
LISTEN_FILE = "listen"  # DATA_DIR/listen: "HOST PORT" of the running server, for the links


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
    users.add_argument("--host", default=os.environ.get("PLOTBRIDGE_HOST", "0.0.0.0"),
                       help="the server's address in the link")  # fmt: skip
    users.add_argument("--port", type=int, default=None,
                       help="the link's port (default: the running server's, else 8000)")


def login_hosts(host: str) -> list[str]:
    """The names a phone on the LAN reaches the server by: listening on every address, the
    LAN addresses and the zeroconf name (NAME.local, which mdns.py announces); else the
    host it listens on."""
    if host not in ("0.0.0.0", "::", ""):
        return [f"[{host}]" if ":" in host else host]
    from plotbridge import mdns

    lan = [a for a in mdns.machine_addresses() if ":" not in a]
    return [*lan[:1], f"{socket.gethostname().split('.')[0]}.local"]


def listening_port(data_dir: Path) -> int:
    """The port the server with this data directory listens on (DATA_DIR/listen), else
    PLOTBRIDGE_PORT, else 8000."""
    try:
        return int((data_dir / LISTEN_FILE).read_text().split()[1])
    except (OSError, IndexError, ValueError):
        return int(os.environ.get("PLOTBRIDGE_PORT", 8000))


def print_link(host: str, port: int, code: str, who: str) -> None:
    """A one-time login link (/login.html#CODE: the code never reaches a log or a Referer)
    by each name a phone may use, and the first one's QR code (for a phone's camera)."""
    import segno

    urls = [f"http://{name}:{port}/login.html#{code}" for name in login_hosts(host)]
    qr = io.StringIO()
    segno.make(urls[0], error="l").terminal(out=qr, compact=True)
    also = "".join(f"\n            or {url}" for url in urls[1:])
    print(f"plotbridge: one-time login link for {who} (it works once, then the browser "
          f"stays logged in):\nplotbridge: open {urls[0]}{also}\n{qr.getvalue()}",
          flush=True)  # fmt: skip


def print_token_link(data_dir: Path, host: str, port: int) -> None:
    """A one-time login link for the token's admin."""
    store = open_store(data_dir)
    try:
        code = store.new_link(TOKEN_OWNER, "token")
    finally:
        store.close()
    print_link(host, port, code, "the admin (the token)")


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
    port = args.port if args.port is not None else listening_port(args.data_dir.expanduser())
    if args.verb == "add":
        store.add_person(args.name, Role.parse(args.role))
        print_link(args.host, port, store.new_link(args.name, "person"), args.name)
    elif args.verb == "remove":
        if not store.remove_person(args.name):
            raise ValueError(f"no person named {args.name!r}")
        print(f"plotbridge: {args.name!r} removed; their sessions have ended")
    elif args.verb == "reset":
        if store.person_role(args.name) is None:
            raise ValueError(f"no person named {args.name!r}")
        store.end_sessions(args.name, "person")
        print_link(args.host, port, store.new_link(args.name, "person"), args.name)
    else:
        for person in store.people():
            print(f"{person['name']}\t{person['role']}")
    return 0
