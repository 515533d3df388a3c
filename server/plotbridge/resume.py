"""Where an interrupted program can safely continue, and how to get there (pure logic)."""

from __future__ import annotations

from pathlib import Path

from plotbridge.program.reader import state_before


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


def resume_preamble(program: Path, line: int) -> list[str]:
    """G-code that puts the machine in the state in which program line `line` (1-based)
    starts: pen up, millimetres, absolute, at the position the line starts from, then
    the pen as it was. Every G1/G2/G3 of the program carries its own F. Blocking."""
    state = state_before(program, line)
    out = ["M5", "G21", "G90", f"G0 X{state.x:.3f} Y{state.y:.3f}"]
    if state.pen_down:
        out.append("M3")
    return out
