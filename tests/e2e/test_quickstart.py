"""The README's quick start, followed from a clean clone: `make run`, open the printed link,
plot a job on the virtual plotter."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import time
from pathlib import Path

import httpx
import pytest

from tests.fixtures.artifacts import ARTIFACTS
from tests.fixtures.server import free_port
from tests.fixtures.waits import wait_until

ROOT = Path(__file__).resolve().parents[2]
LOGIN_LINE = re.compile(
    r"one-time login link for the admin.*\nplotbridge: open (http://\S+/login\.html)#(\S+)")
SQUARE = "G21\nG90\nG0 X10 Y10\nM3\nG1 X30 Y10 F3000\nG1 X30 Y30\nG1 X10 Y30\nG1 X10 Y10\nM5\n"


def wait_for_login_line(log: Path, proc: subprocess.Popen, timeout: float) -> re.Match:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        match = LOGIN_LINE.search(log.read_text(errors="replace"))
        if match:
            return match
        assert proc.poll() is None, f"make run exited:\n{log.read_text()[-4000:]}"
        time.sleep(0.2)
    raise AssertionError(f"no login link after {timeout} s:\n{log.read_text()[-4000:]}")


@pytest.mark.e2e
@pytest.mark.timeout(600)
def test_make_run_from_a_clean_clone_serves_and_plots(tmp_path):
    clone = tmp_path / "plotbridge"
    subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
    port = free_port()
    log = tmp_path / "make-run.log"
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PLOTBRIDGE_", "VIRTUAL_ENV"))}
    started = time.monotonic()
    with log.open("wb") as out:
        proc = subprocess.Popen(
            ["make", "run", f"PORT={port}", "HOST=127.0.0.1", "SIM_SPEED=0"],
            cwd=clone, stdout=out, stderr=subprocess.STDOUT, env=env, start_new_session=True,
        )  # fmt: skip
    try:
        match = wait_for_login_line(log, proc, timeout=420)
        url, code = match.group(1).replace(f"{os.uname().nodename}:", "127.0.0.1:"), match.group(2)
        with httpx.Client(base_url=f"http://127.0.0.1:{port}", timeout=30) as browser:
            page = wait_until(lambda: browser.get(url, follow_redirects=True), bool, 60,
                              "the first page", every=0.1, errors=(httpx.HTTPError,))
            first_page_s = time.monotonic() - started
            assert page.status_code == 200 and "<html" in page.text.lower()
            page_sends = {"X-Plotbridge": "1"}  # as the page's api.js does
            login = {"json": {"link": code}, "headers": page_sends}
            assert browser.post("/api/login", **login).status_code == 204  # its page
            assert "plotbridge_session" in browser.cookies
            assert browser.get("/api/machine").status_code == 200  # the cookie logs in
            assert browser.post("/api/login", **login).status_code == 401  # once

        ARTIFACTS.mkdir(exist_ok=True)
        (ARTIFACTS / "quickstart.txt").write_text(f"make run to first page: {first_page_s:.1f} s\n")

        token = (clone / "data" / "token").read_text().strip()
        api = httpx.Client(
            base_url=f"http://127.0.0.1:{port}", timeout=30,
            headers={"Authorization": f"Bearer {token}"},
        )  # fmt: skip
        with api:

            def machine() -> dict:
                return api.get("/api/machine").json()

            wait_until(machine, lambda m: m["connected"], 60, "the plotter")
            assert api.post("/api/machine/home").status_code in (200, 202)
            wait_until(machine, lambda m: m["state"] == "Idle", 60, "homing")
            job = api.post(
                "/api/jobs", params={"name": "square"}, content=SQUARE,
                headers={"Content-Type": "text/plain"},
            ).json()  # fmt: skip
            assert api.post(f"/api/jobs/{job['id']}/start").status_code == 200
            done = wait_until(lambda: api.get(f"/api/jobs/{job['id']}").json(),
                              lambda j: j["state"] not in ("queued", "running"), 120,
                              "the job to end")
            assert done["state"] == "done", done
            strokes = api.get("/api/sim/trace").json()["strokes"]
            corners = [(round(x), round(y)) for x, y in strokes[-1]]
            assert {(10, 10), (30, 10), (30, 30), (10, 30)} <= set(corners)
    finally:
        os.killpg(proc.pid, signal.SIGTERM)
        try:
            proc.wait(20)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(5)

