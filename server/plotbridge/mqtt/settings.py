"""MQTT settings: `--mqtt URL` and friends, the environment, or the `[mqtt]` table of the
data directory's plotters.toml (the command line wins, then the environment, then the file).

The user name and password never come from the command line (`ps` shows it to every
user): a credentials file (`USER:PASSWORD` on its first line), PLOTBRIDGE_MQTT_USERNAME /
PLOTBRIDGE_MQTT_PASSWORD, or `username` / `password_file` in the table.
"""

from __future__ import annotations

import argparse
import os
import socket
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

from plotbridge.config import NAME_CHARS, PLOTTERS_FILE, ConfigError

COMMANDS = ("stop", "hold", "continue", "home", "start")
"""What the broker may ask for. `stop` (a plotter's, a bridge's, the fleet's) is always
allowed; `start` (taking fleet jobs) is off unless listed."""
RESERVED = frozenset({"cmd", "jobs"})  # levels of plotbridge/FLEET/... that are not bridges
DEFAULT_ACCEPT = frozenset({"stop", "hold", "continue", "home"})
TABLE_KEYS = frozenset({"url", "username", "password_file", "credentials_file", "fleet",
                        "bridge", "discovery_prefix", "accept", "keepalive", "ca_file",
                        "public_url"})  # fmt: skip


@dataclass(frozen=True)
class MqttSettings:
    host: str
    port: int
    tls: bool = False
    username: str | None = None
    password: str | None = field(default=None, repr=False)
    fleet: str = "default"
    bridge: str = "bridge"
    discovery_prefix: str = "homeassistant"
    accept: frozenset[str] = DEFAULT_ACCEPT
    keepalive: int = 10  # s; a dead bridge shows offline within 1.5 times this
    ca_file: Path | None = None
    public_url: str = ""  # where the fleet's pages link to this bridge

    def allows(self, command: str) -> bool:
        return command == "stop" or command in self.accept


def add_arguments(parser: argparse.ArgumentParser) -> None:
    env = os.environ.get
    group = parser.add_argument_group("MQTT (Home Assistant, fleets of bridges)")
    group.add_argument(
        "--mqtt", default=env("PLOTBRIDGE_MQTT"), metavar="URL",
        help="broker mqtt://HOST:PORT or mqtts://HOST:PORT (off unless given here, in "
             "PLOTBRIDGE_MQTT or in [mqtt] of DATA_DIR/plotters.toml)",
    )  # fmt: skip
    group.add_argument(
        "--mqtt-credentials", type=Path, default=env("PLOTBRIDGE_MQTT_CREDENTIALS"),
        metavar="FILE", help="file whose first line is USER:PASSWORD for the broker",
    )  # fmt: skip
    group.add_argument("--mqtt-fleet", default=env("PLOTBRIDGE_MQTT_FLEET"),
                       help="fleet name: bridges with the same broker and fleet see each other")
    group.add_argument("--mqtt-bridge", default=env("PLOTBRIDGE_MQTT_BRIDGE"),
                       help="this bridge's name in the fleet (default: the host name)")
    group.add_argument("--mqtt-accept", default=env("PLOTBRIDGE_MQTT_ACCEPT"),
                       help=f"commands the broker may send, comma-separated, of {COMMANDS} "
                            "(stop always; default stop,hold,continue,home)")  # fmt: skip


def from_args(args: argparse.Namespace, data_dir: Path, port: int) -> MqttSettings | None:
    """The settings, or None when MQTT is off; ConfigError says what is wrong and where."""
    table = _table(data_dir / PLOTTERS_FILE)
    url = args.mqtt or table.get("url")
    if not url:
        return None
    where = "--mqtt" if args.mqtt else f"{data_dir / PLOTTERS_FILE} [mqtt] url"
    host, port_, tls = parse_url(str(url), where)
    username, password = _credentials(args, table, data_dir)
    accept_text = args.mqtt_accept
    accept = (_accept(accept_text.split(","), "--mqtt-accept") if accept_text else
              _accept(table["accept"], "[mqtt] accept") if "accept" in table else DEFAULT_ACCEPT)
    keepalive = table.get("keepalive", 10)
    if not isinstance(keepalive, int) or not 2 <= keepalive <= 600:
        raise ConfigError("[mqtt] keepalive: whole seconds from 2 to 600")
    prefix = str(table.get("discovery_prefix", "homeassistant"))
    if not prefix or any(c in prefix for c in "+#") or prefix.startswith("/"):
        raise ConfigError(f"[mqtt] discovery_prefix {prefix!r}: a topic without + or #")
    ca_file = table.get("ca_file")
    return MqttSettings(
        host=host, port=port_, tls=tls, username=username, password=password,
        fleet=_name(args.mqtt_fleet or table.get("fleet") or "default", "fleet"),
        bridge=_name(args.mqtt_bridge or table.get("bridge") or _host_name(), "bridge"),
        discovery_prefix=prefix, accept=accept, keepalive=keepalive,
        ca_file=Path(ca_file) if ca_file else None,
        public_url=str(table.get("public_url") or ""),
    )  # fmt: skip


def parse_url(url: str, where: str) -> tuple[str, int, bool]:
    parts = urlsplit(url)
    if parts.scheme not in ("mqtt", "mqtts"):
        raise ConfigError(f"{where}: {url!r}: use mqtt://HOST:PORT or mqtts://HOST:PORT")
    if parts.username or parts.password:
        raise ConfigError(f"{where}: no user or password in the URL (they would show in `ps`); "
                          "use --mqtt-credentials FILE or PLOTBRIDGE_MQTT_USERNAME/_PASSWORD")
    try:
        port = parts.port
    except ValueError:
        raise ConfigError(f"{where}: {url!r}: the port must be a number 1-65535") from None
    if not parts.hostname or parts.path not in ("", "/"):
        raise ConfigError(f"{where}: {url!r}: use mqtt://HOST:PORT (no path)")
    tls = parts.scheme == "mqtts"
    return parts.hostname, port or (8883 if tls else 1883), tls


def _table(path: Path) -> dict[str, Any]:
    if not path.exists():
        return {}
    try:
        table = tomllib.loads(path.read_text()).get("mqtt", {})
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise ConfigError(f"{path}: {exc}") from exc
    if not isinstance(table, dict):
        raise ConfigError(f"{path}: mqtt must be a table ([mqtt])")
    unknown = set(table) - TABLE_KEYS
    if unknown:
        raise ConfigError(f"{path}: [mqtt]: unknown keys {', '.join(sorted(unknown))}")
    return table


def _credentials(args: argparse.Namespace, table: dict[str, Any],
                 data_dir: Path) -> tuple[str | None, str | None]:  # fmt: skip
    if args.mqtt_credentials or table.get("credentials_file"):
        path = Path(args.mqtt_credentials or data_dir / str(table["credentials_file"]))
        try:
            line = path.read_text().splitlines()[0] if path.read_text() else ""
        except (OSError, UnicodeDecodeError) as exc:
            raise ConfigError(f"MQTT credentials file: {exc}") from None
        user, sep, password = line.partition(":")
        if not sep or not user:
            raise ConfigError(f"{path}: the first line must be USER:PASSWORD")
        return user, password
    user = os.environ.get("PLOTBRIDGE_MQTT_USERNAME") or table.get("username")
    password = os.environ.get("PLOTBRIDGE_MQTT_PASSWORD")
    if password is None and table.get("password_file"):
        try:
            password = (data_dir / str(table["password_file"])).read_text().strip()
        except (OSError, UnicodeDecodeError) as exc:
            raise ConfigError(f"[mqtt] password_file: {exc}") from None
    if password is not None and not user:
        raise ConfigError("an MQTT password without a user name: set PLOTBRIDGE_MQTT_USERNAME")
    return (str(user) if user else None), password


def _accept(names: list[Any], where: str) -> frozenset[str]:
    wanted = {str(n).strip() for n in names if str(n).strip()}
    unknown = wanted - set(COMMANDS)
    if unknown:
        raise ConfigError(f"{where}: unknown commands {', '.join(sorted(unknown))}; "
                          f"choose from {', '.join(COMMANDS)}")
    return frozenset(wanted | {"stop"})


def _name(name: str, what: str) -> str:
    if not 1 <= len(name) <= 64 or not set(name) <= NAME_CHARS:
        raise ConfigError(f"MQTT {what} name {name!r}: use 1-64 letters, digits, - or _")
    if name in RESERVED:
        raise ConfigError(f"MQTT {what} name {name!r} is taken by the topics; choose another")
    return name


def _host_name() -> str:
    name = "".join(c if c in NAME_CHARS else "-" for c in socket.gethostname().split(".")[0])
    return name[:64] or "bridge"
