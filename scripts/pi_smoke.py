"""The smoke test `scripts/pi-check` drives from outside an emulated Pi, through loopback:
log in with the token's link, home, upload an SVG, plot it, STOP mid-plot, home and resume,
and compare what the virtual plotter drew with the job's preview. Prints each step's time;
exits non-zero at the first step that fails.
Usage: PYTHONPATH=. .venv/bin/python scripts/pi_smoke.py --url URL --token TOKEN [--arch A]
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable
from typing import Any

import httpx

from tests.fixtures.trace import TOLERANCE, deviation

SVG = """<svg xmlns="http://www.w3.org/2000/svg" width="80mm" height="60mm" viewBox="0 0 80 60">
<rect x="5" y="5" width="40" height="40" fill="none" stroke="black"/>
<circle cx="62" cy="30" r="12" fill="none" stroke="black"/>
<path d="M 5 55 L 75 55" stroke="black"/>
</svg>
"""
WAIT_S = 600.0  # s: an emulated server on a loaded machine is slow, a wait is a deadline


class SmokeFailed(Exception):
    pass


def wait_for(what: str, get: Callable[[], Any], ok: Callable[[Any], bool]) -> Any:
    deadline = time.monotonic() + WAIT_S
    while True:
        value = get()
        if ok(value):
            return value
        if time.monotonic() > deadline:
            raise SmokeFailed(f"{what}: not after {WAIT_S:g} s; last: {value}")
        time.sleep(0.2)


class Smoke:
    def __init__(self, url: str, token: str, arch: str):
        self.token = token
        self.arch = arch
        self.http = httpx.Client(base_url=url, timeout=120, headers={"Origin": url})
        self.job_id = ""

    def expect(self, response: httpx.Response, status: int) -> dict:
        if response.status_code != status:
            raise SmokeFailed(f"{response.request.method} {response.request.url.path}: "
                              f"{response.status_code} {response.text[:300]}")
        return response.json() if response.content else {}

    def step(self, name: str, action: Callable[[], str | None]) -> None:
        start = time.monotonic()
        note = action() or ""
        print(f"[smoke {self.arch}] {name:<28} {time.monotonic() - start:7.2f} s  {note}",
              flush=True)

    def job(self) -> dict:
        return self.expect(self.http.get(f"/api/jobs/{self.job_id}"), 200)

    def machine(self) -> dict:
        return self.expect(self.http.get("/api/machine"), 200)

    def login(self) -> str:
        stale = self.http.get("/login", params={"token": "wrong-token-1234567"})
        if stale.status_code != 303 or "link=stale" not in stale.headers.get("location", "") \
                or self.http.cookies:  # fmt: skip
            raise SmokeFailed(f"a wrong token's link gave {stale.status_code} "
                              f"to {stale.headers.get('location')}, not the login page")
        answer = self.http.get("/login", params={"token": self.token})
        if answer.status_code != 303 or not self.http.cookies:
            raise SmokeFailed(f"the login link gave {answer.status_code}, no session cookie")
        server = self.expect(self.http.get("/api/server"), 200)  # by the cookie alone
        return f"version {server['version']}"

    def home(self) -> str:
        wait_for("the board connected", self.machine, lambda m: m["connected"])
        self.expect(self.http.post("/api/machine/home"), 200)
        wait_for("Idle after homing", self.machine, lambda m: m["state"] == "Idle")
        return ""

    def upload(self) -> str:
        job = self.expect(self.http.post(
            "/api/jobs", files={"file": ("pi-smoke.svg", SVG, "image/svg+xml")}), 201)
        self.job_id = job["id"]
        return f"{job['lines_total']} lines, estimate {job['estimate_s']:.1f} s"

    def plot(self) -> str:
        self.expect(self.http.post(f"/api/jobs/{self.job_id}/start"), 200)
        job = wait_for("a third of the plot", self.job,
                       lambda j: j["state"] == "running" and j["progress"] > 0.3)
        return f"progress {job['progress']:.2f}"

    def stop(self) -> str:
        sent = time.monotonic()
        self.expect(self.http.post("/api/machine/estop"), 202)
        answered = time.monotonic() - sent
        job = wait_for("the job stopped", self.job, lambda j: j["state"] == "stopped")
        machine = wait_for("the board in Alarm", self.machine, lambda m: m["state"] == "Alarm")
        return (f"answered in {answered * 1000:.0f} ms; job {job['state']} at "
                f"{job['progress']:.2f}, board {machine['state']}")

    def resume(self) -> str:
        self.home()
        self.expect(self.http.post(f"/api/jobs/{self.job_id}/resume"), 200)
        job = wait_for("the job ended", self.job,
                       lambda j: j["state"] in ("done", "failed", "stopped", "interrupted"))
        if job["state"] != "done":
            raise SmokeFailed(f"the resumed job ended {job['state']}: {job.get('error')}")
        return "done"

    def compare(self) -> str:
        preview = self.expect(self.http.get(f"/api/jobs/{self.job_id}/preview"), 200)["strokes"]
        drawn = self.expect(self.http.get("/api/sim/trace"), 200)["strokes"]
        missing = deviation([p for s in preview for p in s], drawn)
        extra = deviation([p for s in drawn for p in s], preview)
        if max(missing, extra) >= TOLERANCE:
            raise SmokeFailed(f"trace vs preview: {missing:.3f} mm of the preview not drawn, "
                              f"{extra:.3f} mm drawn off it (allowed {TOLERANCE})")
        return f"within {max(missing, extra):.3f} mm (allowed {TOLERANCE})"


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--url", required=True)
    parser.add_argument("--token", required=True)
    parser.add_argument("--arch", default="?")
    args = parser.parse_args()
    smoke = Smoke(args.url, args.token, args.arch)
    try:
        smoke.step("login by the token's link", smoke.login)
        smoke.step("home", smoke.home)
        smoke.step("upload SVG", smoke.upload)
        smoke.step("plot to a third", smoke.plot)
        smoke.step("STOP", smoke.stop)
        smoke.step("home, resume to done", smoke.resume)
        smoke.step("trace vs preview", smoke.compare)
    except (SmokeFailed, httpx.HTTPError) as exc:
        print(f"[smoke {args.arch}] FAILED: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
