"""SVG text placed glyph by glyph: x, y, dx and dy lists on <text> and <tspan> (a
descendant's own values win, an ancestor's fill in the rest), each absolute position
starting a text chunk that its anchor shifts."""

from __future__ import annotations

from tests.fixtures.imports import run_import
from tests.fixtures.text_glyphs import HEAD, I_ADVANCE, glyph_poses


def glyph_origins(tmp_path, body: str) -> list[tuple[float, float]]:
    """Where each "I" was set, upright: its origin (x, baseline y) in SVG user units."""
    poses = glyph_poses(tmp_path, body)
    assert all(angle == 0 for _, _, angle in poses), poses
    return [(x, y) for x, y, _ in poses]


def test_x_and_y_lists_place_each_glyph(tmp_path):
    got = glyph_origins(tmp_path, '<text x="10 30 50" y="40 50 60">III</text>')
    assert got == [(10, 40), (30, 50), (50, 60)]


def test_a_list_shorter_than_the_text_leaves_the_rest_flowing(tmp_path):
    got = glyph_origins(tmp_path, '<text x="10 30" y="40">III</text>')
    assert got == [(10, 40), (30, 40), (30 + I_ADVANCE, 40)]


def test_dx_and_dy_lists_shift_each_glyph_and_all_after_it(tmp_path):
    got = glyph_origins(tmp_path, '<text x="10" y="40" dx="0 5 5" dy="1 0 -3">III</text>')
    assert got == [(10, 41), (10 + I_ADVANCE + 5, 41), (10 + 2 * I_ADVANCE + 10, 38)]


def test_a_tspans_own_values_win_and_its_ancestors_fill_in(tmp_path):
    body = ('<text x="10 20 30 40" y="40">I<tspan x="70" dy="0 5">II</tspan>I'
            '<tspan>I</tspan></text>')
    # characters 0..4: text x gives 10, 20, 30, 40 and nothing for the fifth; the first
    # tspan's own x=70 replaces 20 for its first character, its dy lowers its second
    got = glyph_origins(tmp_path, body)
    assert got == [(10, 40), (70, 40), (30, 45), (40, 45), (40 + I_ADVANCE, 45)]


def test_each_absolute_position_starts_a_chunk_its_anchor_shifts(tmp_path):
    got = glyph_origins(tmp_path, '<text x="20 60" y="40" text-anchor="middle">III</text>')
    # chunks "I" at 20 and "II" at 60, each centred on its position
    assert got == [(20 - I_ADVANCE / 2, 40), (60 - I_ADVANCE, 40), (60, 40)]


def test_lengths_with_units_and_percentages(tmp_path):
    got = glyph_origins(tmp_path, '<text x="10%, 0.5in" y="40px">II</text>')
    assert got == [(10, 40), (48, 40)]


def test_a_bad_position_list_skips_the_text_with_a_warning(tmp_path):
    doc = (HEAD + '<text id="t" x="10 wide" y="40">II</text>'
           '<line x1="0" y1="0" x2="10" y2="0" stroke="black"/></svg>')
    r = run_import(tmp_path, doc, "d.svg")
    assert any('<text id="t"> skipped' in w["message"] and "wide" in w["message"]
               for w in r.warnings)
