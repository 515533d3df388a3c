"""SVG import: refusals (entities, nothing visible), layers, warnings naming elements,
options (fills, font, page clipping). How the strokes look is compared with Chromium
in tests/browser/test_svg_render.py."""

from __future__ import annotations

import pytest
from plotbridge.importing import ImportFailed

from tests.fixtures.imports import program_lines, run_import

HEAD = ('<svg xmlns="http://www.w3.org/2000/svg" '
        'xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape" '
        'width="100mm" height="100mm" viewBox="0 0 100 100">')


def refused(tmp_path, text: str, **options) -> ImportFailed:
    with pytest.raises(ImportFailed) as e:
        run_import(tmp_path, text, "d.svg", **options)
    assert e.value.status == 422
    return e.value


@pytest.mark.parametrize("decl, words", [
    ('<!ENTITY x SYSTEM "file:///etc/passwd">', "external entity"),
    ('<!ENTITY x PUBLIC "-//x//y" "http://example.org/x">', "external entity"),
    ('<!ENTITY % p "x">', "parameter entity"),
    ('<!ENTITY a "1"><!ENTITY x "&a;&a;">', "refers to another entity"),
    ('<!ENTITY x "<g/>">', "markup"),
])
def test_unsafe_entities_are_refused(tmp_path, decl, words):
    doc = f'<?xml version="1.0"?><!DOCTYPE svg [{decl}]>{HEAD}<text>&x;</text></svg>'
    assert words in refused(tmp_path, doc).errors[0]["message"]


def test_entity_expansion_is_bounded(tmp_path):
    big = "x" * 10_000
    doc = (f'<!DOCTYPE svg [<!ENTITY b "{big}">]>{HEAD}<desc>' + "&b;" * 1000 + "</desc>"
           '<line x1="0" y1="0" x2="9" y2="0" stroke="black"/></svg>')
    assert "expansion" in refused(tmp_path, doc).errors[0]["message"]


def test_plain_text_entities_are_expanded(tmp_path):
    doc = ('<!DOCTYPE svg [<!ENTITY w "stroke:black;stroke-width:1">]>' + HEAD +
           '<line x1="10" y1="10" x2="40" y2="10" style="&w;"/></svg>')
    assert run_import(tmp_path, doc, "d.svg").stats["pen_down_mm"] == pytest.approx(30)


def test_filled_shapes_are_outlined_by_default_hatched_or_left_out_on_request(tmp_path):
    doc = HEAD + '<rect x="10" y="10" width="20" height="10" fill="red"/></svg>'
    e = refused(tmp_path, doc, fill="none")
    assert "fill=outline or fill=hatch" in e.errors[0]["message"]
    r = run_import(tmp_path, doc, "d.svg")      # outline: as vpype and AxiDraw draw them
    assert r.stats["pen_down_mm"] == pytest.approx(60)
    hatch = run_import(tmp_path, doc, "d.svg", fill="hatch", hatch_spacing=1, hatch_angle=0)
    assert hatch.stats["pen_down_mm"] == pytest.approx(10 * 20 + 9 * 1, rel=0.02)  # joined
    assert hatch.stats["pen_lifts"] == 1
    cross = run_import(tmp_path, doc, "d.svg", fill="hatch", hatch_spacing=1, hatch_cross=True)
    assert cross.stats["pen_down_mm"] > 1.5 * hatch.stats["pen_down_mm"]
    none = HEAD + '<line x1="0" y1="0" x2="9" y2="0" stroke="black" opacity="0"/></svg>'
    assert "nothing visible" in refused(tmp_path, none).errors[0]["message"]


def test_inkscape_layers_in_order_and_optimized_within_each(tmp_path):
    layers = "".join(
        f'<g inkscape:groupmode="layer" inkscape:label="{name}">'
        + "".join(f'<line x1="{x}" y1="{y}" x2="{x + 5}" y2="{y}" stroke="{colour}"/>'
                  for x in (80, 10, 50) for y in (y0, y0 + 5)) + "</g>"
        for name, colour, y0 in (("outline", "black", 10), ("fill", "red", 40),
                                 ("detail", "blue", 70)))
    r = run_import(tmp_path, HEAD + layers + "</svg>", "d.svg")
    assert [lay["name"] for lay in r.layers] == ["outline", "fill", "detail"]
    assert [lay["colour"] for lay in r.layers] == ["#000000", "#ff0000", "#0000ff"]
    assert [lay["pen_down_mm"] for lay in r.layers] == [30, 30, 30]
    lines = program_lines(r)
    assert lines.count("M0") == 2
    # every stroke of a layer lies between its first and last line
    for lay in r.layers:
        ys = {float(ln.split()[2][1:]) for ln in lines[lay["first_line"] - 1:lay["last_line"]]
              if ln.startswith("G1")}
        assert len(ys) == 2 and max(ys) - min(ys) == pytest.approx(5)


def test_layers_by_colour_without_inkscape_layers(tmp_path):
    doc = HEAD + ''.join(f'<line x1="10" y1="{y}" x2="20" y2="{y}" stroke="{c}"/>'
                         for y, c in ((10, "red"), (20, "blue"), (30, "red"))) + "</svg>"
    r = run_import(tmp_path, doc, "d.svg")
    assert [(lay["name"], lay["strokes"]) for lay in r.layers] == [("#ff0000", 2),
                                                                   ("#0000ff", 1)]


def test_unreadable_elements_are_skipped_with_a_warning_naming_them(tmp_path):
    doc = (HEAD + '<rect id="bad" x="1" y="1" width="wide" height="5" stroke="black"/>'
           '<use id="loop" href="#loop"/><use href="#missing"/>'
           '<line x1="10" y1="10" x2="20" y2="10" stroke="black"/></svg>')
    r = run_import(tmp_path, doc, "d.svg")
    messages = [w["message"] for w in r.warnings]
    assert any('<rect id="bad">' in m and "wide" in m for m in messages)
    assert any('<use id="loop">' in m for m in messages)
    assert any("#missing" in m for m in messages)


def test_page_clipping_can_be_turned_off(tmp_path):
    doc = HEAD + '<line x1="50" y1="50" x2="150" y2="50" stroke="black"/></svg>'
    assert run_import(tmp_path, doc, "d.svg").stats["pen_down_mm"] == pytest.approx(50)
    kept = run_import(tmp_path, doc, "d.svg", clip_to_page=False)
    assert kept.stats["pen_down_mm"] == pytest.approx(100)


def test_text_font_choice_and_substitution_note(tmp_path):
    doc = HEAD + '<text x="10" y="50" font-family="Arial" font-size="10">Hello</text></svg>'
    sans = run_import(tmp_path, doc, "d.svg")
    script = run_import(tmp_path, doc, "d.svg", font="scripts")
    assert sans.stats["pen_down_mm"] != script.stats["pen_down_mm"]
    assert sans.substitutions == [{"element": "<text>", "text": "Hello", "font": "Arial",
                                   "substitute": "futural"}]
    assert any("Arial" in w["message"] for w in sans.warnings)
    hershey = HEAD + '<text x="10" y="50" font-family="Hershey Sans">Hi</text></svg>'
    assert run_import(tmp_path, hershey, "d.svg").substitutions == []


def test_text_path_follows_its_path(tmp_path):
    doc = (HEAD + '<path id="p" d="M 10 80 L 90 20" fill="none"/>'
           '<text font-size="8"><textPath href="#p">along</textPath></text></svg>')
    r = run_import(tmp_path, doc, "d.svg")
    b = r.bounds
    assert b["max_y"] - b["min_y"] > 10 and b["max_x"] - b["min_x"] > 10   # diagonal
