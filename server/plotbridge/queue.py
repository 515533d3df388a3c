"""The queue: every job in order, and which plotter runs which.

The queue keeps the jobs in memory (the truth while running) and mirrors each
change to the store and the event hub. It sends a started job to a free, ready
plotter whose work area fits it (or to the one the job names). A job nothing
can run yet (its plotter in Alarm, disconnected, or busy) `waits` with the
reason and starts by itself when a plotter becomes Idle and free, in queue
order. Refused (409) is only what waiting cannot cure: a job that fits no
plotter's work area, and a stopped or interrupted job (its resume needs a homed
machine, which the user asks for).
"""

from __future__ import annotations

import asyncio
import logging
from pathlib import Path
from typing import Any

from plotbridge.errors import Refused
from plotbridge.events import EventHub, Message
from plotbridge.jobs.imports import Importer
from plotbridge.jobs.lifecycle import Lifecycle
from plotbridge.jobs.model import ACTIVE, RESUMABLE, Job, Layer
from plotbridge.papers import orient
from plotbridge.pens import PenLibrary
from plotbridge.plotter.plotter import Plotter
from plotbridge.resume import ResumePoint, first_line

log = logging.getLogger("plotbridge.queue")


class JobQueue:
    def __init__(self, plotters: list[Plotter], lifecycle: Lifecycle, importer: Importer,
                 events: EventHub, auto_start: bool = False,
                 pens: PenLibrary | None = None) -> None:  # fmt: skip
        if not plotters:
            raise ValueError("a server needs at least one plotter")
        self.plotters = {plotter.name: plotter for plotter in plotters}
        self.lifecycle = lifecycle
        self.store = lifecycle.store
        self.importer = importer
        self.events = events
        self.auto_start = auto_start
        self.pens = pens
        events.subscribe(self._heard)

    @property
    def jobs(self) -> dict[str, Job]:
        """Every job, in queue order (the lifecycle's registry)."""
        return self.lifecycle.jobs

    def _heard(self, message: Message) -> None:
        """A plotter that became free takes what waits."""
        if message.get("type") == "plotter" and message.get("free"):
            self.dispatch()

    @property
    def first(self) -> Plotter:
        return next(iter(self.plotters.values()))

    def plotter(self, name: str | None) -> Plotter:
        """The named plotter (404 if none), or the first one."""
        if name is None:
            return self.first
        plotter = self.plotters.get(name)
        if plotter is None:
            raise Refused(404, f"no plotter named {name!r}; there are: "
                               + ", ".join(self.plotters))  # fmt: skip
        return plotter

    # ---- lifecycle -------------------------------------------------------------------

    def load(self) -> None:
        """Read the store; a job that was running when the server died is interrupted."""
        for job in self.store.load_all():
            job.claim = None
            if job.state in ACTIVE:
                job.resume_line = job.safe_line or 1
                job.error = "the server stopped while this job was running"
                if job.plotter in self.plotters:  # where its board ran out tells the rest
                    self.plotters[job.plotter].runner.orphaned(job)
                self.lifecycle.restarted(job)
                log.info("job %s (%s) interrupted by a server restart", job.id, job.name)
            elif job.state == "waiting":  # waits again once the plotters are there
                job.waiting = "the server restarted"
            self.jobs[job.id] = job

    # ---- reading ------------------------------------------------------------------------

    def get(self, job_id: str) -> Job:
        job = self.jobs.get(job_id)
        if job is None:
            raise Refused(404, f"no job with id {job_id!r}")
        return job

    def list(self) -> list[dict[str, Any]]:
        return [job.public() for job in self.jobs.values()]

    def preview_path(self, job_id: str) -> Path:
        self.get(job_id)
        return self.importer.preview_path(job_id)

    # ---- changes -----------------------------------------------------------------------

    async def create(self, *, kind: str, source: Path | str, filename: str, name: str,
                     options: dict[str, Any], placement: dict[str, Any],
                     target: str | None = None, after: str | None = None,
                     pens: dict[str, Any] | None = None,
                     owner: str | None = None,
                     approval: dict[str, Any] | None = None) -> Job:  # fmt: skip
        """Import an upload (a file already on disk) or a pattern into a new queued job;
        `pens` names pens for some of its layers (the others get their default pen)."""
        plotter = self._planned_for(target)
        placement, turned = self._oriented(placement, plotter)
        options = {**options, **placement}
        job_id, kept, result = await self.importer.create(kind, source, filename, options,
                                                          plotter.import_model())  # fmt: skip
        job = Job(id=job_id, name=name, kind=kind, source=kept, filename=filename,
                  options=options, placement=placement, target=target, after=after,
                  format=result.format, lines_total=result.lines_total,
                  estimate_s=result.estimate_s, owner=owner, approval=approval,
                  state="awaiting_approval" if approval else "queued")  # fmt: skip
        job.imported(result)
        try:
            self._assign_pens(job, pens)
        except Refused:
            await self.importer.delete(job_id)
            raise
        job.warnings += turned
        self.jobs[job_id] = job
        await asyncio.wrap_future(self.store.save(job, len(self.jobs) - 1))
        self.lifecycle.publish(job, save=False)
        log.info("job %s (%s) queued: %d lines", job_id, name, job.lines_total)
        self.dispatch()
        return job

    async def reimport(self, job_id: str, name: str | None,
                       placement: dict[str, Any] | None) -> Job:  # fmt: skip
        job = self.get(job_id)
        self.lifecycle.check(job, "edit")
        if placement is not None:
            plotter = self._planned_for(job.target)
            placement, turned = self._oriented({**job.placement, **placement}, plotter)
            options = {**job.options, **placement}
            result = await self.importer.reimport(
                job_id, job.kind, job.source, job.filename, options, plotter.import_model(),
                still_wanted=lambda: job.state == "queued",
            )  # fmt: skip
            kept = job.layers
            job.imported(result)
            self._assign_pens(job, None, kept)
            job.warnings += turned
            job.options = options
            job.placement = placement
        if name is not None:
            job.name = name
        self.lifecycle.publish(job)
        return job

    def set_pens(self, job_id: str, pens: dict[str, Any]) -> Job:
        """Which pen draws which layer (by layer number or name), while the job does not run."""
        job = self.get(job_id)
        if job.active:
            raise Refused(409, f"job {job_id} is {job.state}; change its pens before it runs")
        self._assign_pens(job, pens, job.layers)
        self.lifecycle.publish(job)
        return job

    def _assign_pens(self, job: Job, wanted: dict[str, Any] | None,
                     kept: list[Layer] | None = None) -> None:  # fmt: skip
        if self.pens is not None:
            self.pens.assign(job.layers, wanted, kept)
        elif wanted:
            raise Refused(409, "this server has no pen library")

    def _planned_for(self, target: str | None) -> Plotter:
        """The plotter an import plans for (its work area, its estimate): the one the job
        names, else the one with the largest work area (the first of equal ones), so an
        import refuses only what no plotter can draw and the queue sends the job to a
        plotter it fits."""
        if target is not None:
            return self.plotter(target)

        def area(plotter: Plotter) -> float:
            a = plotter.work_area
            return a.width * a.height if a is not None else 0.0

        return max(self.plotters.values(), key=area)

    @staticmethod
    def _oriented(placement: dict[str, Any],
                  plotter: Plotter) -> tuple[dict[str, Any], list[dict]]:  # fmt: skip
        """A paper too large upright for the work area the import plans for, turned to
        landscape by itself; the warning that says so (the job shows it)."""
        area, paper = plotter.work_area, placement.get("paper")
        if not (paper and area):
            return placement, []
        name, note = orient(paper, area.width, area.height)
        if note is None:
            return placement, []
        return {**placement, "paper": name}, [{"line": None, "message": note}]

    def move(self, job_id: str, position: int) -> list[dict[str, Any]]:
        job = self.get(job_id)
        self.lifecycle.check(job, "move")
        ids = list(self.jobs)
        movable = ("queued", "waiting")
        waiting = [i for i in ids if self.jobs[i].state in movable and i != job_id]
        position = min(position, len(waiting))
        waiting.insert(position, job_id)
        slots = iter(waiting)
        order = [next(slots) if self.jobs[i].state in movable else i for i in ids]
        self.lifecycle.jobs = {i: self.jobs[i] for i in order}
        self.store.set_order(order)
        self.events.publish({"type": "queue", "order": order})
        log.info("job %s moved to waiting position %d", job_id, position)
        self.dispatch()
        return self.list()

    async def delete(self, job_id: str) -> None:
        job = self.get(job_id)
        self.lifecycle.check(job, "delete")
        self.lifecycle.forget(job)
        await asyncio.wrap_future(self.store.delete(job_id))
        await self.importer.delete(job_id)
        log.info("job %s deleted", job_id)

    # ---- placing and dispatch ----------------------------------------------------------

    def start(self, job: Job, cause: str, point: ResumePoint | None = None) -> None:
        """Run `job` on the plotter it goes to now (`cause`: the action), or, for a start or
        a restart no plotter can take now, let it wait; refused (409) what waiting cannot
        cure: a job that fits no plotter, or a resume (it needs its plotter ready)."""
        plotter, reason = self._place(job)
        if plotter is not None:
            self._begin(job, plotter, cause, point)
        elif cause not in ("start", "restart") or not any(
                p.fits(job) for p in self.candidates(job)):  # fmt: skip
            raise Refused(409, reason)
        else:
            self.lifecycle.move(job, "wait", waiting=reason, error=None)
            log.info("job %s waits: %s", job.id, reason)

    def select_layers(self, job: Job, layers: list[int] | None,
                      start_layer: int | None) -> None:  # fmt: skip
        """The start options: plot `layers` (1-based; None: all) from `start_layer` on."""
        count = max(len(job.layers), 1)
        if layers is None and start_layer is None:
            job.plot_layers = None
            return
        chosen = set(layers if layers is not None else range(1, count + 1))
        wrong = sorted(k for k in chosen | {start_layer or 1} if not 1 <= k <= count)
        if wrong:
            raise Refused(422, f"layer {wrong[0]}: job {job.id} has {count} layer(s), "
                               f"numbered 1 to {count}")  # fmt: skip
        chosen = {k for k in chosen if k >= (start_layer or 1)}
        if not chosen:
            raise Refused(422, f"no layer left to plot: start_layer {start_layer} comes after "
                               f"every layer in {sorted(set(layers or []))}")  # fmt: skip
        job.plot_layers = sorted(chosen)

    def dispatch(self) -> None:
        """Start what waits (and, with auto-start, what is queued) on free plotters, in order."""
        for job in list(self.jobs.values()):
            if job.claim is None and (job.state == "waiting"
                                      or (self.auto_start and job.state == "queued")):
                plotter, reason = self._place(job)
                if plotter is not None:
                    self._begin(job, plotter, "dispatch")
                elif job.state == "waiting" and reason != job.waiting:
                    job.waiting = reason
                    self.lifecycle.publish(job, save=False)

    def candidates(self, job: Job) -> list[Plotter]:
        """The plotters `job` may run on: the one it names, else (resuming) the one it ran
        on, else all."""
        if job.target is not None:
            return [self.plotter(job.target)]
        if job.state in RESUMABLE and job.plotter in self.plotters:
            return [self.plotters[job.plotter]]
        return list(self.plotters.values())

    def _place(self, job: Job) -> tuple[Plotter | None, str]:
        """The plotter to run `job` on now, or None and why not."""
        candidates = self.candidates(job)
        reasons = []
        for plotter in candidates:
            if not plotter.fits(job):
                reasons.append(f"the job does not fit {plotter.name}'s work area "
                               f"({plotter.work_area})")  # fmt: skip
                continue
            if job.state in RESUMABLE and not self._same_size(job, plotter):
                reasons.append(f"the job was interrupted on {job.plotter}, whose work area "
                               f"differs from {plotter.name}'s")  # fmt: skip
                continue
            why = plotter.not_ready()
            if why is None:
                return plotter, ""
            reasons.append(why)
        if len(reasons) == 1:
            return None, reasons[0]
        return None, "no plotter can take it now: " + "; ".join(reasons)

    def _same_size(self, job: Job, plotter: Plotter) -> bool:
        previous = self.plotters.get(job.plotter or "")
        return previous is None or previous is plotter or previous.work_area == plotter.work_area

    def _begin(self, job: Job, plotter: Plotter, cause: str,
               point: ResumePoint | None = None) -> None:  # fmt: skip
        if point is not None:
            plotter.runner.begin(job, cause, point.line, True, point)
        elif job.state in RESUMABLE and job.resume_line is not None and cause != "restart":
            plotter.runner.begin(job, cause, job.resume_line, True)
        else:
            plotter.runner.begin(job, cause, first_line(job.layers, job.plot_layers))

    def running_on(self, job: Job) -> Plotter:
        """The plotter an active job runs on."""
        if not job.active or job.plotter not in self.plotters:
            raise Refused(409, f"job {job.id} is {job.state}, not running or paused")
        return self.plotters[job.plotter]

    def busy_plotter(self, name: str | None) -> Plotter:
        """The plotter a hold or continue without a job acts on: the named one, else the
        one running a job, else the first."""
        if name is not None:
            return self.plotter(name)
        return next((p for p in self.plotters.values() if p.job is not None), self.first)

    # ---- stops ----------------------------------------------------------------------------

    def estop(self, name: str | None, source: str, origin: str | None = None) -> Plotter:
        """Stop one plotter (the first with no name) at once; an unknown name stops
        nothing and is refused (404) with the plotters there are."""
        plotter = self.plotters.get(name) if name is not None else self.first
        if plotter is None:
            raise Refused(404, {"message": f"no plotter named {name!r}; there are: "
                                           + ", ".join(self.plotters),
                                "plotters": list(self.plotters)})  # fmt: skip
        plotter.estop(source, origin)
        return plotter

    def estop_all(self, source: str, origin: str | None = None) -> None:
        """Every plotter's reset byte first, then the bookkeeping."""
        for plotter in self.plotters.values():
            plotter.reset_now()
        for plotter in self.plotters.values():
            plotter.stopped(source, origin)

    def snapshot_messages(self) -> list[dict[str, Any]]:
        """What a new WebSocket client is sent first."""
        messages: list[dict[str, Any]] = [
            {"type": "machine", "plotter": p.name, "machine": p.machine()}
            for p in self.plotters.values()
        ]
        messages.append({"type": "jobs", "jobs": self.list()})
        return messages
