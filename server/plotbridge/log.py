"""Console logging: one line per meaningful event."""

from __future__ import annotations

import logging

LEVELS = ("debug", "info", "warning", "error")


def setup(level: str) -> None:
    logging.basicConfig(
        level=getattr(logging, level.upper(), logging.INFO),
        format="%(asctime)s %(levelname)-7s %(name)s: %(message)s",
        datefmt="%H:%M:%S",
    )
