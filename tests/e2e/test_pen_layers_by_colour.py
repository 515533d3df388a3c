"""End to end: an SVG without Inkscape layers splits into layers by stroke colour (the
colours interleaved in document order) and plots with a pen change between colours.
During each change the pen is up and the carriage stands at the park position; the
job continues on the API's resume, the WebSocket's resume, or the board's resume
button; each layer's strokes are drawn in the preview's order and place, each colour in
one layer only."""

from __future__ import annotations

import json
from collections.abc import Iterator

import pytest
from websockets.sync.client import connect

from tests.fixtures.server import ServerProcess, running_server
from tests.fixtures.trace import assert_parked, assert_same_drawing

pytestmark = pytest.mark.e2e

PARK = (20.0, 30.0)  # mm; not the origin, so a parked carriage is told from a homed one
STEP = 1 / 80  # mm, one step at the simulator's default 80 steps/mm
COLOURS = ("#ff0000", "#00aa00", "#0000ff")


def line(x: int, y: int, colour: str) -> str:
    return f'<line x1="{x}" y1="{y}" x2="{x + 8}" y2="{y + 6}" stroke="{colour}"/>'


def colour_svg(colours: tuple[str, ...], rows: int = 3) -> str:
    """Rows of short lines cycling through `colours` in document order."""
    lines = "".join(
        line(5 + 12 * column, 5 + 10 * row, colour)
        for row in range(rows)
        for column, colour in enumerate(colours)
    )
    return (f'<svg xmlns="http://www.w3.org/2000/svg" width="80mm" height="40mm" '
            f'viewBox="0 0 80 40">{lines}</svg>')


@pytest.fixture
def parked_server(plotter, tmp_path) -> Iterator[ServerProcess]:
    link = ["--serial", str(plotter.port)]
    park = ["--park", f"{PARK[0]:g},{PARK[1]:g}"]
    with running_server(tmp_path / "server-data", link, park) as proc:
        yield proc


def upload(server, svg: str) -> dict:
    response = server.client.post(
        "/api/jobs", files={"file": ("colours.svg", svg)}, data={"start": "true"}
    )
    assert response.status_code == 201, response.text
    return response.json()


def resume_by_websocket(server) -> None:
    url = server.url.replace("http", "ws") + f"/api/ws?token={server.token}"
    with connect(url) as ws:
        ws.send(json.dumps({"type": "resume"}))
        while (message := json.loads(ws.recv(timeout=30)))["type"] not in ("ack", "error"):
            pass
        assert message == {"type": "ack", "command": "resume"}, message


def test_three_colours_two_pen_changes(parked_server, plotter):
    server = parked_server
    server.home()
    plotter.clear()
    job = upload(server, colour_svg(COLOURS))
    assert [layer["colour"] for layer in job["layers"]] == list(COLOURS)  # first appearance
    assert [layer["strokes"] for layer in job["layers"]] == [3, 3, 3]

    drawn_before = [0]  # trace strokes drawn when each layer starts
    for layer, resume in ((2, "api"), (3, "websocket")):
        changing = server.wait_pen_change(job["id"], layer)
        word = ("green", "blue")[layer - 2]  # named in words, never by its code
        assert changing["pen_change"]["message"] == (
            f"Layer {layer} of 3: load the {word} pen, then continue"), changing
        assert changing["layers"][layer - 1]["label"] == changing["pen_change"]["name"] == word
        assert changing["pen_change"]["colour"] == COLOURS[layer - 1]
        trace = assert_parked(plotter, PARK)
        drawn_before.append(len(trace["strokes"]))
        assert drawn_before[-1] == 3 * (layer - 1), "a layer is not drawn whole at its change"
        if resume == "api":
            response = server.client.post(f"/api/jobs/{job['id']}/resume")
            assert response.status_code == 200, response.text
        else:
            resume_by_websocket(server)

    done = server.wait_job(job["id"], ("done", "failed", "stopped", "interrupted"), 120)
    assert done["state"] == "done", done
    shown = server.preview(job["id"])
    drawn = plotter.trace()["strokes"]
    assert len(drawn) == len(shown["strokes"]) == 9
    drawn_before.append(len(drawn))
    columns = []
    for index, colour in enumerate(COLOURS):
        start, end = drawn_before[index], drawn_before[index + 1]
        assert shown["colours"][start:end] == [colour] * 3  # this colour, in this layer only
        for want, got in zip(shown["strokes"][start:end], drawn[start:end], strict=True):
            assert_same_drawing([want], [got])  # in the preview's order, each in place
        # the SVG draws each colour in a column of its own: one layer, one column
        lefts = [min(p[0] for p in stroke) for stroke in drawn[start:end]]
        assert max(lefts) - min(lefts) <= 2 * STEP, lefts
        columns.append(lefts[0])
    assert columns == sorted(columns) and columns[1] - columns[0] > 5, columns


def test_the_board_resume_button_ends_a_colour_change(parked_server, plotter):
    server = parked_server
    server.home()
    plotter.clear()
    job = upload(server, colour_svg(COLOURS[:2], rows=1))
    server.wait_pen_change(job["id"], 2)
    assert len(assert_parked(plotter, PARK)["strokes"]) == 1
    plotter.press("resume")
    try:
        server.wait_job(job["id"], ("running", "done", "failed", "stopped"), 30)
    finally:
        plotter.release("resume")
    done = server.wait_job(job["id"], ("done", "failed", "stopped", "interrupted"), 120)
    assert done["state"] == "done", done
    assert len(plotter.trace()["strokes"]) == 2
