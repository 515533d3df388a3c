"""A pen's servo positions on the board: the firmware's $60 (up) and $61 (down) in µs."""

from __future__ import annotations

from typing import Any, Protocol

from plotbridge.pens.model import PenSpec

PEN_UP_SETTING, PEN_DOWN_SETTING = 60, 61


def servo_lines(pen: PenSpec, settings: dict[int, float]) -> list[str]:
    """The `$60=`/`$61=` lines that give the board `pen`'s positions; only those that
    differ from what the board last reported (`settings`, its `$$`)."""
    lines = []
    for setting, wanted in ((PEN_UP_SETTING, pen.up_us), (PEN_DOWN_SETTING, pen.down_us)):
        current = settings.get(setting)
        if current is None or round(current) != wanted:
            lines.append(f"${setting}={wanted}")
    return lines


class Board(Protocol):
    """What trying a pen needs of a plotter (`plotter.Plotter`)."""

    link: Any

    async def send(self, action: str, line: str, wait: float = 10.0) -> list[str]: ...


async def try_pen(board: Board, pen: PenSpec, down: bool) -> list[str]:
    """Give the board `pen`'s servo positions, then lower (`M3`) or lift (`M5`) the pen, so
    the user sees them; the board's answers. Refused (409) while a job runs (`send`)."""
    action = f"try pen {pen.name!r}"
    answers = []
    for line in [*servo_lines(pen, board.link.settings), "M3" if down else "M5"]:
        answers += [line, *await board.send(action, line)]
    return answers
