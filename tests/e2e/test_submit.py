"""`plotbridge submit` against a real server on the virtual plotter."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import pytest

from tests.fixtures.cli import start_submit
from tests.fixtures.drawings import LONG

SQUARE = "G21\nG90\nG0 X10 Y10\nM3\nG1 X40 Y10 F3000\nG1 X40 Y40\nG1 X10 Y40\nG1 X10 Y10\nM5\n"


@pytest.mark.e2e
def test_submit_start_wait_plots_and_exits_zero(server, plotter, tmp_path):
    server.home()
    drawing = tmp_path / "square.gcode"
    drawing.write_text(SQUARE)
    proc = start_submit(server, str(drawing), "--start", "--wait", "--json")
    out, err = proc.communicate(timeout=120)
    job = json.loads(out)
    assert job["state"] == "done" and job["name"] == "square.gcode", err
    assert job["progress"] == 1
    assert any(len(stroke) >= 5 for stroke in plotter.trace()["strokes"])


@pytest.mark.e2e
def test_submit_reports_validation_errors_with_lines(server, tmp_path):
    drawing = tmp_path / "broken.gcode"
    drawing.write_text("G21\nG1 X10 Y10 F1000\nG1 X10 Q5\nG1 X9000 Y0\n")
    proc = start_submit(server, str(drawing))
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 1
    assert "line 3" in err and "line 4" in err, err
    assert server.client.get("/api/jobs").json() == []


@pytest.mark.e2e
def test_submit_wait_exits_nonzero_when_the_job_is_stopped(server, tmp_path):
    server.home()
    drawing = tmp_path / "long.gcode"
    drawing.write_text(LONG)
    proc = start_submit(server, str(drawing), "--start", "--wait", "--poll", "0.1")
    server.wait_machine(lambda m: m["state"] == "Run", 30)
    time.sleep(0.3)
    assert server.client.post("/api/machine/estop").status_code == 202
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 1, err
    assert server.client.get("/api/jobs").json()[0]["state"] == "stopped"


@pytest.mark.e2e
def test_submit_without_token_or_file_says_what_is_missing(server, tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "PLOTBRIDGE_TOKEN"}
    missing_token = subprocess.run(
        [sys.executable, "-m", "plotbridge", "submit", __file__, "--server", server.url],
        env=env, capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert missing_token.returncode == 2 and "token" in missing_token.stderr
    missing_file = start_submit(server, str(tmp_path / "nope.svg"))
    _, err = missing_file.communicate(timeout=60)
    assert missing_file.returncode == 2 and "no such file" in err
