"""The UI's state never lies (issue 12), in headless Chromium against a real server and
the virtual plotter: a stop shown on every page (saying when another browser pressed
it) and gone on every page when it is cleared; the header while the server is down;
the preview and the placement form of the job they are about, also after a reload;
the settings' ranges, switches, sticky Save and leave guard; upload names and errors;
the phone's header bar."""

from __future__ import annotations

import pytest

from tests.browser.conftest import DESKTOP, PHONE, login, new_page, screenshot
from tests.fixtures.pages import (
    SQUARE_SVG,
    job_id,
    job_row,
    spiral_svg,
    upload,
    wait_job_state,
    wait_text,
)

pytestmark = pytest.mark.browser

BADGE = "() => document.querySelector('#sum-state').dataset.state"


def api_job(server, name: str, data: bytes, start: bool = False) -> dict:
    response = server.client.post(
        "/api/jobs", files={"file": (name, data, "image/svg+xml")},
        data={"start": "true"} if start else {},
    )  # fmt: skip
    assert response.status_code == 201, response.text
    return response.json()


@pytest.fixture
def two_pages(browser):
    pages = [new_page(browser, DESKTOP) for _ in range(2)]
    yield [page for page, _ in pages]
    for page, errors in pages:
        page.context.close()
        assert not errors, f"JavaScript errors on the page: {errors}"


def test_stop_shows_on_every_page_and_goes_with_its_cause(two_pages, server, plotter):
    here, there = two_pages
    server.home()
    done = api_job(server, "done-square.svg", SQUARE_SVG, start=True)
    server.wait_job(done["id"], "done", timeout=60)
    for page in (here, there):
        login(page, server.url, server.token)
    long = api_job(server, "stopped-spiral.svg", spiral_svg(20), start=True)
    wait_job_state(there, "stopped-spiral.svg", ("running",))
    server.wait_drawing(long["id"])  # on a moving carriage: Alarm, which the unlock clears

    here.click("#estop")
    here.wait_for_selector("#estop-panel[data-phase=stopped]")
    assert here.locator("#estop-title").text_content() == "The plotter stopped"
    there.wait_for_selector("#estop-panel[data-phase=stopped]")
    title = there.locator("#estop-title").text_content()
    assert title == "The plotter stopped from another browser"
    server.wait_job(long["id"], "stopped", timeout=10)
    screenshot(there, "desktop-stopped-elsewhere")

    # cleared on the first page: the panel goes on both
    here.click("#estop-unlock")
    for page in (here, there):
        page.wait_for_selector("#estop-panel", state="hidden")
        page.wait_for_function(f"() => ({BADGE})() === 'Idle'")

    # after a reload the preview is the stopped job's, not the earlier finished one
    there.reload()
    there.wait_for_selector("#app:not([hidden])")
    wait_text(there, "#preview-title", "stopped-spiral.svg")
    there.wait_for_function("() => (window.plotbridge.preview.geom?.strokes.count ?? 0) > 0")

    # the server goes away: both headers say so instead of the last state; it comes back
    server.stop()
    for page in (here, there):
        page.wait_for_function(f"() => ({BADGE})() === 'Lost'", timeout=20_000)
        assert page.locator("#sum-pos").text_content() == ""
        assert page.evaluate("window.plotbridge.preview.pen") is None  # no stale carriage
        page.locator("#banners .banner", has_text="does not answer").wait_for()
    screenshot(here, "desktop-connection-lost")
    server.start()
    for page in (here, there):
        page.wait_for_function(
            "() => window.plotbridge.store.state.socket.status === 'open'", timeout=40_000
        )
        page.wait_for_function(f"() => ['Idle', 'Alarm'].includes(({BADGE})())")
        page.wait_for_selector("#banners .banner >> text=live connection", state="detached")


def test_an_answer_older_than_a_live_report_is_not_shown(desktop, server):
    """A REST answer that crossed a newer WebSocket report on the way is dropped: applied
    last, its older state would stay up until the next change (an idle board: never)."""
    page, _ = desktop
    server.home()
    login(page, server.url, server.token)
    page.wait_for_function(f"() => ({BADGE})() === 'Idle'")
    stale = server.machine()
    assert stale["pen"] == "up", stale
    held = []
    page.route("**/api/machine", lambda route: held.append(route))
    with page.expect_request("**/api/machine"):
        load = page.evaluate_handle("() => ({ done: window.plotbridge.actions.loadAll() })")
    response = server.client.post("/api/machine/pen", json={"down": True})
    assert response.status_code == 200, response.text
    page.wait_for_function("() => window.plotbridge.store.state.machine?.pen === 'down'")
    held[0].fulfill(json=stale)
    page.evaluate("(load) => load.done", load)  # the answer has been handled
    assert page.evaluate("window.plotbridge.store.state.machine.pen") == "down"
    assert page.locator("#sum-pen").text_content() == "pen down"


def placement_of(server, job_id: str) -> dict:
    return server.job(job_id)["placement"]


def test_placement_form_shows_the_job_it_edits(desktop, server):
    page, _ = desktop
    server.home()
    login(page, server.url, server.token)
    upload(page, "first.svg", SQUARE_SVG)
    wait_job_state(page, "first.svg", ("queued",))
    first = page.evaluate("() => window.plotbridge.store.state.selectedJobId")
    page.select_option("#placement select[name=paper]", "A5")
    page.select_option("#placement select[name=rotate]", "90")
    page.wait_for_function(
        "(id) => { const j = window.plotbridge.store.state.jobs.find((x) => x.id === id);"
        " return j.placement.paper === 'A5' && j.placement.rotate === 90; }", arg=first,
    )  # fmt: skip
    upload(page, "second.svg", SQUARE_SVG)
    wait_job_state(page, "second.svg", ("queued",))
    page.select_option("#placement select[name=rotate]", "180")
    page.wait_for_function(
        "() => window.plotbridge.store.state.jobs.some((j) => j.placement.rotate === 180)"
    )

    # the first job again, and after a reload: its own placement, its own preview
    job_row(page, "first.svg").locator(".name").click()
    for reload in (False, True):
        if reload:
            page.reload()
            page.wait_for_selector("#app:not([hidden])")
        wait_text(page, "#preview-title", "first.svg")
        page.wait_for_function(
            "() => document.querySelector('#placement select[name=rotate]').value === '90'"
        )
        assert page.locator("#placement select[name=paper]").input_value() == "A5"

    # a refused change (paper larger than the work area) puts back what the job has
    page.select_option("#placement select[name=paper]", "A3")
    wait_text(page, "#place-error", "larger than the work area")
    page.wait_for_function(
        "() => document.querySelector('#placement select[name=paper]').value === 'A5'"
    )
    assert placement_of(server, first)["paper"] == "A5"

    # one field edited: the others stay; the margins are drawn on the paper
    page.fill("#placement input[name=dx]", "5")
    page.wait_for_function(
        "(id) => window.plotbridge.store.state.jobs.find((x) => x.id === id).placement.dx === 5",
        arg=first,
    )
    kept = placement_of(server, first)
    assert (kept["paper"], kept["rotate"], kept["dx"], kept["margin"]) == ("A5", 90, 5, 10)
    assert page.evaluate("window.plotbridge.preview.paper") == {
        "x": 0, "y": 0, "w": 148, "h": 210, "margin": 10
    }

    # "place here": the drawing's lower-left corner goes where the pen is
    server.client.post("/api/machine/jog", json={"dx": 40, "dy": 60, "feed": 3000})
    pos = server.wait_machine(lambda m: m["state"] == "Idle" and m["position"]["x"] > 39)
    page.wait_for_function(
        "(x) => window.plotbridge.store.state.machine.position.x === x", arg=pos["position"]["x"]
    )
    page.click("#place-here")
    page.wait_for_function(
        "([id, x]) => { const j = window.plotbridge.store.state.jobs.find((q) => q.id === id);"
        " return Math.abs(j.bounds.min_x - x) < 0.6; }", arg=[first, pos["position"]["x"]],
    )  # fmt: skip
    bounds = server.job(first)["bounds"]
    assert abs(bounds["min_y"] - pos["position"]["y"]) < 0.6, (bounds, pos)
    assert placement_of(server, first)["rotate"] == 90
    screenshot(page, "desktop-placement-offset")

    # A4 upright does not fit the 300 x 220 mm work area: landscape, and the page says so
    job_row(page, "second.svg").locator(".name").click()
    wait_text(page, "#preview-title", "second.svg")
    page.select_option("#placement select[name=paper]", "A4")
    page.wait_for_function(
        "() => document.querySelector('#placement input[name=landscape]').checked"
    )
    wait_text(page, "#preview-info", "placed in landscape")
    assert placement_of(server, job_id(page, "second.svg"))["paper"] == "A4-landscape"
    assert page.evaluate("window.plotbridge.preview.paper.w") == 297


def word_breaks(page, selector: str) -> dict:
    """How many lines a text takes and how many of its words are split over two."""
    return page.evaluate("""(sel) => {
        const node = document.querySelector(sel);
        const text = node.firstChild;
        const lines = (range) =>
            new Set([...range.getClientRects()].map((r) => Math.round(r.top))).size;
        const all = document.createRange();
        all.selectNodeContents(node);
        let at = 0, split = 0;
        for (const word of text.data.split(' ')) {
            const r = document.createRange();
            r.setStart(text, at);
            r.setEnd(text, at + word.length);
            if (lines(r) > 1) split += 1;
            at += word.length + 1;
        }
        return {lines: lines(all), split};
    }""", selector)


def test_upload_names_wrap_at_words_and_errors_collapse(phone, server):
    page, _ = phone
    page.goto(f"{server.url}/login?token={server.token}")
    page.wait_for_selector("#app:not([hidden])")
    name = "a rather long drawing name of the garden fence seen from the kitchen window.gcode"
    for n, file in enumerate((name, "second bad.gcode", "third bad.gcode")):
        upload(page, file, f"G1 X10 E{n}\nFOO\n".encode(), "text/plain")
    page.wait_for_function(
        "() => document.querySelectorAll('#upload-errors li.upload').length === 3"
    )
    assert page.locator("#upload-failed-title").text_content() == "3 uploads refused"
    assert page.locator("#uploads li.upload").count() == 0  # no second list of failures
    first = page.locator("#upload-errors li.upload", has_text="garden fence")
    assert first.locator(".errors li .line").first.text_content() == "line 1"
    broken = word_breaks(page, "#upload-errors li.upload:last-child .name")
    assert broken["lines"] > 1 and broken["split"] == 0, broken
    screenshot(page, "phone-upload-errors")
    page.click("#upload-clear")
    page.wait_for_selector("#upload-failed", state="hidden")
    assert page.locator("#upload-errors li").count() == 0


def board_setting(server, number: int) -> float:
    settings = server.client.get("/api/machine/settings").json()["settings"]
    return next(s["value"] for s in settings if s["id"] == number)


def test_settings_ranges_switches_sticky_save_try_and_leave_guard(phone, server):
    page, _ = phone
    server.home()  # the pen moves ("Try it") only out of Alarm
    page.goto(f"{server.url}/login?token={server.token}")
    page.wait_for_selector("#app:not([hidden])")
    page.click(".tab[data-tab=settings]")
    page.wait_for_selector("#settings-body tr")
    row61 = page.locator("#settings-body tr", has=page.locator("#setting-61"))
    assert "500 to 2500" in row61.locator(".range").text_content()
    assert page.locator("#setting-22").get_attribute("type") == "checkbox"
    assert page.locator("#setting-2 input[type=checkbox]").count() == 2
    # grouped under headings; the spindle, probe, laser and Z rows only when asked
    headings = page.locator("#settings-body tr.group-head").all_text_contents()
    assert headings[:4] == ["Motion", "Pen", "Switches and homing", "Work area"], headings
    # rows as GRBL users read them: steps, maximum rate, acceleration, each axis together
    keys = page.locator("#settings-body tr").evaluate_all("(rs) => rs.map((r) => r.dataset.key)")
    assert keys[1:7] == ["100", "101", "110", "111", "120", "121"], keys  # after "Motion"
    assert page.locator("#setting-30").count() == 0
    page.check("#settings-all")
    page.wait_for_selector("#setting-30")
    page.uncheck("#settings-all")
    page.wait_for_selector("#setting-30", state="detached")

    # out of range: the server refuses it with the range; the board keeps its value
    before = board_setting(server, 61)
    page.fill("#setting-61", "3000")
    page.click("#settings-save")
    wait_text(page, "#settings-error", "500 to 2500")
    assert board_setting(server, 61) == before

    # in range, with a mask bit ticked; Save stays on screen at the bottom of the list
    page.fill("#setting-61", "2100")
    step_invert = board_setting(server, 2)
    page.locator("#setting-2 input[data-bit='0']").click()
    page.locator("#settings-body tr:last-child").scroll_into_view_if_needed()
    box = page.locator("#settings-save").bounding_box()
    assert box and 0 <= box["y"] and box["y"] + box["height"] <= PHONE["height"], box
    hit = page.evaluate(
        "([x, y]) => document.elementFromPoint(x, y)?.closest('#settings-save') !== null",
        [box["x"] + box["width"] / 2, box["y"] + box["height"] / 2],
    )
    assert hit
    screenshot(page, "phone-settings-sticky-save")
    assert page.locator("#settings-save").text_content() == "Save 2 changes"
    page.click("#settings-save")
    wait_text(page, "#settings-message", "Saved 2")
    assert board_setting(server, 61) == 2100
    assert board_setting(server, 2) == (int(step_invert) ^ 1)

    # the console's $N=V is checked the same way
    page.click(".tab[data-tab=console]")
    page.fill("#command-line", "$61=3000")
    page.press("#command-line", "Enter")
    wait_text(page, "#command-error", "500 to 2500")
    assert board_setting(server, 61) == 2100

    # "Try it" saves a pen position and moves the servo there
    page.click(".tab[data-tab=settings]")
    page.fill("#setting-61", "2200")
    row61.locator("button[data-try]").click()
    wait_text(page, "#settings-message", "Pen moved down")
    assert board_setting(server, 61) == 2200
    server.wait_machine(lambda m: m["pen"] == "down", timeout=10)
    row60 = page.locator("#settings-body tr", has=page.locator("#setting-60"))
    row60.locator("button[data-try]").click()
    server.wait_machine(lambda m: m["pen"] == "up", timeout=10)

    # leaving with unsaved edits asks: in the app, and when the page would unload
    page.fill("#setting-62", "200")
    answers = iter([False, True])
    asked = []

    def answer(dialog) -> None:
        asked.append(dialog.type)
        if dialog.type == "beforeunload" or next(answers):
            dialog.accept()
        else:
            dialog.dismiss()

    page.on("dialog", answer)
    page.click(".tab[data-tab=plot]")
    assert asked == ["confirm"] and page.locator("#tab-settings").is_visible()
    page.click(".tab[data-tab=plot]")
    page.wait_for_selector("#tab-plot:not([hidden])")
    assert asked == ["confirm", "confirm"]
    page.click(".tab[data-tab=settings]")
    page.fill("#setting-62", "210")
    with page.expect_event("dialog") as shown:
        page.close(run_before_unload=True)
    assert shown.value.type == "beforeunload"


def test_phone_hold_and_stop_in_the_header_bar_by_keyboard(phone, server):
    page, _ = phone
    page.goto(f"{server.url}/login?token={server.token}")
    page.wait_for_selector("#app:not([hidden])")
    tabs = page.locator(".tabs").bounding_box()
    for scrolled in (False, True):
        if scrolled:
            page.evaluate("window.scrollTo(0, document.body.scrollHeight)")
        for sel in ("#hold", "#estop"):
            box = page.locator(sel).bounding_box()
            assert box and box["y"] < 20 and box["height"] >= 56, (sel, box)
            assert scrolled or box["y"] + box["height"] <= tabs["y"]  # above the first card
    # the keyboard reaches both, stop first
    page.evaluate("() => document.activeElement.blur()")
    page.keyboard.press("Tab")
    assert page.evaluate("document.activeElement.id") == "estop"
    page.keyboard.press("Tab")
    assert page.evaluate("document.activeElement.id") == "hold"
    screenshot(page, "phone-header-bar")
