"""The importer resolves SVG text `rotate` lists as Chromium does: for each document,
the angle each glyph is drawn at equals Chromium's getRotationOfChar for that
character (the fonts differ, so only the angles are compared)."""

from __future__ import annotations

import pytest

from tests.fixtures.text_glyphs import HEAD, glyph_poses

pytestmark = pytest.mark.browser

BODIES = [
    '<text x="10" y="50" rotate="90 -45 30.5">III</text>',
    '<text x="10" y="50" rotate="0,20">IIII</text>',
    # a tspan's own list, its child without one, the text's list resuming after it
    '<text x="10" y="50" rotate="5 6 7 8 9">I<tspan rotate="90">I<tspan>I</tspan></tspan>'
    'I<tspan>I</tspan>I</text>',
    '<text x="10" y="50">I<tspan rotate="45">I</tspan>I</text>',
    '<text x="10" y="50" rotate="10">I<tspan rotate="45 50">I</tspan>I</text>',
]

ANGLES = """svg => {
  document.body.innerHTML = svg;
  const text = document.querySelector("text");
  return Array.from({length: text.getNumberOfChars()}, (_, k) => text.getRotationOfChar(k));
}"""


@pytest.fixture(scope="module")
def page(browser):
    page = browser.new_page()
    yield page
    page.close()


@pytest.mark.parametrize("body", BODIES)
def test_glyph_angles_match_chromium(page, tmp_path, body):
    chromium = page.evaluate(ANGLES, HEAD + body + "</svg>")
    ours = [angle for _, _, angle in glyph_poses(tmp_path, body)]
    assert ours == pytest.approx(chromium)
