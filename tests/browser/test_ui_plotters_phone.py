"""Three virtual plotters on a 390x844 phone, in headless Chromium against a real server:
the plotter cards stay compact (each a few lines high, all three together well under half
the screen, measured), whatever their jobs offer: one runs a job, one holds a stopped
job with its actions, one is idle; nothing overflows the width."""

from __future__ import annotations

import pytest

from tests.browser.conftest import login, new_page, screenshot
from tests.fixtures.drawings import drawing
from tests.fixtures.server import running_server

pytestmark = pytest.mark.browser

PHONE = {"width": 390, "height": 844}
NAMES = ["plotter1", "plotter2", "plotter3"]
CARD_MAX_PX = 100  # a name and state line, the job line, a row of buttons (was 180)
STRIP_MAX_PX = PHONE["height"] * 0.45  # three cards and STOP ALL (was 493 px, 58 %)

CARDS = """() => {
    const strip = document.querySelector('#plotters').getBoundingClientRect();
    const cards = [...document.querySelectorAll('#plotter-cards [data-plotter]')].map((c) => {
        const r = c.getBoundingClientRect();
        return [c.dataset.plotter, Math.round(r.height), r.left >= 0 && r.right <= innerWidth];
    });
    return {strip: Math.round(strip.height), cards,
            scroll: document.documentElement.scrollWidth};
}"""


def start(server, name: str, circles: int) -> str:
    response = server.client.post(
        "/api/jobs", files={"file": (f"a-job-with-a-long-name-{name}.gcode", drawing(circles))},
        data={"plotter": name, "start": "true"},
    )  # fmt: skip
    assert response.status_code == 201 and response.json()["state"] == "running", response.text
    return response.json()["id"]


def test_three_plotter_cards_stay_compact_on_a_phone(browser, tmp_path):
    with running_server(tmp_path / "data", ["--virtual", "3", "--sim-speed", "1"]) as server:
        for name in NAMES:
            server.wait_plotter(name, lambda m: m["connected"], 60)
        for name in NAMES[:2]:
            server.client.post(f"/api/plotters/{name}/machine/unlock")
            server.wait_plotter(name, lambda m: m["state"] == "Idle", 30)
        running = start(server, "plotter1", 15)
        stopped = start(server, "plotter2", 15)
        assert server.client.post("/api/plotters/plotter2/machine/estop").status_code == 202
        server.wait_job(stopped, ("stopped",), 20)

        page, errors = new_page(browser, PHONE, is_mobile=True, has_touch=True,
                                device_scale_factor=2)  # fmt: skip
        try:
            login(page, server.url, server.token)
            page.wait_for_selector("#plotters:not([hidden])")
            page.wait_for_function(
                """([a, b]) => { const jobs = window.plotbridge.store.state.jobs;
                    return jobs.some((j) => j.id === a && j.state === 'running')
                        && jobs.some((j) => j.id === b && j.state === 'stopped'); }""",
                arg=[running, stopped])  # fmt: skip
            page.wait_for_selector('#plotter-cards [data-plotter="plotter2"] '
                                   '.card-actions button[data-verb="resume"]')  # fmt: skip
            page.evaluate("() => new Promise((r) => requestAnimationFrame(() => "
                          "requestAnimationFrame(r)))")  # the layout of the last render
            screenshot(page, "phone-three-plotters")
            measured = page.evaluate(CARDS)
            print(f"card heights at 390x844: {measured}")
            assert [c[0] for c in measured["cards"]] == NAMES
            assert all(fits for _, _, fits in measured["cards"]), measured
            assert all(height <= CARD_MAX_PX for _, height, _ in measured["cards"]), measured
            assert measured["strip"] <= STRIP_MAX_PX, measured
            assert measured["scroll"] <= PHONE["width"], measured
            # the stopped job's card still offers its actions, its STOP still there
            card = page.locator('#plotter-cards [data-plotter="plotter2"]')
            assert card.locator('[data-verb="stop"]').is_visible()
            assert "stopped" in card.locator(".plotter-job").text_content()
        finally:
            page.context.close()
        assert errors == [], errors
