"""The server verbs MQTT calls: the same ones the REST routes call (api/plotters.py,
api/jobs.py: the queue's stops and the lifecycle's verbs, jobs/actions.py). This is the one
module of the MQTT component that knows the queue and the plotters, so a change of their
interface is a change here only."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from plotbridge.jobs.actions import JobActions
from plotbridge.jobs.model import Job
from plotbridge.queue import JobQueue


class Verbs:
    def __init__(self, queue: JobQueue, actions: JobActions) -> None:
        self.queue = queue
        self.actions = actions

    @property
    def plotters(self) -> list[str]:
        return list(self.queue.plotters)

    def snapshot(self) -> list[dict[str, Any]]:
        return self.queue.snapshot_messages()

    # ---- stops: synchronous, nothing before the reset byte ------------------------------

    def estop(self, plotter: str, source: str) -> None:
        """Refused (404) for a plotter this bridge does not have, as on REST."""
        self.queue.estop(plotter, source)

    def estop_all(self, source: str) -> None:
        self.queue.estop_all(source)

    # ---- the other buttons ------------------------------------------------------------

    def refused_by_job(self, plotter: str, verb: str) -> str | None:
        """Why the plotter's job does not allow `verb` now (its `actions`), or None."""
        job = self.queue.plotter(plotter).job
        if job is None or verb not in ("hold", "continue") or verb in job.actions:
            return None
        return f"{plotter}'s job {job.id} allows {', '.join(job.actions) or 'nothing'} now"

    def hold(self, plotter: str) -> None:
        self.actions.hold_plotter(plotter)

    def go_on(self, plotter: str) -> None:
        self.actions.continue_plotter(plotter)

    async def home(self, plotter: str) -> None:
        await self.queue.plotter(plotter).send("home", "$H", wait=120)

    # ---- fleet jobs ---------------------------------------------------------------------

    def job(self, job_id: str) -> Job | None:
        return self.queue.jobs.get(job_id)

    def free_plotter(self, bounds: dict[str, float] | None) -> str | None:
        """A plotter that could start a job of these bounds now, or None."""
        for unit in self.queue.plotters.values():
            area = unit.work_area
            fits = bounds is None or area is None or (
                bounds["min_x"] >= 0 and bounds["min_y"] >= 0
                and bounds["max_x"] <= area.width + 1e-6 and bounds["max_y"] <= area.height + 1e-6)
            if fits and unit.not_ready() is None and not self._waiting_for(unit.name):
                return unit.name
        return None

    def _waiting_for(self, plotter: str) -> bool:
        """A local job waits to start (it goes first: the fleet takes what is left)."""
        return any(job.state == "waiting" and job.target in (None, plotter)
                   for job in self.queue.jobs.values())  # fmt: skip

    async def create(self, kind: str, source: Path | str, filename: str, name: str,
                     options: dict[str, Any], placement: dict[str, Any],
                     plotter: str | None) -> Job:  # fmt: skip
        """A new queued job from a file (moved into the job) or a pattern's name."""
        return await self.queue.create(kind=kind, source=source, filename=filename, name=name,
                                       options=options, placement=placement, target=plotter)

    async def start(self, job_id: str, plotter: str) -> Job:
        return await self.actions.act(job_id, "start", plotter)

    async def delete(self, job_id: str) -> None:
        await self.actions.act(job_id, "delete")

    def source(self, job_id: str) -> tuple[str, str, str, dict[str, Any], dict[str, Any]]:
        """What a job was made from: its kind, its original file's path (or the pattern's
        name), the file's name, the import options and the placement."""
        job = self.queue.get(job_id)
        source = str(self.queue.importer.jobs_dir / job.id / job.source) if job.kind == "file" \
            else job.source
        return job.kind, source, job.filename, dict(job.options), dict(job.placement)
