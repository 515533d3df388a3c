"""SVG text `rotate` lists: each glyph turned by its angle (degrees, clockwise in SVG's
y-down space) about its own start point; the last angle of a list applies to the rest
of that element's characters; a tspan's own list wins for its characters; a list with
what is not a number skips the text with a warning naming it."""

from __future__ import annotations

import pytest
from plotbridge.importing import svgtext

from tests.fixtures.imports import drawn_strokes, program_lines, run_import
from tests.fixtures.text_glyphs import HEAD, I_ADVANCE, glyph_poses, turned


def test_each_glyph_is_the_upright_glyph_turned_about_its_own_start_point():
    def chars(angles: list[float | None]) -> list[svgtext.Char]:
        # one text chunk, placed by the first character's x and y
        return [svgtext.Char(ch, 0, 20.0, 1.5, 0.0, "middle", x=x, y=x and 40.0, rotate=a)
                for ch, x, a in zip("FRL", (10.0, None, None), angles, strict=True)]

    angles = [30.0, -75.5, 180.0]
    upright = svgtext.layout("futural", chars([None, None, None]))[0]
    got = svgtext.layout("futural", chars(angles))[0]
    # the start points: the chunk's pen positions, shifted left by half its width
    k = 20.0 / svgtext.EM_UNITS
    widths = [svgtext.glyph("futural", ch).width * k + 1.5 for ch in "FRL"]
    starts = [10.0 - sum(widths) / 2 + sum(widths[:n]) for n in range(3)]
    per_glyph = [len(svgtext.glyph("futural", ch).strokes) for ch in "FRL"]
    assert len(got) == len(upright) == sum(per_glyph) == 8
    n = 0
    for start, angle, count in zip(starts, angles, per_glyph, strict=True):
        for _ in range(count):
            assert got[n] == pytest.approx(turned(upright[n], (start, 40.0), angle))
            n += 1


def test_a_rotate_list_turns_each_glyph_and_leaves_the_advance_alone(tmp_path):
    got = glyph_poses(tmp_path, '<text x="10" y="50" rotate="90 -45 30.5">III</text>')
    assert got == [(10, 50, 90), (10 + I_ADVANCE, 50, -45), (10 + 2 * I_ADVANCE, 50, 30.5)]


def test_the_last_angle_applies_to_the_rest_of_the_glyphs(tmp_path):
    got = glyph_poses(tmp_path, '<text x="10 40" y="50" rotate="0,20">IIII</text>')
    assert got == [(10, 50, 0), (40, 50, 20), (40 + I_ADVANCE, 50, 20),
                   (40 + 2 * I_ADVANCE, 50, 20)]


def test_a_tspans_own_list_wins_for_its_glyphs_and_the_parents_resumes_after(tmp_path):
    body = ('<text x="10" y="50" rotate="5 6 7 8 9">I<tspan rotate="90">I'
            '<tspan>I</tspan></tspan>I<tspan>I</tspan>I</text>')
    # the tspan's one angle covers its two glyphs (its child's included); the text's
    # list resumes at its fourth character and its last angle covers the rest
    got = [angle for _, _, angle in glyph_poses(tmp_path, body)]
    assert got == [5, 90, 90, 8, 9, 9]


def test_glyphs_outside_any_rotate_list_stay_upright(tmp_path):
    body = '<text x="10" y="50">I<tspan rotate="45">I</tspan>I</text>'
    got = [angle for _, _, angle in glyph_poses(tmp_path, body)]
    assert got == [0, 45, 0]


@pytest.mark.parametrize("bad", ["10 abc", "10deg", "5, nan", "1e999", "1_0"])
def test_a_bad_rotate_list_skips_the_text_with_a_warning(tmp_path, bad):
    doc = (HEAD + f'<text id="t" x="10" y="40">I<tspan rotate="{bad}">II</tspan></text>'
           '<line x1="0" y1="0" x2="10" y2="0" stroke="black"/></svg>')
    r = run_import(tmp_path, doc, "d.svg")
    word = bad.split()[-1].lstrip(",")
    assert any('<text id="t"> skipped' in w["message"] and "rotate" in w["message"]
               and f"'{word}' is not a number" in w["message"] for w in r.warnings), r.warnings
    assert len(drawn_strokes(program_lines(r))) == 1   # the line, not the text
