"""What the host relies on about a board, defined once and learned from the board.

GRBL 1.1 defaults stand until the board says otherwise: `$I` reports
`[OPT:...,blocks,bytes]` and every status report's `Bf:blocks,bytes` shows the
free planner blocks (an empty planner shows them all, so the largest value seen
is the planner's depth).
"""

from __future__ import annotations

from dataclasses import dataclass

from plotbridge.grbl import RX_BUFFER_SIZE

PLANNER_BLOCKS = 15
"""GRBL's planner depth on an ATmega328P; our firmware reports more in `Bf:`."""

SEGMENT_BLOCKS = 8
"""A block leaves the planner (and `Bf:`) once it is cut into step segments,
before those are stepped: up to one block per segment (GRBL keeps 6, our firmware 7)."""

MOVING_STATES = frozenset({"Run", "Jog", "Home", "Hold"})
"""Machine states in which the carriage moves (or is decelerating in a hold):
machine reports go out at least 5 times a second."""

READY_STATE = "Idle"
"""The only state in which a job may start."""


@dataclass
class BoardFacts:
    planner_blocks: int = PLANNER_BLOCKS
    rx_buffer: int = RX_BUFFER_SIZE
    segment_blocks: int = SEGMENT_BLOCKS
    line_numbers: bool = False
    """The board reports the executing line (`Ln:`) of lines sent with an `N` word."""
    reported: bool = False
    """The board's `$I` gave its options (planner depth, letters): not GRBL's defaults."""

    def learn_options(self, planner_blocks: int, rx_buffer: int, letters: str = "") -> bool:
        """From `$I`'s `[OPT:letters,...]`; True when the receive buffer size changed.

        A receive buffer larger than GRBL's is not trusted (character counting
        beyond it gains nothing and risks overruns); one too small is ignored.
        """
        self.reported = True
        self.planner_blocks = max(self.planner_blocks, planner_blocks)
        self.line_numbers = "N" in letters
        size = min(rx_buffer, RX_BUFFER_SIZE)
        if size >= 16 and size != self.rx_buffer:
            self.rx_buffer = size
            return True
        return False

    def learn_free(self, planner_free: int | None) -> None:
        """From a status report's `Bf:` free planner blocks."""
        if planner_free is not None and planner_free > self.planner_blocks:
            self.planner_blocks = planner_free

    def queued_blocks(self, planner_free: int | None) -> int | None:
        """Blocks not known to be executed when `planner_free` were free (None: unknown)."""
        if planner_free is None:
            return None
        return self.planner_blocks - planner_free + self.segment_blocks

    @property
    def most_queued(self) -> int:
        """Blocks that may be unexecuted when nothing is known: full planner and segments."""
        return self.planner_blocks + self.segment_blocks
