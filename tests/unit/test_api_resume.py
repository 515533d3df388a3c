"""Where an interrupted job resumes: conservative, never skipping a move."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st
from plotbridge.program.reader import motion_flags
from plotbridge.resume import first_unexecuted_line

PROGRAM = ["G21", "G90", "M5", "G0 X1 Y1", "M3", "G1 X2 Y1 F3000", "G1 X3 Y1 F3000", "M5",
           "G0 X5 Y5", "M3", "G2 X6 Y6 I1 J0 F3000", "M5"]  # fmt: skip


def test_motion_flags():
    assert list(motion_flags(PROGRAM)) == [0, 0, 0, 1, 0, 1, 1, 0, 1, 0, 1, 0]


def test_nothing_queued_resumes_after_last_ack():
    assert first_unexecuted_line(motion_flags(PROGRAM), 7, 0) == 8


def test_queued_blocks_walk_back_over_moves_only():
    flags = motion_flags(PROGRAM)
    # 11 acked, 2 blocks queued: the arc (11) and the G0 (9) are not known done.
    assert first_unexecuted_line(flags, 11, 2) == 9
    assert first_unexecuted_line(flags, 11, 3) == 7
    assert first_unexecuted_line(flags, 11, 99) == 1
    assert first_unexecuted_line(flags, 11, 99, floor=6) == 6


@given(st.lists(st.booleans(), min_size=1, max_size=60), st.data())
def test_never_skips_an_unexecuted_move(moves, data):
    flags = bytes(moves)
    acked = data.draw(st.integers(0, len(flags)))
    move_lines = [i + 1 for i in range(acked) if flags[i]]
    queued = data.draw(st.integers(0, len(move_lines) + 3))
    line = first_unexecuted_line(flags, acked, queued)
    pending = move_lines[len(move_lines) - queued:] if queued else []
    assert 1 <= line <= acked + 1
    assert all(line <= move for move in pending)
