"""A job's layers in the jobs view (name, colour swatch, progress bar, estimate and
length) as a real server plots a three-layer drawing on the virtual plotter, and the
browser notifications of a page in the background (pen change due, job done), in
headless Chromium. The browser's Notification is replaced by a recorder: headless
Chromium shows none, and the test needs to see what would have been shown."""

from __future__ import annotations

import json

import pytest

from tests.browser.conftest import PHONE, login, new_page, screenshot
from tests.fixtures.drawings import THREE_LAYERS
from tests.fixtures.pages import job_row, server_job, upload, wait_job_state

pytestmark = pytest.mark.browser

NAME = "three-layers.svg"

# A Notification that records instead of showing; permission starts "default" (never
# asked), and the page can be made to look hidden (in the background).
RECORDER = """
window.__notices = []; window.__asked = 0; window.__hidden = false;
Object.defineProperty(Document.prototype, 'hidden', { get: () => window.__hidden });
window.Notification = class {
  static permission = 'default';
  static requestPermission() {
    window.__asked += 1; this.permission = 'granted'; return Promise.resolve('granted');
  }
  constructor(title, options) { window.__notices.push({ title, ...options }); }
};
"""


def layer_view(page) -> list[dict]:
    return job_row(page, NAME).locator(".job-layers li.layer").evaluate_all(
        """(items) => items.map((li) => ({
            name: li.querySelector('.layer-name').textContent,
            swatch: getComputedStyle(li.querySelector('.swatch')).backgroundColor,
            progress: li.querySelector('progress').value,
            info: li.querySelector('.layer-info').textContent,
            current: li.getAttribute('aria-current'),
            visible: li.getBoundingClientRect().width > 0,
        }))"""
    )


def wait_layers(page, progress: list[float]) -> list[dict]:
    page.wait_for_function(
        """([name, want]) => {
            const row = [...document.querySelectorAll('#queue li.job')]
                .find((li) => li.querySelector('.name').textContent === name);
            const bars = row ? [...row.querySelectorAll('.job-layers progress')] : [];
            return bars.length === want.length && bars.every((b, i) => b.value === want[i]);
        }""",
        arg=[NAME, progress],
        timeout=60_000,
    )
    return layer_view(page)


@pytest.mark.parametrize("viewport", ["desktop", "phone"])
def test_layers_show_progress_and_background_notices(browser, server, plotter, viewport):
    options = {"has_touch": True, "is_mobile": True} if viewport == "phone" else {}
    page, errors = new_page(browser, PHONE if viewport == "phone" else {"width": 1280,
                                                                         "height": 800},
                            **options)  # fmt: skip
    try:
        page.add_init_script(RECORDER)
        server.home()
        login(page, server.url, server.token)
        upload(page, NAME, THREE_LAYERS.encode())
        wait_job_state(page, NAME, ("queued",))
        before = wait_layers(page, [0, 0, 0])
        assert [row["name"] for row in before] == ["outline", "shade", "detail"]
        assert all(row["visible"] and "est. " in row["info"] and " mm" in row["info"]
                   for row in before)  # fmt: skip
        assert before[0]["info"].startswith("0 %") and before[0]["current"] is None

        page.evaluate("window.__hidden = true")  # the user switches to another tab
        job_row(page, NAME).locator("button[data-verb=start]").click()
        wait_job_state(page, NAME, ("running", "pen_change"))  # the click's request is async
        job = server.client.get("/api/jobs").json()[-1]
        server.wait_pen_change(job["id"], 2)
        changing = wait_layers(page, [1, 0, 0])
        assert changing[0]["info"].startswith("100 %")
        assert [row["current"] for row in changing] == [None, "step", None]  # the pen due
        screenshot(page, f"{viewport}-layers-pen-change")
        page.wait_for_function("() => window.__notices.length === 1")

        page.evaluate("window.__hidden = false")  # back on the page: nothing to notify
        assert server.client.post(f"/api/jobs/{job['id']}/resume").status_code == 200
        server.wait_pen_change(job["id"], 3)
        wait_layers(page, [1, 1, 0])
        page.evaluate("window.__hidden = true")  # away again when the job ends
        assert server.client.post(f"/api/jobs/{job['id']}/resume").status_code == 200
        wait_job_state(page, NAME, ("done",), timeout=60_000)  # now in History
        page.wait_for_function("() => window.__notices.length === 2")
        notices = page.evaluate("window.__notices")
        assert [n["title"] for n in notices] == ["plotbridge: change the pen",
                                                 f"plotbridge: “{NAME}” is done"]
        assert notices[0]["body"].startswith(f"“{NAME}”, layer 2 of 3 “shade”: load the pen")
        assert page.evaluate("window.__asked") == 1  # asked on the Start click, once
        colours = [layer["colour"] for layer in server.job(job["id"])["layers"]]
        rgb = [f"rgb({int(c[1:3], 16)}, {int(c[3:5], 16)}, {int(c[5:7], 16)})" for c in colours]
        assert [row["swatch"] for row in changing] == rgb
    finally:
        page.context.close()
    assert not errors, f"JavaScript errors on the page: {errors}"


def test_layer_rows_and_notices_are_pure_functions_of_the_job(desktop, static_web):
    page, _ = desktop
    page.goto(static_web + "/no-such-page")  # any page of that origin: modules load from it
    got = page.evaluate("""async () => {
        const { layerRows } = await import('/js/views/jobs.js');
        const { jobNotice } = await import('/js/notify.js');
        const layer = (name, colour, progress) => ({ name, colour, progress, first_line: 1,
                                                      estimate_s: 65, pen_down_mm: 1234 });
        const A = ACTIONS;
        const job = { id: 'j', name: 'cat', state: 'running', actions: A.running,
                      layers: [layer('a', '#ff0000', 1), layer('', 'red;x', 0.25)] };
        return {
          rows: layerRows(job),
          single: layerRows({ ...job, layers: [layer('a', '#000', 0)] }).length,
          stopped: layerRows({ ...job, state: 'stopped', actions: A.stopped })
            .map((r) => r.current),
          progress: jobNotice(job, { ...job, progress: 0.5 }),
          cancelledWaiting: jobNotice({ state: 'waiting' }, { ...job, state: 'cancelled' }),
          failed: jobNotice(job, { ...job, state: 'failed', error: 'line 4: error:20' }),
          change: jobNotice(job, { ...job, state: 'pen_change', pen_change: null }),
        };
    }""".replace("ACTIONS", json.dumps({s: server_job(s)["actions"]
                                          for s in ("running", "stopped")})))
    assert [(r["name"], r["colour"], r["current"]) for r in got["rows"]] == [
        ("a", "#ff0000", False), ("layer 2", "", True)]  # a colour that is no colour: none
    assert got["rows"][1]["info"] == "25 % · est. 1 min 05 s · 1.23 m"
    assert got["single"] == 1 and got["stopped"] == [False, False]
    assert got["progress"] is None and got["cancelledWaiting"] is None
    assert got["failed"]["title"] == "plotbridge: “cat” failed"
    assert got["failed"]["body"] == "line 4: error:20"
    assert got["change"]["body"] == "“cat” waits for a pen change"
