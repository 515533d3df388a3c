"""Server configuration: one dataclass filled by the CLI (and its environment variables)."""

from __future__ import annotations

import os
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


@dataclass
class Config:
    host: str = "0.0.0.0"
    port: int = 8000
    data_dir: Path = Path(".")
    serial: str | None = None
    baud: int = 115200
    sim_speed: float = 1.0
    token: str | None = None
    token_file: Path | None = None  # where the token came from (watched for rotation)
    allowed_hosts: tuple[str, ...] = ()  # Host names accepted beside our own
    client_connections: int = 32  # open connections per client address
    max_upload_mb: float = 50.0
    auto_start: bool = False
    log_level: str = "info"
    web_dir: Path | None = None
    import_limits: Limits = field(default_factory=Limits)

    @property
    def virtual(self) -> bool:
        return self.serial is None

    @property
    def upload_limit(self) -> int:
        return int(self.max_upload_mb * 1024 * 1024)

    @property
    def db_path(self) -> Path:
        return self.data_dir / "plotbridge.db"

    @property
    def jobs_dir(self) -> Path:
        return self.data_dir / "jobs"
