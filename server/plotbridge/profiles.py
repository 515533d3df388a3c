"""Board profiles: the names `firmware/src/boards/NAME.h` defines.

A board name ends up on make's command line (`make BOARD=NAME`), where make would
expand `$(shell ...)` in it, and in file paths. So a name is accepted only when it
is one of these files' names, checked before anything is built or started.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

DEFAULT_BOARD = "uno-cnc-shield"
_NAME = re.compile(r"[a-z0-9][a-z0-9-]{0,63}")


class UnknownBoard(ValueError):
    """A board name that is no profile; says which names are."""


def firmware_dir() -> Path:
    """The repository's firmware/ (or PLOTBRIDGE_FIRMWARE_DIR)."""
    override = os.environ.get("PLOTBRIDGE_FIRMWARE_DIR")
    if override:
        return Path(override).resolve()
    return Path(__file__).resolve().parents[2] / "firmware"


def board_profiles(firmware: Path | None = None) -> tuple[str, ...]:
    """The profile names, sorted: every `src/boards/NAME.h` with a plain name."""
    boards = (firmware or firmware_dir()) / "src" / "boards"
    return tuple(sorted(p.stem for p in boards.glob("*.h") if _NAME.fullmatch(p.stem)))


def check_board(name: object, firmware: Path | None = None) -> str:
    """`name` when it is a profile; UnknownBoard naming the profiles otherwise."""
    known = board_profiles(firmware)
    if isinstance(name, str) and name in known:
        return name
    shown = repr(name)[:80]
    raise UnknownBoard(f"unknown board {shown}: one of {', '.join(known) or '(no profiles found)'}")
