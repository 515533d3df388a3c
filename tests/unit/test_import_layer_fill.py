"""Hatch fill per layer, group or fill colour: the `layer_fill` field's checks and what
each layer's own spacing, angle and on/off do to its strokes."""

from __future__ import annotations

import itertools
import json

import pytest
from plotbridge.importing.fields import import_fields, layer_fills

from tests.fixtures.imports import drawn_strokes, program_lines, run_import

HEAD = ('<svg xmlns="http://www.w3.org/2000/svg" '
        'xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape" '
        'width="100mm" height="100mm" viewBox="0 0 100 100">')
# Two layers of one filled-only 20 x 10 mm rectangle each, and two rectangles outside
# any layer (they go by fill colour).
DOC = (HEAD
       + '<g inkscape:groupmode="layer" inkscape:label="A">'
         '<rect x="10" y="10" width="20" height="10" fill="black"/></g>'
       + '<g inkscape:groupmode="layer" inkscape:label="B">'
         '<rect x="50" y="10" width="20" height="10" fill="black"/></g>'
       + '<rect x="10" y="50" width="20" height="10" fill="#ff0000"/>'
       + '<rect x="50" y="50" width="20" height="10" fill="blue"/></svg>')


def imported(tmp_path, table: dict, **options):
    fields = import_fields({"layer_fill": json.dumps(table)})
    return run_import(tmp_path, DOC, "d.svg", **options, **fields)


def layer_strokes(result, name: str) -> list[list[tuple[float, float]]]:
    lay = next(lay for lay in result.layers if lay["name"] == name)
    lines = program_lines(result)[lay["first_line"] - 1:lay["last_line"]]
    return drawn_strokes(lines)


def directions(strokes) -> set[str]:
    """'h' and 'v' for the long segments of the strokes."""
    out = set()
    for s in strokes:
        for (x0, y0), (x1, y1) in itertools.pairwise(s):
            if abs(x1 - x0) > 5:
                out.add("h")
            if abs(y1 - y0) > 5:
                out.add("v")
    return out


def test_each_layer_and_colour_gets_its_own_hatch(tmp_path):
    r = imported(tmp_path, {"A": {"hatch_spacing": 1, "hatch_angle": 0},
                            "B": {"hatch_spacing": 2, "hatch_angle": 90},
                            "#ff0000": {"fill": "none"}},
                 fill="hatch", hatch_spacing=5, hatch_angle=0)
    by_name = {lay["name"]: lay for lay in r.layers}
    assert list(by_name) == ["A", "B", "#0000ff"]       # red: fill off, not drawn
    # A: 10 rows 1 mm apart, 20 mm long, joined by 1 mm links
    assert by_name["A"]["pen_down_mm"] == pytest.approx(10 * 20 + 9 * 1, rel=0.02)
    assert directions(layer_strokes(r, "A")) == {"h"}
    # B: 10 columns 2 mm apart, 10 mm long, joined by 2 mm links
    assert by_name["B"]["pen_down_mm"] == pytest.approx(10 * 10 + 9 * 2, rel=0.02)
    assert directions(layer_strokes(r, "B")) == {"v"}
    # the blue rectangle has the import's own hatch: 2 rows 5 mm apart
    assert by_name["#0000ff"]["pen_down_mm"] == pytest.approx(2 * 20 + 5, rel=0.02)


def test_a_layer_can_hatch_when_the_import_does_not(tmp_path):
    r = imported(tmp_path, {"B": {"hatch_spacing": 1, "hatch_cross": True}}, fill="none")
    assert [lay["name"] for lay in r.layers] == ["B"]
    # cross-hatch at 45 and 135 degrees: both directions, about twice one hatch's ink
    one = imported(tmp_path, {"B": {"hatch_spacing": 1}}, fill="none")
    assert r.stats["pen_down_mm"] > 1.8 * one.stats["pen_down_mm"]


def test_an_entry_that_matches_nothing_is_a_warning(tmp_path):
    r = imported(tmp_path, {"A": {}, "Nope": {"hatch_spacing": 2}, "green": {}})
    messages = [w["message"] for w in r.warnings]
    assert any("'Nope' matches no layer" in m for m in messages)
    assert any("'green' matches no layer" in m for m in messages)
    assert not any("'A'" in m for m in messages)


def test_a_group_id_inside_a_layer_wins_over_the_layer(tmp_path):
    doc = (HEAD + '<g inkscape:groupmode="layer" inkscape:label="L">'
           '<g id="dense"><rect x="10" y="10" width="20" height="10" fill="black"/></g>'
           '<rect x="50" y="10" width="20" height="10" fill="black"/></g></svg>')
    fields = import_fields({"layer_fill": json.dumps({"L": {"hatch_spacing": 5,
                                                            "hatch_angle": 0},
                                                      "dense": {"hatch_spacing": 1,
                                                                "hatch_angle": 0}})})
    r = run_import(tmp_path, doc, "d.svg", **fields)
    dense, sparse = 10 * 20 + 9, 2 * 20 + 5
    assert r.stats["pen_down_mm"] == pytest.approx(dense + sparse, rel=0.02)


@pytest.mark.parametrize("raw, words", [
    ("{", "layer_fill: not JSON"),
    ("[1, 2]", "expected a JSON object"),
    ('{"A": 3}', "layer_fill: 'A': expected an object"),
    ('{"A": {"spacing": 1}}', "layer_fill: 'A': unknown setting 'spacing'"),
    ('{"A": {"hatch_spacing": 0}}', "layer_fill: 'A': hatch_spacing: must be between 0.05"),
    ('{"A": {"hatch_spacing": "wide"}}', "hatch_spacing: expected a number, got 'wide'"),
    ('{"A": {"hatch_angle": true}}', "hatch_angle: expected a number, got true"),
    ('{"A": {"hatch_angle": 1e999}}', "hatch_angle: must be between"),
    ('{"A": {"fill": "solid"}}', "fill: expected one of none, outline, hatch"),
    ('{"A": {"hatch_cross": "maybe"}}', "hatch_cross: expected true or false"),
    ('{" ": {}}', "name is empty"),
    ("[" * 50_000 + "]" * 50_000, "longer than 65536 characters"),
    ("[" * 30_000 + "]" * 30_000, "nested too deeply"),
    (json.dumps({f"L{n}": {} for n in range(300)}), "at most 256 layers"),
])
def test_bad_values_are_refused_naming_the_entry(raw, words):
    with pytest.raises(ValueError) as e:
        import_fields({"layer_fill": raw})
    assert words in str(e.value)


def test_good_values_are_normalized():
    assert layer_fills('{"A": {"fill": "HATCH", "hatch_spacing": "1.5", "hatch_cross": true},'
                       ' "#f00": {"hatch_angle": -30}}') == {
        "A": {"fill": "hatch", "hatch_spacing": 1.5, "hatch_cross": True},
        "#f00": {"hatch_angle": -30.0}}
    assert layer_fills("") == {}
