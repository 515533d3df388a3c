"""The pens page and the per-layer pen pickers, in headless Chromium against a real server
and the virtual plotter: add (with a refused value first), try the servo positions, edit,
pick a layer's pen on a job, see the odometer after the job, reset it, delete."""

from __future__ import annotations

import pytest

from tests.browser.conftest import login, screenshot
from tests.fixtures.drawings import THREE_LAYERS

pytestmark = pytest.mark.browser
SERVO_US = 8  # the servo timer ticks 4 µs (firmware/src/servo.c)


def pen_row(page, name: str):
    return page.locator("#pens-list li.pen", has=page.locator(".name", has_text=name))


def wait_pen_us(plotter, pen: str, us: int) -> None:
    plotter.wait_trace(lambda t: t["pen"] == pen and abs(t["pen_us"] - us) <= SERVO_US, 20)


def test_pens_page_and_layer_pickers(desktop, server, plotter):
    page, _ = desktop
    server.home()
    login(page, server.url, server.token)
    page.click(".tab[data-tab=pens]")
    page.wait_for_selector("#pens-empty:not([hidden])")

    page.click("#pens-add")
    page.fill("#pen-form [name=name]", "fineliner")
    page.fill("#pen-form [name=up_us]", "1200")
    page.fill("#pen-form [name=down_us]", "3000")
    page.click("#pen-save")
    page.wait_for_function(
        "() => document.querySelector('#pens-error').textContent.startsWith('Pen down:')")
    page.fill("#pen-form [name=down_us]", "1800")
    page.fill("#pen-form [name=reink_m]", "50")
    page.fill("#pen-form [name=colour]", "#ff0000")  # the drawing below is black: no match
    page.click("#pen-save")
    row = pen_row(page, "fineliner")
    row.locator(".servo", has_text="1200 / 1800 µs").wait_for()
    page.locator("#pen-form").wait_for(state="hidden")  # when the POST answers: after the row

    row.locator("button[data-verb=try-down]").click()  # $60/$61 written, then M3
    wait_pen_us(plotter, "down", 1800)
    row.locator("button[data-verb=try-up]").click()
    wait_pen_us(plotter, "up", 1200)

    row.locator("button[data-verb=edit]").click()
    page.fill("#pen-form [name=name]", "fineliner 0.3")
    page.click("#pen-save")
    pen_row(page, "fineliner 0.3").wait_for()
    screenshot(page, "desktop-pens")

    # a job's layer pickers: the second layer gets the fineliner
    job = server.client.post("/api/jobs", files={"file": ("three.svg", THREE_LAYERS)}).json()
    page.click(".tab[data-tab=plot]")
    row_of_job = f"#queue li[data-key='{job['id']}']"
    picker = page.locator(f"{row_of_job} li.layer[data-number='2'] select.layer-pen")
    picker.select_option(label="fineliner 0.3")
    page.wait_for_function(
        "id => window.plotbridge.store.state.jobs.find((j) => j.id === id).layers[1].pen !== null",
        arg=job["id"])  # fmt: skip
    assert [layer["pen"] for layer in server.job(job["id"])["layers"]] == [None, 1, None]

    server.client.post(f"/api/jobs/{job['id']}/start")
    server.wait_pen_change(job["id"], 2)
    page.click(".tab[data-tab=pens]")
    assert row.locator("button[data-verb=try-down]").is_disabled()  # not while a job runs
    server.client.post(f"/api/jobs/{job['id']}/resume")
    server.wait_pen_change(job["id"], 3)
    server.client.post(f"/api/jobs/{job['id']}/resume")
    assert server.wait_job(job["id"], ("done", "failed"), 120)["state"] == "done"
    row = pen_row(page, "fineliner 0.3")
    row.locator(".odometer", has_text="0.06 m").wait_for()  # a 15 mm square
    row.locator("button[data-verb=reset]").click()
    row.locator(".odometer", has_text="0.00 m").wait_for()

    row.locator("button[data-verb=delete]").click()
    page.wait_for_selector("#pens-empty:not([hidden])")
    assert server.client.get("/api/pens").json() == []
