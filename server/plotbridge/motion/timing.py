"""Host-side timing of a plot: everything the estimate needs that is not the firmware's
motion code (which runs as itself, see library.py). In one place:

- Serial transfer: a line reaches the board `bytes * 10 / baud` seconds after the
  sender starts it (8N1: ten bits a byte), and the sender starts it only when the
  bytes of the lines not yet acknowledged plus its own fit the board's receive buffer
  (`rx_size`, character counting). A line is acknowledged once it is planned.
- Per-line firmware time (`MachineProfile.plan_block_s`): parsing and planning one line in the main
  loop; the next line is read only after it (and after any wait for planner room).
- Planner depth: how many blocks the board's planner holds (`MachineProfile.planner_blocks`).
- Pen moves and dwells wait for motion to stop, then `$62` ms (pen, only when it
  moves) or the dwell.

Segment timing (the step interrupt runs each segment's events at its period) and
everything about speeds comes from the firmware code itself.
"""

from __future__ import annotations

from dataclasses import replace

from ..grbl import build_of
from ..importing.models import MachineProfile

RX_SIZE = 128               # GRBL's receive buffer; both boards use it
GRBL_LINE_S = 0.0033        # stock GRBL 1.1 on a 328P (~300 short lines/s)
GRBL_PLANNER_BLOCKS = 15    # GRBL's BLOCK_BUFFER_SIZE 16 on a 328P, one kept free


def stock_grbl(settings: dict[int, float], baud: int = 115200) -> MachineProfile:
    """The estimate's profile for a stock GRBL 1.1 board with these $ settings: the same
    motion library, configured with GRBL's planner depth and line time."""
    return replace(MachineProfile.from_settings(settings), planner_blocks=GRBL_PLANNER_BLOCKS,
                   plan_block_s=GRBL_LINE_S, baud=baud, line_numbers=False)


def profile_for(settings: dict[int, float], firmware: str | None) -> MachineProfile:
    """The estimate's profile for a board with these $ settings and this `$I` version:
    stock GRBL's when the build is not ours, our firmware's when it is or is unknown."""
    build = build_of(firmware)
    if build is not None and build.lower() != "plotbridge":
        return stock_grbl(settings)
    return MachineProfile.from_settings(settings)
