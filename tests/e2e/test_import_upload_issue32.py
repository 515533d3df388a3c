"""Issue 32's inputs through a real server's upload path (worker processes, the API's
fields): the path data that used to hold a worker for the whole time limit imports at
once and leaves the workers free; a Unicorn file's dwells and a placed vpype file's
pen-downs; filled shapes outlined by default; masks and markers."""

from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor

import pytest

from tests.fixtures.server import ServerProcess, running_server

pytestmark = pytest.mark.e2e

REDOS = ('<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm" '
         'viewBox="0 0 100 100"><path stroke="black" fill="none" d="M0 0'
         + "L10.5 10.5" * 40 + 'A1 1 0 0 1 2 2"/></svg>')
SQUARE = ('<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm" '
          'viewBox="0 0 100 100"><rect x="10" y="10" width="20" height="20" fill="black"/>'
          '</svg>')


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    data = tmp_path_factory.mktemp("issue32") / "server-data"
    with running_server(data, ["--virtual", "--sim-speed", "0"]) as proc:
        proc.wait_machine(lambda m: m["connected"], 60)
        yield proc


def upload(server: ServerProcess, name: str, text: str, **fields: str):
    return server.client.post("/api/jobs", files={"file": (name, text)},
                              data={"start": "false", **fields}, timeout=150)


def test_the_backtracking_path_imports_within_a_second_and_frees_the_workers(server):
    assert upload(server, "warm.svg", SQUARE).status_code == 201     # workers warmed up
    start = time.monotonic()
    response = upload(server, "redos.svg", REDOS, fill="outline")
    took = time.monotonic() - start
    assert response.status_code == 201, response.text
    assert took < 1.0, took
    # as many at once as there are workers, and again: none is held
    with ThreadPoolExecutor(4) as pool:
        start = time.monotonic()
        codes = list(pool.map(lambda n: upload(server, f"r{n}.svg", REDOS).status_code,
                              range(4)))
    assert codes == [201] * 4 and time.monotonic() - start < 5.0


def test_filled_shapes_are_outlined_by_default_and_left_out_on_request(server):
    outlined = upload(server, "square.svg", SQUARE)
    assert outlined.status_code == 201, outlined.text
    assert outlined.json()["stats"]["pen_down_mm"] == pytest.approx(80)
    refused = upload(server, "square.svg", SQUARE, fill="none")
    assert refused.status_code == 422
    assert "fill=outline" in refused.text


UNICORN = """G21 (metric ftw)
G90 (absolute mode)
G92 X0.00 Y0.00 Z0.00 (you are here)
M300 S30 (pen down)
G4 P150 (wait 150ms)
M300 S50 (pen up)
G4 P150 (wait 150ms)
G1 X10.00 Y10.00 F3500.00
M300 S30.00 (pen down)
G4 P150 (wait 150ms)
G1 X50.00 Y10.00 F3500.00
G1 X50.00 Y40.00 F3500.00
M300 S50.00 (pen up)
G4 P150 (wait 150ms)
G1 X0 Y0 F3500.00
"""


def test_a_unicorn_file_dwells_milliseconds_and_its_origin_dot_is_not_drawn(server):
    response = upload(server, "logo.gcode", UNICORN, paper="A5", fit="true")
    assert response.status_code == 201, response.text
    job = response.json()
    assert job["estimate_s"] < 10            # 4 dwells of 0.15 s, not 150 s
    b = job["bounds"]
    # fitted from the 40 x 30 mm stroke alone (A5 less 10 mm margins: 128 x 190 mm)
    assert b["max_x"] - b["min_x"] == pytest.approx(128, abs=0.01)
    assert any("pen-down with no move" in w["message"] for w in job["warnings"])
    preview = server.preview(job["id"])
    first = preview["strokes"][0]
    assert first[0] == pytest.approx([b["min_x"], b["min_y"]], abs=0.01)


MARKED = ('<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm" '
          'viewBox="0 0 100 100"><defs><marker id="a" viewBox="0 0 10 10" refX="10" '
          'refY="5" markerWidth="4" markerHeight="4" orient="auto"><path d="M0 0 L10 5 L0 '
          '10" fill="none" stroke="black"/></marker><mask id="m" maskUnits="userSpaceOnUse">'
          '<rect width="50" height="100" fill="white"/></mask></defs><line x1="10" y1="50" '
          'x2="40" y2="50" stroke="black" stroke-width="2" marker-end="url(#a)"/><line '
          'x1="30" y1="80" x2="70" y2="80" stroke="black" mask="url(#m)"/></svg>')


def test_markers_and_masks_through_the_upload(server):
    response = upload(server, "marked.svg", MARKED)
    assert response.status_code == 201, response.text
    head = 2 * (4 ** 2 + 8 ** 2) ** 0.5 * 2 / 2     # two 8 x 4 mm arms, scaled by width 2
    assert response.json()["stats"]["pen_down_mm"] == pytest.approx(30 + head + 20, abs=0.05)
