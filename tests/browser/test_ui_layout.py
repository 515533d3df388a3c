"""Layout, in headless Chromium against a real server with content on every page: at 390 px
every tab fits (no horizontal scroll, no control cut off at the edge, every tab of the
strip on screen); at 1400x900 HOLD and STOP stay over the header, never over content; a
stale login link shows the login page saying why; no console error in either session."""

from __future__ import annotations

import pytest

from tests.browser.conftest import new_page
from tests.fixtures.drawings import THREE_LAYERS, drawing

pytestmark = pytest.mark.browser

TABS = ["plot", "history", "control", "pens", "settings", "console", "fleet"]
PHONE = {"width": 390, "height": 844}
DESKTOP = {"width": 1400, "height": 900}

# every control shown, and how far it reaches past the viewport's left and right edges
OVERFLOW = """() => {
    const w = document.documentElement.clientWidth;
    const out = [];
    for (const el of document.querySelectorAll('button, input, select, textarea, .badge')) {
        const r = el.getBoundingClientRect();
        if (r.width === 0 || r.height === 0 || el.closest('[hidden]')) continue;
        if (el.classList.contains('visually-hidden')) continue;
        const what = `${el.tagName} ${el.id || el.className || el.textContent}`;
        if (r.left < -0.5 || r.right > w + 0.5) out.push(`${what} ${r.left}..${r.right}`);
    }
    return {scroll: document.documentElement.scrollWidth, width: w, clipped: out};
}"""


def watch_console(page) -> list[str]:
    errors: list[str] = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    return errors


def stage(server) -> None:
    server.home()
    for name in ("Black fineliner", "Red brush pen with a long name"):
        server.client.post("/api/pens", json={"name": name, "colour": "#d40000",
                                              "up_us": 1000, "down_us": 2000})  # fmt: skip
    done = server.submit(drawing(circles=1))
    server.wait_job(done["id"], ("done",), 120)
    # a stopped job in layers: its row offers the layer choice of its resume
    stopped = server.client.post("/api/jobs", data={"start": "true"}, files={
        "file": ("a-stopped-poster-with-a-long-name.svg", THREE_LAYERS)}).json()  # fmt: skip
    server.wait_pen_change(stopped["id"], 2, 120)
    server.client.post("/api/machine/estop")
    server.wait_job(stopped["id"], ("stopped",), 20)
    server.home()
    server.client.post("/api/jobs", files={"file": ("a-poster-with-a-rather-long-name.svg",
                                                    THREE_LAYERS)})  # fmt: skip


def test_every_tab_fits_a_phone_and_stop_never_covers_content(browser, server_virtual):
    stage(server_virtual)
    url, token = server_virtual.url, server_virtual.token

    phone, page_errors = new_page(browser, PHONE, is_mobile=True, has_touch=True,
                                  device_scale_factor=2)  # fmt: skip
    console = watch_console(phone)
    try:
        phone.goto(f"{url}/login?token=a-stale-token-from-last-week")
        phone.wait_for_selector("#login-view:not([hidden])")
        assert "no longer valid" in phone.locator("#login-notice").text_content()
        phone.goto(f"{url}/login?token={token}")
        phone.wait_for_selector("#app:not([hidden])")
        phone.wait_for_function("() => window.plotbridge.store.state.socket.status === 'open'")
        tabs = phone.locator(".tab").evaluate_all(
            "(ts) => ts.map((t) => { const r = t.getBoundingClientRect();"
            " return [t.dataset.tab, r.left >= 0 && r.right <= innerWidth && r.height > 0]; })")
        assert tabs == [[tab, True] for tab in TABS]  # every tab on screen, none scrolled off
        for tab in TABS:
            phone.click(f'.tab[data-tab="{tab}"]')
            phone.wait_for_selector(f"#tab-{tab}:not([hidden])")
            phone.wait_for_timeout(300)
            fit = phone.evaluate(OVERFLOW)
            assert fit["scroll"] <= PHONE["width"], (tab, fit)
            assert fit["clipped"] == [], (tab, fit["clipped"])
    finally:
        phone.context.close()
    assert page_errors == [] and console == [], (page_errors, console)

    desk, page_errors = new_page(browser, DESKTOP)
    console = watch_console(desk)
    try:
        desk.goto(f"{url}/login?token={token}")
        desk.wait_for_selector("#app:not([hidden])")
        desk.wait_for_function("() => window.plotbridge.store.state.socket.status === 'open'")
        for tab in TABS:
            desk.click(f'.tab[data-tab="{tab}"]')
            desk.wait_for_selector(f"#tab-{tab}:not([hidden])")
            assert desk.evaluate(OVERFLOW)["clipped"] == [], tab
            for scroll in (0, 300, 2000):
                desk.evaluate(f"window.scrollTo(0, {scroll})")
                desk.wait_for_timeout(100)
                inside = desk.evaluate("""() => {
                    const bar = document.querySelector('.topbar').getBoundingClientRect();
                    return ['#estop', '#hold'].map((sel) => {
                        const r = document.querySelector(sel).getBoundingClientRect();
                        return r.top >= bar.top && r.bottom <= bar.bottom;
                    });
                }""")
                assert inside == [True, True], (tab, scroll)  # over the header only
        desk.click('.tab[data-tab="plot"]')
        desk.evaluate("window.scrollTo(0, 0)")
        card = desk.locator(".preview-card").bounding_box()
        assert card and card["y"] + card["height"] <= DESKTOP["height"], card  # fits 900 px
        # also with the resume panel above the canvas (a finished job, opened from History)
        desk.click('.tab[data-tab="history"]')
        desk.locator("#history-body tr .name").first.click()
        desk.wait_for_selector("#tab-plot:not([hidden]) #resume-point:not([hidden])")
        desk.evaluate("window.scrollTo(0, 0)")
        card = desk.locator(".preview-card").bounding_box()
        assert card and card["y"] + card["height"] <= DESKTOP["height"], card
    finally:
        desk.context.close()
    assert page_errors == [] and console == [], (page_errors, console)
