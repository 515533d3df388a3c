"""End to end: a feed hold in the middle of a pen-down stroke is pen-safe, whether it
comes from the API (`POST /api/machine/hold`) or the board's pause button. The trace
shows the pen lifted during the hold where the carriage stopped, and lowered at that
same point (within one step) before the carriage moves on; joined at those points, the
trace's strokes are the drawing exactly once (no dot, no piece drawn twice)."""

from __future__ import annotations

import math
from collections.abc import Callable

import pytest

from tests.fixtures.trace import assert_same_drawing, stroke_length

pytestmark = pytest.mark.e2e

STEP = 1 / 80  # mm, one step at the simulator's default 80 steps/mm ($100)
SVG = ('<svg xmlns="http://www.w3.org/2000/svg" width="200mm" height="80mm" '
       'viewBox="0 0 200 80">{}</svg>')
# one pen-down stroke of about 180 mm: about 3.6 s at the default 3000 mm/min
LINE = SVG.format('<line x1="10" y1="20" x2="190" y2="20" stroke="black"/>')
CIRCLE = SVG.format('<circle cx="100" cy="40" r="29" fill="none" stroke="black"/>')  # many blocks


@pytest.fixture
def plotter(plotter_factory):
    """The real firmware at real time, so a stroke lasts long enough to hold inside it."""
    return plotter_factory(speed=1)


def length(stroke: list) -> float:
    return stroke_length([stroke])


def joined(strokes: list) -> list:
    """The strokes with each one that starts where the one before ended (within a step)
    appended to it: a hold lifts and lowers the pen at the same point."""
    out: list = []
    for stroke in strokes:
        if out and math.dist(out[-1][-1][:2], stroke[0][:2]) <= STEP + 1e-9:
            out[-1] = out[-1] + stroke[1:]
        else:
            out.append(list(stroke))
    return out


def start_and_hold(server, plotter, svg: str, hold: Callable[[], None]) -> tuple[str, tuple]:
    """Starts a job of `svg`, holds it 30 mm into its stroke and checks the pen is lifted
    where the carriage stopped; returns the job id and that point."""
    server.home()
    plotter.clear()
    response = server.client.post(
        "/api/jobs", files={"file": ("stroke.svg", svg)}, data={"start": "true"}
    )
    assert response.status_code == 201, response.text
    job_id = response.json()["id"]

    drawing = plotter.wait_trace(lambda t: t["pen"] == "down" and t["strokes"]
                                 and length(t["strokes"][-1]) > 30, 60)
    hold()
    server.wait_machine(lambda m: m["state"].startswith("Hold"), 30)
    held = plotter.wait_trace(lambda t: t["pen"] == "up", 30)
    assert server.job(job_id)["state"] == "paused"
    assert len(held["strokes"]) == 1
    stopped = (held["position"]["x"], held["position"]["y"])
    # the pen left the paper where the carriage stopped, not while it still moved
    assert math.dist(held["strokes"][0][-1][:2], stopped) <= STEP + 1e-9
    assert length(drawing["strokes"][0]) <= length(held["strokes"][0]) < 175  # mid-stroke
    assert server.machine()["state"].startswith("Hold")
    assert plotter.trace()["position"] == held["position"]  # still there, pen still up
    return job_id, stopped


def assert_drawn_once(server, plotter, job_id: str, lifts: int) -> None:
    """The job ends done; its trace, joined where the pen was lowered where it was lifted,
    is the preview's one stroke exactly once; `lifts` pen lifts came before the end."""
    done = server.wait_job(job_id, ("done", "failed", "stopped", "interrupted"), 60)
    assert done["state"] == "done", done
    expected = server.preview(job_id)["strokes"]
    trace = plotter.trace()
    drawn = joined(trace["strokes"])
    assert len(drawn) == len(expected) == 1
    assert_same_drawing(expected, drawn)
    # nothing drawn twice; a curve's trace follows the steps' staircase, up to 0.1% longer
    assert abs(length(drawn[0]) - length(expected[0])) < max(4 * STEP, 1e-3 * length(drawn[0]))
    assert trace["pen_lifts"] == lifts + 1  # the holds' and the stroke's end: no dot


def hold_mid_stroke(
    server, plotter, svg: str, hold: Callable[[], None], go_on: Callable[[], None]
) -> None:
    job_id, stopped = start_and_hold(server, plotter, svg, hold)
    go_on()
    going = plotter.wait_trace(lambda t: len(t["strokes"]) == 2, 30)
    # lowered at the stop point before moving: the new stroke starts there
    assert math.dist(going["strokes"][1][0][:2], stopped) <= STEP + 1e-9
    assert_drawn_once(server, plotter, job_id, lifts=1)


def click(plotter, button: str) -> Callable[[], None]:
    """Presses a board button until the simulator shows it pressed, then lets go."""
    def press() -> None:
        plotter.press(button)
        try:
            plotter.wait_trace(lambda t: t["buttons"][button], 10)
        finally:
            plotter.release(button)
    return press


def post(server, path: str) -> Callable[[], None]:
    def send() -> None:
        response = server.client.post(path)
        assert response.status_code == 200, response.text
    return send


def hold_and_go_on(how: str, server, plotter) -> tuple[Callable[[], None], Callable[[], None]]:
    if how == "api":
        return post(server, "/api/machine/hold"), post(server, "/api/machine/continue")
    return click(plotter, "pause"), click(plotter, "resume")


def test_api_hold_mid_stroke_lifts_and_lowers_the_pen_in_place(server, plotter):
    hold_mid_stroke(server, plotter, LINE, *hold_and_go_on("api", server, plotter))


def test_pause_button_mid_stroke_lifts_and_lowers_the_pen_in_place(server, plotter):
    hold_mid_stroke(server, plotter, CIRCLE, *hold_and_go_on("buttons", server, plotter))


@pytest.mark.parametrize("how", ["api", "buttons"])
def test_a_hold_while_the_pen_goes_back_down_holds(server, plotter, how):
    """Held again while the resume lowers the pen and waits for it to settle ($64 + $62
    ms): the machine stays held, the pen goes up again, nothing moves."""
    hold, go_on = hold_and_go_on(how, server, plotter)
    job_id, stopped = start_and_hold(server, plotter, LINE, hold)
    go_on()
    hold()  # well within the 150 ms settle
    since = plotter.trace()["sim_time"]
    # a simulated second on, the resume would long be over: still held, pen up, in place
    held = plotter.wait_trace(lambda t: t["sim_time"] > since + 1, 30)
    assert (held["position"]["x"], held["position"]["y"]) == stopped, "it moved on"
    assert held["pen"] == "up" and len(held["strokes"]) <= 2  # maybe the lowering began
    assert server.machine()["state"].startswith("Hold")
    assert server.job(job_id)["state"] == "paused"
    go_on()
    assert_drawn_once(server, plotter, job_id, lifts=held["pen_lifts"])
