"""Console logging: one line per meaningful event."""

from __future__ import annotations

import logging

from plotbridge.guard import logs

LEVELS = ("debug", "info", "warning", "error")


def setup(level: str) -> None:
    """Console logging with user text escaped and repeats rate-limited (guard/logs.py)."""
    handler = logging.StreamHandler()
    logs.install(handler, "%(asctime)s %(levelname)-7s %(name)s: %(message)s", "%H:%M:%S")
    logging.basicConfig(level=getattr(logging, level.upper(), logging.INFO), handlers=[handler])
