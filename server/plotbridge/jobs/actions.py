"""The job actions: each one verb, called by REST (api/jobs.py), the WebSocket (api/ws.py),
the command line (through the client) and MQTT (docs/INTERNALS.md, "The job lifecycle").

`JobActions.act(job_id, action, plotter=None, body=None)` is the one entry point: it checks
the action against the job's state (409 with the state and the allowed actions), runs the
verb and answers the job. Verbs that await (homing, picking a point) hold the job meanwhile
(`Lifecycle.claim`), so of two racing actions one wins and the other gets 409.
"""

from __future__ import annotations

import asyncio
import logging
import time
from typing import Any

from pydantic import ValidationError

from plotbridge.errors import Refused
from plotbridge.jobs.lifecycle import Lifecycle
from plotbridge.jobs.model import Job
from plotbridge.models import DeclineBody, MoveBody, PatchJobBody, ResumeBody, StartBody
from plotbridge.people.actor import ACTOR
from plotbridge.plotter.plotter import HOMING_S, Plotter
from plotbridge.queue import JobQueue
from plotbridge.resume import PickError, ResumePoint, pick

log = logging.getLogger("plotbridge.actions")

Body = dict[str, Any]


def _model(kind: type, body: Body | None) -> Any:
    try:
        return kind(**(body or {}))
    except ValidationError as exc:
        raise Refused(422, exc.errors(include_url=False)) from exc


class JobActions:
    def __init__(self, queue: JobQueue, lifecycle: Lifecycle) -> None:
        self.queue = queue
        self.lifecycle = lifecycle

    async def act(self, job_id: str, action: str, plotter: str | None = None,
                  body: Body | None = None) -> Job:  # fmt: skip
        """Do `action` to the job (`plotter`: the plotter to run it on, where that applies;
        `body`: the action's options, as its REST body). Raises Refused."""
        job = self.queue.get(job_id)
        if plotter is not None:
            self.queue.plotter(plotter)  # an unknown one: 404 naming those there are
        self.lifecycle.check(job, action)
        verb = getattr(self, action if action != "continue" else "continue_")
        result = verb(job, plotter, body)
        if asyncio.iscoroutine(result):
            await result
        return job

    # ---- the verbs (state already checked) -------------------------------------------------

    def start(self, job: Job, plotter: str | None, body: Body | None) -> None:
        self._options(job, body)
        self._target(job, plotter)
        self.queue.start(job, "start")

    def restart(self, job: Job, plotter: str | None, body: Body | None) -> None:
        self._options(job, body)
        self._target(job, plotter)
        self.queue.start(job, "restart")

    def hold(self, job: Job, _plotter: str | None, _body: Body | None) -> None:
        self.queue.running_on(job).runner.pause()

    def continue_(self, job: Job, _plotter: str | None, _body: Body | None) -> None:
        self.queue.running_on(job).runner.resume()

    def stop(self, job: Job, _plotter: str | None, _body: Body | None) -> None:
        self.queue.running_on(job).estop("REST/WebSocket: stop job " + job.id)

    async def cancel(self, job: Job, _plotter: str | None, _body: Body | None) -> None:
        if job.active:
            await self.queue.running_on(job).runner.cancel(job)
        else:
            self.lifecycle.move(job, "cancel", error=None, waiting=None)

    async def resume(self, job: Job, plotter: str | None, body: Body | None) -> None:
        """Exactly where the pen stopped (then the layers chosen: `layers`); a plotter in
        Alarm is homed first."""
        options = self._resume_options(body)
        await self._resume(job, "resume", plotter, options, home=True if options.home else None)

    async def home_then_resume(self, job: Job, plotter: str | None,
                               body: Body | None) -> None:  # fmt: skip
        await self._resume(job, "home_then_resume", plotter, self._resume_options(body),
                           home=True)  # fmt: skip

    async def resume_from(self, job: Job, plotter: str | None, body: Body | None) -> None:
        options: ResumeBody = _model(ResumeBody, body)
        if options.where() is None:
            raise Refused(422, "from: say where to resume from ({x, y}, {line} or {layer})")
        await self._resume(job, "resume_from", plotter, options, options.home)

    async def frame(self, job: Job, plotter: str | None, _body: Body | None) -> None:
        unit = self.queue.plotter(plotter or job.target or (
            job.plotter if job.plotter in self.queue.plotters else None))  # fmt: skip
        if not unit.fits(job):
            raise Refused(409, f"job {job.id} does not fit {unit.name}'s work area "
                               f"({unit.work_area})")  # fmt: skip
        await unit.trace_frame(job)

    def move(self, job: Job, _plotter: str | None, body: Body | None) -> None:
        self.queue.move(job.id, _model(MoveBody, body).position)

    async def edit(self, job: Job, _plotter: str | None, body: Body | None) -> None:
        patch: PatchJobBody = _model(PatchJobBody, body)
        placement = patch.placement.model_dump(exclude_unset=True) if patch.placement else None
        if patch.name is not None or placement is not None:
            await self.queue.reimport(job.id, patch.name, placement)
        if patch.pens is not None:
            self.queue.set_pens(job.id, patch.pens)

    async def delete(self, job: Job, _plotter: str | None, _body: Body | None) -> None:
        await self.queue.delete(job.id)

    def approve(self, job: Job, plotter: str | None, _body: Body | None) -> None:
        """It joins the queue; and starts, if its sender asked to start it (the approval
        stands when it cannot start now: the answer's job says so)."""
        asked = dict(job.approval or {})
        decision = {**asked, "decision": "approved", "by": ACTOR.get(), "at": time.time()}
        self.lifecycle.move(job, "approve", approval=decision)
        if asked.get("start"):
            self._target(job, plotter)
            try:
                self.queue.start(job, "start")
            except Refused as exc:
                log.info("job %s approved; not started: %s", job.id, exc.detail)

    def decline(self, job: Job, _plotter: str | None, body: Body | None) -> None:
        """Cancelled, with the reason its sender sees (`approval.reason`, `error`)."""
        reason = _model(DeclineBody, body).reason
        who = ACTOR.get()
        decision = {**(job.approval or {}), "decision": "declined", "by": who,
                    "reason": reason, "at": time.time()}  # fmt: skip
        self.lifecycle.move(job, "decline", approval=decision, error=f"declined by {who}: {reason}")

    # ---- the legacy forms ---------------------------------------------------------------

    async def resume_legacy(self, job_id: str, plotter: str | None,
                            body: Body | None) -> Job:  # fmt: skip
        """`POST /resume` and WebSocket `resume`: continue a held job or a pen change, resume
        a stopped or interrupted one; with `from` a resume from a point, with `home` after
        homing."""
        job = self.queue.get(job_id)
        options: ResumeBody = _model(ResumeBody, body)
        if options.from_ is not None:
            return await self.act(job_id, "resume_from", plotter, body)
        if options.home:
            return await self.act(job_id, "home_then_resume", plotter, body)
        if "continue" in job.actions:
            if options.layers is not None:
                raise Refused(422, "layers: a held job or a pen change continues as it is; "
                                   "layers are chosen when resuming a stopped job")  # fmt: skip
            return await self.act(job_id, "continue", plotter)
        return await self.act(job_id, "resume", plotter, body)

    def hold_plotter(self, name: str | None) -> Job | None:
        """Feed hold of the plotter's job, or of its machine when no job runs (a jog, a
        console move): the board lifts the pen while held."""
        return self._machine_or_job(name, b"!", "hold")

    def continue_plotter(self, name: str | None) -> Job | None:
        return self._machine_or_job(name, b"~", "continue")

    def _machine_or_job(self, name: str | None, byte: bytes, action: str) -> Job | None:
        """The realtime byte to the machine when no job runs, else the job's own action."""
        unit = self.queue.busy_plotter(name)
        if unit.job is None:
            unit.realtime(byte)
            return None
        self.lifecycle.check(unit.job, action)
        return unit.runner.pause() if action == "hold" else unit.runner.resume()

    # ---- helpers ----------------------------------------------------------------------------

    def _options(self, job: Job, body: Body | None) -> None:
        options: StartBody = _model(StartBody, body)
        self.queue.select_layers(job, options.layers, options.start_layer)
        if options.pens is not None:
            self.queue.set_pens(job.id, options.pens)

    def _target(self, job: Job, plotter: str | None) -> None:
        if plotter is not None:
            self.queue.plotter(plotter)  # 404 for an unknown one
            job.target = plotter

    @staticmethod
    def _resume_options(body: Body | None) -> ResumeBody:
        """A resume's body without a point: `layers` and `home` only."""
        options: ResumeBody = _model(ResumeBody, body)
        if options.from_ is not None or options.overlap:
            raise Refused(422, "from: a resume from a point is the action resume_from")
        return options

    async def _resume(self, job: Job, action: str, plotter: str | None, options: ResumeBody,
                      home: bool | None) -> None:  # fmt: skip
        """Resume `job` exactly (no `from`) or from a point, homing its plotter first when
        `home` (None: when it is in Alarm), then plotting the layers `options` choose. The
        job is held throughout: one racer wins."""
        chosen = job.plot_layers
        if options.layers is not None:  # checked (422) before anything moves
            self.queue.select_layers(job, options.layers, None)
        try:
            async with self.lifecycle.claim(job, action):
                point = await self._point(job, options.where(), options.overlap)
                self._target(job, plotter)
                unit = self.queue.candidates(job)[0]
                if home or (home is None and unit.state == "Alarm"):
                    await self._home(job, unit)
                if point is not None:
                    job.lines_done = point.line - 1
        except BaseException:
            job.plot_layers = chosen  # refused or failed: the choice it had stands
            raise
        self.queue.start(job, action, point)

    async def _point(self, job: Job, where: dict[str, Any] | None,
                     overlap: float) -> ResumePoint | None:  # fmt: skip
        if where is None:
            return None
        program = self.queue.importer.program_path(job.id)
        try:
            return await asyncio.to_thread(pick, program, job.layers, job.lines_total, where,
                                           overlap)  # fmt: skip
        except PickError as exc:
            raise Refused(422, f"from: {exc}") from exc
        except OSError as exc:
            raise Refused(409, f"job {job.id} has no program to resume: {exc}") from exc

    @staticmethod
    async def _home(job: Job, unit: Plotter) -> None:
        log.info("job %s: homing %s before the resume", job.id, unit.name)
        await unit.send("home", "$H", wait=HOMING_S)
