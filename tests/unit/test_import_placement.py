"""Placement: scale, quarter turns, translation, paper fitting."""

from __future__ import annotations

import pytest
from plotbridge.importing import ImportFailed, ImportOptions, MachineProfile
from plotbridge.importing.placement import Transform, paper_size, placement

from tests.fixtures.imports import run_import

BOX = (10.0, 20.0, 60.0, 40.0)   # 50 x 20 mm drawing
M = MachineProfile()


def placed(**options) -> tuple[float, float, float, float]:
    return placement(BOX, ImportOptions(**options), M).box(BOX)


def test_default_keeps_coordinates():
    assert placement(None, ImportOptions(), M) == Transform()
    assert placed() == pytest.approx(BOX)


def test_scale_and_translate():
    assert placed(scale=2, dx=5, dy=-5) == pytest.approx((25, 35, 125, 75))


@pytest.mark.parametrize("rotate", [90, 180, 270])
def test_quarter_turns_keep_the_lower_left_corner(rotate):
    b = placed(rotate=rotate)
    assert b[:2] == pytest.approx(BOX[:2])
    size = (b[2] - b[0], b[3] - b[1])
    assert size == pytest.approx((20, 50) if rotate in (90, 270) else (50, 20))


def test_rotation_direction():
    t = placement(BOX, ImportOptions(rotate=90), M)
    # Counter-clockwise: the right end of the drawing ends up at the top.
    (x0, y0), (x1, y1) = t.apply(10, 30), t.apply(60, 30)
    assert y1 > y0 and x1 == pytest.approx(x0)


def test_fit_to_paper_scales_and_centres():
    b = placed(paper="A4-landscape", fit=True, margin=10)
    # A4 landscape is 297 x 210; the box 277 x 190 limits the 50 x 20 drawing to 5.54x.
    assert b[2] - b[0] == pytest.approx(277)
    assert (b[1] + b[3]) / 2 == pytest.approx(105)
    assert (b[0] + b[2]) / 2 == pytest.approx(148.5)


def test_fit_to_work_area_without_paper():
    b = placed(fit=True, margin=0)
    assert b[2] - b[0] == pytest.approx(300)
    assert b[0] == pytest.approx(0)


def test_paper_without_fit_centres_or_refuses():
    b = placed(paper="A6-landscape")
    assert (b[0] + b[2]) / 2 == pytest.approx(74)
    with pytest.raises(ImportFailed) as e:
        placed(paper="A6", scale=4)
    assert "does not fit" in e.value.errors[0]["message"]


def test_papers():
    assert paper_size("a4") == (210, 297)
    assert paper_size("letter-landscape") == (279.4, 215.9)
    with pytest.raises(ImportFailed):
        paper_size("B5")
    with pytest.raises(ImportFailed) as e:
        placed(paper="A3")
    assert "larger than the work area" in e.value.errors[0]["message"]


@pytest.mark.parametrize("bad", [{"rotate": 45}, {"scale": 0}, {"margin": -1}, {"feed": 0}])
def test_bad_options_are_refused(bad):
    with pytest.raises(ImportFailed) as e:
        placed(**bad)
    assert e.value.status == 422


def test_gcode_placement_rotates_arcs(tmp_path):
    text = "G0 X10 Y10\nM3\nG2 X30 Y10 I10 J0 F600\nM5\n"   # upper half circle, r=10
    r = run_import(tmp_path, text, rotate=90)
    # Turned a quarter counter-clockwise in place: now the left half of the circle.
    assert r.bounds == pytest.approx({"min_x": 10, "min_y": 10, "max_x": 20, "max_y": 30},
                                     abs=1e-3)
    lines = r.program_path.read_text().splitlines()
    assert "G2 X20.000 Y30.000 I0.000 J10.000 F600" in lines
