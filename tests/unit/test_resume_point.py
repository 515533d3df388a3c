"""Resume points: a picked point on a stroke, a line or layer with an overlap back along the stroke,
mid-arc splits, where a dead server's board ran out, and which lines a layer selection
plots (plotbridge.resume, pure logic on program files)."""

from __future__ import annotations

import math

import pytest
from plotbridge.jobs.model import Layer
from plotbridge.resume import (
    Mark,
    PickError,
    ResumePoint,
    executing_line,
    layer_runs,
    locate,
    moves,
    pick,
    resume_preamble,
)  # fmt: skip

# line:    1      2      3     4              5     6                        7
PROGRAM = ["G21", "G90", "M5", "G0 X10 Y10", "M3", "G1 X20 Y10 F600", "G1 X20 Y20 F600",
           # 8                  9     10            11    12
           "G1 X10 Y20 F600", "M5", "G0 X50 Y10", "M3", "G2 X70 Y10 I10 J0 F600",
           # 13   14    15            16    17                 18
           "M5", "M0", "G0 X10 Y50", "M3", "G1 X30 Y50 F600", "M5"]  # fmt: skip
LAYERS = [Layer(name="a", first_line=4, last_line=13), Layer(name="b", first_line=15, last_line=18)]


@pytest.fixture
def program(tmp_path):
    path = tmp_path / "program.gcode"
    path.write_text("\n".join(PROGRAM) + "\n")
    return path


def close(a, b, eps=1e-6):
    return a.line == b.line and (a.at is None) == (b.at is None) and (
        a.at is None or math.dist(a.at, b.at) < eps)


def test_a_picked_point_resolves_to_the_nearest_point_on_a_stroke(program):
    # mid-edge: the foot of the perpendicular on the nearest move, not a vertex
    assert close(pick(program, LAYERS, 18, {"x": 19.0, "y": 19.4}), ResumePoint(8, (19.0, 20.0)))
    assert close(pick(program, LAYERS, 18, {"x": 15.3, "y": 9.0}), ResumePoint(6, (15.3, 10.0)))
    # on an arc: the point of the arc, not of its chord (the arc's top, above its centre)
    assert close(pick(program, LAYERS, 18, {"x": 60, "y": 21}), ResumePoint(12, (60.0, 20.0)))
    # past a stroke's end: its end
    assert pick(program, LAYERS, 18, {"x": 9, "y": 21}) == ResumePoint(8, (10.0, 20.0))
    # pen-up travel ends are not vertices
    assert pick(program, LAYERS, 18, {"x": 50, "y": 50}).at != (50.0, 50.0)


def test_overlap_goes_back_along_the_stroke_splitting_mid_move(program):
    # from (20, 20) back 1 mm: on line 7, at (20, 19)
    got = pick(program, LAYERS, 18, {"x": 20, "y": 20}, overlap=1.0)
    assert close(got, ResumePoint(7, (20.0, 19.0)))
    # back 12 mm crosses the corner at (20, 10): line 6, 2 mm before it
    got = pick(program, LAYERS, 18, {"x": 20, "y": 20}, overlap=12.0)
    assert close(got, ResumePoint(6, (18.0, 10.0)))
    # never past the stroke's start (pen-up travel before it is not drawn)
    got = pick(program, LAYERS, 18, {"x": 20, "y": 20}, overlap=500.0)
    assert close(got, ResumePoint(6, (10.0, 10.0)))
    # a line's start, 5 mm back
    assert close(pick(program, LAYERS, 18, {"line": 8}, overlap=5.0),
                 ResumePoint(7, (20.0, 15.0)))


def test_overlap_back_along_an_arc_stays_on_the_arc(program):
    # the arc (line 12) from (50, 10) clockwise over (60, 20) to (70, 10): its end, back a
    # quarter turn (5 pi mm) is its top
    got = pick(program, LAYERS, 18, {"x": 70, "y": 10}, overlap=5 * math.pi)
    assert close(got, ResumePoint(12, (60.0, 20.0)))
    line, preamble = resume_preamble(program, got)
    assert line == 13  # the rest of the arc is in the preamble, the stream goes on after it
    assert preamble[-2:] == ["M3", "G2 X70.0000 Y10.0000 I0.0000 J-10.0000 F600"]


def test_layers_and_lines_and_errors(program):
    assert pick(program, LAYERS, 18, {"layer": 1}) == ResumePoint(1)
    assert pick(program, LAYERS, 18, {"layer": 2}) == ResumePoint(15)
    with pytest.raises(PickError, match="layer 3: the job has 2 layer"):
        pick(program, LAYERS, 18, {"layer": 3})
    with pytest.raises(PickError, match="line 19: the program has lines 1 to 18"):
        pick(program, LAYERS, 18, {"line": 19})


def test_a_program_that_draws_nothing_has_no_vertex(tmp_path):
    path = tmp_path / "program.gcode"
    path.write_text("G21\nG90\nM5\nG0 X5 Y5\n")
    with pytest.raises(PickError, match="draws nothing"):
        pick(path, [], 4, {"x": 0, "y": 0})


def test_locate_on_an_arc_and_where_the_board_ran_out(program):
    assert locate(program, Mark(9, 13, 60.0, 20.0)) == ResumePoint(12, (60.0, 20.0))
    # the server died at (15, 10) on line 6; the board ran on to (20, 17) on line 7
    assert locate(program, Mark(4, 7, 15.0, 10.0, (20.0, 17.0))) == ResumePoint(7, (20.0, 17.0))
    # ran on within the same move
    assert locate(program, Mark(4, 7, 15.0, 10.0, (17.0, 10.0))) == ResumePoint(6, (17.0, 10.0))
    # a position behind the mark (a reset board at its origin) is not taken: the mark is
    assert locate(program, Mark(4, 7, 15.0, 10.0, (0.0, 0.0))) == ResumePoint(6, (15.0, 10.0))


def test_layer_runs_skip_layers_and_pause_only_between_plotted_ones():
    three = [Layer(name=str(k), first_line=first, last_line=first)
             for k, first in enumerate((4, 10, 20))]
    assert layer_runs(three, None, 1) == [(1, 9, 0), (10, 19, 1), (20, None, 2)]
    assert layer_runs(three, [1, 3], 1) == [(1, 9, 0), (20, None, 2)]
    assert layer_runs(three, [2, 3], 10) == [(10, 19, 1), (20, None, 2)]
    # a resume inside layer 2 (or at its M0) goes on with the plotted layers after it
    assert layer_runs(three, [2], 12) == [(12, 19, 1)]
    assert layer_runs(three, None, 9) == [(10, 19, 1), (20, None, 2)]
    assert layer_runs([], None, 7) == [(7, None, 0)]


def test_moves_know_their_arc_geometry(program):
    arc = next(m for m in moves(program) if m.line == 12)
    assert arc.centre == (60.0, 10.0) and arc.clockwise
    assert arc.length == pytest.approx(10 * math.pi)
    assert arc.nearest((60.0, 25.0)) == (pytest.approx(5.0), pytest.approx(0.5))


def test_a_reported_executing_line_replaces_the_conservative_bound():
    assert executing_line(40, 13, floor=1) == 40
    assert executing_line(40, None, floor=1) == 40  # no Bf: in the report
    # a number from before this stream (a previous layer's) tells nothing
    assert executing_line(5, 13, floor=10) == 13


def test_locate_from_the_reported_line_finds_the_point_on_it(tmp_path):
    # the same point lies on line 2 and on line 4 (the stroke comes back over it):
    # the conservative window finds line 2, the reported Ln: 4 finds the right one
    program = tmp_path / "p.gcode"
    program.write_text("M3\nG1 X10 Y10 F1000\nG1 X10 Y0\nG1 X0 Y10\nM5\n")
    point = (5.0, 5.0)
    assert locate(program, Mark(1, 5, *point)) == ResumePoint(2, point)
    assert locate(program, Mark(4, 5, *point)) == ResumePoint(4, point)


def test_a_point_a_step_past_a_lines_end_resumes_on_the_next_line(tmp_path):
    program = tmp_path / "p.gcode"
    program.write_text("M3\nG1 X10 Y0 F1000\nG1 X20 Y0\nM5\n")
    assert locate(program, Mark(2, 3, 10.025, 0.0)) == ResumePoint(3, (10.025, 0.0))
    assert locate(program, Mark(2, 3, 9.975, 0.0)) == ResumePoint(2, (9.975, 0.0))
    assert locate(program, Mark(2, 3, 10.0, 0.0)) == ResumePoint(2, (10.0, 0.0))
