"""End to end: each layer of a job carries its estimate, pen-down length and progress,
updated as the real server streams the job to the simulated plotter: a layer under way
is part done and the ones after it untouched, a layer before a pen change is complete
and the simulator drew its length, and a done job has every layer complete."""

from __future__ import annotations

import pytest

from tests.fixtures.drawings import drawing

pytestmark = pytest.mark.e2e

SQUARE = ["G0 X20 Y80", "M3", "G1 X40 Y80 F3000", "G1 X40 Y100 F3000", "G1 X20 Y100 F3000",
          "G1 X20 Y80 F3000", "M5"]  # fmt: skip
# three layers split at M0 (named by its message): two circles, a square, a smaller square
PROGRAM = (drawing(circles=2, radius=8) + "M0 red pen\n" + "\n".join(SQUARE) + "\nM0 blue pen\n"
           + "\n".join(SQUARE).replace("X40", "X30").replace("Y100", "Y90") + "\n")  # fmt: skip


def test_layers_carry_estimate_length_and_progress(server, plotter):
    server.home()
    plotter.clear()
    job = server.submit(PROGRAM)
    layers = job["layers"]
    assert len(layers) == 3
    # the layers' times leave out only the travel between them and the pen changes
    assert 0.8 * job["estimate_s"] < sum(layer["estimate_s"] for layer in layers) <= \
        job["estimate_s"]
    assert sum(layer["pen_down_mm"] for layer in layers) == pytest.approx(
        job["stats"]["pen_down_mm"], rel=1e-3)  # fmt: skip
    assert layers[1]["pen_down_mm"] == pytest.approx(80, abs=0.01)  # the 20 mm square
    assert layers[2]["pen_down_mm"] == pytest.approx(40, abs=0.01)  # the 10 mm square
    assert all(layer["progress"] == 0 and layer["lines_done"] == 0 for layer in layers)

    # part way through the first layer
    running = server.wait_progress(job["id"], 60)
    first, second, third = running["layers"]
    assert 0 < first["progress"] < 1
    # the layer's lines are the job's finished ones (both from the same report)
    assert first["lines_done"] == running["lines_done"] - first["first_line"] + 1
    assert second["progress"] == third["progress"] == 0 and second["lines_done"] == 0

    changing = server.wait_pen_change(job["id"], 2)
    first, second, third = changing["layers"]
    total = first["last_line"] - first["first_line"] + 1
    assert first["progress"] == 1 and first["lines_done"] == total
    assert second["progress"] == third["progress"] == 0
    drawn = plotter.trace()["draw_mm"]
    assert drawn == pytest.approx(first["pen_down_mm"], rel=0.01)  # the length it announced
    assert server.client.post(f"/api/jobs/{job['id']}/resume").status_code == 200

    changing = server.wait_pen_change(job["id"], 3)
    assert [layer["progress"] for layer in changing["layers"]] == [1, 1, 0]
    assert plotter.trace()["draw_mm"] - drawn == pytest.approx(80, rel=0.01)
    assert server.client.post(f"/api/jobs/{job['id']}/resume").status_code == 200

    done = server.wait_job(job["id"], ("done", "failed", "stopped"), 120)
    assert done["state"] == "done", done
    assert [layer["progress"] for layer in done["layers"]] == [1, 1, 1]
    assert all(layer["lines_done"] == layer["last_line"] - layer["first_line"] + 1
               for layer in done["layers"])  # fmt: skip
