"""End to end: a job's progress on a board that does not report the line it draws (stock
GRBL without line numbers: our firmware in the simulator behind tests/fixtures/stock_grbl.py,
which hides `Ln:` and the `N` option, so the server learns `facts.line_numbers` False and
sends no `N` words), through a real `plotbridge serve`: the executed line is the acked one
less what the planner holds, the summary says it is an estimate; `lines_done`, `progress`
and `drawn_mm` never run ahead of what the pen drew while it draws, equal it where the board
stands (a pen change, a stop, the end), and nothing past the resume point counts as done."""

from __future__ import annotations

import pytest

from tests.fixtures.drawings import PROGRESS_THREE_LAYERS, STROKE
from tests.fixtures.server import running_server
from tests.fixtures.trace import DRAWN_TOL_MM, assert_nothing_past_the_resume_point, settled_drawn
from tests.fixtures.waits import wait_until

pytestmark = pytest.mark.e2e

ESTIMATED = "(estimated: the board does not report the line it draws)"


@pytest.fixture
def stock_server(stock_grbl, tmp_path):
    with running_server(tmp_path / "data", ["--serial", stock_grbl.port]) as server:
        server.wait_machine(lambda m: m["connected"], 30)
        yield server


def test_progress_follows_the_pen_without_line_numbers(stock_server, stock_grbl, plotter):
    server = stock_server
    server.home()
    job = server.submit(PROGRESS_THREE_LAYERS)
    share = job["layers"][0]["estimate_s"] / job["estimate_s"]
    samples: list[tuple[dict, float]] = []
    lines_told: set = set()  # the machine object's `line` while it draws

    def sample() -> dict:
        seen = server.job(job["id"])
        samples.append((seen, plotter.trace()["draw_mm"]))  # the pen, read after the job
        lines_told.add(server.machine()["line"])
        return seen

    changing = wait_until(sample, lambda j: j["state"] == "pen_change", 120,
                          "the first pen change", every=0.05)  # fmt: skip
    drawing = [(j, pen) for j, pen in samples if j["state"] == "running"]
    assert len(drawing) >= 3, "the test saw too little of layer 1 being drawn"
    assert all(j["drawn_mm"] <= pen + DRAWN_TOL_MM for j, pen in drawing), [
        (j["drawn_mm"], pen) for j, pen in drawing]  # never ahead of the pen
    done_lines = [j["lines_done"] for j, _ in drawing]
    assert done_lines == sorted(done_lines)
    told = [j["summary"] for j, _ in drawing if j["done_point"] is not None]  # after a report
    assert told and all(summary.endswith(ESTIMATED) for summary in told), told
    assert lines_told == {None}  # no `Ln:` while it draws
    assert stock_grbl.options_hidden > 0 and stock_grbl.numbered == 0  # no `N` either way

    by_lines = changing["lines_done"] / changing["lines_total"]
    print(f"without line numbers, at the first pen change: progress {changing['progress']:.3f},"
          f" plan's share {share:.3f}, lines {by_lines:.3f}")  # fmt: skip
    assert by_lines < 0.10
    assert changing["progress"] == pytest.approx(share, abs=0.05)
    assert changing["drawn_mm"] == pytest.approx(plotter.trace()["draw_mm"], abs=DRAWN_TOL_MM)
    assert changing["layers"][0]["progress"] == 1
    for layer in (2, 3):
        assert server.client.post(f"/api/jobs/{job['id']}/continue").status_code == 200
        if layer == 2:
            server.wait_pen_change(job["id"], 3, 120)
    done = server.wait_job(job["id"], ("done", "failed", "stopped"), 120)
    assert done["state"] == "done" and done["progress"] == 1 and done["eta_s"] == 0
    assert done["drawn_mm"] == pytest.approx(plotter.trace()["draw_mm"], abs=DRAWN_TOL_MM)


def test_a_stop_counts_what_the_pen_drew_without_line_numbers(stock_server, plotter):
    server = stock_server
    server.home()
    job = server.submit(STROKE)
    server.wait_progress(job["id"], 15)
    assert server.client.post("/api/machine/estop").status_code == 202
    server.wait_job(job["id"], ("stopped",), 10)
    stopped, drawn = settled_drawn(server, plotter, job["id"])
    print(f"without line numbers, stopped: drawn_mm {stopped['drawn_mm']:.3f}, the pen drew "
          f"{drawn:.3f}")  # fmt: skip
    assert 0 < stopped["progress"] < 1 and stopped["summary"].startswith("stopped at X ")
    assert_nothing_past_the_resume_point(stopped)
    resumed = server.client.post(f"/api/jobs/{job['id']}/home_then_resume")
    assert resumed.status_code == 200, resumed.text
    done = server.wait_job(job["id"], ("done", "failed", "stopped"), 60)
    assert done["state"] == "done" and done["drawn_mm"] == pytest.approx(160, abs=0.01)
    assert plotter.trace()["draw_mm"] == pytest.approx(160, abs=DRAWN_TOL_MM)  # nothing twice
