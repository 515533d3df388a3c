"""Runs one job at a time on one board, and settles how it ended.

The runner owns the job while it is active on its plotter: it streams the program a
layer at a time (`LayerStream`), with each layer's pen and the stops to change or re-ink
it (`PenChanges`), follows where the pen is (`StopPoint`: progress, the resume mark, the
exact stop), the board's hold and resume buttons, and when the stream ends takes the job
to `done` (then the after-job moves, `AfterJobMoves`), `failed`, `cancelled`, `stopped` or
`interrupted` through the lifecycle.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Callable
from pathlib import Path

from plotbridge.errors import Refused
from plotbridge.jobs.lifecycle import Lifecycle
from plotbridge.jobs.model import AfterJob, Job
from plotbridge.jobs.progress import summary
from plotbridge.pens import PenLibrary
from plotbridge.plotter.afterjob import AfterJobMoves
from plotbridge.plotter.halt import halt
from plotbridge.plotter.layers import LayerRuns
from plotbridge.plotter.layerstream import LayerStream
from plotbridge.plotter.link import Link, LinkDown, MachineStatus, StreamAborted
from plotbridge.plotter.penchange import PenChanges
from plotbridge.plotter.stoppoint import StopPoint
from plotbridge.resume import ResumePoint

log = logging.getLogger("plotbridge.runner")

SAVE_INTERVAL = 1.0  # s between progress writes to the store while running
SETTLE_S = 0.5  # s for the board to report our own ! or ~ (button presses are told apart)
JOB_POLL_HZ = 15.0  # status reports while a job runs: a lost link redraws at most 1/15 s
ENDINGS = {"done": "done", "failed": "fail", "cancelled": "cancel", "stopped": "estop",
           "interrupted": "lost"}  # how a run ended: the lifecycle's cause


class Runner:
    def __init__(self, plotter: str, link: Link, jobs_dir: Path, lifecycle: Lifecycle,
                 busy_changed: Callable[[], None], after_job: AfterJob = "none",
                 park: tuple[float, float] = (0.0, 0.0),
                 pens: PenLibrary | None = None) -> None:  # fmt: skip
        self.plotter = plotter
        self.link = link
        self.jobs_dir = jobs_dir
        self.lifecycle = lifecycle
        self.busy_changed = busy_changed
        """Told when the runner takes a job, and when it is free again."""
        self.pens = pens
        self.after = AfterJobMoves(plotter, link, after_job, park)
        self.point = StopPoint(link, jobs_dir, lifecycle)
        self.changes = PenChanges(link, lifecycle, pens, self.after.park_lines)
        self.stream = LayerStream(link)
        self.layers = LayerRuns(self.point, self.changes, self.stream, self._on_ack)
        self.job: Job | None = None
        self._task: asyncio.Task[None] | None = None
        self._last_save = 0.0
        self._control_at = 0.0
        self._idle_poll_hz = link.poll_hz

    @property
    def busy(self) -> str | None:
        """Why the plotter takes no job although none runs (the after-job moves)."""
        return self.after.busy

    # ---- starting and stopping -----------------------------------------------------------

    def begin(self, job: Job, cause: str, line: int, resumed: bool = False,
              point: ResumePoint | None = None) -> None:  # fmt: skip
        """Run `job` from `line` (its start, or its first plotted layer's), or resume it:
        from `point` (picked by the user), else from where the last run's mark shows the pen
        stopped, else from `line`. `cause`: the action or event (lifecycle)."""
        if self.job is not None:
            raise RuntimeError(f"{self.plotter} runs job {self.job.id} already")
        fresh = {} if resumed else {"lines_done": 0, "lines_acked": 0, "progress": 0.0,
                                    "drawn_mm": 0.0, "resume_line": None}  # fmt: skip
        self.lifecycle.move(job, cause, error=None, waiting=None, plotter=self.plotter,
                            started_at=time.time(), finished_at=None, safe_line=line,
                            **fresh)  # fmt: skip
        self.job = job
        self.stream.begin()
        self.point.reset(line)
        self.link.poll_hz = JOB_POLL_HZ
        self.busy_changed()
        log.info("job %s (%s) %s on %s at line %d", job.id, job.name,
                 "resumed" if resumed else "started", self.plotter, line)  # fmt: skip
        self._task = asyncio.create_task(self._run(job, line, resumed, point),
                                         name=f"run-{self.plotter}")  # fmt: skip

    async def close(self) -> None:
        if self._task:
            self._task.cancel()
            with contextlib.suppress(BaseException):
                await self._task

    def pause(self) -> Job:
        return self._hold_or_go(b"!", "running", "hold")

    def resume(self) -> Job:
        job = self.job
        if job is not None and job.state == "pen_change":
            return self.changes.loaded(job, "continue")
        return self._hold_or_go(b"~", "paused", "continue")

    async def cancel(self, job: Job) -> None:
        """Cancel the running job: what the board holds is stopped too."""
        self._control_at = time.monotonic()
        self._finish(job, "cancelled", None)
        await self.halt()

    def stopped(self) -> None:
        """After an emergency stop: the job (if any) is `stopped`, resumable."""
        job = self.job
        if job is not None and job.active:
            job.resume_line = self.point.resume_line(job)
            self.point.estopped(job)
            self._finish(job, "stopped", "emergency stop")

    def orphaned(self, job: Job) -> None:
        """`job` ran here when the server died: the board ran on through what it held, and
        its first standing report tells where that ended (kept in the job's mark)."""
        self.point.orphaned(job)

    def lost(self) -> None:
        """The plotter dropped out: its job is `interrupted`, resumable."""
        if self.job is not None:
            self._interrupt(self.job)

    async def exact_stop_known(self) -> None:
        await self.point.exact_stop_known()

    async def halt(self) -> None:
        await halt(self.link)

    # ---- what the board reports ----------------------------------------------------------

    def on_status(self, status: MachineStatus) -> None:
        job = self.job
        if job is None or not job.active:
            self.point.standing(status)
            return
        if job.state == "pen_change":  # the board's resume button (Pn:S) ends the change
            if "S" in (status.pins or ""):
                self.changes.loaded(job, "released")
            return
        self.point.report(job, status)
        settled = time.monotonic() - self._control_at > SETTLE_S
        if job.state == "running" and status.state == "Hold" and settled:
            self.lifecycle.move(job, "held")  # the board's hold button
        elif job.state == "paused" and status.state == "Run" and settled:
            self.lifecycle.move(job, "released")

    def _on_ack(self, line: int) -> None:
        job = self.job
        if line <= 0 or job is None:
            return
        job.lines_acked = line
        self.layers.acked(line)
        now = time.monotonic()
        if now - self._last_save >= SAVE_INTERVAL:
            self._last_save = now
            self.lifecycle.publish(job, save=True)

    # ---- a run ---------------------------------------------------------------------------

    async def _run(self, job: Job, line: int, resumed: bool, point: ResumePoint | None) -> None:
        program = self.jobs_dir / job.id / "program.gcode"
        try:
            await self.point.written()
            await self.point.measure(job)
            floor, line, preamble = await asyncio.to_thread(self.point.preamble, job, line,
                                                            resumed, point)  # fmt: skip
            state = await self.layers.plot(job, program, line, preamble, floor)
            if state == "Idle":
                self.point.follow(job, job.lines_total + 1, None)
                after = self.after.claim(job)
                self._finish(job, "done", None)
                await self.after.run(job, after)
            elif state == "Alarm":
                code = self.link.status.alarm
                self._finish(job, "failed", "the board raised an alarm: "
                             + (f"ALARM:{code}" if code is not None else "alarm"))
            elif state == "Disconnected":
                self._interrupt(job)
        except StreamAborted as exc:
            settled = not job.active
            self._aborted(job, exc)
            if exc.reason == "error" and not settled:
                await self.halt()  # the board would go on with the lines it holds
        except LinkDown:
            self._interrupt(job)
        except asyncio.CancelledError:
            raise
        except Exception as exc:  # keep the queue consistent whatever went wrong
            log.exception("job %s crashed", job.id)
            settled = not job.active
            self._finish(job, "failed", f"server error while streaming: {exc}")
            if not settled:  # e.g. the program could not be read on: stop what was sent
                with contextlib.suppress(Exception):
                    await self.halt()
        finally:
            if self.pens is not None:
                self.pens.flush()
            self.link.poll_hz = self._idle_poll_hz
            if self.job is job:
                self.job = None
            self.busy_changed()

    # ---- how a run ends -------------------------------------------------------------------

    def _aborted(self, job: Job, exc: StreamAborted) -> None:
        if not job.active:
            return  # already settled (estop, cancel)
        if exc.last_acked is not None and exc.last_acked > 0:
            job.lines_acked = max(job.lines_acked, exc.last_acked)
        if exc.reason == "disconnected":
            self._interrupt(job)
        elif exc.reason == "estop":
            self.stopped()
        elif exc.reason == "cancelled":
            self._finish(job, "cancelled", None)
        else:  # error or alarm from the board
            line = exc.error_line or job.lines_acked + 1
            self._finish(job, "failed", f"line {line}: {exc.message or exc}")

    def _interrupt(self, job: Job) -> None:
        if not job.active:
            return
        job.resume_line = self.point.resume_line(job)
        if job.resume_line > job.lines_done + 1:  # acks since the last report: it ran on
            self.point.follow(job, job.resume_line, None)
        self._finish(job, "interrupted", "the link to the plotter was lost")
        asyncio.get_running_loop().create_task(self.point.settle(job))

    def _finish(self, job: Job, state: str, error: str | None) -> None:
        self.changes.ended()
        if self.job is job:
            self.job = None
        job.summary = summary(job, state)
        self.lifecycle.move(job, ENDINGS[state], error=error)
        log.info("job %s %s on %s: %s%s", job.id, state, self.plotter, job.summary,
                 f" ({error})" if error else "")  # fmt: skip

    # ---- hold and cycle start ------------------------------------------------------------

    def _hold_or_go(self, byte: bytes, before: str, cause: str) -> Job:
        """Feed hold (`!`) or cycle start (`~`) for the running job in state `before`."""
        job = self.job
        if job is None:
            raise Refused(409, f"no job is running on {self.plotter}")
        if job.state != before:
            self.lifecycle.check(job, cause)
        self._control_at = time.monotonic()
        try:
            self.link.realtime(byte)
        except LinkDown as exc:
            raise Refused(409, "the plotter is not connected") from exc
        self.lifecycle.move(job, cause)
        return job
