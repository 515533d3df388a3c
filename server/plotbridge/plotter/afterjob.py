"""What a plotter does once a job is done (`--after-job`, the job's `after`): pen up and
park, or home. The plotter takes no job meanwhile (`busy`)."""

from __future__ import annotations

import logging

from plotbridge.jobs.model import AfterJob, Job
from plotbridge.plotter.link import Link

log = logging.getLogger("plotbridge.runner")

AFTER_JOB_S = 120.0  # s a park move or a homing cycle after a job may take


class AfterJobMoves:
    def __init__(self, plotter: str, link: Link, default: AfterJob,
                 park: tuple[float, float]) -> None:  # fmt: skip
        self.plotter = plotter
        self.link = link
        self.default = default
        self.park = park
        self.busy: str | None = None
        """Why the plotter takes no job although none runs (the moves under way)."""

    def park_lines(self) -> list[str]:
        """Pen up, carriage to the park position; G4 P0 is answered once it stands."""
        x, y = self.park
        return ["M5", f"G0 X{x:.3f} Y{y:.3f}", "G4 P0"]

    def lines(self, job: Job) -> list[str]:
        """The G-code of the job's action (the server's default if unset)."""
        action = job.after or self.default
        if action == "park":
            return self.park_lines()
        if action == "home":
            return ["M5", "$H"]
        return []

    def claim(self, job: Job) -> list[str]:
        """Before the job is told done: its lines, and the plotter busy if there are any."""
        lines = self.lines(job)
        if lines:
            self.busy = f"{self.plotter} finishes job {job.id} ({job.after or self.default})"
        return lines

    async def run(self, job: Job, lines: list[str]) -> None:
        """Send them; a failure is logged (the job stays done)."""
        try:
            for line in lines:
                await self.link.command(line, timeout=AFTER_JOB_S)
        except Exception as exc:  # the board says what went wrong
            log.warning("after job %s: %s failed: %s", job.id, line, exc)
        finally:
            self.busy = None
