"""The plotter switcher: a card per plotter with its own STOP, STOP ALL, selection."""

from __future__ import annotations

import pytest

from tests.browser.conftest import login
from tests.fixtures.drawings import drawing
from tests.fixtures.server import running_server

pytestmark = pytest.mark.browser


def start_long_job(server, name: str) -> str:
    response = server.client.post(
        "/api/jobs", files={"file": ("long.gcode", drawing(circles=15))},
        data={"plotter": name, "start": "true"},
    )  # fmt: skip
    assert response.status_code == 201 and response.json()["state"] == "running", response.text
    return response.json()["id"]


def test_cards_stop_one_then_all_and_select(desktop, tmp_path):
    page, errors = desktop
    args = ["--virtual", "2", "--sim-speed", "1"]
    with running_server(tmp_path / "server-data", args) as server:
        for name in ("plotter1", "plotter2"):
            server.wait_plotter(name, lambda m: m["connected"], 30)
            home = server.client.post(f"/api/plotters/{name}/machine/home", timeout=130)
            assert home.status_code == 200, home.text
        login(page, server.url, server.token)
        page.wait_for_selector("#plotters:not([hidden])")
        names = page.locator("#plotter-cards [data-plotter]").evaluate_all(
            "(cards) => cards.map((c) => c.dataset.plotter)")
        assert names == ["plotter1", "plotter2"]
        jobs = {name: start_long_job(server, name) for name in names}
        card = '#plotter-cards [data-plotter="{}"]'
        page.wait_for_selector(card.format("plotter2") + " progress:not([hidden])")
        page.click(card.format("plotter2") + ' [data-verb="stop"]')
        server.wait_job(jobs["plotter2"], ("stopped",), 20)
        assert server.job(jobs["plotter1"])["state"] == "running"  # the other plots on
        page.click('#plotters [data-verb="stop-all"]')
        server.wait_job(jobs["plotter1"], ("stopped",), 20)
        page.click(card.format("plotter2") + " .name")
        page.wait_for_function("""() => {
            const s = window.plotbridge.store.state;
            return s.plotter === "plotter2" && s.machine.state === s.plotters.plotter2.state;
        }""")
        queue_text = page.locator("#queue").inner_text()
        assert "on plotter1" in queue_text and "on plotter2" in queue_text
    assert list(errors) == []
