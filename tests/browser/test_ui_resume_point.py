"""Picking a resume point on the preview, in headless Chromium against a real server and
the virtual plotter: a click in the middle of a straight edge picks the point on that edge
(not a vertex), the panel names where along the stroke it is, and "Resume from here" puts
the pen down there, within one motor step (the simulator's trace shows it)."""

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


def test_a_click_mid_edge_resumes_there(desktop, server, plotter):
    page, errors = desktop
    server.home()
    job = server.submit(TWO_STROKES)
    first_run = server.wait_job(job["id"], ("done", "failed"), 120)
    assert first_run["state"] == "done", first_run
    login(page, server.url, server.token)
    # a finished job is in History; its name opens it on the Plot tab
    page.click(".tab[data-tab=history]")
    page.click(f"#history-body tr[data-key='{job['id']}'] .name")
    page.wait_for_selector("#tab-plot:not([hidden]) #resume-point:not([hidden])")
    page.wait_for_function("() => window.plotbridge.preview.view !== null")
    page.wait_for_function(
        "id => { const e = window.plotbridge.store.state.previews[id]; return e && e.geom; }",
        arg=job["id"])
    assert page.locator("#resume-here").is_disabled()  # nothing picked yet

    click_at_mm(page, 40.0, 20.6)  # above the middle of the first edge, (20,20)-(60,20)
    page.wait_for_function(f"() => ({PICKED})() !== null")
    picked = page.evaluate(PICKED)
    assert math.dist((picked["x"], picked["y"]), (40, 20)) < 0.05, picked  # on the edge
    text = page.locator("#resume-point-text").text_content()
    assert "20.0 mm along a 60.0 mm stroke" in text and "X 40." in text, text
    panel = page.locator("#resume-point").bounding_box()
    assert panel and 0 <= panel["y"] and panel["y"] + panel["height"] <= 900, panel  # in view
    screenshot(page, "desktop-resume-point")

    plotter.clear()
    page.fill("#resume-overlap", "0")
    page.locator("#resume-overlap").dispatch_event("change")
    page.click("#resume-here")
    done = wait_until(lambda: server.job(job["id"]),
                      lambda j: j["started_at"] != first_run["started_at"]
                      and j["state"] in ("done", "failed", "stopped"), 120, "the resumed run")
    assert done["state"] == "done", done
    listed = server.client.get("/api/machine/settings").json()["settings"]
    settings = {s["id"]: s["value"] for s in listed}
    step = 1 / min(settings[100], settings[101])
    first = plotter.trace()["strokes"][0][0]
    assert math.dist(first[:2], (picked["x"], picked["y"])) <= step + 1e-9, (first, picked)
    assert not errors, errors
