"""Layers chosen on the page, through a real server and the virtual plotter, in headless
Chromium: the job row lists each layer (colour, pen, length, estimate); unticking one and
choosing the layer to start at plots only those layers (the simulator's trace); the pen
the first plotted layer needs is asked for at Start, by name, and at a resume from a
layer's start; and in every state the job passes through, its row offers exactly the
job's `actions` from the server's own JSON."""

from __future__ import annotations

import math

import pytest

from tests.browser.conftest import login, screenshot
from tests.fixtures.drawings import THREE_LAYERS
from tests.fixtures.pages import job_row, upload, wait_job_state

pytestmark = pytest.mark.browser

NAME = "three-layers.svg"


def shown_verbs(page, job_id: str) -> list[str]:
    """The action buttons the job's queue row shows (the ↑/↓ pair is the `move` action)."""
    return page.locator(f"#queue li.job[data-key='{job_id}'] .actions button").evaluate_all(
        "(bs) => bs.map((b) => b.dataset.verb)")


def assert_offers_its_actions(page, server, job_id: str) -> None:
    """The row's buttons are the job's actions, as the server lists them now."""
    def matches() -> bool:
        actions = server.job(job_id)["actions"]
        want = [a for a in actions if a not in ("edit", "move")]
        want += ["up", "down"] if "move" in actions else []
        return shown_verbs(page, job_id) == want
    deadline_ms = 10_000
    for _ in range(deadline_ms // 200):
        if matches():
            return
        page.wait_for_timeout(200)
    assert shown_verbs(page, job_id) == server.job(job_id)["actions"], "the row's buttons"


def bbox(points) -> tuple[float, float, float, float]:
    xs, ys = [p[0] for p in points], [p[1] for p in points]
    return min(xs), min(ys), max(xs), max(ys)


def test_start_layer_and_ticks_plot_only_those_layers_with_the_pen_asked(desktop, server,
                                                                         plotter):  # fmt: skip
    page, errors = desktop
    server.home()
    red = server.client.post("/api/pens", json={"name": "Red brush pen", "colour": "#d40000",
                                                "up_us": 1000, "down_us": 2000}).json()  # fmt: skip
    login(page, server.url, server.token)
    upload(page, NAME, THREE_LAYERS.encode())
    wait_job_state(page, NAME, ("queued",))
    row = job_row(page, NAME)
    job_id = row.get_attribute("data-key")
    assert_offers_its_actions(page, server, job_id)

    layers = row.locator("li.layer")
    assert layers.count() == 3
    info = layers.nth(1).locator(".layer-info").text_content()
    assert "est. " in info and " mm" in info  # length and estimate
    # the pen of layer 2, chosen on the row by its name
    layers.nth(1).locator("select.layer-pen").select_option(label="Red brush pen")
    page.wait_for_function(
        "id => window.plotbridge.store.state.jobs.find((j) => j.id === id).layers[1].pen !== null",
        arg=job_id)  # fmt: skip
    assert [layer["pen"] for layer in server.job(job_id)["layers"]] == [None, red["id"], None]

    # start at layer 2, without layer 3: only the middle square is drawn
    layers.nth(1).locator("input.start").check()
    layers.nth(2).locator("input.tick").uncheck()
    screenshot(page, "desktop-layer-choice")
    plotter.clear()
    row.locator("button[data-verb=start]").click()
    # the pen layer 2 needs is asked for, by name (nobody knows which pen is loaded)
    page.wait_for_selector("#pen-prompt:not([hidden])")
    prompt = page.locator("#pen-prompt-text").text_content()
    assert "layer 2 “shade”" in prompt and "load pen “Red brush pen”" in prompt, prompt
    assert "#d40000" not in prompt
    assert server.job(job_id)["state"] == "queued"  # nothing starts before the answer
    page.click("#pen-prompt button[data-answer=loaded]")
    page.wait_for_selector("#pen-prompt", state="hidden")
    wait_job_state(page, NAME, ("running", "done"))
    assert server.job(job_id)["plot_layers"] == [2]
    done = server.wait_job(job_id, ("done", "failed", "stopped"), 120)
    assert done["state"] == "done", done

    strokes = plotter.trace()["strokes"]
    preview = server.preview(job_id)["strokes"]
    assert len(strokes) == 1, strokes  # one square: layer 2's
    drawn, planned = bbox(strokes[0]), bbox(preview[1])
    assert all(math.isclose(a, b, abs_tol=0.1) for a, b in zip(drawn, planned, strict=True)), (
        drawn, planned)

    # done: it left the queue for History, which offers its actions there
    page.click(".tab[data-tab=history]")
    history_row = page.locator(f"#history-body tr[data-key='{job_id}']")
    verbs = history_row.locator(".actions button").evaluate_all(
        "(bs) => bs.map((b) => b.dataset.verb)")
    assert verbs == [a for a in ("restart", "delete") if a in done["actions"]]
    assert not errors, errors


def test_a_row_offers_exactly_its_actions_in_every_state(desktop, server):
    """...and a resume from a later layer's start asks for that layer's pen first."""
    page, errors = desktop
    server.home()
    server.client.post("/api/pens", json={"name": "Blue fineliner", "colour": "#1f5fbf",
                                          "up_us": 1000, "down_us": 2000})  # fmt: skip
    login(page, server.url, server.token)
    upload(page, NAME, THREE_LAYERS.encode())
    wait_job_state(page, NAME, ("queued",))
    job_id = job_row(page, NAME).get_attribute("data-key")
    assert_offers_its_actions(page, server, job_id)  # queued
    layers = job_row(page, NAME).locator("li.layer")
    layers.nth(2).locator("select.layer-pen").select_option(label="Blue fineliner")
    page.wait_for_function(
        "id => window.plotbridge.store.state.jobs.find((j) => j.id === id).layers[2].pen !== null",
        arg=job_id)  # fmt: skip
    job_row(page, NAME).locator("button[data-verb=start]").click()  # no pens: no prompt
    server.wait_pen_change(job_id, 2)
    wait_job_state(page, NAME, ("pen_change",))
    assert_offers_its_actions(page, server, job_id)  # at the pen change: Continue
    job_row(page, NAME).locator("button[data-verb=continue]").click()
    wait_job_state(page, NAME, ("running", "pen_change"))
    if server.job(job_id)["state"] == "running":
        job_row(page, NAME).locator("button[data-verb=hold]").click()
        wait_job_state(page, NAME, ("paused", "pen_change"))
        assert_offers_its_actions(page, server, job_id)  # held: Continue instead of Hold
    job_row(page, NAME).locator("button[data-verb=stop]").click()
    server.wait_job(job_id, ("stopped",), 20)
    wait_job_state(page, NAME, ("stopped",))
    title = page.locator("#estop-title").text_content()
    assert "another" not in title, title  # this page sent it
    assert_offers_its_actions(page, server, job_id)  # stopped: resume, home then resume...

    layers.nth(2).locator("input.start").check()  # go on from layer 3: its pen is asked for
    job_row(page, NAME).locator("button[data-verb=resume]").click()
    page.wait_for_selector("#pen-prompt:not([hidden])")
    prompt = page.locator("#pen-prompt-text").text_content()
    assert "goes on from layer 3" in prompt and "load pen “Blue fineliner”" in prompt, prompt
    assert server.job(job_id)["state"] == "stopped"  # nothing moves before the answer
    page.click("#pen-prompt button[data-answer=loaded]")
    done = server.wait_job(job_id, ("done", "failed", "stopped"), 120)
    assert done["state"] == "done", done
    assert not errors, errors
