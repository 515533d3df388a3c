"""Server configuration: one dataclass filled by the CLI (and its environment variables)."""

from __future__ import annotations

import os
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from plotbridge.importing.workers import Limits

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


def read_plotters_file(path: Path) -> list[PlotterConfig]:
    """`[[plotter]]` tables: name, device or virtual = true, board, baud, width, height."""
    try:
        data = tomllib.loads(path.read_text())
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise ConfigError(f"{path}: {exc}") from exc
    tables = data.get("plotter")
    if not isinstance(tables, list) or not tables:
        raise ConfigError(f"{path}: no [[plotter]] tables")
    plotters = []
    for index, table in enumerate(tables, 1):
        where = f"{path}: plotter {index}"
        if not isinstance(table, dict):
            raise ConfigError(f"{where}: not a table")
        unknown = set(table) - {"name", "device", "virtual", "board", "baud", "width", "height"}
        if unknown:
            raise ConfigError(f"{where}: unknown keys {', '.join(sorted(unknown))}")
        name = table.get("name", f"plotter{index}")
        device = table.get("device")
        if table.get("virtual") is True:
            if device is not None:
                raise ConfigError(f"{where}: give either device or virtual = true")
        elif not isinstance(device, str) or not device:
            raise ConfigError(f"{where}: needs device = \"/dev/...\" or virtual = true")
        baud = table.get("baud", 115200)
        if not isinstance(baud, int) or baud <= 0:
            raise ConfigError(f"{where}: baud must be a positive integer")
        area = None
        if "width" in table or "height" in table:
            width, height = table.get("width"), table.get("height")
            if not all(isinstance(v, int | float) and v > 0 for v in (width, height)):
                raise ConfigError(f"{where}: width and height must both be positive numbers (mm)")
            area = (float(width), float(height))
        board = table.get("board")
        if board is not None and not isinstance(board, str):
            raise ConfigError(f"{where}: board must be a profile name")
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
