"""A job's actions from the page, through a real server and the virtual plotter, in headless
Chromium: each goes over the WebSocket as one `job_action` message (no REST call while the
socket is up), over REST while it is down, and what a closing socket (or an open one that
does not answer) left unanswered goes over REST too; a stopped job resumes with the layers
ticked on its row from the layer chosen there (the simulator's trace: only that layer is
drawn); layers split by colour are named in words on the page and in the pen-change
prompt, never by a colour code."""

from __future__ import annotations

import json
import math
import re

import pytest

from tests.browser.conftest import login, screenshot
from tests.fixtures.pages import job_row, upload, wait_job_state
from tests.fixtures.waits import wait_until

pytestmark = pytest.mark.browser

NAME = "four-colours.svg"
COLOURS = ("#000000", "#d40000", "#1f5fbf", "#2e8b3e")  # black, red, blue, green
FOUR_COLOURS = (
    '<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="40mm" viewBox="0 0 100 40">'
    + "".join(f'<rect x="{5 + 24 * i}" y="10" width="15" height="15" fill="none" '
              f'stroke="{colour}"/>' for i, colour in enumerate(COLOURS))
    + "</svg>").encode()  # fmt: skip

# the page's WebSocket objects, so a test can close one (tests/fixtures has no such page hook)
KEEP_SOCKETS = """(() => {
    const Real = window.WebSocket;
    window.__sockets = [];
    window.WebSocket = class extends Real {
        constructor(...args) { super(...args); window.__sockets.push(this); }
    };
})()"""
SOCKET_DOWN = """() => {
    window.__Open = window.WebSocket;
    window.WebSocket = Object.assign(function () { throw new Error('offline'); }, {OPEN: 1});
    for (const s of window.__sockets) s.close();
}"""
SOCKET_UP = "() => { window.WebSocket = window.__Open; }"


def bbox(points) -> tuple[float, float, float, float]:
    xs, ys = [p[0] for p in points], [p[1] for p in points]
    return min(xs), min(ys), max(xs), max(ys)


class Traffic:
    """The page's job actions as they leave it: `job_action` frames and REST calls."""

    def __init__(self, page) -> None:
        self.frames: list[dict] = []
        self.rest: list[str] = []
        page.on("websocket", lambda ws: ws.on("framesent", self._frame))
        page.on("request", self._request)

    def _frame(self, payload) -> None:
        message = json.loads(payload) if isinstance(payload, str) else {}
        if message.get("type") == "job_action":
            self.frames.append(message)

    def _request(self, request) -> None:
        path = request.url.split("//", 1)[-1].split("/", 1)[-1]
        if re.fullmatch(r"api/jobs/[^/?]+(/\w+)?", path.split("?")[0]) and request.method != "GET":
            self.rest.append(f"{request.method} /{path}")

    def actions(self) -> list[str]:
        return [m["action"] for m in self.frames]


def test_actions_go_over_the_socket_and_a_stopped_job_resumes_the_layers_chosen(
        desktop, server, plotter):  # fmt: skip
    page, errors = desktop
    server.home()
    page.add_init_script(KEEP_SOCKETS)
    traffic = Traffic(page)
    login(page, server.url, server.token)
    upload(page, NAME, FOUR_COLOURS)
    wait_job_state(page, NAME, ("queued",))
    row = job_row(page, NAME)
    job_id = row.get_attribute("data-key")
    names = row.locator("li.layer .layer-name").all_text_contents()
    assert names == ["black", "red", "blue", "green"], names  # not "#d40000"

    row.locator("button[data-verb=start]").click()
    server.wait_pen_change(job_id, 2, 120)
    banner = page.locator("#banners .banner", has_text="layer 2 of 4")
    banner.wait_for()
    assert "layer 2 of 4 “red”: load the pen" in banner.text_content(), banner.text_content()
    assert server.job(job_id)["pen_change"]["message"] == (
        "Layer 2 of 4: load the red pen, then continue")
    assert traffic.actions() == ["start"] and traffic.rest == []  # the socket, not REST
    assert not re.search(r"#[0-9a-f]{6}", page.locator("body").inner_text(), re.I)

    row.locator("button[data-verb=stop]").click()
    server.wait_job(job_id, ("stopped",), 20)
    page.wait_for_selector("#estop-panel[data-phase=stopped]")
    page.click("#estop-home")  # home the stopped plotter, as the panel offers
    server.wait_machine(lambda m: m["state"] == "Idle", 120)
    wait_job_state(page, NAME, ("stopped",))
    layers = row.locator("li.layer")
    stopped = wait_until(lambda: server.job(job_id), lambda j: j["done_point"]["layer"] == 2,
                         15, "the stop point at the pen change: layer 2's start")  # fmt: skip
    assert stopped["summary"].startswith("stopped in layer 2 'red' at X "), stopped["summary"]
    assert stopped["layers"][0]["progress"] == 1  # layer 1 was drawn, not lost to the park
    here = 2
    assert layers.nth(here - 1).locator(".start-at").text_content() == "resume here"
    assert layers.nth(here - 1).locator("input.start").is_checked()
    assert layers.nth(0).locator(".start-at").text_content() == "start here"
    # from layer 3, without layer 4: only the blue square is drawn
    layers.nth(2).locator("input.start").check()
    layers.nth(3).locator("input.tick").uncheck()
    screenshot(page, "desktop-resume-layer-choice")
    plotter.clear()
    row.locator("button[data-verb=resume]").click()
    done = server.wait_job(job_id, ("done", "failed", "stopped"), 120)
    assert done["state"] == "done", done
    assert done["plot_layers"] == [1, 2, 3]
    sent = traffic.frames[-1]
    assert (sent["action"], sent["from"], sent["layers"]) == ("resume_from", {"layer": 3},
                                                             [1, 2, 3])  # fmt: skip
    assert traffic.rest == []
    strokes = plotter.trace()["strokes"]
    planned = bbox(server.preview(job_id)["strokes"][2])
    assert len(strokes) == 1, strokes
    drawn = bbox(strokes[0])
    assert all(math.isclose(a, b, abs_tol=0.1) for a, b in zip(drawn, planned, strict=True)), (
        drawn, planned)

    # the socket down: an action goes over REST; one the closing socket left unanswered too
    page.click(".tab[data-tab=history]")
    history = page.locator(f"#history-body tr[data-key='{job_id}']")
    page.evaluate("() => { window.__send = WebSocket.prototype.send;"
                  " WebSocket.prototype.send = () => {}; }")  # fmt: skip
    history.locator("button[data-verb=restart]").click()  # lost on the way
    page.evaluate("() => { WebSocket.prototype.send = window.__send; }")
    page.evaluate(SOCKET_DOWN)
    page.wait_for_function("() => window.plotbridge.store.state.socket.status !== 'open'")
    restarted = server.wait_job(job_id, ("running", "pen_change", "done"), 20)
    assert restarted["state"] in ("running", "pen_change", "done")
    assert traffic.rest == [f"POST /api/jobs/{job_id}/restart"], traffic.rest
    server.wait_pen_change(job_id, 2, 120)
    wait_job_state(page, NAME, ("pen_change",))
    page.click(".tab[data-tab=plot]")
    job_row(page, NAME).locator("button[data-verb=cancel]").click()
    server.wait_job(job_id, ("cancelled",), 20)
    assert traffic.rest[-1] == f"POST /api/jobs/{job_id}/cancel"
    page.evaluate(SOCKET_UP)
    page.wait_for_function("() => window.plotbridge.store.state.socket.status === 'open'",
                           timeout=20_000)  # fmt: skip

    # an open socket that never answers (its frame lost): the action goes over REST
    page.evaluate("() => { window.__send = WebSocket.prototype.send;"
                  " WebSocket.prototype.send = function (m) {"
                  " if (!String(m).includes('job_action')) window.__send.call(this, m); }; }")
    page.click(".tab[data-tab=history]")
    history.locator("button[data-verb=delete]").click()
    history.wait_for(state="detached", timeout=20_000)
    assert traffic.rest[-1] == f"DELETE /api/jobs/{job_id}", traffic.rest
    assert server.client.get(f"/api/jobs/{job_id}").status_code == 404
    assert not errors, errors
