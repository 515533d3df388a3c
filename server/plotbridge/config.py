"""Server configuration: one dataclass filled by the CLI (and its environment variables)."""

from __future__ import annotations

import math
import os
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from plotbridge.importing.workers import Limits
from plotbridge.profiles import UnknownBoard, check_board

PACKAGE_DIR = Path(__file__).resolve().parent


def default_data_dir() -> Path:
    base = os.environ.get("XDG_DATA_HOME") or str(Path.home() / ".local" / "share")
    return Path(base) / "plotbridge"


def find_web_dir() -> Path | None:
    """`web/` next to the repository's server/ (override: PLOTBRIDGE_WEB_DIR)."""
    override = os.environ.get("PLOTBRIDGE_WEB_DIR")
    if override:
        return Path(override)
    for candidate in (PACKAGE_DIR.parent.parent / "web", PACKAGE_DIR / "web"):
        if candidate.is_dir():
            return candidate
    return None


PLOTTERS_FILE = "plotters.toml"
NAME_CHARS = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_")


class ConfigError(ValueError):
    """A plotters file or option that cannot be used; says what and where."""


@dataclass(frozen=True)
class PlotterConfig:
    """One plotter: a serial `device`, or virtual (device None)."""

    name: str
    device: str | None = None
    board: str | None = None
    baud: int = 115200
    work_area: tuple[float, float] | None = None  # mm; None: the board's $130/$131

    @property
    def virtual(self) -> bool:
        return self.device is None


BAUD_RANGE = (300, 4_000_000)
AREA_RANGE_MM = (1.0, 10_000.0)  # a work area's width and height
_TABLE = re.compile(r"\s*\[\[\s*plotter\s*\]\]")


def _key_line(text: str, table: int, key: str) -> int | None:
    """The line (from 1) giving `key` in the `table`-th [[plotter]] table, if found."""
    seen = 0
    assign = re.compile(rf"\s*(?:{re.escape(key)}|\"{re.escape(key)}\")\s*=")
    for number, line in enumerate(text.splitlines(), 1):
        if _TABLE.match(line):
            seen += 1
        elif seen == table and assign.match(line):
            return number
    return None


def _number(value: object, low: float, high: float, integer: bool = False) -> float | None:
    """`value` when it is a finite number in [low, high] (an integer if asked), else None."""
    kinds = int if integer else int | float
    if isinstance(value, bool) or not isinstance(value, kinds):
        return None
    if not math.isfinite(value) or not low <= value <= high:
        return None
    return value


def read_plotters_file(path: Path) -> list[PlotterConfig]:
    """`[[plotter]]` tables: name, device or virtual = true, board, baud, width, height.
    Every refusal names the file, the line and the key."""
    try:
        text = path.read_text()
        data = tomllib.loads(text)
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise ConfigError(f"{path}: {exc}") from exc
    tables = data.get("plotter")
    if not isinstance(tables, list) or not tables:
        raise ConfigError(f"{path}: no [[plotter]] tables")
    plotters = []
    for index, table in enumerate(tables, 1):

        def refuse(key: str | None, message: str, index: int = index) -> ConfigError:
            line = _key_line(text, index, key) if key else None
            where = f"{path}:{line}" if line else str(path)
            return ConfigError(f"{where}: plotter {index}: {key + ': ' if key else ''}{message}")

        if not isinstance(table, dict):
            raise refuse(None, "not a table")
        unknown = set(table) - {"name", "device", "virtual", "board", "baud", "width", "height"}
        if unknown:
            raise refuse(sorted(unknown)[0], f"unknown keys {', '.join(sorted(unknown))}")
        name = table.get("name", f"plotter{index}")
        device = table.get("device")
        if table.get("virtual") is True:
            if device is not None:
                raise refuse("device", "give either device or virtual = true")
        elif not isinstance(device, str) or not device:
            raise refuse("device", 'needs device = "/dev/..." or virtual = true')
        baud = table.get("baud", 115200)
        if _number(baud, *BAUD_RANGE, integer=True) is None:
            raise refuse("baud", f"an integer from {BAUD_RANGE[0]} to {BAUD_RANGE[1]}, "
                                 f"got {baud!r}")
        area = None
        if "width" in table or "height" in table:
            for key in ("width", "height"):
                if _number(table.get(key), *AREA_RANGE_MM) is None:
                    raise refuse(key if key in table else None,
                                 f"width and height must both be finite numbers from "
                                 f"{AREA_RANGE_MM[0]:g} to {AREA_RANGE_MM[1]:g} mm, "
                                 f"got {key} = {table.get(key)!r}")
            area = (float(table["width"]), float(table["height"]))
        board = table.get("board")
        if board is not None:
            try:
                check_board(board)
            except UnknownBoard as exc:
                raise refuse("board", str(exc)) from None
        plotters.append(PlotterConfig(str(name), device, board, baud, area))
    return check_names(plotters, str(path))


def check_names(plotters: list[PlotterConfig], where: str) -> list[PlotterConfig]:
    names = [p.name for p in plotters]
    for name in names:
        if not name or len(name) > 64 or not set(name) <= NAME_CHARS:
            raise ConfigError(f"{where}: plotter name {name!r}: use 1-64 letters, digits, - or _")
    if len(set(names)) != len(names):
        raise ConfigError(f"{where}: plotter names must differ: {', '.join(names)}")
    return plotters


@dataclass
class Config:
    host: str = "0.0.0.0"
    port: int = 8000
    data_dir: Path = Path(".")
    plotters: list[PlotterConfig] = field(default_factory=lambda: [PlotterConfig("plotter1")])
    sim_speed: float = 1.0
    token: str | None = None
    token_file: Path | None = None  # where the token came from (watched for rotation)
    allowed_hosts: tuple[str, ...] = ()  # Host names accepted beside our own
    client_connections: int = 32  # open connections per client address
    max_upload_mb: float = 50.0
    auto_start: bool = False
    log_level: str = "info"
    zeroconf: bool = True  # announce on the LAN (plotbridge.mdns)
    home_on_connect: bool = False  # $H when a plotter connects in Alarm (it has switches)
    after_job: str = "none"  # park | home | none: the default "after the job" action
    park: tuple[float, float] = (0.0, 0.0)  # mm, where "park" leaves the carriage
    webhooks: tuple[str, ...] = ()  # --webhook URLs (more in DATA_DIR/webhooks.json)
    webhook_allow_local: bool = False  # settings' webhooks may reach this machine
    web_dir: Path | None = None
    import_limits: Limits = field(default_factory=Limits)
    mqtt: object | None = None  # plotbridge.mqtt.settings.MqttSettings; None: MQTT is off

    @property
    def virtual(self) -> bool:
        """Every plotter is virtual."""
        return all(p.virtual for p in self.plotters)

    @property
    def serial(self) -> str | None:
        """The first plotter's serial device (None when virtual)."""
        return self.plotters[0].device

    @property
    def tmp_dir(self) -> Path:
        return self.data_dir / "tmp"

    @property
    def upload_limit(self) -> int:
        return int(self.max_upload_mb * 1024 * 1024)

    @property
    def db_path(self) -> Path:
        return self.data_dir / "plotbridge.db"

    @property
    def jobs_dir(self) -> Path:
        return self.data_dir / "jobs"
