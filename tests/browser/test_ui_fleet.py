"""The fleet tab in Chromium: two bridges on one Mosquitto; A's page lists both bridges'
plotters, its STOP stops B's job through the broker, STOP EVERYTHING stops every one; the
view comes over the WebSocket, not by polling."""

from __future__ import annotations

import pytest

from tests.browser.conftest import login
from tests.fixtures.drawings import drawing
from tests.fixtures.mqtt_bridges import bridge_server

pytestmark = pytest.mark.browser


def test_fleet_tab_lists_every_plotter_and_stops_them(desktop, broker, tmp_path):
    page, errors = desktop
    a = bridge_server(tmp_path / "A", ["--virtual", "--sim-speed", "1"], broker, "A")
    b = bridge_server(tmp_path / "B", ["--virtual", "--sim-speed", "1"], broker, "B")
    try:
        for server in (a, b):
            server.home()
        login(page, a.url, a.token)
        reads: list[str] = []
        page.on("request", lambda r: reads.append(r.url) if r.method == "GET" and
                r.url.endswith("/api/fleet") else None)  # fmt: skip
        page.click('.tab[data-tab="fleet"]')
        card = '#fleet-bridges .fleet-bridge[data-key="{}"] .fleet-plotter[data-key="plotter1"]'
        for bridge in ("A", "B"):
            page.wait_for_selector(card.format(bridge), timeout=20_000)
        assert page.locator(f'#fleet-bridges a.bridge-link[href="{b.url}/"]').count() == 1
        on_b = b.submit(drawing(circles=15))
        page.wait_for_selector(card.format("B") + " progress:not([hidden])", timeout=20_000)
        page.click(card.format("B") + ' [data-verb="fleet-stop"]')
        b.wait_job(on_b["id"], ("stopped",), 20)
        b.home()
        on_a, on_b = a.submit(drawing(circles=15)), b.submit(drawing(circles=15))
        b.wait_progress(on_b["id"], 20)
        a.wait_progress(on_a["id"], 20)
        page.click("#fleet-stop-all")
        a.wait_job(on_a["id"], ("stopped",), 20)
        b.wait_job(on_b["id"], ("stopped",), 20)
        page.wait_for_selector(card.format("B") + ' .badge[data-state="Alarm"]', timeout=20_000)
        assert len(reads) <= 1, reads  # at most a first view; "fleet" messages keep it fresh
    finally:
        a.close()
        b.close()
    assert list(errors) == []
