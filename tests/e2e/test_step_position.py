"""The firmware's position when motion stops part way through a block.

The step interrupt counts no steps: the position is where the block under
way ends, less what its Bresenham state says is still to come, and a block
the ring does not go on with is forgotten when the steppers start again.
These run the real firmware in the simulator (in real time, so that a stop
can come in the middle of a move) and compare the board's MPos with the
steps the simulated motors actually made: after a hold (the block goes on
afterwards) and after a reset (its rest is flushed, the next move starts a
new block)."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from tests.fixtures.grbl import Grbl, clean, mpos, session, unlocked
from tests.fixtures.plotsim import Plotter
from tests.fixtures.waits import wait_until

STEP_MM = 1 / 80  # the default profile's steps/mm


def board_and_motors_agree(g: Grbl, plotter) -> tuple[float, float]:
    x, y = mpos(g.status())
    pos = plotter.trace()["position"]
    # MPos has 3 decimals; a step is 0.0125 mm
    assert abs(x - pos["x"]) < STEP_MM / 2 and abs(y - pos["y"]) < STEP_MM / 2, ((x, y), pos)
    return x, y


def moved(g: Grbl, start: tuple[float, float], mm: float) -> None:
    """Waits until X is mm away from start (the move under way)."""
    wait_until(g.status, lambda status: abs(mpos(status)[0] - start[0]) > mm, 30,
               f"X {mm} mm from {start}")  # fmt: skip


@pytest.fixture
def board(plotter_factory) -> Iterator[tuple[Plotter, Grbl]]:
    """Real time (a stop comes in the middle of a move), after a soft reset and $X."""
    plotter = plotter_factory(speed=1.0)
    with session(plotter) as g:
        yield plotter, unlocked(g)


def test_a_hold_part_way_reads_where_the_motors_stand_and_resumes_exactly(board) -> None:
    plotter, g = board
    g.ok("G1 X60 Y7 F900")  # 4 s: one block, held part way
    moved(g, (0.0, 0.0), 3.0)
    g.ser.write(b"!")
    g.wait_state("Hold:0")
    x, _ = board_and_motors_agree(g, plotter)
    assert 3.0 < x < 59.0
    # the rest of the same block: its steps made so far are kept
    g.ser.write(b"~")
    g.wait_state("Idle")
    assert board_and_motors_agree(g, plotter) == (60.0, 7.0)
    clean(plotter.trace())


def test_a_reset_mid_move_keeps_the_position_the_motors_reached(board) -> None:
    plotter, g = board
    g.ok("G0 X50 Y60")
    g.wait_state("Idle")
    g.ok("G1 X20 Y15 F900")  # negative on both axes, 3.6 s
    moved(g, (50.0, 60.0), 3.0)
    g.ser.write(b"\x18")
    g.wait_for(r"^Grbl ")
    x, y = board_and_motors_agree(g, plotter)
    assert 21.0 < x < 47.0 and 16.0 < y < 56.0
    g.ok("$X")
    g.ok("G90 G0 X5 Y5")
    g.wait_state("Idle")
    assert board_and_motors_agree(g, plotter) == (5.0, 5.0)
    clean(plotter.trace())
