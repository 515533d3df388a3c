"""/docs and /redoc render in Chromium with every request outside the server refused:
the API pages work on a LAN with no internet."""

from __future__ import annotations

from urllib.parse import urlsplit

import pytest

PAGES = {
    "/docs": "#swagger-ui .opblock",  # one block per operation
    "/redoc": "[data-section-id^='tag/'], [data-section-id^='operation/']",
}


@pytest.mark.e2e
def test_api_pages_render_offline(desktop, server_virtual):
    page, _ = desktop
    host = urlsplit(server_virtual.url).netloc
    outside: list[str] = []

    def only_this_server(route, request) -> None:
        if urlsplit(request.url).netloc in (host, ""):
            route.continue_()
        else:
            outside.append(request.url)
            route.abort()

    page.context.route("**/*", only_this_server)
    for path, rendered in PAGES.items():
        page.goto(server_virtual.url + path)
        page.wait_for_selector(rendered, timeout=60_000)
        assert page.locator(rendered).count() >= 5, path
        assert "/api/jobs" in page.content(), path
    assert outside == [], f"the API pages asked the internet for {outside}"
