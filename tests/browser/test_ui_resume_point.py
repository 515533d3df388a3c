"""Picking a resume point on the preview, in headless Chromium against a real server and
the virtual plotter: a click near a stroke vertex highlights that vertex, and "Resume from
here" with a 1 mm overlap plots from 1 mm before it (the simulator's trace shows it)."""

from __future__ import annotations

import math

import pytest

from tests.browser.conftest import login, screenshot
from tests.fixtures.drawings import TWO_STROKES
from tests.fixtures.waits import wait_until

pytestmark = pytest.mark.browser

PICKED = "() => window.plotbridge.preview.picked"


def click_at_mm(page, x: float, y: float) -> None:
    """Click the preview canvas where the drawing's point (x, y) mm is shown."""
    view = page.evaluate("() => window.plotbridge.preview.view")
    box = page.locator("#preview").bounding_box()
    page.mouse.click(box["x"] + view["ox"] + x * view["scale"],
                     box["y"] + view["oy"] - y * view["scale"])  # fmt: skip


def test_pick_a_point_on_the_preview_and_resume_from_it(desktop, server, plotter):
    page, errors = desktop
    server.home()
    job = server.submit(TWO_STROKES)
    first_run = server.wait_job(job["id"], ("done", "failed"), 120)
    assert first_run["state"] == "done", first_run
    login(page, server.url, server.token)
    # a finished job is previewed only once the user picks it in the queue
    page.click(f"#queue li[data-key='{job['id']}'] .name")
    page.wait_for_selector("#resume-point:not([hidden])")
    page.wait_for_function("() => window.plotbridge.preview.view !== null")
    # a click picks only once the job's drawing is loaded (before, it is ignored)
    page.wait_for_function(
        "id => { const e = window.plotbridge.store.state.previews[id]; return e && e.geom; }",
        arg=job["id"])
    assert page.locator("#resume-here").is_disabled()  # nothing picked yet

    click_at_mm(page, 59.2, 20.6)  # near the L's corner
    page.wait_for_function(f"() => ({PICKED})() !== null")
    picked = page.evaluate(PICKED)
    assert math.dist((picked["x"], picked["y"]), (60, 20)) < 1e-3, picked  # the vertex
    assert "X 60.00, Y 20.00" in page.locator("#resume-point-text").text_content()
    screenshot(page, "desktop-resume-point")

    plotter.clear()
    page.fill("#resume-overlap", "1")
    page.locator("#resume-overlap").dispatch_event("change")
    page.click("#resume-here")
    # the job was done before: wait for the end of the run the click started
    done = wait_until(lambda: server.job(job["id"]),
                      lambda j: j["started_at"] != first_run["started_at"]
                      and j["state"] in ("done", "failed", "stopped"), 120, "the resumed run")
    assert done["state"] == "done", done
    first = plotter.trace()["strokes"][0][0]
    assert math.dist(first[:2], (59, 20)) <= 0.05, first  # 1 mm before the picked vertex
    assert not errors, errors
