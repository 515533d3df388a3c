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


def strokes_of(result):
    from tests.fixtures.imports import drawn_strokes, program_lines
    return drawn_strokes(program_lines(result))


# ---- masks ---------------------------------------------------------------------------

def test_a_shape_masked_away_entirely_is_not_drawn(tmp_path):
    r = imported(tmp_path, '<mask id="m"><rect width="100" height="100" fill="black"/></mask>'
                           '<rect x="10" y="10" width="20" height="20" fill="red" mask="url(#m)"/>'
                           '<line x1="50" y1="50" x2="60" y2="50" stroke="black"/>')
    assert r.stats["pen_down_mm"] == pytest.approx(10)


def test_a_partly_masked_shape_is_drawn_where_the_mask_is_visible(tmp_path):
    # the white half of the mask shows the left 10 mm of a 20 mm line; a black shape
    # painted over the white one hides again
    r = imported(tmp_path, '<mask id="m" maskUnits="userSpaceOnUse" x="0" y="0" width="100" '
                           'height="100"><rect width="50" height="100" fill="white"/>'
                           '<rect x="0" y="0" width="45" height="30" fill="#000"/></mask>'
                           '<line x1="40" y1="50" x2="60" y2="50" stroke="black" '
                           'mask="url(#m)"/>'
                           '<line x1="40" y1="20" x2="60" y2="20" stroke="black" '
                           'mask="url(#m)"/>')
    assert r.stats["pen_down_mm"] == pytest.approx(10 + 5, abs=0.01)


def test_a_mask_region_is_ten_percent_around_the_bounding_box_by_default(tmp_path):
    white = '<mask id="m"><rect width="100" height="100" fill="white"/></mask>'
    r = imported(tmp_path, white + '<line x1="10" y1="50" x2="90" y2="60" stroke="black" '
                                   'mask="url(#m)"/>')
    assert r.stats["pen_down_mm"] == pytest.approx((80 ** 2 + 10 ** 2) ** 0.5, abs=0.01)
    # a box of no height has no region: the masked line is not drawn (as Chromium)
    with pytest.raises(ImportFailed):
        imported(tmp_path, white + '<line x1="10" y1="50" x2="90" y2="50" stroke="black" '
                                   'mask="url(#m)"/>')


# ---- markers -------------------------------------------------------------------------

ARROW = ('<marker id="a" viewBox="0 0 10 10" refX="10" refY="5" markerWidth="4" '
         'markerHeight="4" orient="auto" markerUnits="strokeWidth">'
         '<path d="M0 0 L10 5 L0 10" fill="none" stroke="black"/></marker>')


def test_markers_are_drawn_at_the_vertices_turned_and_scaled(tmp_path):
    r = imported(tmp_path, f'<defs>{ARROW}</defs><path d="M10 50 L50 50 L50 90" '
                           'stroke="black" stroke-width="2" fill="none" marker-end="url(#a)"/>')
    # the path (80 mm) and one arrow head at the end: 4 x 2 = 8 mm wide, tip on the
    # vertex, pointing along the last segment (down the page: -y after the flip)
    strokes = strokes_of(r)
    head = [s for s in strokes if len(s) == 3 and s[0][1] == pytest.approx(18, abs=0.01)]
    assert len(head) == 1 and len(strokes) == 2
    (x0, y0), tip, (x1, y1) = head[0]
    assert tip == pytest.approx((50, 10), abs=0.01)
    assert y0 == pytest.approx(18, abs=0.01) and y1 == pytest.approx(18, abs=0.01)
    assert abs(x1 - x0) == pytest.approx(8, abs=0.01)


def test_marker_start_mid_end_and_fixed_orient_user_space_units(tmp_path):
    dot = ('<marker id="d" markerWidth="4" markerHeight="4" refX="2" refY="2" '
           'markerUnits="userSpaceOnUse" orient="45deg"><path d="M1 2 L3 2" stroke="red"/>'
           '</marker>')
    r = imported(tmp_path, f'<defs>{dot}</defs><polyline points="10 10 20 10 30 10 40 10" '
                           'fill="none" stroke="black" stroke-width="3" marker="url(#d)"/>')
    ticks = [s for s in strokes_of(r) if len(s) == 2 and abs(s[0][0] - s[1][0]) < 2]
    assert len(ticks) == 4           # start, two mid vertices, end; 2 mm at 45 degrees
    for (xa, ya), (xb, yb) in ticks:
        assert abs(xb - xa) == pytest.approx(2 ** 0.5, abs=0.01)
        assert abs(yb - ya) == pytest.approx(2 ** 0.5, abs=0.01)


def test_auto_start_reverse_turns_the_start_marker_back(tmp_path):
    mk = ARROW.replace('orient="auto"', 'orient="auto-start-reverse"')
    r = imported(tmp_path, f'<defs>{mk}</defs><line x1="20" y1="50" x2="80" y2="50" '
                           'stroke="black" marker-start="url(#a)" marker-end="url(#a)"/>')
    heads = sorted((s for s in strokes_of(r) if len(s) == 3), key=lambda s: s[1][0])
    assert [h[1][0] for h in heads] == pytest.approx([20, 80], abs=0.01)
    assert heads[0][0][0] > 20 and heads[1][0][0] < 80     # both point outwards


# ---- clip paths ----------------------------------------------------------------------

def test_text_in_a_clip_path_clips_to_its_glyphs(tmp_path):
    r = imported(tmp_path, '<clipPath id="c"><text x="10" y="60" font-size="40">I</text>'
                           '</clipPath><g clip-path="url(#c)">' + "".join(
                               f'<line x1="0" y1="{y}" x2="100" y2="{y}" stroke="black"/>'
                               for y in range(20, 80, 2)) + '</g>')
    assert 0 < r.stats["pen_down_mm"] < 30 * 10     # only across the I's stem
    assert r.bounds["max_x"] - r.bounds["min_x"] < 10


def test_a_clip_path_child_with_its_own_clip_path_is_cut_by_it(tmp_path):
    r = imported(tmp_path, '<clipPath id="inner"><rect x="0" y="0" width="30" height="100"/>'
                           '</clipPath><clipPath id="c"><rect x="10" y="0" width="80" '
                           'height="100" clip-path="url(#inner)"/></clipPath>'
                           '<line x1="0" y1="50" x2="100" y2="50" stroke="black" '
                           'clip-path="url(#c)"/>')
    assert r.stats["pen_down_mm"] == pytest.approx(20, abs=0.01)


# ---- use, CSS, shapes, paths, text ---------------------------------------------------

def test_use_width_and_height_size_a_referenced_svg(tmp_path):
    r = imported(tmp_path, '<defs><svg id="s" viewBox="0 0 10 10" width="10" height="10">'
                           '<rect width="10" height="10" fill="none" stroke="black"/></svg>'
                           '</defs><use href="#s" x="10" y="10" width="40" height="40"/>')
    assert r.stats["pen_down_mm"] == pytest.approx(160, abs=0.01)


def test_css_important_and_the_transform_property(tmp_path):
    r = imported(tmp_path, '<style>.a { stroke: black !important; '
                           'transform: translate(10px, 10px) rotate(90deg) }</style>'
                           '<line class="a" x1="0" y1="0" x2="20" y2="0" style="stroke: none"'
                           ' transform="scale(3)"/>')
    assert r.stats["pen_down_mm"] == pytest.approx(20)
    assert (r.bounds["min_x"], r.bounds["max_x"]) == pytest.approx((10, 10))


def test_an_ellipse_with_one_radius_is_a_circle(tmp_path):
    r = imported(tmp_path, '<ellipse cx="50" cy="50" rx="10" fill="none" stroke="black"/>'
                           '<ellipse cx="50" cy="50" ry="20" rx="auto" fill="none" '
                           'stroke="black"/>')
    assert r.stats["pen_down_mm"] == pytest.approx(2 * 3.14159 * 30, rel=0.01)


def test_path_data_is_drawn_up_to_its_first_error_with_a_warning(tmp_path):
    r = imported(tmp_path, '<path id="p" d="M10 10 L20 10 L20 x20 L30 30" stroke="black" '
                           'fill="none"/><polyline id="q" points="10 50 20 50 30 oops" '
                           'stroke="black" fill="none"/>')
    assert r.stats["pen_down_mm"] == pytest.approx(20)
    messages = [w["message"] for w in r.warnings]
    assert any('<path id="p">' in m and "unexpected 'x'" in m for m in messages)
    assert any('<polyline id="q">' in m and "unexpected 'o'" in m for m in messages)


def test_the_redos_path_of_issue_32_imports_at_once(tmp_path):
    import time
    d = "M0 0" + "L10.5 10.5" * 40 + "A1 1 0 0 1 2 2"
    start = time.process_time()
    r = imported(tmp_path, f'<path stroke="black" fill="none" d="{d}"/>', fill="outline")
    assert time.process_time() - start < 1.0
    assert r.stats["pen_down_mm"] > 0


def test_nested_em_and_percent_font_sizes_compound(tmp_path):
    def height(body: str) -> float:
        r = imported(tmp_path, body)
        return r.bounds["max_y"] - r.bounds["min_y"]

    plain = height('<text x="10" y="50" font-size="20">H</text>')
    nested = height('<g font-size="40"><text x="10" y="50" font-size="0.5em">H</text></g>')
    percent = height('<g style="font-size: 10px"><g font-size="400%"><text x="10" y="50" '
                     'font-size="50%">H</text></g></g>')
    assert nested == pytest.approx(plain, rel=1e-6) and percent == pytest.approx(plain, rel=1e-6)


def test_glyphs_outside_the_font_are_named_greek_drawn_from_the_greek_set(tmp_path):
    r = imported(tmp_path, '<text id="t" x="10" y="50" font-size="10">Ωé Ж</text>')
    messages = " ".join(w["message"] for w in r.warnings)
    assert "'Ж' U+0416" in messages and "drawn as '?'" in messages
    assert "'é' U+00E9" in messages and "without their accents" in messages
    assert "Ω" not in messages.replace("'Ωé Ж'", "")


def test_outlines_are_drawn_only_for_shapes_with_an_area(tmp_path):
    # a line never fills; a path along one line encloses nothing; a figure eight does
    r = imported(tmp_path, '<line x1="0" y1="5" x2="50" y2="5"/>'
                           '<path d="M 10 10 L 30 10 L 20 10"/>'
                           '<path d="M 10 50 L 30 70 L 30 50 L 10 70 Z"/>')
    assert r.stats["pen_down_mm"] == pytest.approx(2 * 20 + 2 * 20 * 2 ** 0.5, abs=0.002)


def test_the_preview_carries_the_outlines_of_filled_shapes_placed(tmp_path):
    import json
    r = imported(tmp_path, '<rect x="10" y="10" width="20" height="10" fill="red"/>'
                           '<rect x="50" y="50" width="10" height="10" fill="none" '
                           'stroke="black"/>', dx=5)
    fills = json.loads(r.preview_path.read_text())["fills"]
    assert len(fills) == 1                                   # the stroked one is not filled
    xs, ys = zip(*fills[0], strict=True)
    assert (min(xs), max(xs), min(ys), max(ys)) == pytest.approx((15, 35, 80, 90))
