"""Three virtual plotters on one page, in headless Chromium against a real server: a card
per plotter with its job and the job's actions (Hold turns into Continue), the header
showing the selected plotter's job, a card's STOP (also with the WebSocket down: REST)
acknowledged like the big one and naming its plotter, never "another client", the Alarm
banner naming its plotter, a stopped job's card offering its actions, STOP ALL, then
"Home all"."""

from __future__ import annotations

import threading

import pytest

from tests.browser.conftest import login, screenshot
from tests.fixtures.drawings import drawing
from tests.fixtures.server import running_server

pytestmark = pytest.mark.browser

NAMES = ["plotter1", "plotter2", "plotter3"]
CARD = '#plotter-cards [data-plotter="{}"]'
NOT_ON_CARD = {"stop", "frame", "delete", "resume_from", "move", "edit"}


def start_long_job(server, name: str) -> str:
    response = server.client.post(
        "/api/jobs", files={"file": (f"long-{name}.gcode", drawing(circles=15))},
        data={"plotter": name, "start": "true"},
    )  # fmt: skip
    assert response.status_code == 201 and response.json()["state"] == "running", response.text
    return response.json()["id"]


def card_verbs(page, name: str) -> list[str]:
    return page.locator(CARD.format(name) + " .card-actions button").evaluate_all(
        "(bs) => bs.map((b) => b.dataset.verb)")


def wait_card_verbs(page, server, name: str, job_id: str) -> list[str]:
    """The card's buttons become its job's actions (those a card offers)."""
    want = [a for a in server.job(job_id)["actions"] if a not in NOT_ON_CARD]
    page.wait_for_function(
        """([sel, want]) => JSON.stringify([...document.querySelectorAll(sel)]
            .map((b) => b.dataset.verb)) === JSON.stringify(want)""",
        arg=[CARD.format(name) + " .card-actions button", want], timeout=15_000)
    return want


def home_all(server) -> None:
    threads = [threading.Thread(target=lambda n=name: server.client.post(
        f"/api/plotters/{n}/machine/home", timeout=180)) for name in NAMES]  # fmt: skip
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    for name in NAMES:
        server.wait_plotter(name, lambda m: m["state"] == "Idle", 60)


def test_three_plotters_stops_banners_and_home_all(desktop, tmp_path):
    page, errors = desktop
    with running_server(tmp_path / "server-data", ["--virtual", "3", "--sim-speed", "1"]) as server:
        for name in NAMES:
            server.wait_plotter(name, lambda m: m["connected"], 60)
        home_all(server)
        login(page, server.url, server.token)
        page.wait_for_selector("#plotters:not([hidden])")
        names = page.locator("#plotter-cards [data-plotter]").evaluate_all(
            "(cards) => cards.map((c) => c.dataset.plotter)")
        assert names == NAMES
        jobs = {name: start_long_job(server, name) for name in NAMES[:2]}

        # a card's Hold turns into Continue (the job's actions), and back
        wait_card_verbs(page, server, "plotter1", jobs["plotter1"])
        page.click(CARD.format("plotter1") + ' [data-verb="hold"]')
        server.wait_job(jobs["plotter1"], ("paused",), 20)
        assert "continue" in wait_card_verbs(page, server, "plotter1", jobs["plotter1"])
        page.click(CARD.format("plotter1") + ' [data-verb="continue"]')
        server.wait_job(jobs["plotter1"], ("running",), 20)
        wait_card_verbs(page, server, "plotter1", jobs["plotter1"])

        # the header shows the selected plotter's job, not another's
        page.click(CARD.format("plotter3") + " .name")
        page.wait_for_function("() => document.querySelector('#sum-state').textContent"
                               ".startsWith('plotter3')")  # fmt: skip
        assert page.locator("#sum-job").text_content() == ""
        page.click(CARD.format("plotter1") + " .name")
        page.wait_for_function("() => document.querySelector('#sum-job').textContent"
                               ".startsWith('long-plotter1')")  # fmt: skip

        # a card's STOP with the WebSocket's send lost: acknowledged over REST all the same
        page.evaluate("() => { window.__send = WebSocket.prototype.send;"
                      " WebSocket.prototype.send = () => {}; }")  # fmt: skip
        page.click(CARD.format("plotter2") + ' [data-verb="stop"]')
        server.wait_job(jobs["plotter2"], ("stopped",), 20)
        page.wait_for_selector("#estop-panel[data-phase=stopped]")
        assert page.evaluate("window.plotbridge.store.state.estop.ackVia") == "rest"
        assert page.locator("#estop-title").text_content() == "plotter2 stopped"
        page.evaluate("() => { WebSocket.prototype.send = window.__send; }")
        assert server.job(jobs["plotter1"])["state"] == "running"  # the others plot on
        # its card shows the stopped job with its actions (Resume, Home then resume, ...)
        verbs = wait_card_verbs(page, server, "plotter2", jobs["plotter2"])
        assert "resume" in verbs
        assert "stopped" in page.locator(CARD.format("plotter2") + " .plotter-job").text_content()
        page.click("#estop-close")
        page.click(CARD.format("plotter2") + " .name")
        banner = page.locator("#banners .banner", has_text="alarm")
        banner.wait_for()
        assert banner.text_content().startswith("plotter2: alarm"), banner.text_content()
        screenshot(page, "desktop-three-plotters")

        # STOP ALL: the same panel, naming them all; then Home all homes every plotter
        page.click('#plotters [data-verb="stop-all"]')
        server.wait_job(jobs["plotter1"], ("stopped",), 20)
        page.wait_for_selector("#estop-panel[data-phase=stopped]")
        title = page.locator("#estop-title").text_content()
        assert title.startswith("All plotters") and "another" not in title, title
        assert page.locator("#estop-home").text_content() == "Home all"
        stop_all = page.locator('#plotters [data-verb="stop-all"]')
        assert not stop_all.is_disabled()
        stop_all.hover()
        colour = stop_all.evaluate("(b) => getComputedStyle(b).backgroundColor")
        assert colour == "rgb(165, 17, 17)", colour  # still red under the pointer: usable
        page.click("#estop-home")
        for name in NAMES:
            server.wait_plotter(name, lambda m: m["state"] == "Idle", 120)
        page.wait_for_selector("#estop-panel", state="hidden", timeout=30_000)
    assert list(errors) == []
