"""The command line's client verbs (status, queue, pause, resume, stop, act, home) against
a real server on the virtual plotter."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys

import pytest

from tests.fixtures.cli import run_cli
from tests.fixtures.drawings import LONG


def answer(server, *args: str, **kwargs) -> dict | list:
    done = run_cli(server, *args, "--json", **kwargs)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


@pytest.mark.e2e
def test_verbs_drive_a_job_through_pause_resume_and_stop(server_virtual, tmp_path):
    token_file = tmp_path / "token"
    token_file.write_text(server_virtual.token)
    home = answer(server_virtual, "home", token_file=token_file)
    assert home["machine"]["state"] == "Idle"
    assert answer(server_virtual, "queue") == []
    status = answer(server_virtual, "status")
    assert status["url"] == server_virtual.url and status["job"] is None
    assert status["plotters"][0]["machine"]["state"] == "Idle"
    job = server_virtual.client.post("/api/jobs", files={"file": ("long.gcode", LONG)},
                                     data={"start": "true"}).json()  # fmt: skip
    server_virtual.wait_job(job["id"], "running", 60)
    assert answer(server_virtual, "pause")["state"] == "paused"
    text = run_cli(server_virtual, "status")
    assert f"job {job['id']}  paused" in text.stdout, text.stdout
    assert answer(server_virtual, "resume", job["id"])["state"] == "running"
    assert answer(server_virtual, "stop", "--all")["status"] == "stopped"
    server_virtual.wait_job(job["id"], "stopped", 30)
    [listed] = answer(server_virtual, "queue")
    assert listed["id"] == job["id"] and listed["state"] == "stopped"
    assert f"{job['id']}  stopped" in run_cli(server_virtual, "queue").stdout
    shown = run_cli(server_virtual, "queue").stdout  # the server's words and actions
    assert "stopped at X " in shown and "actions: resume, home_then_resume" in shown, shown
    refused = run_cli(server_virtual, "act", job["id"], "continue")
    assert refused.returncode == 1 and "is stopped: cannot continue it" in refused.stderr
    assert "(it allows: resume, home_then_resume, resume_from" in refused.stderr
    assert answer(server_virtual, "act", job["id"], "cancel")["actions"] == [
        "resume_from", "restart", "frame", "delete"]


@pytest.mark.e2e
def test_verbs_report_failures_clearly(server_virtual):
    nothing = run_cli(server_virtual, "pause")
    assert nothing.returncode == 1 and "no job is running" in nothing.stderr
    refused = subprocess.run(
        [sys.executable, "-m", "plotbridge", "queue", "--url", server_virtual.url,
         "--token", "a-wrong-token-of-enough-length"],
        capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert refused.returncode == 1 and "(401)" in refused.stderr
    env = {k: v for k, v in os.environ.items() if not k.startswith("PLOTBRIDGE_")}
    no_token = subprocess.run([sys.executable, "-m", "plotbridge", "status", "--url",
                               server_virtual.url], env=env, capture_output=True, text=True,
                              timeout=60)  # fmt: skip
    assert no_token.returncode == 2 and "no token" in no_token.stderr
    nowhere = subprocess.run([sys.executable, "-m", "plotbridge", "status", "--url",
                              "http://127.0.0.1:9", "--token", "a-token-of-enough-length"],
                             capture_output=True, text=True, timeout=60)  # fmt: skip
    assert nowhere.returncode == 2 and "cannot reach" in nowhere.stderr  # no server: 2
    unknown = run_cli(server_virtual, "home", "--plotter", "nope")
    # 404 from a server with several plotters; 405 from one without per-plotter paths
    assert unknown.returncode == 1 and re.search(r"homing failed \(40[45]\)", unknown.stderr)
