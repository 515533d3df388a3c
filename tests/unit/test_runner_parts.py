"""The runner's parts through their interfaces, on a fake board (tests/fixtures/fake_app.py):
streaming a stretch of a program (LayerStream), where the pen is and the stop point
(StopPoint), pen changes and re-ink prompts (PenChanges), the after-job moves."""

from __future__ import annotations

import asyncio
import time

import pytest
from plotbridge.jobs.model import Layer
from plotbridge.pens import Pen, PenFeed
from plotbridge.plotter.afterjob import AfterJobMoves
from plotbridge.plotter.layerstream import LayerStream
from plotbridge.plotter.penchange import PenChanges
from plotbridge.plotter.stoppoint import MARK_FILE, StopPoint
from plotbridge.resume import Mark

from tests.fixtures.fake_app import FakeLink
from tests.fixtures.jobs import a_job, lifecycle_with
from tests.fixtures.waits import settle

PROGRAM = ["G21", "G90", "G0 X0 Y0", "M3"] + [f"G1 X{k} Y0 F600" for k in range(1, 11)] + ["M5"]


@pytest.fixture
def folder(tmp_path):
    (tmp_path / "j1").mkdir()
    (tmp_path / "j1" / "program.gcode").write_text("\n".join(PROGRAM) + "\n")
    return tmp_path


async def started_link() -> FakeLink:
    link = FakeLink()
    link.auto_ack = True
    link.facts.line_numbers = True
    asyncio.get_running_loop().create_task(link.run())
    await asyncio.sleep(0)
    return link


async def test_a_layer_streams_its_lines_after_the_preamble_and_waits_for_idle(folder):
    link = await started_link()
    acked, flags = [], []
    feed = PenFeed(None, 0.0, lambda _pen, _mm: None)
    state = await LayerStream(link).run(folder / "j1" / "program.gcode", 5, 9, ["G0 X3 Y0"],
                                        feed, acked.append, flags.append)  # fmt: skip
    assert state == "Idle"
    assert [n for n, _ in link.streamed] == [0, 5, 6, 7, 8]  # line 9 is the stop: not sent
    assert link.streamed[0][1] == "G0X3Y0" and acked == [0, 5, 6, 7, 8]
    assert len(flags) == 1 and len(flags[0]) >= 8  # the reader's motion flags, as read


async def test_the_stop_point_follows_reports_and_settles_exactly_at_the_stop(folder):
    link = await started_link()
    job = a_job("running", lines_total=len(PROGRAM), estimate_s=10.0,
                timeline=[(4, 0.0), (15, 10.0)])  # fmt: skip
    life, heard = lifecycle_with(job)
    point = StopPoint(link, folder, life)
    point.reset(1)
    await point.measure(job)
    link.status.line, link.status.x = 7, 2.5  # the board draws line 7 (X2 to X3)
    point.report(job, link.status)
    assert job.lines_done == 0, "not streaming yet: the progress stands"
    point.streaming(bytearray(b"\x01" * 15))
    point.report(job, link.status)  # half way along line 7
    assert job.lines_done == 6 and job.drawn_mm == pytest.approx(2.5)
    assert job.done_point["line"] == 7 and heard and heard[-1]["type"] == "job"
    await point.written()
    assert Mark.load(folder / "j1" / MARK_FILE) == Mark(7, 7, 2.5, 0.0)
    # an emergency stop: the first standing report after it is where the steps stopped
    life.move(job, "estop")
    point.estopped(job)
    link.status.state, link.status.x, link.status.updated_at = "Alarm", 2.75, time.time()
    point.standing(link.status)
    await settle(lambda: job.drawn_mm == pytest.approx(2.75))
    assert job.done_point["x"] == 2.75 and job.lines_done == 6
    assert job.summary == "stopped at X 2.8 Y 0.0, 28 % drawn"  # 2.75 s of the plan's 10
    await point.exact_stop_known(0.1)  # told: no wait


class Library:
    """The pen library's side PenChanges uses."""

    def __init__(self, pen: Pen) -> None:
        self.pen = pen

    def layer_pen(self, _layer) -> Pen:
        return self.pen

    def odometer_mm(self, _pen_id: int) -> float:
        return 263.0

    def flush(self) -> None:
        pass

    def drawn(self, _pen_id: int, _mm: float) -> None:
        pass


async def test_a_pen_change_waits_for_continue_and_says_a_due_reink_in_one_prompt():
    link = await started_link()
    job = a_job("running", layers=[Layer(name="a", first_line=1, last_line=5),
                                   Layer(name="b", first_line=7, last_line=10)])  # fmt: skip
    life, heard = lifecycle_with(job)
    pen = Pen(id=1, name="fine", reink_m=0.25)
    changes = PenChanges(link, life, Library(pen), lambda: ["M5", "G0 X0 Y0", "G4 P0"])  # type: ignore[arg-type]
    prompt = changes.layer_prompt(job, 1, reink=pen)
    assert prompt["message"] == ("Layer 2 of 2, 'b': load pen 'fine', then continue "
                                 "(pen 'fine' is due for re-inking: 0.263 m drawn)")
    assert changes.reink_prompt(job, pen, 1)["message"].startswith(
        "Re-ink pen 'fine': 0.263 m drawn")  # the odometer's metres, not rounded up
    waiting = asyncio.create_task(changes.wait(job, prompt))
    await settle(lambda: job.state == "pen_change")
    assert link.commands == ["M5", "G0 X0 Y0", "G4 P0"]  # parked first
    assert heard[-1]["transition"]["to"] == "pen_change" and job.actions[0] == "continue"
    changes.loaded(job, "continue")
    assert await waiting is True and job.state == "running" and job.pen_change is None
    again = asyncio.create_task(changes.wait(job, prompt))
    await settle(lambda: job.state == "pen_change")
    life.move(job, "estop")
    changes.ended()
    assert await again is False


async def test_parked_for_a_pen_the_stop_point_is_the_boundary_not_the_park(folder):
    link = await started_link()
    job = a_job("running", lines_total=len(PROGRAM), estimate_s=10.0,
                timeline=[(4, 0.0), (15, 10.0)])  # fmt: skip
    life, _ = lifecycle_with(job)
    point = StopPoint(link, folder, life)
    point.reset(1)
    await point.measure(job)
    point.streaming(bytearray(b"\x01" * 15))
    link.status.line, link.status.x = 10, 5.5
    point.report(job, link.status)
    point.live = False  # the stretch stands: lines up to 10 drawn, the carriage parks
    point.parked(job, 11)
    assert job.lines_done == 10 and job.done_point["x"] == 6.0
    link.status.line, link.status.x = None, 0.0  # reports from the park position
    point.report(job, link.status)
    await point.written()
    assert Mark.load(folder / "j1" / MARK_FILE) == Mark(11, 11, 6.0, 0.0)
    life.move(job, "pen_change")
    life.move(job, "estop")  # stopped while it waits for the pen
    point.estopped(job)
    link.status.state, link.status.updated_at = "Alarm", time.time()
    point.standing(link.status)
    await point.written()
    assert Mark.load(folder / "j1" / MARK_FILE) == Mark(11, 11, 6.0, 0.0)
    await settle(lambda: "stopped" in job.summary)
    assert job.lines_done == 10 and job.drawn_mm == pytest.approx(6.0), job.summary
    assert job.summary == "stopped at X 6.0 Y 0.0, 60 % drawn"


class NoPens(Library):
    def layer_pen(self, _layer) -> None:
        return None


async def test_a_pen_change_names_the_pen_else_the_layer_else_the_colour_never_a_code():
    link = await started_link()
    layers = [Layer(name="#000000", first_line=1, last_line=2),
              Layer(name="#d40000", colour="#d40000", first_line=4, last_line=5),
              Layer(name="shade", colour="#1f77b4", first_line=7, last_line=8)]  # fmt: skip
    job = a_job("running", layers=layers)
    life, _ = lifecycle_with(job)
    park = lambda: []  # noqa: E731
    named = PenChanges(link, life, Library(Pen(id=1, name="Red brush")), park)  # type: ignore[arg-type]
    unnamed = PenChanges(link, life, NoPens(Pen(id=1, name="x")), park)  # type: ignore[arg-type]
    prompts = [changes.layer_prompt(job, i) for changes in (named, unnamed) for i in (1, 2)]
    assert [p["message"] for p in prompts] == [
        "Layer 2 of 3 (red): load pen 'Red brush', then continue",
        "Layer 3 of 3, 'shade': load pen 'Red brush', then continue",
        "Layer 2 of 3: load the red pen, then continue",
        "Layer 3 of 3, 'shade': load its pen, then continue",  # not the preview's colour
    ]
    assert [p["name"] for p in prompts[2:]] == ["red", "shade"]
    assert not any("#" in str(p["message"]) + str(p["name"]) for p in prompts)


async def test_after_job_moves_keep_the_plotter_busy_until_done():
    link = await started_link()
    moves = AfterJobMoves("p1", link, "park", (5.0, 7.5))
    job = a_job("done")
    lines = moves.claim(job)
    assert lines == ["M5", "G0 X5.000 Y7.500", "G4 P0"] and "finishes job j1" in moves.busy
    await moves.run(job, lines)
    assert link.commands == lines and moves.busy is None
    job.after = "none"
    assert moves.claim(job) == [] and moves.busy is None
    job.after = "home"
    assert moves.lines(job) == ["M5", "$H"]
