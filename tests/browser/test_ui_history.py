"""History, in headless Chromium against a real server and the virtual plotter: after three
jobs, a compact row each (name, plotter, pens, started, finished, time taken beside the
estimate, metres drawn, outcome), sortable; plot again and delete from a row, clear the
finished ones; a finished job's preview keeps its layer colours (no "drawn" overlay)."""

from __future__ import annotations

import pytest

from tests.browser.conftest import login, screenshot
from tests.fixtures.drawings import THREE_LAYERS, drawing

pytestmark = pytest.mark.browser

CELLS = ["name", "plotter", "pens", "started", "finished", "took", "metres", "outcome"]


def rows(page) -> list[dict[str, str]]:
    return page.locator("#history-body tr").evaluate_all(
        """(trs) => trs.map((tr) => ({
            id: tr.dataset.key,
            name: tr.querySelector('.name').textContent,
            plotter: tr.querySelector('.plotter').textContent,
            pens: tr.querySelector('.pens').textContent,
            started: tr.querySelector('.started').textContent,
            finished: tr.querySelector('.finished').textContent,
            took: tr.querySelector('.took').textContent,
            metres: tr.querySelector('.metres').textContent,
            outcome: tr.querySelector('.outcome .badge').dataset.state,
            height: tr.getBoundingClientRect().height,
        }))""")


def run_job(server, name: str, body: str, cancel: bool = False, pens=None) -> dict:
    job = server.client.post("/api/jobs", files={"file": (name, body)}, data={"name": name}).json()
    if pens:
        server.client.patch(f"/api/jobs/{job['id']}", json={"pens": pens}).raise_for_status()
    if cancel:
        server.client.post(f"/api/jobs/{job['id']}/cancel").raise_for_status()
        return server.job(job["id"])
    server.client.post(f"/api/jobs/{job['id']}/start").raise_for_status()
    while (state := server.wait_job(job["id"], ("done", "pen_change", "failed"), 120)["state"]) \
            == "pen_change":  # fmt: skip
        server.client.post(f"/api/jobs/{job['id']}/resume").raise_for_status()
    assert state == "done"
    return server.job(job["id"])


def test_history_after_three_jobs(desktop, server):
    page, errors = desktop
    server.home()
    pen = server.client.post("/api/pens", json={"name": "Blue gel", "colour": "#1c5fd4",
                                                "up_us": 1000, "down_us": 2000}).json()  # fmt: skip
    first = run_job(server, "a-square.gcode", drawing(circles=0))
    layered = run_job(server, "b-layers.svg", THREE_LAYERS, pens={"1": pen["id"]})
    run_job(server, "c-never.gcode", drawing(circles=1), cancel=True)
    login(page, server.url, server.token)
    page.click(".tab[data-tab=history]")
    page.wait_for_function("() => document.querySelectorAll('#history-body tr').length === 3")
    got = rows(page)
    assert [r["name"] for r in got] == ["c-never.gcode", "b-layers.svg", "a-square.gcode"]
    by_name = {r["name"]: r for r in got}
    square = by_name["a-square.gcode"]
    assert square["plotter"] == "plotter1" and square["outcome"] == "done"
    assert square["started"] != "–" and square["finished"] != "–"
    took, estimate = square["took"].split(" / ")
    assert took.endswith(" s") and estimate.endswith(" s"), square["took"]
    assert square["metres"].endswith("mm") and square["metres"] != "0 mm"
    assert by_name["b-layers.svg"]["pens"] == "Blue gel"  # the pen's name, not its colour
    assert by_name["c-never.gcode"]["outcome"] == "cancelled"
    assert by_name["c-never.gcode"]["started"] == "–"
    assert all(r["height"] < 80 for r in got), [r["height"] for r in got]  # compact
    screenshot(page, "desktop-history")

    page.click("#tab-history button[data-sort=name]")  # newest first -> by name, A first
    page.wait_for_function(
        "() => document.querySelector('#history-body tr .name').textContent === 'a-square.gcode'")
    page.click("#tab-history button[data-sort=name]")  # again: Z first
    page.wait_for_function(
        "() => document.querySelector('#history-body tr .name').textContent === 'c-never.gcode'")

    # a finished job's preview keeps its layer colours: nothing painted as "drawn"
    page.click(f"#history-body tr[data-key='{layered['id']}'] .name")
    page.wait_for_selector("#tab-plot:not([hidden])")
    page.wait_for_function(
        "id => { const e = window.plotbridge.store.state.previews[id]; return e && e.geom; }",
        arg=layered["id"])
    colours = page.evaluate(f"""() => window.plotbridge.store.state.previews['{layered["id"]}']
        .geom.colours.map((c) => c.colour)""")
    assert set(colours) == {layer["colour"] for layer in layered["layers"]}, colours
    assert page.evaluate("window.plotbridge.preview.done") == 0  # none in the "drawn" colour

    page.click(".tab[data-tab=history]")
    page.click(f"#history-body tr[data-key='{first['id']}'] button[data-verb=restart]")
    server.wait_job(first["id"], ("done",), 120)
    page.wait_for_function(f"""() => window.plotbridge.store.state.jobs
        .find((j) => j.id === '{first['id']}').started_at > {first['started_at']}""")
    page.click(f"#history-body tr[data-key='{first['id']}'] button[data-verb=delete]")
    page.wait_for_function("() => document.querySelectorAll('#history-body tr').length === 2")
    assert server.client.get(f"/api/jobs/{first['id']}").status_code == 404
    page.click("#history-clear")
    page.wait_for_selector("#history-empty:not([hidden])")
    assert server.client.get("/api/jobs").json() == []
    assert not errors, errors
