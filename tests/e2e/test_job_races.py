"""End to end: racing actions on one job (issue 26), through a real `plotbridge serve`
with two simulated plotters: two resumes from a point, a resume and a restart, a cancel and
a resume, sent together many times to a job started without a target. One wins, the
other answers 409 with the job's state and actions, and the job never runs on two
plotters."""

from __future__ import annotations

import threading
import time

import httpx
import pytest

from tests.fixtures.drawings import LONG
from tests.fixtures.server import TOKEN, ServerProcess, running_server

pytestmark = pytest.mark.e2e

NAMES = ("plotter1", "plotter2")
ROUNDS = 3
PAIRS = {
    "two resumes from a point": (("resume_from", {"from": {"line": 40}}),
                                 ("resume_from", {"from": {"line": 40}})),
    "a resume and a restart": (("resume", None), ("restart", None)),
    "a cancel and a resume": (("cancel", None), ("resume", None)),
}  # fmt: skip


def home(server: ServerProcess, name: str) -> None:
    server.wait_plotter(name, lambda m: m["connected"], 30)
    response = server.client.post(f"/api/plotters/{name}/machine/home", timeout=130)
    assert response.status_code == 200, response.text
    server.wait_plotter(name, lambda m: m["state"] == "Idle", 30)


def together(server: ServerProcess, job_id: str, pair) -> list[httpx.Response]:
    """Both actions sent at the same moment, each on its own connection."""
    barrier = threading.Barrier(len(pair))
    answers: list[httpx.Response | None] = [None] * len(pair)

    def send(index: int, action: str, body) -> None:
        with httpx.Client(base_url=server.url, timeout=130,
                          headers={"Authorization": f"Bearer {TOKEN}"}) as client:  # fmt: skip
            client.get("/api/health")  # connected before the barrier
            barrier.wait()
            answers[index] = client.post(f"/api/jobs/{job_id}/{action}", json=body)

    threads = [threading.Thread(target=send, args=(i, *p)) for i, p in enumerate(pair)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(150)
    assert all(answer is not None for answer in answers)
    return answers  # type: ignore[return-value]


def runs_on(server: ServerProcess, job_id: str) -> list[str]:
    return [name for name, p in server.plotters().items() if p["job"] == job_id]


@pytest.mark.parametrize("pair_name", list(PAIRS))
def test_racing_actions_one_wins_the_other_409(plotter_factory, tmp_path, pair_name):
    sims = [plotter_factory(speed=0) for _ in NAMES]
    serial = [arg for sim in sims for arg in ("--serial", str(sim.port))]
    with running_server(tmp_path / "data", serial) as server:
        for name in NAMES:
            home(server, name)
        response = server.client.post("/api/jobs", files={"file": ("long.gcode", LONG)})
        job = response.json()
        for _ in range(ROUNDS):
            state = server.job(job["id"])["state"]
            if state in ("queued", "cancelled"):  # first round, or a cancel won the last
                started = server.client.post(f"/api/jobs/{job['id']}/restart"
                                             if state == "cancelled" else
                                             f"/api/jobs/{job['id']}/start")  # fmt: skip
                assert started.status_code == 200, started.text
            server.wait_job(job["id"], ("running",), 30)
            stop = server.client.post(f"/api/jobs/{job['id']}/stop")
            assert stop.status_code == 200, stop.text
            stopped = server.wait_job(job["id"], ("stopped",), 10)
            assert stopped["actions"][:2] == ["resume", "home_then_resume"]
            for name in NAMES:
                home(server, name)
            answers = together(server, job["id"], PAIRS[pair_name])
            codes = sorted(answer.status_code for answer in answers)
            after = server.job(job["id"])
            if codes == [200, 200]:  # a resume, then the cancel of the running job: no loser
                assert pair_name == "a cancel and a resume" and after["state"] == "cancelled"
            else:
                assert codes == [200, 409], [a.text for a in answers]
                lost = next(a for a in answers if a.status_code == 409).json()["detail"]
                assert {"message", "state", "actions"} <= set(lost), lost
            assert after["state"] in ("running", "cancelled"), after
            deadline = time.monotonic() + 1.0  # never on two plotters, also a moment later
            while time.monotonic() < deadline:
                assert len(runs_on(server, job["id"])) <= 1
                moving = [n for n, p in server.plotters().items()
                          if p["machine"]["state"] == "Run"]  # fmt: skip
                assert len(moving) <= 1, moving
                time.sleep(0.1)
        server.client.post(f"/api/jobs/{job['id']}/cancel")
