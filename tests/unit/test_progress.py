"""Progress from where the pen is (jobs/progress.py): the program's measure, the plan's
time per line, and what `follow` makes of a point on a line."""

from __future__ import annotations

import math

import pytest
from plotbridge.jobs.model import Layer
from plotbridge.jobs.progress import Measure, follow, plan_of, summary

from tests.fixtures.jobs import a_job

# a 10 mm stroke in two lines, travel, a half circle of radius 5 (an arc), at F600
PROGRAM = ["G21", "G90", "G0 X0 Y0", "M3", "G1 X5 Y0 F600", "G1 X10 Y0 F600", "M5",
           "G0 X20 Y0", "M3", "G2 X30 Y0 I5 J0 F600", "M5"]  # fmt: skip
ARC_MM = math.pi * 5


@pytest.fixture
def measure(tmp_path) -> Measure:
    path = tmp_path / "program.gcode"
    path.write_text("\n".join(PROGRAM) + "\n")
    return Measure.of(path)


def test_the_measure_counts_pen_down_length_per_line(measure):
    assert measure.lines == len(PROGRAM)
    assert measure.mm[5] == 5 and measure.mm[6] == 10 and measure.mm[8] == 10  # travel: no
    assert measure.mm[10] == pytest.approx(10 + ARC_MM)
    assert list(measure.syncs) == [4, 7, 9, 11]  # pen down/up, and the last line


def test_a_point_along_a_line_and_an_arc(measure):
    assert measure.along(5, (2.5, 0)) == pytest.approx(0.5)
    assert measure.drawn_mm(5, 0.5) == pytest.approx(2.5)
    top = (25, 5)  # a G2 from (20,0) about (25,0) goes over the top: the middle
    assert measure.along(10, top) == pytest.approx(0.5)
    assert measure.drawn_mm(10, 0.5) == pytest.approx(10 + ARC_MM / 2)
    assert measure.drawn_mm(8, 0.7) == 10  # travel draws nothing


def test_the_plans_time_splits_a_stretch_by_length_at_feed(measure):
    # the estimate: line 4 (M3) accepted at 1 s, line 7 (M5) at 3 s: the stroke takes 2 s
    job = a_job("running", lines_total=len(PROGRAM), estimate_s=6.0,
                timeline=[(4, 1.0), (7, 3.0), (9, 3.5), (11, 6.0)])  # fmt: skip
    plan = plan_of(job, measure)
    assert plan.ends(5) == pytest.approx(2.0)  # half the stroke's length: half its time
    assert plan.at(6, 0.5) == pytest.approx(2.5)
    assert plan.total == 6.0


def test_follow_sets_the_numbers_and_names_the_position(measure):
    job = a_job("running", lines_total=len(PROGRAM), estimate_s=6.0,
                timeline=[(4, 1.0), (7, 3.0), (9, 3.5), (11, 6.0)],
                layers=[Layer(name="outline", first_line=1, last_line=7),
                        Layer(name="arc", first_line=8, last_line=11)])  # fmt: skip
    follow(job, measure, plan_of(job, measure), 10, (25, 5))
    assert job.lines_done == 9 and job.drawn_mm == pytest.approx(10 + ARC_MM / 2, abs=0.01)
    assert job.progress == pytest.approx((3.5 + 0.5 * 2.5) / 6, abs=1e-3)
    assert job.eta_s == pytest.approx(6 - 4.75, abs=0.06)  # to 0.1 s
    assert job.done_point == {"line": 10, "x": 25, "y": 5, "layer": 2, "layer_name": "arc"}
    assert [layer.progress for layer in job.layers] == [1, pytest.approx(1.75 / 3, abs=1e-3)]
    assert job.layers[1].drawn_mm == pytest.approx(ARC_MM / 2, abs=0.01)
    assert summary(job, "stopped") == "stopped in layer 2 'arc' at X 25.0 Y 5.0, 79 % drawn"
    follow(job, measure, plan_of(job, measure), len(PROGRAM) + 1, None)
    assert job.progress == 1 and job.eta_s == 0 and job.done_point is None
    assert summary(job, "done") == f"done, {(10 + ARC_MM) / 1000:.2f} m drawn"
