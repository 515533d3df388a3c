"""End to end: a drawing in layers plots with a pen change between layers. During each
change the pen is up and the carriage parked; it continues on the API's resume, the
WebSocket's resume, or the simulated board's resume button; each layer's strokes are
drawn in order and in place."""

from __future__ import annotations

import json
import time

import pytest
from websockets.sync.client import connect

from tests.fixtures.drawings import THREE_LAYERS, layer
from tests.fixtures.trace import assert_parked, assert_same_drawing

pytestmark = pytest.mark.e2e

def test_three_inkscape_layers_two_pen_changes(server, plotter):
    server.home()
    plotter.clear()
    response = server.client.post(
        "/api/jobs", files={"file": ("layers.svg", THREE_LAYERS)}, data={"start": "true"}
    )
    assert response.status_code == 201, response.text
    job = response.json()
    assert [layer["name"] for layer in job["layers"]] == ["outline", "shade", "detail"]

    changing = server.wait_pen_change(job["id"], 2)
    assert changing["pen_change"]["message"].startswith("Layer 2 of 3, 'shade'")
    assert_parked(plotter)
    assert len(plotter.trace()["strokes"]) == 1  # only the first layer is drawn
    resumed = server.client.post(f"/api/jobs/{job['id']}/resume")  # by the API
    assert resumed.status_code == 200, resumed.text

    server.wait_pen_change(job["id"], 3)
    assert_parked(plotter)
    assert len(plotter.trace()["strokes"]) == 2
    url = server.url.replace("http", "ws") + f"/api/ws?token={server.token}"
    with connect(url) as ws:  # by the WebSocket
        ws.send(json.dumps({"type": "resume"}))
        while (message := json.loads(ws.recv(timeout=10)))["type"] not in ("ack", "error"):
            pass
        assert message == {"type": "ack", "command": "resume"}, message

    done = server.wait_job(job["id"], ("done", "failed", "stopped", "interrupted"), 120)
    assert done["state"] == "done", done
    expected = server.preview(job["id"])["strokes"]
    drawn = plotter.trace()["strokes"]
    assert len(drawn) == len(expected) == 3
    for want, got in zip(expected, drawn, strict=True):  # in layer order, each in place
        assert_same_drawing([want], [got])


def test_the_board_resume_button_ends_a_pen_change(server, plotter):
    server.home()
    two = THREE_LAYERS.replace(layer("detail", 55), "")
    job = server.client.post(
        "/api/jobs", files={"file": ("two.svg", two)}, data={"start": "true"}
    ).json()
    server.wait_pen_change(job["id"], 2)
    plotter.press("resume")
    try:
        deadline = time.monotonic() + 20
        while server.job(job["id"])["state"] == "pen_change":
            assert time.monotonic() < deadline, "the resume button was not seen"
            time.sleep(0.05)
    finally:
        plotter.release("resume")
    assert server.wait_job(job["id"], ("done", "failed", "stopped"), 120)["state"] == "done"
