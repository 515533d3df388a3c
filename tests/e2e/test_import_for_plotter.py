"""An upload is imported for the plotter it will run on: the work area it is checked and
placed against, and the estimate's motion model (settings, the board's firmware build
and the planner depth its `$I` reports), through a real server with two virtual plotters
of different boards and work areas (plotters.toml)."""

from __future__ import annotations

import pytest
from plotbridge.jobs.imports import run_import

from tests.fixtures.server import ServerProcess, running_server

pytestmark = pytest.mark.e2e

PLOTTERS = """
[[plotter]]
name = "small"
virtual = true

[[plotter]]
name = "big"
virtual = true
board = "mega-ramps14"
width = 420
height = 297
"""


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    data = tmp_path_factory.mktemp("import-for-plotter") / "server-data"
    data.mkdir()
    (data / "plotters.toml").write_text(PLOTTERS)
    with running_server(data, [], ["--sim-speed", "0"]) as proc:
        for name in ("small", "big"):
            proc.wait_plotter(name, lambda m: m["connected"] and m["firmware"], 60)
        yield proc


def upload(server: ServerProcess, text: str, name: str, **fields: str):
    return server.client.post("/api/jobs", files={"file": (name, text)},
                              data={"start": "false", **fields})  # fmt: skip


def messages(response) -> str:
    return " ".join(e["message"] for e in response.json()["detail"]["errors"])


WIDE = "G21\nG90\nG0 X10 Y10\nM3\nG1 X400 Y250 F3000\nM5\n"   # fits only the big one


def test_a_move_is_checked_against_the_named_plotters_work_area(server):
    assert upload(server, WIDE, "wide.gcode", plotter="big").status_code == 201
    refused = upload(server, WIDE, "wide.gcode", plotter="small")
    assert refused.status_code == 422, refused.text
    assert "X400.000 Y250.000 is outside the work area" in messages(refused)
    assert "420" not in messages(refused)        # the small plotter's area, not the big one's


def test_a_job_for_no_plotter_is_planned_for_the_largest_and_goes_there(server):
    uploaded = upload(server, WIDE, "wide.gcode")
    assert uploaded.status_code == 201, uploaded.text
    job_id = uploaded.json()["id"]
    started = server.client.post(f"/api/jobs/{job_id}/start")
    assert started.status_code == 200, started.text
    job = server.job(job_id)
    # it runs on big, or waits for big (which boots in Alarm until homed), never for small
    assert job["plotter"] == "big" or "does not fit small" in (job["waiting"] or ""), job
    server.client.post(f"/api/jobs/{job_id}/cancel")


SVG = ('<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm" '
       'viewBox="0 0 100 100"><rect x="0" y="0" width="100" height="100" fill="none" '
       'stroke="black"/></svg>')


def test_paper_and_fit_use_the_named_plotters_area(server):
    a3 = upload(server, SVG, "square.svg", plotter="big", paper="A3", margin="0")
    assert a3.status_code == 201, a3.text
    # turned landscape to fit the 420 x 297 mm plotter; the square centred on it
    assert a3.json()["bounds"]["max_x"] == pytest.approx(260, abs=0.01)
    assert any("landscape" in w["message"] for w in a3.json()["warnings"])
    small = upload(server, SVG, "square.svg", plotter="small", paper="A3")
    assert small.status_code == 422, small.text
    assert "larger than the work area" in messages(small)
    fit = upload(server, SVG, "square.svg", plotter="big", fit="true", margin="0")
    assert fit.json()["bounds"]["max_y"] == pytest.approx(297, abs=0.01)


def dense_line(lines: int = 600, segment: float = 0.2) -> str:
    """A straight stroke of short collinear segments: no corner slows it down."""
    moves = (f"G1 X{10 + k * segment:.3f} Y50 F6000" for k in range(1, lines + 1))
    return "\n".join(["G21", "G90", "G0 X10 Y50", "M3", *moves, "M5"]) + "\n"


def settings(server: ServerProcess, name: str) -> dict[int, float]:
    listed = server.client.get(f"/api/plotters/{name}/machine/settings").json()["settings"]
    return {s["id"]: s["value"] for s in listed}


def test_the_estimate_runs_the_named_boards_model(server, tmp_path):
    # short segments at a low acceleration: the planner's depth sets the speed
    slow = {"120": 100, "121": 100}
    for name in ("small", "big"):
        put = server.client.put(f"/api/plotters/{name}/machine/settings", json={"settings": slow})
        assert put.status_code == 200, put.text
    drawing = dense_line()
    estimates = {}
    for name in ("small", "big"):
        job = upload(server, drawing, "line.gcode", plotter=name)
        assert job.status_code == 201, job.text
        estimates[name] = job.json()["estimate_s"]
    machine = server.plotters()["big"]["machine"]
    board = {"settings": {**settings(server, "big"), 130: 420, 131: 297},
             "firmware": machine["firmware"], "profile": "mega-ramps14"}

    def estimate(blocks: int) -> float:
        source = tmp_path / f"line-{blocks}.gcode"
        source.write_text(drawing)
        dest = tmp_path / f"out-{blocks}"
        out = run_import("file", str(source), "line.gcode", str(dest), {},
                         {**board, "planner_blocks": blocks, "line_numbers": True})  # fmt: skip
        assert out[0] == "ok", out
        return out[1]["estimate_s"]

    assert estimates["big"] == estimate(63)        # the Mega's depth, as its $I reports
    assert estimates["big"] < estimate(33) * 0.95  # not the Uno's
    assert estimates["big"] < estimates["small"] * 0.95
