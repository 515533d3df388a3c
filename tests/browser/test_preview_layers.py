"""The preview in Chromium draws each layer in its colour (pixels read from the canvas)
and maps a job's progress onto strokes exactly across the M0 between layers: a real
import's preview in the page's own modules, and a real server plotting on the virtual
plotter, stopped at each pen change."""

from __future__ import annotations

import json

import pytest
from plotbridge.importing import ImportOptions, MachineProfile, import_file

from tests.browser.conftest import login, screenshot
from tests.fixtures.drawings import INK
from tests.fixtures.pages import run, upload, wait_job_state

pytestmark = pytest.mark.browser

COLOURS = ("red", "green", "blue")


def layers_svg() -> bytes:
    """Three Inkscape layers of squares in red, green and blue; many points each."""
    def layer(n: int, colour: str) -> str:
        x = 10 + 70 * n
        return (f'<g inkscape:groupmode="layer" inkscape:label="{colour} pen">'
                + "".join(f'<rect x="{x + d}" y="{10 + d}" width="{60 - 2 * d}" '
                          f'height="{60 - 2 * d}" fill="none" stroke="{colour}"/>'
                          for d in (0, 6, 12)) + "</g>")
    return (f'<svg xmlns="http://www.w3.org/2000/svg" {INK} width="220mm" height="80mm" '
            f'viewBox="0 0 220 80">' + "".join(layer(n, c) for n, c in enumerate(COLOURS))
            + "</svg>").encode()


def test_points_done_is_exact_at_every_layer_boundary(modules, tmp_path):
    src = tmp_path / "layers.svg"
    src.write_bytes(layers_svg())
    r = import_file(src, "layers.svg", tmp_path / "out", ImportOptions(), MachineProfile())
    data = json.loads(r.preview_path.read_text())
    boundaries = [lay["first_line"] - 1 for lay in r.layers[1:]]     # the M0 lines
    # points of the strokes drawn before each M0
    expected = [sum(len(s) for s, (down, _) in zip(data["strokes"], data["lines"],
                                                  strict=True) if down < m0)
                for m0 in boundaries]
    got = run(modules, f"""
        const g = m.buildGeometry({json.dumps(data)});
        const total = {r.lines_total};
        return {json.dumps(boundaries)}.map((m0) =>
            [m.pointsDone(g, m0 - 1, total), m.pointsDone(g, m0, total),
             m.pointsDone(g, m0 + 2, total)]);
    """)
    for (before, at, after), want in zip(got, expected, strict=True):
        assert before == at == want      # the M5, M0, G0 of the next layer: nothing new
        assert after == want + 1         # its M3 reaches its first point
    colours = run(modules, f"return m.buildGeometry({json.dumps(data)}).colours;")
    assert [c["colour"] for c in colours] == ["#ff0000", "#008000", "#0000ff"]


# Pixel classes of 1-pixel hairlines blended with the light paper: the hue decides.
COUNT_PIXELS = """() => {
    const c = document.querySelector('#preview');
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    const n = {red: 0, green: 0, blue: 0, done: 0};
    for (let i = 0; i < d.length; i += 4) {
        const [r, g, b] = [d[i], d[i + 1], d[i + 2]];
        if (r - Math.max(g, b) > 60 && Math.abs(g - b) < 25) n.red++;
        else if (r - b > 60 && g - b > 30) n.done++;             // orange: the drawn part
        else if (g - Math.max(r, b) > 40) n.green++;
        else if (b - Math.max(r, g) > 60) n.blue++;
    }
    return n;
}"""


def pixels(page, want) -> dict:
    """Canvas pixel counts once `want(counts)` holds (the canvas is built over frames)."""
    last = {}
    for _ in range(100):
        last = page.evaluate(COUNT_PIXELS)
        if want(last):
            return last
        page.wait_for_timeout(100)
    raise AssertionError(f"canvas pixels never matched: {last}")


def test_layers_in_their_colours_and_progress_across_each_pen_change(desktop, server):
    page, errors = desktop
    login(page, server.url, server.token)
    server.home()
    upload(page, "layers.svg", layers_svg())
    wait_job_state(page, "layers.svg", ("queued",))
    page.wait_for_function("() => (window.plotbridge.preview.geom?.lines?.first.length ?? 0) "
                           "=== 9")
    before = pixels(page, lambda n: min(n["red"], n["green"], n["blue"]) > 300)
    assert before["done"] == 0
    screenshot(page, "preview-layer-colours")

    job = next(j for j in server.client.get("/api/jobs").json() if j["name"] == "layers.svg")
    assert server.client.post(f"/api/jobs/{job['id']}/start").status_code == 200
    server.wait_pen_change(job["id"], 2)
    # the first layer is drawn, all of it, and nothing of the second
    at2 = pixels(page, lambda n: n["red"] < before["red"] * 0.02 and n["done"] > 300)
    assert at2["green"] > before["green"] * 0.9 and at2["blue"] > before["blue"] * 0.9
    screenshot(page, "preview-at-pen-change-2")
    assert server.client.post(f"/api/jobs/{job['id']}/resume").status_code == 200
    server.wait_pen_change(job["id"], 3)
    at3 = pixels(page, lambda n: n["green"] < before["green"] * 0.02 and n["done"] > 600)
    assert at3["blue"] > before["blue"] * 0.9
    assert server.client.post(f"/api/jobs/{job['id']}/resume").status_code == 200
    server.wait_job(job["id"], ("done",), 120)
    # finished: the preview keeps the layers' own colours, nothing in the drawn colour
    pixels(page, lambda n: n["done"] == 0 and min(n["red"], n["green"], n["blue"]) > 300)
    assert not errors


def test_the_preview_geometry_keeps_the_filled_shapes(modules, tmp_path):
    src = tmp_path / "filled.svg"
    src.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="50mm" height="50mm" '
                   'viewBox="0 0 50 50"><circle cx="25" cy="25" r="10" fill="red"/></svg>')
    r = import_file(src, "filled.svg", tmp_path / "out", ImportOptions(), MachineProfile())
    data = json.loads(r.preview_path.read_text())
    fills = run(modules, f"return m.buildGeometry({json.dumps(data)}).fills;")
    assert fills == data["fills"] and len(fills) == 1 and len(fills[0]) > 8
