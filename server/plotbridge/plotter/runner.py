"""Streams one job at a time to one board, and settles how it ended.

The runner owns the job while it is `running` or `paused` on its plotter: it
streams the program through the link (from line 1, or from a resume line after
a preamble that puts the machine where that line starts), counts progress,
follows the board's pause and resume buttons, and when the stream ends sets the
job `done`, `failed`, `cancelled`, `stopped` (emergency stop) or `interrupted`
(link lost) with the line it can safely resume from.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import AsyncIterator, Callable
from pathlib import Path

from plotbridge.errors import Refused
from plotbridge.jobs.lifecycle import Lifecycle
from plotbridge.jobs.model import AfterJob, Job
from plotbridge.jobs.progress import follow, plan_of
from plotbridge.pens import PenFeed, PenLibrary, servo_lines
from plotbridge.plotter.link import Link, LinkDown, MachineStatus, StreamAborted
from plotbridge.program import wire
from plotbridge.program.reader import ProgramReader
from plotbridge.resume import (
    Mark,
    ResumePoint,
    executing_line,
    first_unexecuted_line,
    layer_runs,
    locate,
    resume_preamble,
)  # fmt: skip

log = logging.getLogger("plotbridge.runner")

PROGRESS_INTERVAL = 0.2  # s between job progress messages (5 Hz)
SAVE_INTERVAL = 1.0  # s between progress writes to the store while running
SETTLE_S = 0.5  # s for the board to report our own ! or ~ (button presses are told apart)
AFTER_JOB_S = 120.0  # s a park move or a homing cycle after a job may take
JOB_POLL_HZ = 15.0  # status reports while a job runs: a lost link redraws at most 1/15 s
EXACT_STOP_S = 2.0  # s a command after an estop waits for the report of where the steps stopped
MARK_FILE = "resume.mark"  # in the job folder: the last report's line range and position
ENDINGS = {"done": "done", "failed": "fail", "cancelled": "cancel", "stopped": "estop",
           "interrupted": "lost"}  # how a run ended: the lifecycle's cause



async def _until(lines: AsyncIterator[tuple[int, str]],
                 stop: int | None) -> AsyncIterator[tuple[int, str]]:  # fmt: skip
    """The lines before program line `stop` (all with None); the preamble (0) passes."""
    async with contextlib.aclosing(lines):
        async for number, text in lines:
            if stop is not None and number >= stop:
                return
            yield number, text


class Runner:
    def __init__(self, plotter: str, link: Link, jobs_dir: Path, lifecycle: Lifecycle,
                 busy_changed: Callable[[], None], after_job: AfterJob = "none",
                 park: tuple[float, float] = (0.0, 0.0),
                 pens: PenLibrary | None = None) -> None:  # fmt: skip
        self.plotter = plotter
        self.pens = pens
        self._feed: PenFeed | None = None  # the streaming layer's pen (odometer, re-ink)
        self.after_job = after_job
        self.park = park
        self.busy: str | None = None
        """Why the plotter takes no job although none runs (the after-the-job action)."""
        self.link = link
        self.jobs_dir = jobs_dir
        self.lifecycle = lifecycle
        self.busy_changed = busy_changed
        """Told when the runner takes a job, and when it is free again."""
        self.job: Job | None = None
        self._task: asyncio.Task[None] | None = None
        self._motion = bytearray()
        self._floor = 1
        self._last_progress = 0.0
        self._last_save = 0.0
        self._control_at = 0.0
        self._pen_done = asyncio.Event()
        self._mark: Mark | None = None        # the last report's, for the job streaming
        self._unsaved_mark: Mark | None = None
        self._mark_writer: asyncio.Task[None] | None = None
        self._stopped_job: Job | None = None  # waits for the exact position after a reset
        self._stopped_at = 0.0
        self._stop_known = asyncio.Event()  # set: no stop waits for its exact report
        self._stop_known.set()
        self._orphan: Job | None = None  # ran here when the server died (see orphaned)
        self._orphan_at = 0.0
        self._orphan_writer: asyncio.Task[None] | None = None
        self._idle_poll_hz = link.poll_hz

    # ---- starting and stopping -----------------------------------------------

    def begin(self, job: Job, cause: str, line: int, resumed: bool = False,
              point: ResumePoint | None = None) -> None:  # fmt: skip
        """Start streaming `job` from `line` (its start, or its first plotted layer's), or
        resume it: from `point` (picked by the user), else from where the last run's mark
        shows the pen stopped, else from `line`. `cause`: the action or event (lifecycle)."""
        if self.job is not None:
            raise RuntimeError(f"{self.plotter} runs job {self.job.id} already")
        fields = {} if resumed else {"lines_done": 0, "lines_acked": 0, "progress": 0.0,
                                     "drawn_mm": 0.0, "resume_line": None}  # fmt: skip
        self.lifecycle.move(job, cause, error=None, waiting=None, plotter=self.plotter,
                            started_at=time.time(), finished_at=None, safe_line=line,
                            **fields)  # fmt: skip
        self.job = job
        self._floor = line
        self._motion = bytearray()
        self._mark = None
        self._stop_told()
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
        return self._hold_or_go(b"!", "running", "paused")

    def resume(self) -> Job:
        job = self.job
        if job is not None and job.state == "pen_change":
            return self._pen_loaded(job, "resumed")
        return self._hold_or_go(b"~", "paused", "running")

    def _pen_loaded(self, job: Job, how: str) -> Job:
        self.lifecycle.move(job, "continue" if how == "resumed" else "released")
        self._pen_done.set()
        log.info("job %s: pen change done (%s)", job.id, how)
        return job

    async def cancel(self, job: Job) -> None:
        """Cancel the running job: what the board holds is stopped too."""
        self._control_at = time.monotonic()
        self._finish(job, "cancelled", None)
        await self.halt()

    def stopped(self) -> None:
        """After an emergency stop: the job (if any) is `stopped`, resumable."""
        job = self.job
        if job is not None and job.active:
            self._estopped(job)

    def orphaned(self, job: Job) -> None:
        """`job` ran here when the server died: the board ran on through what it held,
        and its first standing report tells where that ended (kept in the job's mark)."""
        self._orphan, self._orphan_at = job, time.time()

    def lost(self) -> None:
        """The plotter dropped out: its job is `interrupted`, resumable."""
        if self.job is not None:
            self._interrupt(self.job)

    async def halt(self) -> None:
        """Stop what the board still has queued: hold, soft reset once the hold has
        stopped motion, then lift the pen (`$X` first if the reset left an alarm)."""
        with contextlib.suppress(Exception):
            self.link.realtime(b"!")
        await self._wait_state(lambda s: s in ("Hold", "Idle", "Alarm", "Disconnected"), 5.0)
        await asyncio.sleep(0.3)  # let the deceleration complete
        self.link.estop()
        if await self._wait_state(lambda s: s in ("Idle", "Alarm"), 5.0) == "Alarm":
            await self._quiet_command("$X")
        await self._quiet_command("M5")

    # ---- what the board reports --------------------------------------------------

    def on_status(self, status: MachineStatus) -> None:
        job = self.job
        if job is None or not job.active:
            self._exact_stop(status)
            self._ran_out(status)
            return
        if job.state == "pen_change":  # the board's resume button (Pn:S) ends the change
            if "S" in (status.pins or ""):
                self._pen_loaded(job, "the board's resume button")
            return
        queued = self.link.facts.queued_blocks(status.planner_free)
        safe = None if queued is None else first_unexecuted_line(
            self._motion, job.lines_done, queued, self._floor)  # fmt: skip
        if self.link.facts.line_numbers and status.line is not None:
            # the board names the line it executes: the position lies on it
            safe = executing_line(status.line, safe, self._floor)
        if safe is not None:
            job.safe_line = safe
            if status.x is not None and status.y is not None:
                last = max(job.lines_done, safe)  # its ok may still be on the way
                self._keep_mark(job, Mark(safe, last, status.x, status.y))
        self._follow_buttons(job, status.state)

    async def exact_stop_known(self, limit: float = EXACT_STOP_S) -> None:
        """Before a command after an emergency stop (`$H` moves the carriage): wait (at
        most `limit` s) for the report that tells where the steps stopped."""
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(limit):
                await self._stop_known.wait()
        self._stop_told()  # none came: the last report's mark stands

    def _stop_told(self) -> None:
        self._stopped_job = None
        self._stop_known.set()

    def _exact_stop(self, status: MachineStatus) -> None:
        """The first report after an emergency stop's reset: where the steps stopped (Alarm
        after a reset in motion, Idle if the planner had run dry). Commands wait for it
        (`exact_stop_known`), so it is never a report from after a `$H`; one read before
        the reset's banner was sent before the reset (late only on a busy host)."""
        job = self._stopped_job
        if (job is None or job.state != "stopped" or status.updated_at <= self._stopped_at
                or self.link.awaiting_banner
                or status.state not in ("Alarm", "Idle") or status.x is None
                or status.y is None or self._mark is None):
            return
        self._stop_told()
        log.info("job %s: the steps stopped at %s, %s (%s, the first report after the reset)",
                 job.id, status.x, status.y, status.state)  # fmt: skip
        last = max(job.lines_done, self._mark.last)
        self._keep_mark(job, Mark(self._mark.first, last, status.x, status.y))

    def _ran_out(self, status: MachineStatus) -> None:
        """The first Idle (or Alarm) report while an orphaned job waits: where the board
        stood once it had run out of the moves the dead server had sent."""
        job = self._orphan
        if (job is None or status.state not in ("Idle", "Alarm") or not status.connected
                or status.updated_at <= self._orphan_at or status.x is None or status.y is None):
            return
        self._orphan = None
        log.info("job %s: after the server's restart the board stands at %s, %s (%s)",
                 job.id, status.x, status.y, status.state)  # fmt: skip
        if job.state == "interrupted":
            path = self.jobs_dir / job.id / MARK_FILE
            self._orphan_writer = asyncio.get_running_loop().create_task(
                asyncio.to_thread(Mark.ran_out, path, (status.x, status.y)))  # fmt: skip

    def _keep_mark(self, job: Job, mark: Mark) -> None:
        """Remember the mark and write it to the job folder, one write at a time (the
        latest wins: a report that comes while a write is under way waits for it)."""
        self._mark = mark
        self._unsaved_mark = mark
        if self._mark_writer is None or self._mark_writer.done():
            path = self.jobs_dir / job.id / MARK_FILE
            self._mark_writer = asyncio.get_running_loop().create_task(self._write_marks(path))

    async def _marks_written(self) -> None:
        """Wait for the mark writes under way: the preamble reads the mark from the job
        folder, and the stop point told just before a resume may still be on its way."""
        for writer in (self._mark_writer, self._orphan_writer):
            if writer is not None and not writer.done():
                with contextlib.suppress(Exception):
                    await asyncio.shield(writer)

    async def _write_marks(self, path: Path) -> None:
        while self._unsaved_mark is not None:
            mark, self._unsaved_mark = self._unsaved_mark, None
            try:
                await asyncio.to_thread(mark.save, path)
            except OSError as exc:
                log.warning("could not keep the resume mark in %s: %s", path, exc)

    def _follow_buttons(self, job: Job, state: str) -> None:
        """The board's pause and resume buttons change the job state too."""
        settled = time.monotonic() - self._control_at > SETTLE_S
        if job.state == "running" and state == "Hold" and settled:
            self.lifecycle.move(job, "held")
        elif job.state == "paused" and state == "Run" and settled:
            self.lifecycle.move(job, "released")

    # ---- streaming -------------------------------------------------------------------

    async def _run(self, job: Job, line: int, resumed: bool, point: ResumePoint | None) -> None:
        program = self.jobs_dir / job.id / "program.gcode"
        try:
            await self._marks_written()
            floor, line, preamble = await asyncio.to_thread(self._preamble, job, program, line,
                                                            resumed, point)  # fmt: skip
            runs = layer_runs(job.layers, job.plot_layers, line)
            for number, (start, stop, layer) in enumerate(runs):  # a layer at a time
                if number:  # after a layer: the M0s (not sent) and skipped layers are done
                    job.lines_done = start - 1
                    if not await self._pen_change(job, layer):
                        return  # stopped, cancelled or lost during the change
                    floor, preamble = start, await self._travel(program, start)
                state = await self._stream_layer(job, program, layer, start, stop, preamble, floor)
                if state is None:
                    return  # settled meanwhile (estop, cancel)
                if state != "Idle":
                    break
            if state == "Idle":
                job.lines_done = job.lines_total
                after = self._after_lines(job)
                if after:
                    action = job.after or self.after_job
                    self.busy = f"{self.plotter} finishes job {job.id} ({action})"
                self._finish(job, "done", None)
                await self._after(job, after)
            elif state == "Alarm":
                self._finish(job, "failed", f"the board raised an alarm: {self._alarm_text()}")
            else:
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
            self._feed = None
            if self.pens is not None:
                self.pens.flush()
            self.link.poll_hz = self._idle_poll_hz
            if self.job is job:
                self.job = None
            self.busy = None
            self.busy_changed()

    def _park_lines(self) -> list[str]:
        """Pen up, carriage to the park position; G4 P0 is answered once it stands."""
        x, y = self.park
        return ["M5", f"G0 X{x:.3f} Y{y:.3f}", "G4 P0"]

    def _after_lines(self, job: Job) -> list[str]:
        """The G-code of the job's "after the job" action (the server's default if unset)."""
        action = job.after or self.after_job
        if action == "park":
            return self._park_lines()
        if action == "home":
            return ["M5", "$H"]
        return []

    async def _travel(self, program: Path, start: int) -> list[str]:
        """After a pen change: pen up, back from the park position to where the layer
        starts (the program's travel to it may lie before the `M0`, or in a skipped layer)."""
        return (await asyncio.to_thread(resume_preamble, program, ResumePoint(start)))[1]

    async def _stream_layer(self, job: Job, program: Path, index: int, line: int,
                            stop: int | None, preamble: list[str],
                            floor: int) -> str | None:  # fmt: skip
        """Stream the program from `line` to `stop` (not sent; None: the end) with the pen
        of layer `index` (0-based), pausing to re-ink where due; `floor`: the earliest line
        a resume may need. The board's state once it stands (None: the job ended meanwhile:
        emergency stop, cancel, link lost during a re-ink)."""
        while True:
            feed = self._feed = await self._load_pen(job, index)
            reader = ProgramReader(program, line, preamble)
            self._motion, self._floor = reader.motion, floor  # motion: filled as it goes
            start_time = time.time()
            async with contextlib.aclosing(_until(reader.lines(), stop)) as lines:
                await self.link.stream(wire.compact_async(feed.lines(lines), self.link.settings,
                                                          self.link.facts.line_numbers),
                                       self._on_ack)  # fmt: skip
            state = await self._wait_done(start_time)
            if not job.active:
                return None
            if state != "Idle" or feed.stopped_at is None:
                return state
            job.lines_done = feed.stopped_at  # due for re-inking, at a stroke's end
            if not await self._wait_for_pen(job, self._reink_prompt(job, feed, index)):
                return None
            x, y = feed.position  # back where the pen went up, then on
            line, preamble = feed.stopped_at + 1, [f"G0 X{x:.3f} Y{y:.3f}"]
            floor = line

    async def _load_pen(self, job: Job, index: int) -> PenFeed:
        """The pen of layer `index` (0-based): its servo positions written to the
        board ($60/$61, only those that differ), and its feed for the stream."""
        pen = None
        if self.pens is not None and job.layers:
            pen = self.pens.layer_pen(job.layers[index])
        if pen is not None:
            for setting in servo_lines(pen, self.link.settings):
                await self.link.command(setting)
                log.info("job %s: pen %r: %s", job.id, pen.name, setting)
        odometer = self.pens.odometer_mm(pen.id) if self.pens and pen else 0.0
        return PenFeed(pen, odometer, self.pens.drawn if self.pens else lambda _p, _mm: None)

    async def _pen_change(self, job: Job, index: int) -> bool:
        """Between layers: wait for the pen of layer `index` (0-based) to be loaded."""
        return await self._wait_for_pen(job, self._layer_prompt(job, index))

    def _layer_prompt(self, job: Job, index: int) -> dict[str, object]:
        """What to load before layer `index` (0-based)."""
        layer = job.layers[index]
        name, colour = layer.name or f"layer {index + 1}", layer.colour
        pen = self.pens.layer_pen(layer) if self.pens is not None else None
        load = (f"load pen '{pen.name}'" if pen is not None
                else "load its pen" + (f" ({colour})" if colour else ""))  # fmt: skip
        return {"reason": "layer", "layer": index + 1, "layers": len(job.layers), "name": name,
                "colour": colour, "pen": pen.name if pen else None,
                "message": f"Layer {index + 1} of {len(job.layers)}, '{name}': {load}, "
                           "then continue"}  # fmt: skip

    def _reink_prompt(self, job: Job, feed: PenFeed, index: int) -> dict[str, object]:
        """The pen of layer `index` went past a multiple of its re-ink interval."""
        assert feed.pen is not None
        prompt = self._layer_prompt(job, index)
        metres = (self.pens.odometer_mm(feed.pen.id) if self.pens else 0.0) / 1000
        prompt.update(reason="reink", message=f"Re-ink pen '{feed.pen.name}': {metres:.1f} m "
                                              "drawn; continue when it is ready")  # fmt: skip
        return prompt

    async def _wait_for_pen(self, job: Job, prompt: dict[str, object]) -> bool:
        """Pen up, carriage parked, the job `pen_change` with `prompt` until it is resumed
        (UI, REST, WebSocket, or the board's resume button): between layers, or to re-ink.
        False when the job ended meanwhile (emergency stop, cancel, link lost)."""
        for line in self._park_lines():
            await self.link.command(line, timeout=AFTER_JOB_S)
        self._progress(job)
        self.lifecycle.move(job, "pen_change", pen_change=prompt)
        log.info("job %s: %s", job.id, prompt["message"])
        self._pen_done.clear()
        await self._pen_done.wait()  # resumed, or the job ended (_finish)
        job.pen_change = None
        return job.state == "running"

    async def _after(self, job: Job, lines: list[str]) -> None:
        for line in lines:
            try:
                await self.link.command(line, timeout=AFTER_JOB_S)
            except Exception as exc:  # the job is done; the board says what went wrong
                log.warning("after job %s: %s failed: %s", job.id, line, exc)
                return

    def _preamble(self, job: Job, program: Path, line: int, resumed: bool,
                  point: ResumePoint | None) -> tuple[int, int, list[str]]:  # fmt: skip
        """The resume point's line, the line to stream from and what goes before it
        (blocking): nothing from line 1 (the last run's mark goes), the way to `line` from
        a later start or to a `point` picked; on a resume, the way to the point where the
        pen stopped when the last run's mark tells it, else to the start of `line`."""
        path = self.jobs_dir / job.id / MARK_FILE
        mark = Mark.load(path)
        if not resumed or point is not None:
            path.unlink(missing_ok=True)
            if point is None and line == 1:
                return 1, 1, []
            point = point or ResumePoint(line)
        else:
            point = locate(program, mark) if mark is not None else ResumePoint(line)
            if point.at is None:  # two safe bounds: the later wins
                point = ResumePoint(max(point.line, line))
        if point.line != line:
            log.info("job %s resumes at line %d, at %s (conservative line %d)",
                     job.id, point.line, point.at, line)  # fmt: skip
        return point.line, *resume_preamble(program, point)

    async def _wait_done(self, since: float) -> str:
        """After the last ok: wait until the board is Idle (or fails)."""
        while True:
            status = self.link.status
            state = status.state if status.connected else "Disconnected"
            if state in ("Alarm", "Disconnected"):
                return state
            if state == "Idle" and status.updated_at > since:
                return state
            await asyncio.sleep(0.05)

    def _alarm_text(self) -> str:
        code = self.link.status.alarm
        return f"ALARM:{code}" if code is not None else "alarm"

    def _on_ack(self, line: int) -> None:
        job = self.job
        if line <= 0 or job is None:
            return
        job.lines_done = line
        if self._feed is not None:
            self._feed.acked(line)
        now = time.monotonic()
        save = now - self._last_save >= SAVE_INTERVAL
        if save or now - self._last_progress >= PROGRESS_INTERVAL:
            self._last_progress = now
            self._progress(job)
            if save:
                self._last_save = now
            self.lifecycle.publish(job, save)

    def _aborted(self, job: Job, exc: StreamAborted) -> None:
        if not job.active:
            return  # already settled (estop, cancel)
        if exc.last_acked is not None and exc.last_acked > 0:
            job.lines_done = max(job.lines_done, exc.last_acked)
        if exc.reason == "disconnected":
            self._interrupt(job)
        elif exc.reason == "estop":
            self._estopped(job)
        elif exc.reason == "cancelled":
            self._finish(job, "cancelled", None)
        else:  # error or alarm from the board
            line = exc.error_line or job.lines_done + 1
            self._finish(job, "failed", f"line {line}: {exc.message or exc}")

    def _estopped(self, job: Job) -> None:
        job.resume_line = self._resume_line(job)
        self._stopped_job, self._stopped_at = job, time.time()
        self._stop_known.clear()
        self._finish(job, "stopped", "emergency stop")

    def _interrupt(self, job: Job) -> None:
        if not job.active:
            return
        job.resume_line = self._resume_line(job)
        self._finish(job, "interrupted", "the link to the plotter was lost")

    def _resume_line(self, job: Job) -> int:
        """Two safe bounds, the later wins: the last status report's (acked minus the
        blocks it still had queued) and now's (acked minus full planner and segment
        buffers: a line is acknowledged only once it is in the planner)."""
        full = first_unexecuted_line(self._motion, job.lines_done,
                                     self.link.facts.most_queued, self._floor)  # fmt: skip
        return max(job.safe_line or self._floor, full)

    def _progress(self, job: Job) -> None:
        follow(job, None, plan_of(job, None, 0), job.lines_done + 1, None)

    def _finish(self, job: Job, state: str, error: str | None) -> None:
        self._pen_done.set()
        self._progress(job)
        if state == "done":
            job.eta_s = 0.0
        if self.job is job:
            self.job = None
        self.lifecycle.move(job, ENDINGS[state], error=error)
        at = f" at line {job.lines_done}" if state != "done" else ""
        log.info("job %s %s on %s%s%s", job.id, state, self.plotter, at,
                 f": {error}" if error else "")  # fmt: skip

    # ---- hold and cycle start ------------------------------------------------------

    def _hold_or_go(self, byte: bytes, before: str, after: str) -> Job:
        """Feed hold (`!`) or cycle start (`~`) for the running job in state `before`."""
        job = self.job
        if job is None:
            raise Refused(409, f"no job is running on {self.plotter}")
        if job.state != before:
            raise Refused(409, f"job {job.id} is {job.state}, not {before}")
        self._control_at = time.monotonic()
        try:
            self.link.realtime(byte)
        except LinkDown as exc:
            raise Refused(409, "the plotter is not connected") from exc
        self.lifecycle.move(job, "hold" if after == "paused" else "continue")
        return job

    async def _quiet_command(self, line: str) -> None:
        try:
            await self.link.command(line)
        except Exception as exc:
            log.warning("%s after stopping a job failed: %s", line, exc)

    async def _wait_state(self, predicate: Callable[[str], bool], limit: float) -> str:
        """Wait (at most `limit` s) for the machine state to satisfy `predicate`."""
        deadline = time.monotonic() + limit
        while True:
            status = self.link.status
            state = status.state if status.connected else "Disconnected"
            if predicate(state) or time.monotonic() > deadline:
                return state
            await asyncio.sleep(0.02)

