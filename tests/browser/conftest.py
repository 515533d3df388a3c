"""Browser-test fixtures: Debian's Chromium driven by Playwright (never a downloaded
browser), a static server for the pure-module checks, and page helpers.

The end-to-end browser tests use the shared `server` fixture (tests/fixtures/server.py):
a real `plotbridge serve` on loopback streaming to the virtual plotter.
"""

from __future__ import annotations

import functools
import http.server
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any, ClassVar

import pytest
from playwright.sync_api import Browser, Page, sync_playwright

from tests.fixtures.artifacts import ARTIFACTS

REPO = Path(__file__).resolve().parents[2]
WEB = REPO / "web"
CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = [
    "--no-sandbox", "--disable-gpu", "--disable-background-networking",
    "--disable-component-update", "--disable-sync", "--no-first-run",
]  # fmt: skip
DESKTOP = {"width": 1280, "height": 800}
PHONE = {"width": 360, "height": 740}


@pytest.fixture(scope="module")
def browser() -> Iterator[Browser]:
    """Chromium for one test file: Playwright's sync API runs an event loop in this thread
    while it is open, which the asyncio tests that pytest-xdist runs next on the same
    worker could not start beside."""
    with sync_playwright() as pw:
        chromium = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            yield chromium
        finally:
            chromium.close()


class PageErrors(list):
    """JavaScript exceptions raised on a page; a test fails if any happened."""


def new_page(browser: Browser, viewport: dict[str, int], **options: Any) -> tuple[Page, PageErrors]:
    context = browser.new_context(viewport=viewport, **options)
    page = context.new_page()
    errors = PageErrors()
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    return page, errors


@pytest.fixture
def desktop(browser: Browser) -> Iterator[tuple[Page, PageErrors]]:
    page, errors = new_page(browser, DESKTOP)
    yield page, errors
    page.context.close()
    assert not errors, f"JavaScript errors on the page: {errors}"


@pytest.fixture
def phone(browser: Browser) -> Iterator[tuple[Page, PageErrors]]:
    page, errors = new_page(browser, PHONE, has_touch=True, is_mobile=True, device_scale_factor=2)
    yield page, errors
    page.context.close()
    assert not errors, f"JavaScript errors on the page: {errors}"


@pytest.fixture(scope="session")
def static_web() -> Iterator[str]:
    """web/ over plain HTTP, for checks of the pure modules that need no server API."""
    handler = functools.partial(QuietHandler, directory=str(WEB))
    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{httpd.server_address[1]}"
    finally:
        httpd.shutdown()
        httpd.server_close()


class QuietHandler(http.server.SimpleHTTPRequestHandler):
    extensions_map: ClassVar[dict[str, str]] = {
        **http.server.SimpleHTTPRequestHandler.extensions_map, ".js": "text/javascript"
    }

    def log_message(self, *args: Any) -> None:
        pass


@pytest.fixture
def modules(desktop, static_web) -> Page:
    """A page of the static web/ origin, for `run` (tests/fixtures/pages.py)."""
    page, _ = desktop
    page.goto(static_web + "/no-such-page")  # any page of that origin: modules load from it
    return page


def screenshot(page: Page, name: str) -> None:
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(ARTIFACTS / f"{name}.png"))


def login(page: Page, url: str, token: str) -> None:
    """Log in through the form, as a person would."""
    page.goto(url + "/")
    page.wait_for_selector("#login-view:not([hidden])")
    page.fill("#login-token", token)
    page.click("#login-submit")
    page.wait_for_selector("#app:not([hidden])")
    page.wait_for_function("() => window.plotbridge.store.state.socket.status === 'open'")

