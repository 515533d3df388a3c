"""Where the pen is, for the job streaming on one board: the line it executes and its
position from each status report, kept as the job's resume mark (in its folder, so it
outlives the server) and as its progress (jobs/progress.py); the exact point after an
emergency stop, and where the board ran out after the server died.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from pathlib import Path

from plotbridge.jobs.lifecycle import Lifecycle
from plotbridge.jobs.model import Job
from plotbridge.jobs.progress import Measure, Plan, follow, plan_of
from plotbridge.plotter.link import Link, MachineStatus
from plotbridge.resume import (
    Mark,
    ResumePoint,
    executing_line,
    first_unexecuted_line,
    locate,
    resume_preamble,
)  # fmt: skip

log = logging.getLogger("plotbridge.runner")

MARK_FILE = "resume.mark"  # in the job folder: the last report's line range and position
EXACT_STOP_S = 2.0  # s a command after an estop waits for the report of where the steps stopped
PROGRESS_INTERVAL = 0.2  # s between job progress messages (5 Hz)


class StopPoint:
    def __init__(self, link: Link, jobs_dir: Path, lifecycle: Lifecycle) -> None:
        self.link = link
        self.jobs_dir = jobs_dir
        self.lifecycle = lifecycle
        self.motion = bytearray()  # the streaming layer's motion flags (ProgramReader's)
        self.floor = 1  # the earliest line a resume may need
        self._measure: tuple[str, Measure] | None = None
        self._mark: Mark | None = None
        self._unsaved: Mark | None = None
        self._writer: asyncio.Task[None] | None = None
        self._stopped: Job | None = None  # waits for the exact position after a reset
        self._stopped_at = 0.0
        self._known = asyncio.Event()  # set: no stop waits for its exact report
        self._known.set()
        self._orphan: Job | None = None
        self._orphan_at = 0.0
        self._orphan_writer: asyncio.Task[None] | None = None
        self._last_progress = 0.0
        self._parked = False  # the carriage left the program: the mark stands

    # ---- a run ---------------------------------------------------------------------------

    def reset(self, line: int) -> None:
        self.floor, self.motion, self._mark = line, bytearray(), None
        self.live, self._high, self._parked = False, 0, False
        self._told()

    def streaming(self, motion: bytearray) -> None:
        """The motion flags of the stretch streaming now (filled as it is read); reports
        tell the pen's progress until `live` goes False (the stretch stands)."""
        self.motion, self.live, self._parked = motion, True, False

    def parked(self, job: Job, line: int) -> None:
        """Everything before `line` is drawn and the carriage left the program (parked for
        a pen, or to re-ink): the job's progress and its mark are `line`'s start until the
        next stretch streams. The park position in reports meanwhile, or in the first one
        after a stop, is no point of the program to resume from."""
        self.follow(job, line, None)
        measure = self._plan(job)[0]
        self._parked = True
        if measure is not None and line < len(measure.x):
            self._keep(job, Mark(line, max(job.lines_acked, line), measure.x[line],
                                 measure.y[line]))  # fmt: skip

    async def measure(self, job: Job) -> None:
        """Read the job's program for its progress (once per job; in a thread)."""
        if self._measure is None or self._measure[0] != job.id:
            program = self.jobs_dir / job.id / "program.gcode"
            self._measure = (job.id, await asyncio.to_thread(Measure.of, program))

    def _plan(self, job: Job) -> tuple[Measure | None, Plan]:
        measure = self._measure[1] if self._measure and self._measure[0] == job.id else None
        return measure, plan_of(job, measure)

    def follow(self, job: Job, line: int, at: tuple[float, float] | None) -> None:
        """The job's progress with the pen at `at` on `line`."""
        measure, plan = self._plan(job)
        follow(job, measure, plan, line, at)
        if not self.link.facts.line_numbers and job.active:
            job.summary += " (estimated: the board does not report the line it draws)"

    def draws_between(self, job: Job, after: int, last: int) -> bool:
        """Whether the pen draws anything on lines `after` + 1 .. `last`."""
        measure = self._plan(job)[0]
        if measure is None:
            return True  # not known: as if it did
        last = min(last, measure.lines)
        return last > after and measure.mm[last] - measure.mm[min(after, last)] > 1e-6

    def report(self, job: Job, status: MachineStatus) -> None:
        """A status report while `job` runs: its safe line, mark and progress."""
        queued = self.link.facts.queued_blocks(status.planner_free)
        safe = None if queued is None else first_unexecuted_line(
            self.motion, job.lines_acked, queued, self.floor)  # fmt: skip
        if self.link.facts.line_numbers and status.line is not None:
            safe = executing_line(status.line, safe, self.floor)  # the position lies on it
        if safe is None or status.x is None or status.y is None:
            return
        job.safe_line = safe
        if self._parked:
            return  # the park position: the mark at the boundary stands
        self._keep(job, Mark(safe, max(job.lines_acked, safe), status.x, status.y))
        if not self.live or safe < self._high:
            return  # parked for a pen, or an older report: the progress stands
        self._high = safe
        self.follow(job, safe, (status.x, status.y))
        now = time.monotonic()
        if now - self._last_progress >= PROGRESS_INTERVAL:
            self._last_progress = now
            self.lifecycle.publish(job, save=False)

    def resume_line(self, job: Job) -> int:
        """Two safe bounds, the later wins: the last report's and now's (acked minus full
        planner and segment buffers)."""
        full = first_unexecuted_line(self.motion, job.lines_acked,
                                     self.link.facts.most_queued, self.floor)  # fmt: skip
        return max(job.safe_line or self.floor, full)

    # ---- the exact stop ----------------------------------------------------------------

    def estopped(self, job: Job) -> None:
        """An emergency stop: the next standing report tells where the steps stopped."""
        self._stopped, self._stopped_at = job, time.time()
        self._known.clear()

    async def exact_stop_known(self, limit: float = EXACT_STOP_S) -> None:
        """Before a command after an emergency stop (`$H` moves the carriage): wait (at
        most `limit` s) for the report that tells where the steps stopped."""
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(limit):
                await self._known.wait()
        self._told()

    def _told(self) -> None:
        self._stopped = None
        self._known.set()

    def standing(self, status: MachineStatus) -> None:
        """A report while no job runs here: the exact stop, or where an orphan ran out."""
        job = self._stopped
        if (job is not None and job.state == "stopped" and status.updated_at > self._stopped_at
                and not self.link.awaiting_banner and status.state in ("Alarm", "Idle")
                and status.x is not None and status.y is not None and self._mark is not None):
            self._told()
            log.info("job %s: the steps stopped at %s, %s (%s, the first report after the "
                     "reset)", job.id, status.x, status.y, status.state)  # fmt: skip
            if not self._parked:  # parked: the boundary's mark is where it stopped
                last = max(job.lines_acked, self._mark.last)
                self._keep(job, Mark(self._mark.first, last, status.x, status.y))
            asyncio.get_running_loop().create_task(self.settle(job))
        self._ran_out(status)

    async def settle(self, job: Job) -> None:
        """A job that stopped: its progress exactly at its resume point."""
        await self.written()
        program = self.jobs_dir / job.id / "program.gcode"
        mark = Mark.load(self.jobs_dir / job.id / MARK_FILE)
        if mark is None:
            return
        try:
            await self.measure(job)
            point = await asyncio.to_thread(locate, program, mark)
        except OSError as exc:
            log.warning("job %s: no progress at its stop: %s", job.id, exc)
            return
        if not job.active:
            if job.resume_line is not None and point.line < job.resume_line:
                self.follow(job, job.resume_line, None)  # the board ran on past the mark
            else:
                self.follow(job, point.line, point.at)
            self.lifecycle.publish(job)

    # ---- a server killed mid-job --------------------------------------------------------

    def orphaned(self, job: Job) -> None:
        self._orphan, self._orphan_at = job, time.time()

    def _ran_out(self, status: MachineStatus) -> None:
        job = self._orphan
        if (job is None or status.state not in ("Idle", "Alarm") or not status.connected
                or status.updated_at <= self._orphan_at or status.x is None or status.y is None):
            return
        self._orphan = None
        log.info("job %s: after the server's restart the board stands at %s, %s (%s)",
                 job.id, status.x, status.y, status.state)  # fmt: skip
        if job.state == "interrupted":
            path = self.jobs_dir / job.id / MARK_FILE
            point = (status.x, status.y)
            self._orphan_writer = asyncio.get_running_loop().create_task(
                self._ran_to(job, path, point))  # fmt: skip

    async def _ran_to(self, job: Job, path: Path, point: tuple[float, float]) -> None:
        await asyncio.to_thread(Mark.ran_out, path, point)
        self._orphan_writer = None
        await self.settle(job)

    # ---- the mark file -----------------------------------------------------------------

    def _keep(self, job: Job, mark: Mark) -> None:
        """Remember the mark and write it to the job folder, one write at a time (the
        latest wins: a report that comes while a write is under way waits for it)."""
        self._mark = self._unsaved = mark
        if self._writer is None or self._writer.done():
            path = self.jobs_dir / job.id / MARK_FILE
            self._writer = asyncio.get_running_loop().create_task(self._write(path))

    async def _write(self, path: Path) -> None:
        while self._unsaved is not None:
            mark, self._unsaved = self._unsaved, None
            try:
                await asyncio.to_thread(mark.save, path)
            except OSError as exc:
                log.warning("could not keep the resume mark in %s: %s", path, exc)

    async def written(self) -> None:
        """Wait for the mark writes under way (a resume reads the mark from the file)."""
        for writer in (self._writer, self._orphan_writer):
            if writer is not None and not writer.done() and writer is not asyncio.current_task():
                with contextlib.suppress(Exception):
                    await asyncio.shield(writer)

    def preamble(self, job: Job, line: int, resumed: bool,
                 point: ResumePoint | None) -> tuple[int, int, list[str]]:  # fmt: skip
        """(blocking) The resume point's line, the line to stream from and what goes before
        it: nothing from line 1 (the last run's mark goes), the way to `line` from a later
        start or to a `point` picked; on a resume, the way to where the mark shows the pen
        stopped, else to the start of `line`."""
        program = self.jobs_dir / job.id / "program.gcode"
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
