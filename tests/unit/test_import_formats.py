"""Format detection, text checks, SVG, coordinates lists and test patterns."""

from __future__ import annotations

import itertools
import json
import math

import pytest
from plotbridge.importing import (
    PATTERNS,
    ImportFailed,
    ImportOptions,
    MachineProfile,
    import_pattern,
)

from tests.fixtures.imports import drawn_strokes, program_lines, run_import

SVG_HEAD = '<svg xmlns="http://www.w3.org/2000/svg" '


def refused(tmp_path, text, name="x.gcode", **options) -> ImportFailed:
    with pytest.raises(ImportFailed) as e:
        run_import(tmp_path, text, name, **options)
    return e.value


def test_binary_empty_and_unknown_files_are_refused(tmp_path):
    assert refused(tmp_path, b"\x89PNG\r\n\x1a\n\x00\x00").status == 415
    e = refused(tmp_path, b"   \n\n")
    assert e.status == 422
    assert "empty" in e.errors[0]["message"]
    e = refused(tmp_path, "hello world\nthis is prose\n", "notes.doc")
    assert e.status == 415
    assert "unknown format" in e.errors[0]["message"]
    assert refused(tmp_path, "<html><body>hi</body></html>", "page.html").status == 415


def test_latin1_gcode_is_read(tmp_path):
    r = run_import(tmp_path, "(caf\xe9 plan)\nG0 X1 Y1\nM3\nG1 X2 F100\n".encode("latin-1"))
    assert "G1 X2.000 Y1.000 F100" in program_lines(r)


def test_format_is_detected_by_content(tmp_path):
    svg = (SVG_HEAD + 'width="10mm" height="10mm">'
           '<line x1="1" y1="1" x2="5" y2="1" stroke="k"/></svg>')
    assert run_import(tmp_path, svg, "drawing.txt").format == "svg"
    assert run_import(tmp_path, "G0 X1 Y1\nM3\nG1 X5 F100\n", "upload.bin").format == "gcode"
    assert run_import(tmp_path, "1\n1\n5\n1\n", "points").format == "coords"


def test_svg_units_viewbox_transform_and_y_flip(tmp_path):
    svg = (SVG_HEAD + 'width="100mm" height="50mm" viewBox="0 0 200 100">'
           '<g transform="translate(20,10)"><rect x="0" y="0" width="20" height="10" '
           'fill="none" stroke="black"/></g></svg>')
    r = run_import(tmp_path, svg, "d.svg")
    # 0.5 mm per user unit; page y 5..10 mm is 40..45 mm from the front of a 50 mm page.
    assert r.bounds == pytest.approx({"min_x": 10, "min_y": 40, "max_x": 20, "max_y": 45})
    assert r.stats["pen_lifts"] == 1
    assert r.stats["pen_down_mm"] == pytest.approx(30.0)


def test_svg_not_mirrored(tmp_path):
    # An "L": a vertical bar at the left going down the page, then a foot to the right at
    # the bottom. On the plotter the foot must be at the front (low y), on the right.
    svg = (SVG_HEAD + 'width="20mm" height="20mm" viewBox="0 0 20 20">'
           '<polyline points="2,2 2,18 10,18" fill="none" stroke="black"/></svg>')
    r = run_import(tmp_path, svg, "l.svg")
    (stroke,) = drawn_strokes(program_lines(r))
    pts = sorted(stroke)
    assert pts[0] == pytest.approx((2.0, 2.0)) and pts[-1] == pytest.approx((10.0, 2.0))
    assert (2.0, 18.0) in [tuple(round(v, 3) for v in p) for p in stroke]


def test_svg_curves_are_flattened_within_tolerance(tmp_path):
    svg = (SVG_HEAD + 'width="100mm" height="100mm" viewBox="0 0 100 100">'
           '<circle cx="50" cy="50" r="30" fill="none" stroke="black"/>'
           '<path d="M 10 90 C 30 60 70 60 90 90" fill="none" stroke="black"/>'
           '<ellipse cx="50" cy="20" rx="20" ry="5" stroke="black"/></svg>')
    r = run_import(tmp_path, svg, "c.svg")
    strokes = drawn_strokes(program_lines(r))
    circle = max(strokes, key=lambda s: max(math.hypot(x - 50, y - 50) for x, y in s)
                 if all(25 < math.hypot(x - 50, y - 50) < 35 for x, y in s) else 0)
    radii = [math.hypot(x - 50, y - 50) for x, y in circle]
    assert max(radii) == pytest.approx(30, abs=0.002)
    # Chord midpoints stay within the tolerance (0.02 mm) plus rounding.
    mids = [math.hypot((a[0] + b[0]) / 2 - 50, (a[1] + b[1]) / 2 - 50)
            for a, b in itertools.pairwise(circle)]
    assert min(mids) > 30 - 0.025
    assert r.stats["pen_down_mm"] == pytest.approx(2 * math.pi * 30 + 96.9 + 87.6, rel=0.02)


def test_svg_layers_by_label_id_and_colour(tmp_path):
    svg = (SVG_HEAD + 'xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape" '
           'width="100mm" height="100mm" viewBox="0 0 100 100">'
           '<g id="g1" inkscape:label="Outline"><line x1="10" y1="10" x2="20" y2="10" '
           'stroke="black"/></g>'
           '<g id="g2"><line x1="10" y1="50" x2="40" y2="50" stroke="#ff0000"/></g></svg>')
    assert run_import(tmp_path, svg, "a.svg", layers=["Outline"]).stats["pen_down_mm"] == 10
    assert run_import(tmp_path, svg, "a.svg", layers=["g2"]).stats["pen_down_mm"] == 30
    assert run_import(tmp_path, svg, "a.svg", layers=["red"]).stats["pen_down_mm"] == 30
    assert run_import(tmp_path, svg, "a.svg").stats["pen_down_mm"] == 40
    e = refused(tmp_path, svg, "a.svg", layers=["nope"])
    assert "Outline" in e.errors[0]["message"]


def test_svg_nested_entities_are_refused(tmp_path):
    bomb = ('<?xml version="1.0"?><!DOCTYPE lolz [<!ENTITY lol "lol">'
            '<!ENTITY lol2 "&lol;&lol;&lol;&lol;">]>' + SVG_HEAD + '><text>&lol2;</text></svg>')
    e = refused(tmp_path, bomb, "bomb.svg")
    assert e.status == 422
    assert "refers to another entity" in e.errors[0]["message"]
    e = refused(tmp_path, SVG_HEAD + '><line x1="0"', "broken.svg")
    assert "well-formed" in e.errors[0]["message"]


def test_svg_without_shapes_is_refused(tmp_path):
    e = refused(tmp_path, SVG_HEAD + 'width="10mm" height="10mm"></svg>', "empty.svg")
    assert "no visible shapes" in e.errors[0]["message"]


def test_coordinates_list(tmp_path):
    r = run_import(tmp_path, "10\n10\n20\n10\n20\n30\n", "plot.txt")
    assert r.format == "coords"
    assert drawn_strokes(program_lines(r)) == [[(10.0, 10.0), (20.0, 10.0), (20.0, 30.0)]]
    lines = program_lines(r)
    assert lines[3:5] == ["G0 X10.000 Y10.000", "M3"]


def test_malformed_coordinates_list(tmp_path):
    e = refused(tmp_path, "10\n10\nabc\n20\n", "plot.txt")
    assert e.errors == [{"line": 3, "message": "expected one number, found 'abc'"}]
    e = refused(tmp_path, "10\n10\n20\n", "plot.txt")
    assert "odd count" in e.errors[0]["message"]


@pytest.mark.parametrize("name", sorted(PATTERNS))
def test_patterns(tmp_path, name):
    r = import_pattern(name, tmp_path, ImportOptions(paper="A5-landscape"), MachineProfile())
    assert r.format == "pattern"
    assert r.lines_total > 5 and r.estimate_s > 0
    preview = json.loads(r.preview_path.read_text())
    assert preview["bounds"] == r.bounds
    # Centred on the A5 landscape sheet (210 x 148 mm).
    assert (r.bounds["min_x"] + r.bounds["max_x"]) / 2 == pytest.approx(105, abs=0.01)
    assert (r.bounds["min_y"] + r.bounds["max_y"]) / 2 == pytest.approx(74, abs=0.01)


def test_radial_pattern_covers_all_octants(tmp_path):
    r = import_pattern("radial", tmp_path, ImportOptions(), MachineProfile())
    octants = set()
    for stroke in drawn_strokes(program_lines(r)):
        for x, y in stroke:
            if math.hypot(x - 50, y - 50) > 10:
                octants.add(int(math.atan2(y - 50, x - 50) // (math.pi / 4)) % 8)
    assert octants == set(range(8))


def test_unknown_pattern(tmp_path):
    with pytest.raises(ImportFailed) as e:
        import_pattern("spiral", tmp_path, ImportOptions(), MachineProfile())
    assert e.value.status == 422
