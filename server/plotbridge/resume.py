"""Where an interrupted program can safely continue (pure logic)."""

from __future__ import annotations

from collections.abc import Iterable

MOTION_WORDS = ("G0", "G1", "G2", "G3", "G00", "G01", "G02", "G03")


def motion_flags(lines: Iterable[str]) -> bytearray:
    """One flag per program line: 1 when the line queues a planner block (a move)."""
    flags = bytearray()
    for line in lines:
        word = line.split(maxsplit=1)[0].upper() if line.strip() else ""
        flags.append(1 if word in MOTION_WORDS else 0)
    return flags


def first_unexecuted_line(motion: bytes, acked: int, queued_blocks: int, floor: int = 1) -> int:
    """The first line not known to be executed.

    `acked` lines had been acknowledged when the board last reported
    `queued_blocks` planner blocks still waiting (the block in motion included).
    Every move queues at least one block, so walking back over that many move
    lines never skips motion; the cost is redrawing at most one status interval.
    """
    line = acked + 1
    remaining = max(queued_blocks, 0)
    while remaining > 0 and line > floor:
        line -= 1
        if line - 1 < len(motion) and motion[line - 1]:
            remaining -= 1
    return max(line, floor)
