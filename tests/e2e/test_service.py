"""The server as a Raspberry Pi's service runs it (deploy/plotbridge.service): its journal
holds no token, and a job it acknowledged survives the process being killed and the page
cache being dropped (what a power cut leaves is the disk: SQLite in WAL with
synchronous=FULL, and the job's files synced before the 201)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.fixtures.drawings import TWO_STROKES
from tests.fixtures.server import ServerProcess, running_server
from tests.fixtures.trace import assert_same_drawing

pytestmark = pytest.mark.e2e
VIRTUAL = ["--virtual", "--sim-speed", "0"]


class ServiceProcess(ServerProcess):
    """`plotbridge serve` without --token: it generates one, as the service does."""

    def command(self) -> list[str]:
        command = super().command()
        at = command.index("--token")
        return command[:at] + command[at + 2:]


def test_the_journal_gets_no_token(tmp_path, monkeypatch):
    server = ServiceProcess(tmp_path / "data", VIRTUAL)
    server.log_path.touch()  # the server's output, standing for the journal's stream:
    st = server.log_path.stat()  # systemd names it in JOURNAL_STREAM as device:inode
    monkeypatch.setenv("JOURNAL_STREAM", f"{st.st_dev}:{st.st_ino}")
    server.start()
    try:
        token = (tmp_path / "data" / "token").read_text().strip()
        server.token = token
        server.client.headers["Authorization"] = f"Bearer {token}"
        server.wait_machine(lambda m: m["connected"], 60)
        log = server.log()
        assert token not in log
        assert f"plotbridge token --data-dir {tmp_path / 'data'}` prints the login link" in log
    finally:
        server.close()


def drop_page_cache() -> None:
    """Clean pages out of memory, so the restart reads the disk (root only: CI runs as root)."""
    Path("/proc/sys/vm/drop_caches").write_text("3\n")


def test_acknowledged_jobs_survive_a_kill_and_a_dropped_page_cache(tmp_path):
    data = tmp_path / "data"
    with running_server(data, VIRTUAL) as server:
        server.wait_machine(lambda m: m["connected"], 60)
        acknowledged = [server.submit(TWO_STROKES, start=False) for _ in range(5)]
        server.kill()  # SIGKILL right after the last 201: no shutdown, no checkpoint
        server.stop()  # reaps the strays (the virtual plotter)
        drop_page_cache()
        server.start()
        server.wait_machine(lambda m: m["connected"], 60)
        listed = {job["id"]: job for job in server.client.get("/api/jobs").json()}
        for job in acknowledged:
            assert listed[job["id"]]["state"] == "queued"
            assert listed[job["id"]]["lines_total"] == job["lines_total"]
        # and their files are whole: the last one plots
        last = acknowledged[-1]["id"]
        server.home()
        assert server.client.post(f"/api/jobs/{last}/start").status_code == 200
        assert server.wait_job(last, ("done", "failed", "stopped"), 120)["state"] == "done"
        trace = server.client.get("/api/sim/trace").json()
        assert_same_drawing(server.preview(last)["strokes"], trace["strokes"])


def test_a_board_unplugged_and_plugged_back_is_found_again(server, plotter):
    """The server opens the board by a stable name (plotsim's --pty-link, as udev's
    /dev/plotter/... link from deploy/70-plotbridge.rules): the name outlives the device."""
    server.home()
    plotter.kill()  # unplugged: the device behind the name is gone
    server.wait_machine(lambda m: not m["connected"], 30)
    plotter.restart()  # plugged back: a new device behind the same name
    server.wait_machine(lambda m: m["connected"], 60)
    server.home()
    job = server.submit(TWO_STROKES)
    assert server.wait_job(job["id"], ("done", "failed", "stopped"), 120)["state"] == "done"
    assert_same_drawing(server.preview(job["id"])["strokes"], plotter.trace()["strokes"])


def test_a_stale_journal_variable_keeps_the_login_link(tmp_path, monkeypatch):
    """Run by hand from a shell that inherited JOURNAL_STREAM, the link is printed."""
    monkeypatch.setenv("JOURNAL_STREAM", "8:12345")
    server = ServiceProcess(tmp_path / "data", VIRTUAL)
    server.start()
    try:
        token = (tmp_path / "data" / "token").read_text().strip()
        assert "/login.html#" in server.log() and token not in server.log()
    finally:
        server.close()

