"""The importer draws each SVG fixture as a real renderer does: Debian's Chromium
renders the fixture, the importer's plotted strokes are laid over it at the same scale
(10 px/mm), and they must agree within 1 px: every plotted point on ink, every inked
stroke pixel near a plotted stroke (fills only where they are hatched)."""

from __future__ import annotations

import base64
from pathlib import Path

import numpy as np
import pytest
from plotbridge.importing import ImportOptions, MachineProfile, import_file
from scipy.spatial import cKDTree

from tests.fixtures.imports import drawn_strokes, program_lines

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "svg"
PX_PER_MM = 10
PAGE = (60, 40)        # every fixture's page, mm
HALF_STROKE_PX = 1.0   # fixtures draw 0.2 mm wide strokes

RENDER = """async ([svg, w, h]) => {
  const img = new Image();
  img.src = "data:image/svg+xml;base64," + svg;
  await img.decode();
  const canvas = document.createElement("canvas");
  canvas.width = w; canvas.height = h;
  const ctx = canvas.getContext("2d");
  ctx.fillStyle = "white"; ctx.fillRect(0, 0, w, h);
  ctx.drawImage(img, 0, 0, w, h);
  const data = ctx.getImageData(0, 0, w, h).data;
  const out = new Uint8Array(w * h);
  for (let i = 0; i < w * h; i++) {
    const lum = 0.299 * data[4 * i] + 0.587 * data[4 * i + 1] + 0.114 * data[4 * i + 2];
    out[i] = lum < 128 ? 1 : 0;
  }
  let s = "";
  for (let i = 0; i < out.length; i += 8192) s += String.fromCharCode(...out.subarray(i, i + 8192));
  return btoa(s);
}"""


@pytest.fixture(scope="module")
def render_page(browser):
    page = browser.new_page()
    page.set_content("<html><body></body></html>")
    yield page
    page.close()


def ink(page, svg: Path) -> np.ndarray:
    """Centres (px) of the pixels Chromium inks for the SVG at 10 px/mm."""
    w, h = PAGE[0] * PX_PER_MM, PAGE[1] * PX_PER_MM
    b64 = base64.b64encode(svg.read_bytes()).decode()
    mask = np.frombuffer(base64.b64decode(page.evaluate(RENDER, [b64, w, h])), dtype=np.uint8)
    rows, cols = np.nonzero(mask.reshape(h, w))
    return np.column_stack([cols + 0.5, rows + 0.5])


def plotted(tmp_path: Path, svg: Path, **options) -> list[np.ndarray]:
    """The plotted strokes in page pixels (y down), sampled every 0.1 px."""
    result = import_file(svg, svg.name, tmp_path / svg.stem, ImportOptions(**options),
                         MachineProfile())
    out = []
    for stroke in drawn_strokes(program_lines(result)):
        p = np.asarray(stroke, dtype=float)
        p = np.column_stack([p[:, 0], PAGE[1] - p[:, 1]]) * PX_PER_MM
        seg = np.diff(p, axis=0)
        n = np.maximum(np.ceil(np.hypot(seg[:, 0], seg[:, 1]) / 0.1), 1).astype(int)
        pts = [p[:1]] + [p[k] + seg[k] * (np.arange(1, n[k] + 1)[:, None] / n[k])
                         for k in range(len(seg))]
        out.append(np.vstack(pts))
    return out


def assert_agree(inked: np.ndarray, strokes: list[np.ndarray], reach: float) -> None:
    assert len(inked), "the renderer drew nothing"
    assert strokes, "the importer plotted nothing"
    points = np.vstack(strokes)
    off_ink, _ = cKDTree(inked).query(points)
    worst = int(np.argmax(off_ink))
    assert off_ink.max() <= 1.0, (f"plotted point {points[worst] / PX_PER_MM} mm is "
                                  f"{off_ink.max():.2f} px from ink")
    missed, _ = cKDTree(points).query(inked)
    worst = int(np.argmax(missed))
    assert missed.max() <= reach, (f"inked pixel at {inked[worst] / PX_PER_MM} mm is "
                                   f"{missed.max():.2f} px from any plotted stroke")


@pytest.mark.parametrize("name", [
    "use_nested", "symbol_viewbox", "doctype_public", "illustrator_entities",
    "prefixed_namespace", "viewport_clip", "clip_path", "switch", "mask", "invisible",
    # issue 32: markers, masks, CSS !important and transform, auto radii, <use> sizing
    # an <svg>, path data drawn up to its error, the page's edge
    "markers", "mask_partial", "css_transform", "use_svg_size", "path_errors", "page_edge",
])
def test_strokes_match_chromium(render_page, tmp_path, name):
    svg = FIXTURES / f"{name}.svg"
    assert_agree(ink(render_page, svg), plotted(tmp_path, svg), HALF_STROKE_PX + 1.0)


def test_hatch_with_holes_matches_chromium_fill(render_page, tmp_path):
    """Hatch lines lie on the rendered fill (never in a hole, even-odd or nonzero), and
    every filled pixel is within half a hatch spacing (plus 1 px) of a hatch line."""
    svg = FIXTURES / "hatch_holes.svg"
    spacing = 0.5
    assert_agree(ink(render_page, svg),
                 plotted(tmp_path, svg, fill="hatch", hatch_spacing=spacing, hatch_angle=30),
                 spacing * PX_PER_MM / 2 + 1.0)


def test_text_anchors_match_chromium(render_page, tmp_path):
    """The substitute single-stroke font has its own glyph shapes and widths, so only the
    placement is compared: each line of text starts (start), is centred (middle) or ends
    (end) where Chromium puts it, and sits on the same baseline band."""
    svg = FIXTURES / "text_anchors.svg"
    inked = ink(render_page, svg)
    strokes = np.vstack(plotted(tmp_path, svg))
    for row, (anchor, baseline) in enumerate((("start", 10), ("middle", 22), ("end", 34))):
        band = baseline * PX_PER_MM
        ours = strokes[(strokes[:, 1] > band - 60) & (strokes[:, 1] < band + 20)]
        theirs = inked[(inked[:, 1] > band - 60) & (inked[:, 1] < band + 20)]
        assert len(ours) and len(theirs), row
        pick = {"start": np.min, "end": np.max,
                "middle": lambda a: (a.min() + a.max()) / 2}[anchor]
        assert abs(pick(ours[:, 0]) - pick(theirs[:, 0])) <= 6, anchor   # 0.6 mm
        assert abs(ours[:, 1].max() - theirs[:, 1].max()) <= 6, anchor  # baseline


PATH_LENGTH = """(ds) => ds.map((d) => {
  const svg = document.createElementNS("http://www.w3.org/2000/svg", "svg");
  const p = document.createElementNS("http://www.w3.org/2000/svg", "path");
  p.setAttribute("d", d);
  svg.appendChild(p);
  document.body.appendChild(svg);
  const b = p.getBBox();
  const out = [p.getTotalLength(), b.x, b.y, b.x + b.width, b.y + b.height];
  svg.remove();
  return out;
})"""


@pytest.mark.parametrize("d", [
    "M 25 5 a 8 6 30 1 1 10 10 S 50 20 55 5 T 55 20",
    "M 5 20 q 5 -5 10 0 t 10 0 t 10 0 L 40 25 L 45,,30",      # up to the double comma
    "M 5 5 L 20 5 L 20 15 x L 40 40",                         # up to the 'x'
    "M5 38h10v-2h10l2-.5.5 1.5",
    "M 10 10 A 5 5 0 1 0 30 10 A 20 10 -45 0 1 40 30",
    "M 0 0 A 1 1 0 0 1 40 0",                                  # radii scaled up
    "M5 5a3 3 0 1110 0z m 20 0 c 5 -10 10 10 15 0 s 5 10 10 0",
    "M 10 10 L 20 20 M 30 30",
])
def test_path_data_length_and_bounds_match_chromium(render_page, d):
    """The importer's reading of path data (pathdata.py) against Chromium's: the length
    of what is drawn (getTotalLength) and its bounding box (getBBox), broken data
    included (both draw up to the first error)."""
    from plotbridge.importing import curves

    (length, *box), = render_page.evaluate(PATH_LENGTH, [d])
    geo, _ = curves.path_data(d, 0.0005)
    ours = sum(float(np.hypot(*np.diff(p, axis=0).T).sum()) for p, _ in geo)
    assert ours == pytest.approx(length, rel=2e-3, abs=1e-3)
    pts = np.vstack([p for p, _ in geo if len(p) > 1])     # a lone moveto draws nothing
    assert [*pts.min(axis=0), *pts.max(axis=0)] == pytest.approx(box, abs=0.01)
