"""End to end: tracing a job's frame moves the carriage around its bounds, pen up."""

from __future__ import annotations

import pytest

from tests.fixtures.drawings import drawing

pytestmark = pytest.mark.e2e


def test_frame_goes_around_the_bounds_without_ink(server, plotter):
    server.home()
    plotter.clear()
    job = server.submit(drawing(), start=False)
    bounds = job["bounds"]
    response = server.client.post(f"/api/jobs/{job['id']}/frame", timeout=120)
    assert response.status_code == 200, response.text
    trace = plotter.trace()
    assert trace["strokes"] == [] and trace["pen"] == "up"
    width, height = bounds["max_x"] - bounds["min_x"], bounds["max_y"] - bounds["min_y"]
    assert trace["travel_mm"] >= 2 * (width + height) - 0.1
    assert abs(trace["position"]["x"] - bounds["min_x"]) < 0.02
    assert abs(trace["position"]["y"] - bounds["min_y"]) < 0.02
    assert server.job(job["id"])["state"] == "queued"
