"""End to end through a real server and the virtual plotter: an SVG in two Inkscape
layers and a fill colour outside them, uploaded with a hatch of its own per layer and per
colour (`layer_fill`), moved by a re-import that keeps them; each layer is plotted
between pen changes as the import said, with its own spacing and angle; a bad entry is
refused naming it."""

from __future__ import annotations

import itertools
import json

import pytest

from tests.fixtures.trace import assert_same_drawing

pytestmark = pytest.mark.e2e

SVG = """<svg xmlns="http://www.w3.org/2000/svg"
     xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape"
     width="90mm" height="40mm" viewBox="0 0 90 40">
  <g inkscape:groupmode="layer" inkscape:label="rows">
    <rect x="5" y="5" width="20" height="12" fill="black" stroke="red"/>
  </g>
  <g inkscape:groupmode="layer" inkscape:label="columns">
    <rect x="35" y="5" width="20" height="12" fill="blue"/>
  </g>
  <rect x="65" y="5" width="20" height="12" fill="#008000"/>
  <rect x="5" y="25" width="80" height="10" fill="#ffa500"/>
</svg>
"""
LAYER_FILL = {"rows": {"hatch_spacing": 2, "hatch_angle": 0},
              "columns": {"hatch_spacing": 2.5, "hatch_angle": 90},
              "#008000": {"hatch_spacing": 3, "hatch_angle": 45, "hatch_cross": True}}


def long_segments(strokes: list) -> set[str]:
    """'h', 'v' or 'd' (diagonal) for each segment longer than 5 mm (links between hatch
    lines are shorter)."""
    out = set()
    for s in strokes:
        for a, b in itertools.pairwise(s):
            dx, dy = abs(b[0] - a[0]), abs(b[1] - a[1])
            if max(dx, dy) > 5:
                out.add("h" if dy < 0.01 else "v" if dx < 0.01 else "d")
    return out


def layer_strokes(data: dict, layer: dict) -> list:
    return [s for s, (down, _) in zip(data["strokes"], data["lines"], strict=True)
            if layer["first_line"] <= down <= layer["last_line"]]


def test_hatch_per_layer_and_colour_plots_layer_by_layer(server, plotter):
    bad = server.client.post("/api/jobs", files={"file": ("h.svg", SVG)},
                             data={"layer_fill": '{"rows": {"hatch_spacing": 0}}'})
    assert bad.status_code == 422
    assert "layer_fill: 'rows': hatch_spacing: must be between" in bad.text

    server.home()
    plotter.clear()
    response = server.client.post("/api/jobs", files={"file": ("h.svg", SVG)},
                                  data={"layer_fill": json.dumps(LAYER_FILL), "fill": "none"})
    assert response.status_code == 201, response.text
    uploaded = response.json()
    # moved by a re-import: the job keeps its layers' own fills
    moved = server.client.patch(f"/api/jobs/{uploaded['id']}",
                                json={"placement": {"dx": 5, "dy": 5}})
    assert moved.status_code == 200, moved.text
    job = moved.json()
    assert job["bounds"]["min_x"] == pytest.approx(uploaded["bounds"]["min_x"] + 5)
    def ink(j: dict) -> list:
        return [(lay["name"], lay["strokes"], lay["pen_down_mm"]) for lay in j["layers"]]
    assert ink(job) == ink(uploaded)
    assert server.client.post(f"/api/jobs/{job['id']}/start").status_code == 200
    # the orange rectangle has no entry and the import's fill is none (asked for; the
    # default outlines): not drawn
    assert [lay["name"] for lay in job["layers"]] == ["rows", "columns", "#008000"]
    data = server.preview(job["id"])
    expected = [layer_strokes(data, lay) for lay in job["layers"]]
    assert long_segments(expected[0]) == {"h", "v"}      # the red outline and its rows
    assert long_segments(expected[1]) == {"v"}
    assert long_segments(expected[2]) == {"d"}

    drawn_before = 0
    for n in (2, 3):
        server.wait_pen_change(job["id"], n)
        drawn = plotter.trace()["strokes"]
        assert_same_drawing(expected[n - 2], drawn[drawn_before:])   # that layer only
        drawn_before = len(drawn)
        assert server.client.post(f"/api/jobs/{job['id']}/resume").status_code == 200
    done = server.wait_job(job["id"], ("done", "failed", "stopped", "interrupted"), 120)
    assert done["state"] == "done", done
    trace = plotter.trace()
    assert_same_drawing(expected[2], trace["strokes"][drawn_before:])
    assert trace["draw_mm"] == pytest.approx(job["stats"]["pen_down_mm"], rel=0.01)
    assert sum(trace["violations"].values()) == 0
    # each layer's ink: rows 2 mm apart (6 rows of 20 mm) and the 64 mm outline ...
    pen_down = [lay["pen_down_mm"] for lay in job["layers"]]
    assert pen_down[0] == pytest.approx(64 + 6 * 20 + 5 * 2, rel=0.03)
    # ... columns 2.5 mm apart (8 of 12 mm)
    assert pen_down[1] == pytest.approx(8 * 12 + 7 * 2.5, rel=0.03)
