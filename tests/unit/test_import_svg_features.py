"""What authors draw (issue 32): page edges kept, percentage sizes, masks, markers, text
in clip paths, CSS transforms and !important, auto radii, broken path data drawn up to
its error, nested font sizes, glyphs outside the font; each against its documented
result (docs/INTERNALS.md, "Importer API"); tests/browser/test_svg_render.py lays the
same features over what Chromium draws."""

from __future__ import annotations

import pytest
from plotbridge.importing import ImportFailed

from tests.fixtures.imports import run_import

PAGE = ('<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm" '
        'viewBox="0 0 100 100">')


def svg(body: str, head: str = PAGE) -> str:
    return head + body + "</svg>"


def imported(tmp_path, body: str, head: str = PAGE, **options):
    return run_import(tmp_path, svg(body, head), "d.svg", **options)


def test_lines_on_the_page_edge_are_kept(tmp_path):
    r = imported(tmp_path, '<rect width="100" height="100" fill="none" stroke="black"/>')
    assert r.stats["pen_down_mm"] == pytest.approx(400)


def test_lines_a_rounding_error_outside_the_page_are_kept(tmp_path):
    r = imported(tmp_path, '<rect x="-0.0002" y="-0.0002" width="100.0004" height="100.0004" '
                           'fill="none" stroke="black"/>')
    assert r.stats["pen_down_mm"] == pytest.approx(400, abs=0.01)


def test_lines_further_outside_are_dropped_and_crossing_ones_cut_at_the_edge(tmp_path):
    r = imported(tmp_path, '<line x1="-5" y1="-0.05" x2="50" y2="-0.05" stroke="black"/>'
                           '<line x1="-5" y1="50" x2="50" y2="50" stroke="black"/>')
    assert r.stats["pen_down_mm"] == pytest.approx(50)
    assert r.bounds["min_x"] == 0


def test_a_root_sized_in_percent_without_a_viewbox_is_sized_by_its_drawing(tmp_path):
    head = '<svg xmlns="http://www.w3.org/2000/svg" width="100%" height="100%">'
    r = imported(tmp_path, '<line x1="10" y1="10" x2="106" y2="10" stroke="black"/>', head)
    assert r.stats["pen_down_mm"] == pytest.approx(25.4)


def test_a_root_sized_in_percent_with_a_viewbox_takes_the_viewbox_size(tmp_path):
    head = ('<svg xmlns="http://www.w3.org/2000/svg" width="100%" height="100%" '
            'viewBox="0 0 96 96">')
    r = imported(tmp_path, '<rect width="96" height="96" fill="none" stroke="black"/>', head)
    assert r.stats["pen_down_mm"] == pytest.approx(4 * 25.4)


def test_zero_size_is_still_refused(tmp_path):
    with pytest.raises(ImportFailed):
        imported(tmp_path, '<line x2="5" stroke="black"/>',
                 '<svg xmlns="http://www.w3.org/2000/svg" width="0" height="10">')
