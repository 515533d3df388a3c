"""The UI end to end in headless Chromium against a real server and the virtual plotter:
log in, upload, preview, start, watch, stop, unlock, start the next job; on a desktop and
on a 360 x 740 phone; refused uploads; the 200,000-point preview's frame time."""

from __future__ import annotations

import math
import os
import time

import pytest

from tests.browser.conftest import DESKTOP, PHONE, login, screenshot
from tests.fixtures.artifacts import record
from tests.fixtures.pages import (
    SQUARE_SVG,
    circles_svg,
    job_id,
    job_row,
    spiral_svg,
    upload,
    wait_job_state,
    wait_text,
)

pytestmark = pytest.mark.browser


@pytest.fixture
def plotter(plotter_factory):
    """The real firmware at real time: the server streams ahead of it, so the planner is
    full when the stop comes (an unthrottled simulator drains it between lines, and a
    stop that finds it empty and the carriage standing is no ALARM:3, as in GRBL)."""
    return plotter_factory(speed=1)


# Starts the stop timer at the first input event, resolves when the page shows stopped.
ARM_STOP_TIMER = """(eventName) => {
    window.__stopped = new Promise((resolve) => {
        let t0 = null;
        window.addEventListener(eventName, () => { t0 = performance.now(); },
                                {capture: true, once: true});
        const panel = document.querySelector('#estop-panel');
        const check = () => {
            if (t0 !== null && !panel.hidden && panel.dataset.phase === 'stopped') {
                observer.disconnect();
                const now = performance.now();
                // ms from the input; and the input's wall-clock time (epoch seconds)
                resolve([now - t0, (performance.timeOrigin + t0) / 1000]);
            }
        };
        const observer = new MutationObserver(check);
        observer.observe(panel, {attributes: true, attributeFilter: ['data-phase', 'hidden']});
    });
}"""


def assert_stop_on_screen(page, viewport: dict[str, int]) -> None:
    box = page.locator("#estop").bounding_box()
    assert box is not None
    assert box["x"] >= 0 and box["y"] >= 0
    assert box["x"] + box["width"] <= viewport["width"]
    assert box["y"] + box["height"] <= viewport["height"]
    assert box["height"] >= 56 and box["width"] >= 150, box  # large: easy to hit
    # nothing covers it: the element at its centre is the button
    hit = page.evaluate(
        "([x, y]) => document.elementFromPoint(x, y)?.id",
        [box["x"] + box["width"] / 2, box["y"] + box["height"] / 2],
    )
    assert hit == "estop"


def preview_pixels(page) -> dict[str, int]:
    """Count canvas pixels in the 'to draw' (the strokes' own colour: black here, blue
    where none is known) and 'drawn' (orange) colours."""
    return page.evaluate("""() => {
        const c = document.querySelector('#preview');
        const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
        let todo = 0, done = 0;
        for (let i = 0; i < d.length; i += 4) {
            const [r, g, b] = [d[i], d[i + 1], d[i + 2]];
            if ((b > 120 && r < 110 && b - r > 60) || Math.max(r, g, b) < 90) todo++;
            else if (r > 180 && g > 60 && g < 150 && b < 90) done++;
        }
        return {todo, done};
    }""")


def wait_preview_pixels(page, colour: str, more_than: int, timeout: float = 5) -> None:
    """The preview is painted over a few frames: wait until `colour` covers enough pixels."""
    deadline = time.monotonic() + timeout
    while (pixels := preview_pixels(page))[colour] <= more_than:
        assert time.monotonic() < deadline, pixels
        page.wait_for_timeout(50)


def wait_drawing(server) -> None:
    """Waits for the carriage to move with the pen down: past the pen's settle, in the
    stroke (a stop during the settle would find nothing moving, so no alarm to clear)."""
    settling = server.wait_machine(lambda m: m["pen"] == "down" and m["state"] == "Run")
    server.wait_machine(
        lambda m: m["pen"] == "down" and m["position"] != settling["position"], timeout=10
    )


def plot_stop_unlock_next(
    page, server, plotter, viewport, prefix: str, press_stop, clear_from_banner: bool = False,
    pause_resume: bool = False, cancel_next: bool = False,
) -> tuple[float, float]:
    """The main story; returns the ms from the stop input to 'stopped' shown, and
    to the plotter's last step pulse."""
    long_name, next_name = f"{prefix}-spiral.svg", f"{prefix}-square.svg"
    # with homing enabled the board starts in Alarm: the banner offers Home
    page.wait_for_function(
        "() => ['Idle', 'Alarm'].includes(document.querySelector('#sum-state').dataset.state)"
    )
    if page.locator("#sum-state").get_attribute("data-state") == "Alarm":
        page.locator("#banners button[data-action=home]").click()
        page.wait_for_function(
            "() => document.querySelector('#sum-state').dataset.state === 'Idle'", timeout=60_000
        )
    upload(page, long_name, spiral_svg(30))
    wait_job_state(page, long_name, ("queued",))
    page.wait_for_function("() => (window.plotbridge.preview.geom?.strokes.count ?? 0) > 100")
    page.wait_for_function("() => window.plotbridge.preview.layersBuilt > 0")
    wait_preview_pixels(page, "todo", 500)  # the strokes are on the canvas
    screenshot(page, f"{prefix}-preview")

    job_row(page, long_name).locator("button[data-verb=start]").click()
    wait_job_state(page, long_name, ("running",))
    # progress, and the live pen moving
    page.wait_for_function(
        """(name) => window.plotbridge.store.state.jobs.some((j) =>
            j.name === name && j.lines_done > 0)""",
        arg=long_name,
    )
    first = page.locator("#sum-pos").text_content()
    page.wait_for_function(
        "(first) => document.querySelector('#sum-pos').textContent !== first", arg=first
    )
    # drawn part known and painted (the frame after it changed has run)
    page.wait_for_function(
        "() => window.plotbridge.preview.done > 0 && !window.plotbridge.preview.dirty"
    )
    page.wait_for_function(
        "(name) => document.querySelector('#queue li.job .pct')?.textContent.includes('%')",
        arg=long_name,
    )
    wait_preview_pixels(page, "done", 0)  # the drawn part in its own colour
    assert_stop_on_screen(page, viewport)
    page.locator("#preview").scroll_into_view_if_needed()
    screenshot(page, f"{prefix}-running")
    page.locator("#queue").scroll_into_view_if_needed()  # where a phone user pressed Start
    if pause_resume:
        row = job_row(page, long_name)
        row.locator("button[data-verb=hold]").click()
        wait_job_state(page, long_name, ("paused",))
        server.wait_machine(lambda m: m["state"] == "Hold", timeout=10)
        row.locator("button[data-verb=continue]").click()
        wait_job_state(page, long_name, ("running",))
        server.wait_machine(lambda m: m["state"] == "Run", timeout=10)
    # manual control is locked while the job runs
    page.click(".tab[data-tab=control]")
    wait_text(page, "#control-lock", "Disabled while a job")
    assert all(b.is_disabled() for b in page.locator("#tab-control button").all())
    page.click(".tab[data-tab=plot]")

    wait_drawing(server)  # the stop lands on a moving carriage: ALARM:3
    page.evaluate(ARM_STOP_TIMER, "pointerdown")
    press_stop()
    elapsed, input_epoch = page.evaluate("window.__stopped")
    clicked_at = input_epoch - (time.time() - time.monotonic())  # on the monotonic clock
    assert elapsed < 1000, f"stopped shown after {elapsed:.0f} ms"
    assert page.locator("#estop-title").text_content() == "The plotter stopped"
    panel = page.locator("#estop-panel").bounding_box()
    assert panel and panel["y"] >= 0 and panel["y"] < viewport["height"] / 2, panel  # in view
    # the server agrees: the job is stopped and the carriage stands still
    assert server.wait_job(job_id(page, long_name), "stopped", timeout=20)["state"] == "stopped"
    wait_job_state(page, long_name, ("stopped",))
    # the simulated carriage stands still, and its last step came soon after the click
    time.sleep(0.3)
    first = plotter.trace()
    time.sleep(0.3)
    second = plotter.trace()
    assert second["steps"] == first["steps"]
    last_step_ms = (second["last_step_monotonic"] - clicked_at) * 1000
    # the page never claims "stopped" while the carriage still moves (5 ms: clock reads)
    assert last_step_ms < elapsed + 5, (last_step_ms, elapsed)
    screenshot(page, f"{prefix}-stopped")

    if clear_from_banner:
        # closing the stop panel leaves the alarm banner, with the action that clears it
        page.click("#estop-close")
        page.locator("#banners .banner", has_text="Alarm").wait_for()
        page.locator("#banners button[data-action=unlock]").click()
    else:
        page.click("#estop-unlock")
    page.wait_for_selector("#estop-panel", state="hidden")
    page.wait_for_selector("#banners .banner >> text=Alarm", state="detached")
    page.wait_for_function("() => document.querySelector('#sum-state').dataset.state === 'Idle'")

    upload(page, next_name, circles_svg(10) if cancel_next else SQUARE_SVG)
    wait_job_state(page, next_name, ("queued",))
    job_row(page, next_name).locator("button[data-verb=start]").click()
    if cancel_next:
        wait_job_state(page, next_name, ("running",))
        job_row(page, next_name).locator("button[data-verb=cancel]").click()
        wait_job_state(page, next_name, ("cancelled",))
        server.wait_machine(lambda m: m["state"] == "Idle" and m["pen"] == "up", timeout=10)
    else:
        wait_job_state(page, next_name, ("running", "done"))
        wait_job_state(page, next_name, ("done",), timeout=60_000)
        assert server.job(job_id(page, next_name))["state"] == "done"
    screenshot(page, f"{prefix}-next-job")
    return elapsed, last_step_ms


def manual_control_settings_console(page, server) -> None:
    """Jog and pen from the Control tab, a $ setting saved to the board, a raw command."""
    page.click(".tab[data-tab=control]")
    x0 = server.machine()["position"]["x"]
    page.check("input[name=step][value='10']")
    page.click(".jog[data-dx='1'][data-dy='0']")
    server.wait_machine(lambda m: abs(m["position"]["x"] - x0 - 10) < 0.05 and m["state"] == "Idle")
    page.wait_for_function(
        "(x) => window.plotbridge.store.state.machine.position.x.toFixed(2) === x",
        arg=f"{x0 + 10:.2f}",
    )
    page.click("#ctl-pen-down")
    page.wait_for_function("() => document.querySelector('#m-pen').textContent === 'down'")
    page.click("#ctl-pen-up")
    page.wait_for_function("() => document.querySelector('#m-pen').textContent === 'up'")
    screenshot(page, "desktop-control")

    page.click(".tab[data-tab=settings]")
    page.wait_for_selector("#settings-body tr")
    page.fill("#setting-110", "5000")
    page.wait_for_function(
        "() => document.querySelector('#settings-save').textContent === 'Save 1 change'"
    )
    page.click("#settings-save")
    page.wait_for_function(
        "() => document.querySelector('#settings-message').textContent.startsWith('Saved 1')"
    )
    assert page.locator("#setting-110").input_value() == "5000"
    assert page.locator("#server-info").text_content() != ""
    screenshot(page, "desktop-settings")

    page.click(".tab[data-tab=console]")
    page.fill("#command-line", "$$")
    page.press("#command-line", "Enter")
    page.locator("#log li.rx", has_text="$110=5000").wait_for()  # read back from the board
    # ?, ! and ~ are accepted as GRBL's realtime bytes; Esc in the line never stops
    page.fill("#command-line", "?")
    page.press("#command-line", "Enter")
    page.locator("#log li", has_text="status report: sent as a realtime byte").wait_for()
    page.fill("#command-line", "!")
    page.press("#command-line", "Escape")
    assert page.locator("#estop-panel").is_hidden()
    screenshot(page, "desktop-console")


def test_desktop_plot_stop_unlock_next(desktop, server, plotter, capsys):
    page, _ = desktop
    page.goto(server.url + "/")
    page.wait_for_selector("#login-view:not([hidden])")
    screenshot(page, "desktop-login")
    page.fill("#login-token", "wrong-token")
    page.click("#login-submit")
    page.wait_for_function("() => document.querySelector('#login-error').textContent !== ''")
    assert page.locator("#login-error").text_content() == "Wrong token."
    login(page, server.url, server.token)

    elapsed, last_step = plot_stop_unlock_next(
        page, server, plotter, DESKTOP, "desktop", lambda: page.click("#estop"),
        pause_resume=True,
    )
    manual_control_settings_console(page, server)
    record("stop_desktop_click", {"shown_ms": round(elapsed, 1), "last_step_ms": round(last_step)})
    with capsys.disabled():
        print(
            f"\n[ui] desktop: click on stop -> 'stopped' shown: {elapsed:.0f} ms; "
            f"last step pulse {last_step:.0f} ms after the click"
        )


def test_phone_plot_stop_unlock_next(phone, server, plotter, capsys):
    page, _ = phone
    # the link printed on the console logs in directly
    page.goto(f"{server.url}/login?token={server.token}")
    page.wait_for_selector("#app:not([hidden])")
    page.wait_for_function("() => window.plotbridge.store.state.socket.status === 'open'")
    for tab in ("plot", "control", "settings", "console"):
        page.click(f".tab[data-tab={tab}]")
        page.wait_for_selector(f"#tab-{tab}:not([hidden])")
        assert_stop_on_screen(page, PHONE)
        page.evaluate("window.scrollTo(0, document.body.scrollHeight)")
        assert_stop_on_screen(page, PHONE)
        screenshot(page, f"phone-{tab}")
        page.evaluate("window.scrollTo(0, 0)")
    page.click(".tab[data-tab=plot]")

    elapsed, last_step = plot_stop_unlock_next(
        page, server, plotter, PHONE, "phone", lambda: page.tap("#estop"),
        clear_from_banner=True, cancel_next=True,
    )
    record("stop_phone_tap", {"shown_ms": round(elapsed, 1), "last_step_ms": round(last_step)})
    with capsys.disabled():
        print(
            f"\n[ui] phone: tap on stop -> 'stopped' shown: {elapsed:.0f} ms; "
            f"last step pulse {last_step:.0f} ms after the tap"
        )


def test_refused_upload_lists_errors_and_names_stay_text(desktop, server, capsys):
    page, _ = desktop
    login(page, server.url, server.token)
    # keyboard: the stop button is the first stop in the tab order, and a real button
    page.evaluate("() => document.activeElement.blur()")
    page.keyboard.press("Tab")
    assert page.evaluate("[document.activeElement.id, document.activeElement.tagName]") == [
        "estop", "BUTTON"
    ]
    page.keyboard.press("Enter")
    page.wait_for_selector("#estop-panel[data-phase=stopped]")
    page.click("#estop-close")
    bad = b"G21\nG90\nG1 X10 Y10 F1000\nG1 X10 E9\nFOO 12\nG1 X10 Y10 Q\n"
    upload(page, "bad.gcode", bad, "text/plain")
    item = page.locator("#upload-errors li.upload.failed", has_text="bad.gcode")
    item.wait_for()
    lines = item.locator(".errors li .line").all_text_contents()
    assert "line 4" in lines and "line 5" in lines, lines
    assert all(m for m in item.locator(".errors li .msg").all_text_contents())
    screenshot(page, "desktop-upload-errors")

    # a name made of markup is shown as text and creates no element
    evil = '<img src=x onerror="window.__pwned=1">.svg'
    upload(page, evil, SQUARE_SVG)
    wait_job_state(page, evil, ("queued",))
    assert page.evaluate("document.querySelectorAll('#app img').length") == 0
    assert page.evaluate("window.__pwned") is None
    assert job_row(page, evil).locator(".name").text_content() == evil

    # the preview pans with a drag, zooms with the wheel and with two fingers
    def view() -> dict:
        return page.evaluate("() => window.plotbridge.preview.view")

    page.wait_for_function(
        "() => { const p = window.plotbridge.preview;"
        " return (p.geom?.strokes.count ?? 0) > 0 && p.view; }"
    )
    box = page.locator("#preview").bounding_box()
    cx, cy = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    v0 = view()
    page.mouse.move(cx, cy)
    page.mouse.down()
    page.mouse.move(cx + 50, cy + 30, steps=5)
    # a drawing that arrives mid-drag does not take the view from under the pointer
    page.evaluate("() => { const p = window.plotbridge.preview; p.setGeometry({ ...p.geom }); }")
    page.mouse.up()
    v1 = view()
    assert (round(v1["ox"] - v0["ox"]), round(v1["oy"] - v0["oy"])) == (50, 30)
    page.mouse.wheel(0, -300)
    page.wait_for_function("(s) => window.plotbridge.preview.view.scale > s * 1.3", arg=v1["scale"])
    v2 = view()
    page.evaluate("""() => {
        const c = document.querySelector('#preview');
        const r = c.getBoundingClientRect();
        const ev = (type, id, x) => c.dispatchEvent(new PointerEvent(type, {pointerId: id,
            pointerType: 'touch', clientX: r.left + x, clientY: r.top + 100, bubbles: true}));
        ev('pointerdown', 11, 100); ev('pointerdown', 12, 200);
        ev('pointermove', 12, 300);   // fingers 100 px apart, then 200 px: twice the size
        ev('pointerup', 11, 100); ev('pointerup', 12, 300);
    }""")
    assert view()["scale"] == pytest.approx(v2["scale"] * 2, rel=1e-6)
    page.click("#zoom-fit")

    # reorder and delete in the queue; the placement form applies to uploads
    page.select_option("#placement select[name=rotate]", "90")
    upload(page, "second.svg", SQUARE_SVG)
    wait_job_state(page, "second.svg", ("queued",))
    second = server.job(job_id(page, "second.svg"))
    assert second["placement"]["rotate"] == 90

    def order() -> list[str]:
        return [j["name"] for j in server.client.get("/api/jobs").json()]

    assert order() == [evil, "second.svg"]
    job_row(page, "second.svg").locator("button[data-verb=up]").click()
    page.wait_for_function(
        "() => document.querySelector('#queue li.job .name').textContent === 'second.svg'"
    )
    assert order() == ["second.svg", evil]
    assert job_row(page, "second.svg").locator("button[data-verb=up]").is_disabled()
    job_row(page, "second.svg").locator("button[data-verb=delete]").click()
    job_row(page, "second.svg").wait_for(state="detached")
    assert order() == [evil]
    job_row(page, evil).locator(".name").click()  # show it again
    page.wait_for_function("() => window.plotbridge.preview.geom !== null")

    # placement: changing it re-imports the queued job and reloads its preview
    before = page.evaluate("() => window.plotbridge.preview.geom.bounds")
    page.select_option("#placement select[name=paper]", "A5")
    page.check("#placement input[name=fit]")
    page.wait_for_function(
        """(name) => {
            const j = window.plotbridge.store.state.jobs.find((x) => x.name === name);
            return j.placement.paper === 'A5' && j.placement.fit === true;
        }""",
        arg=evil,
    )
    page.wait_for_function(
        "(b) => JSON.stringify(window.plotbridge.preview.geom?.bounds) !== JSON.stringify(b)",
        arg=before,
    )
    assert page.evaluate("window.plotbridge.preview.paper") == {
        "x": 0, "y": 0, "w": 148, "h": 210, "margin": 10
    }
    b = page.evaluate("window.plotbridge.preview.geom.bounds")
    assert 9 < b["minX"] and b["maxX"] < 139 and 9 < b["minY"] and b["maxY"] < 201, b
    screenshot(page, "desktop-placement")
    # a 180° turn keeps the bounds: the preview drawn must still be the new one, not the
    # browser's cached copy of the old (the endpoint is no-cache with a changing ETag)
    evil_id = job_id(page, evil)
    preview_file = server.data_dir / "jobs" / evil_id / "preview.json"
    hour_ago = time.time() - 3600
    os.utime(preview_file, (hour_ago, hour_ago))  # an hour old: heuristically fresh for long
    page.evaluate(
        "async (id) => { const {api} = await import('/js/api.js');"
        " await api.get(`/api/jobs/${id}/preview`); }", evil_id
    )  # the browser caches that copy, as the preview of an old job would be
    first = page.evaluate(
        "() => Array.from(window.plotbridge.preview.geom.strokes.coords.slice(0, 2))"
    )
    page.select_option("#placement select[name=rotate]", "180")
    page.wait_for_function(
        """(p) => {
            const c = window.plotbridge.preview.geom?.strokes.coords;
            return !!c && (Math.abs(c[0] - p[0]) > 1 || Math.abs(c[1] - p[1]) > 1);
        }""",
        arg=first,
    )
    # a paper larger than the work area is refused with the reason, the job is kept as it was
    page.select_option("#placement select[name=paper]", "A3")
    page.wait_for_function("() => document.querySelector('#place-error').textContent !== ''")
    assert "larger than the work area" in page.locator("#place-error").text_content()

    # Escape is the stop key, from anywhere on the page, also with the machine idle
    page.evaluate(ARM_STOP_TIMER, "keydown")
    page.keyboard.press("Escape")
    elapsed = page.evaluate("window.__stopped")[0]
    assert elapsed < 1000
    record("stop_idle_escape", {"ms": round(elapsed, 1)})
    with capsys.disabled():
        print(f"\n[ui] Escape key (machine idle) -> 'stopped' shown: {elapsed:.0f} ms")

    # the REST fallback: at once when the socket cannot send, after ~300 ms without an ack
    for breakage, fallback_ms in (("throw new Error('down')", 0), ("", 300)):
        page.click("#estop-close")
        page.evaluate(
            "(body) => { window.__send = WebSocket.prototype.send;"
            " WebSocket.prototype.send = new Function(body); }",
            breakage,
        )
        page.evaluate(ARM_STOP_TIMER, "keydown")
        with page.expect_request(
            lambda r: r.method == "POST" and r.url.endswith("/api/machine/estop")
        ):
            page.keyboard.press("Escape")
        elapsed = page.evaluate("window.__stopped")[0]
        assert fallback_ms <= elapsed < fallback_ms + 700, elapsed
        page.evaluate("() => { WebSocket.prototype.send = window.__send; }")

    # Esc in a text field leaves the field and never stops; outside it, it stops
    page.click("#estop-close")
    page.evaluate("""() => {
        window.__estops = 0;
        const send = WebSocket.prototype.send;
        WebSocket.prototype.send = function (data) {
            if (String(data).includes('"estop"')) window.__estops += 1;
            return send.call(this, data);
        };
    }""")
    page.focus("#placement input[name=margin]")
    page.keyboard.press("Escape")
    assert page.evaluate("document.activeElement.name") != "margin"  # left the field
    page.keyboard.press("Escape")  # now the stop key: events come in order
    page.wait_for_function("() => window.__estops >= 1")
    assert page.evaluate("window.__estops") == 1
    page.wait_for_selector("#estop-panel:not([hidden])")
    page.evaluate("() => { WebSocket.prototype.send = window.__send; }")

    # the live connection drops with the server and comes back by itself
    page.click("#estop-close")
    page.evaluate("""() => {
        window.__banners = new Set();
        new MutationObserver(() => {
            for (const b of document.querySelectorAll('#banners .banner')) {
                window.__banners.add(b.textContent);
            }
        }).observe(document.querySelector('#banners'),
                   {subtree: true, childList: true, characterData: true});
    }""")
    server.restart()
    page.wait_for_function("() => window.plotbridge.store.state.socket.status === 'open'")
    page.wait_for_selector("#banners .banner >> text=live connection", state="detached")
    seen = page.evaluate("[...window.__banners]")
    assert any("Lost the live connection" in text for text in seen), seen

    # while the socket cannot come back, the page keeps up over REST
    page.evaluate("""() => {
        window.__WebSocket = window.WebSocket;
        window.WebSocket = function () { throw new Error('blocked for the test'); };
    }""")
    server.restart()
    page.locator("#banners .banner", has_text="Lost the live connection").wait_for()
    server.wait_machine(lambda m: m["connected"] and m["state"] in ("Idle", "Alarm"))
    server.client.post("/api/machine/unlock").raise_for_status()
    server.client.post("/api/machine/pen", json={"down": True}).raise_for_status()
    page.wait_for_function(
        "() => document.querySelector('#sum-pen').textContent === 'pen down'", timeout=10_000
    )
    page.evaluate("() => { window.WebSocket = window.__WebSocket; }")
    page.locator("#banners button[data-action=reconnect]").click()
    page.wait_for_function("() => window.plotbridge.store.state.socket.status === 'open'")

    # a 401 anywhere (here: the session is gone) returns to the login view
    page.context.clear_cookies()
    # the Settings tab's read of the webhooks, answered 401 (called, not clicked: another
    # read may meet the 401 first and hide the tabs before a click lands)
    page.evaluate("() => window.plotbridge.actions.loadWebhooks()")
    page.wait_for_selector("#login-view:not([hidden])")
    assert page.locator("#app").is_hidden()


def big_gcode(strokes: int = 500, points: int = 500) -> bytes:
    """A plot of strokes * points distinct points, wobbly enough to survive simplification."""
    out = ["G21", "G90"]
    for s in range(strokes):
        cx, cy = 20 + (s % 25) * 10.5, 20 + (s // 25) * 9
        for i in range(points):
            a = i * 0.09
            r = 1 + i * 0.01 + math.sin(i * 2.3) * 0.5
            x, y = cx + r * math.cos(a), cy + r * math.sin(a)
            if i == 0:
                out += [f"G0 X{x:.3f} Y{y:.3f}", "M3"]
            else:
                out.append(f"G1 X{x:.3f} Y{y:.3f} F3000")
        out.append("M5")
    return ("\n".join(out) + "\n").encode()


# After each zoom step (the static layer must be rebuilt), every frame until the picture
# is crisp again: each frame's drawing time (rasterizing included: the page flushes its
# offscreen layer inside the frame), and the time until crisp. Then the frame interval
# while panning, as requestAnimationFrame sees it.
MEASURE_FRAMES = """async () => {
    const p = window.plotbridge.preview;
    const frames = [], crisp = [];
    const render = p.render.bind(p);
    p.render = () => { const ms = render(); frames.push(ms); return ms; };
    const nextFrame = () => new Promise((resolve) => requestAnimationFrame(resolve));
    for (let k = 0; k < 12; k++) {
        await nextFrame();
        const t = performance.now();
        p.view = {...p.view, scale: p.view.scale * (k % 2 ? 1.05 : 1 / 1.05)};
        p.invalidate();
        do { await nextFrame(); } while (p.build || p.dirty);
        crisp.push(performance.now() - t);
    }
    p.render = render;
    const pan = [];
    await new Promise((resolve) => {
        let last = performance.now(), n = 0;
        const step = () => {
            const now = performance.now();
            if (n > 0) pan.push(now - last);
            last = now;
            if (++n > 40) return resolve();
            p.panBy(4, 2);
            requestAnimationFrame(step);
        };
        requestAnimationFrame(step);
    });
    const sorted = (a) => [...a].sort((x, y) => x - y);
    const med = (a) => sorted(a)[Math.floor(a.length / 2)];
    return {points: p.geom.strokes.count, frames: frames.length, frameMedian: med(frames),
            frameMax: Math.max(...frames), crispMedian: med(crisp), crispMax: Math.max(...crisp),
            panMedian: med(pan), panMax: Math.max(...pan)};
}"""


SWAP_IN_200K = """async () => {
    const {buildGeometry} = await import('/js/preview-data.js');
    const {previewJob} = await import('/js/store.js');
    const {store} = window.plotbridge;
    const strokes = [];
    for (let s = 0; s < 400; s++) {
        const line = [];
        const cx = 20 + (s % 20) * 13, cy = 20 + Math.floor(s / 20) * 9;
        for (let i = 0; i < 500; i++) {
            const a = i * 0.09, r = 1 + i * 0.012 + Math.sin(i * 1.7) * 0.3;
            line.push([cx + r * Math.cos(a), cy + r * Math.sin(a)]);
        }
        strokes.push(line);
    }
    const travel = strokes.slice(1).map((l, i) => [strokes[i][499], l[0]]);
    store.update((st) => {
        const entry = st.previews[previewJob(st).id];
        entry.geom = buildGeometry({strokes, travel});
    });
}"""


def test_200k_point_preview_frame_time(desktop, server, capsys):
    page, _ = desktop
    login(page, server.url, server.token)
    page.evaluate("""() => {
        window.__seen = new Set();
        new MutationObserver(() => {
            for (const s of document.querySelectorAll('#uploads .status')) {
                window.__seen.add(s.textContent.includes(' of ') ? 'bytes' : s.textContent);
            }
        }).observe(document.querySelector('#uploads'),
                   {subtree: true, childList: true, characterData: true});
    }""")
    # a LAN-like upload speed (4 MB/s), so the upload takes a while
    cdp = page.context.new_cdp_session(page)
    cdp.send("Network.enable")
    cdp.send("Network.emulateNetworkConditions", {
        "offline": False, "latency": 5, "downloadThroughput": -1, "uploadThroughput": 4e6,
    })  # fmt: skip
    upload(page, "big.gcode", big_gcode(), "text/plain")
    wait_job_state(page, "big.gcode", ("queued",), timeout=120_000)
    seen = page.evaluate("[...window.__seen]")
    # the upload showed its progress in bytes, then the import
    assert "bytes" in seen and "importing…" in seen, seen
    page.wait_for_function(
        "() => (window.plotbridge.preview.geom?.strokes.count ?? 0) >= 150000", timeout=60_000
    )
    served = page.evaluate(MEASURE_FRAMES)
    # exactly 200,000 points (the server simplifies uploads to at most that): fed to the
    # shown job's preview in the page's state, drawn by the same render path
    page.evaluate(SWAP_IN_200K)
    page.wait_for_function("() => window.plotbridge.preview.geom.strokes.count === 200000")
    exact = page.evaluate(MEASURE_FRAMES)
    page.click("#zoom-fit")
    page.wait_for_timeout(200)
    screenshot(page, "desktop-preview-200k")
    for label, result in (("uploaded", served), ("synthetic", exact)):
        record(f"preview_frame_ms_{label}", result)
        with capsys.disabled():
            print(
                f"\n[ui] {label} preview of {result['points']} points, redrawn after 12 zoom "
                f"steps: frame time median {result['frameMedian']:.1f} ms, max "
                f"{result['frameMax']:.1f} ms over {result['frames']} frames; crisp again after "
                f"{result['crispMedian']:.0f} ms (max {result['crispMax']:.0f}); frame interval "
                f"while panning median {result['panMedian']:.1f} ms (max {result['panMax']:.1f})"
            )
        # the frame-time goal itself is a figure the print above reports; this bound only
        # catches a render path that stopped being progressive (a loaded host slows frames)
        assert result["frameMedian"] < 250
        assert result["panMedian"] < 250
