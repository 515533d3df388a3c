"""The big Hold/Continue button beside STOP, in headless Chromium against a real server
and the virtual plotter: click and keyboard (never while typing), and the phone layout."""

from __future__ import annotations

import pytest

from tests.browser.conftest import PHONE, login, screenshot
from tests.fixtures.pages import circles_svg, upload, wait_job_state

pytestmark = pytest.mark.browser


def hold_label(page) -> str:
    return page.locator("#hold").text_content()


# Does the button's text fit inside it, with each label it shows (its style per action)?
LABELS_FIT = """() => {
    const b = document.querySelector('#hold');
    const was = [b.textContent, b.dataset.action];
    const fits = [['HOLD', 'hold'], ['CONTINUE', 'continue']].map(([text, action]) => {
        b.textContent = text;
        b.dataset.action = action;
        return [text, b.scrollWidth <= b.clientWidth];
    });
    [b.textContent, b.dataset.action] = was;
    return fits;
}"""


def assert_labels_fit(page) -> None:
    """Neither label runs over the button's edge (on a phone, onto STOP beside it)."""
    assert page.evaluate(LABELS_FIT) == [["HOLD", True], ["CONTINUE", True]]


def test_hold_and_continue_by_click_and_key(desktop, server, plotter):
    page, _ = desktop
    server.home()
    login(page, server.url, server.token)
    assert page.locator("#hold").get_attribute("aria-disabled") == "true"  # nothing to hold
    upload(page, "hold-circles.svg", circles_svg(12))
    wait_job_state(page, "hold-circles.svg", ("queued",))
    page.locator("#queue li.job button[data-verb=start]").click()
    wait_job_state(page, "hold-circles.svg", ("running",))
    server.wait_machine(lambda m: m["state"] == "Run", timeout=20)
    page.wait_for_function("() => document.querySelector('#hold').textContent === 'HOLD'")

    page.click("#hold")
    wait_job_state(page, "hold-circles.svg", ("paused",))
    server.wait_machine(lambda m: m["state"] == "Hold", timeout=10)
    page.wait_for_function("() => document.querySelector('#hold').textContent === 'CONTINUE'")
    assert_labels_fit(page)
    screenshot(page, "desktop-hold")

    # typing an "h" in a text field does not continue
    page.click(".tab[data-tab=console]")
    page.fill("#command-line", "")
    page.press("#command-line", "h")
    page.wait_for_timeout(300)
    assert server.machine()["state"] == "Hold" and hold_label(page) == "CONTINUE"
    page.click(".tab[data-tab=plot]")

    # the key, with nothing focused that takes text, continues
    page.locator("#hold").focus()
    page.keyboard.press("h")
    wait_job_state(page, "hold-circles.svg", ("running",))
    server.wait_machine(lambda m: m["state"] == "Run", timeout=10)
    page.keyboard.press("h")  # and holds again
    wait_job_state(page, "hold-circles.svg", ("paused",))
    job = server.client.get("/api/jobs").json()[-1]
    assert server.client.post(f"/api/jobs/{job['id']}/cancel").status_code == 200
    page.wait_for_function("() => document.querySelector('#hold').textContent === 'HOLD'")
    assert page.locator("#hold").get_attribute("aria-disabled") == "true"


def test_phone_hold_beside_stop_on_every_tab(phone, server):
    page, _ = phone
    page.goto(f"{server.url}/login?token={server.token}")
    page.wait_for_selector("#app:not([hidden])")
    for tab in ("plot", "control", "settings", "console"):
        page.click(f".tab[data-tab={tab}]")
        page.evaluate("window.scrollTo(0, document.body.scrollHeight)")
        hold, stop = page.locator("#hold").bounding_box(), page.locator("#estop").bounding_box()
        assert hold and stop
        for box in (hold, stop):
            assert box["x"] >= 0 and box["x"] + box["width"] <= PHONE["width"]
            assert box["y"] + box["height"] <= PHONE["height"] and box["height"] >= 56
        assert hold["x"] + hold["width"] <= stop["x"], (hold, stop)  # side by side, apart
        assert stop["width"] >= 150 and hold["width"] >= 100
        hit = page.evaluate(
            "([x, y]) => document.elementFromPoint(x, y)?.id",
            [hold["x"] + hold["width"] / 2, hold["y"] + hold["height"] / 2],
        )
        assert hit == "hold"
    assert_labels_fit(page)
    screenshot(page, "phone-hold")
