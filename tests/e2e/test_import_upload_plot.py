"""End to end through a real server: an SVG with clones, a symbol, a clip-path and
text, and a G-code file in a laser plug-in's dialect, uploaded with the import fields,
plotted on the virtual plotter; the pen draws what the import said it would."""

from __future__ import annotations

import pytest

from tests.fixtures.trace import assert_same_drawing

pytestmark = pytest.mark.e2e

SVG = """<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink"
     width="80mm" height="50mm" viewBox="0 0 80 50">
  <defs>
    <symbol id="box" viewBox="0 0 10 10"><rect x="1" y="1" width="8" height="8"
      fill="none" stroke="black"/></symbol>
    <clipPath id="half"><rect x="40" y="0" width="40" height="25"/></clipPath>
  </defs>
  <use xlink:href="#box" x="5" y="5" width="20" height="20"/>
  <use href="#box" x="30" y="5" width="10" height="10" transform="rotate(10 35 10)"/>
  <circle cx="60" cy="25" r="12" fill="none" stroke="black" clip-path="url(#half)"/>
  <text x="40" y="45" font-size="8" text-anchor="middle" font-family="Helvetica">OK</text>
  <rect x="60" y="35" width="10" height="10" fill="black"/>
</svg>
"""

LASER = """; laser plug-in style
G90
G21
M03 S1
G0 X20 Y20
G1 X60 Y20 F3000
G1 X60 Y50
G0 X80 Y20
G1 X80 Y50
G0 X0 Y0
M05 S0
"""


def upload(server, name: str, body: str, **fields) -> dict:
    response = server.client.post("/api/jobs", files={"file": (name, body)},
                                  data={k: str(v) for k, v in fields.items()})
    assert response.status_code == 201, response.text
    return response.json()


def plot(server, plotter, job: dict) -> dict:
    plotter.clear()
    started = server.client.post(f"/api/jobs/{job['id']}/start")
    assert started.status_code == 200, started.text
    done = server.wait_job(job["id"], ("done", "failed", "stopped", "interrupted"), 180)
    assert done["state"] == "done", done
    return plotter.trace()


def test_svg_upload_plots_what_the_import_shows(server, plotter):
    server.home()
    job = upload(server, "drawing.svg", SVG, fill="hatch", hatch_spacing=1, font="futural")
    assert job["substitutions"][0]["font"] == "Helvetica"
    assert [lay["name"] for lay in job["layers"]] == ["#000000"]
    trace = plot(server, plotter, job)
    expected = server.preview(job["id"])
    assert_same_drawing(expected["strokes"], trace["strokes"])
    assert trace["draw_mm"] == pytest.approx(job["stats"]["pen_down_mm"], rel=0.01)
    assert sum(trace["violations"].values()) == 0


def test_laser_gcode_upload_with_dialect_field(server, plotter):
    server.home()
    refused = server.client.post("/api/jobs", files={"file": ("l.gcode", LASER)},
                                 data={"pen_dialect": "plasma"})
    assert refused.status_code == 422 and "pen_dialect" in refused.text
    job = upload(server, "laser.gcode", LASER, pen_dialect="laser")
    assert job["stats"]["pen_down_mm"] == pytest.approx(100)   # G0 travel not drawn
    trace = plot(server, plotter, job)
    assert trace["draw_mm"] == pytest.approx(100, rel=0.01)
