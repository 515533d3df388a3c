"""The job queue and job lifecycle: import, start, pause, resume, cancel, stop, resume.

The manager keeps every job in memory (the truth while running) and mirrors it
to the SQLite store through one worker thread, so disk writes never block the
event loop. Imports run in a worker process. It talks to the board only
through `Link`.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import shutil
import time
import uuid
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Any

from plotbridge.config import Config
from plotbridge.importing.eta import eta  # numpy-free, unlike the rest of the importer
from plotbridge.importing.workers import ImportLimit, ImportService
from plotbridge.program_reader import ProgramReader
from plotbridge.resume import first_unexecuted_line
from plotbridge.store import JobStore
from plotbridge.ws import Hub

log = logging.getLogger("plotbridge.jobs")

ACTIVE = ("running", "paused")
FINISHED = ("done", "failed", "cancelled", "stopped")
RESUMABLE = ("interrupted", "stopped")
MOVING = ("Run", "Jog", "Home", "Hold")
PROGRESS_INTERVAL = 0.2  # s between job progress messages (5 Hz)
SAVE_INTERVAL = 1.0  # s between progress writes to the store while running
DEFAULT_PLANNER_BLOCKS = 15  # GRBL's planner size on an ATmega328P
# A block leaves the planner (and Bf) once it is cut into step segments, before those
# are stepped: up to one block per segment (GRBL buffers 6 segments, our firmware 7).
SEGMENT_BLOCKS = 8
PUBLIC_FIELDS = (
    "id", "name", "state", "format", "created_at", "lines_total", "lines_done", "progress",
    "estimate_s", "eta_s", "bounds", "error", "stats", "placement", "resume_line",
    "started_at", "finished_at",
)  # fmt: skip


class JobError(Exception):
    """A request the current state does not allow; `status` is the HTTP status."""

    def __init__(self, status: int, detail: Any) -> None:
        super().__init__(detail)
        self.status = status
        self.detail = detail


def _failed(status: int, message: str, line: int | None = None) -> JobError:
    return JobError(status, {"errors": [{"line": line, "message": message}]})


def run_import(kind: str, source: str, filename: str, dest: str, options: dict, settings: dict):
    """Worker-process entry: import one upload or pattern; never raises.

    Returns ("ok", job fields) or ("failed", status, errors), in plain Python types:
    unpickling the importer's own classes would load its modules (numpy) into the server.
    """
    from plotbridge import importing

    try:
        profile = importing.MachineProfile.from_settings(settings)
        opts = importing.ImportOptions(**options)
        if kind == "pattern":
            result = importing.import_pattern(source, Path(dest), opts, profile)
        else:
            result = importing.import_file(Path(source), filename, Path(dest), opts, profile)
        return ("ok", job_fields(result))
    except importing.ImportFailed as exc:
        return ("failed", exc.status, list(exc.errors)[:100])
    except Exception as exc:  # an importer bug must still answer as a refused upload
        return ("failed", 422, [{"line": None, "message": f"import failed: {exc}"}])


def job_fields(result: Any) -> dict[str, Any]:
    estimate = round(float(result.estimate_s), 1)
    return {
        "format": str(result.format),
        "lines_total": int(result.lines_total),
        "estimate_s": estimate,
        "eta_s": estimate,
        "bounds": {key: float(value) for key, value in result.bounds.items()},
        "stats": {key: float(value) for key, value in result.stats.items()},
        "timeline": [[int(line), float(seconds)] for line, seconds in result.timeline],
    }


def resume_preamble(program: str, line: int) -> list[str]:
    """Worker-process entry for `importing.resume_preamble`."""
    from plotbridge.importing import resume_preamble as preamble

    return preamble(Path(program), line)


def patterns() -> dict[str, str]:
    """Worker-process entry: the importer's pattern names and descriptions."""
    from plotbridge.importing import PATTERNS

    return dict(PATTERNS)


def public(job: dict[str, Any]) -> dict[str, Any]:
    return {key: job.get(key) for key in PUBLIC_FIELDS}


def machine_view(status: Any) -> dict[str, Any]:
    """The DESIGN.md machine object from the link's MachineStatus."""
    connected = bool(getattr(status, "connected", False))
    return {
        "connected": connected,
        "state": (getattr(status, "state", None) if connected else None) or "Disconnected",
        "position": {
            "x": round(float(getattr(status, "x", 0.0) or 0.0), 3),
            "y": round(float(getattr(status, "y", 0.0) or 0.0), 3),
        },
        "pen": "down" if getattr(status, "pen", "up") in ("down", True) else "up",
        "firmware": getattr(status, "firmware", None),
        "alarm": getattr(status, "alarm", None),
        "feed": getattr(status, "feed", None),
        "pins": getattr(status, "pins", None) or None,
    }


class JobManager:
    def __init__(self, config: Config, link: Any, hub: Hub, store: JobStore) -> None:
        self.config = config
        self.link = link
        self.hub = hub
        self.store = store
        self.jobs: dict[str, dict[str, Any]] = {}  # in queue order
        self.active: str | None = None
        self._task: asyncio.Task[None] | None = None
        self._db = ThreadPoolExecutor(1, thread_name_prefix="plotbridge-db")
        self.imports = ImportService(config.import_limits)
        self._motion = bytearray()
        self._run_floor = 1
        self._planner_blocks = DEFAULT_PLANNER_BLOCKS
        self._last_progress: dict[str, float] = {}
        self._last_save = 0.0
        self._last_machine: dict[str, Any] | None = None
        self._last_machine_sent = 0.0
        self._unsubscribe: Callable[[], None] | None = None
        self._patterns: dict[str, str] | None = None
        self._control_at = 0.0

    # ---- lifecycle -------------------------------------------------------

    def load(self) -> None:
        """Read the store; a job that was running when the server died is interrupted.
        What a crash left half-done (uploads, imports) is removed."""
        for leftover in self.config.jobs_dir.glob(".*"):
            shutil.rmtree(leftover, ignore_errors=True)
        for leftover in (self.config.data_dir / "tmp").glob("upload-*"):
            leftover.unlink(missing_ok=True)
        for job in self.store.load_all():
            if job["state"] in ACTIVE:
                job["state"] = "interrupted"
                job["resume_line"] = job.get("safe_line") or 1
                job["error"] = "the server stopped while this job was running"
                self.store.save(job, len(self.jobs))
                log.info("job %s (%s) interrupted by a server restart", job["id"], job["name"])
            self.jobs[job["id"]] = job

    def start(self) -> None:
        self._unsubscribe = self.link.subscribe(self._on_link_event)

    async def stop(self) -> None:
        if self._unsubscribe:
            self._unsubscribe()
        if self._task:
            self._task.cancel()
            with contextlib.suppress(BaseException):
                await self._task
        self.imports.close()
        self._db.shutdown(wait=True)

    # ---- persistence and broadcast ----------------------------------------

    def _save(self, job: dict[str, Any]) -> Future[None]:
        position = list(self.jobs).index(job["id"]) if job["id"] in self.jobs else 0
        snapshot = dict(job)
        return self._db.submit(self.store.save, snapshot, position)

    def _publish(self, job: dict[str, Any]) -> None:
        self._last_progress[job["id"]] = time.monotonic()
        self.hub.broadcast({"type": "job", "job": public(job)})

    def _changed(self, job: dict[str, Any]) -> None:
        self._save(job)
        self._publish(job)

    def machine(self) -> dict[str, Any]:
        return machine_view(self.link.status)

    def list(self) -> list[dict[str, Any]]:
        return [public(job) for job in self.jobs.values()]

    def get(self, job_id: str) -> dict[str, Any]:
        job = self.jobs.get(job_id)
        if job is None:
            raise JobError(404, f"no job with id {job_id!r}")
        return job

    def snapshot_messages(self) -> list[dict[str, Any]]:
        """What a new WebSocket client is sent first."""
        messages: list[dict[str, Any]] = [{"type": "machine", "machine": self.machine()}]
        messages.append({"type": "jobs", "jobs": self.list()})
        return messages

    # ---- link events --------------------------------------------------------

    def _on_link_event(self, event: Any) -> None:
        kind = getattr(event, "kind", None)
        if kind == "status":
            self._on_status()
        elif kind == "log":
            self._on_log(getattr(event, "direction", "rx"), getattr(event, "line", ""))
        elif kind == "alarm":
            log.warning("board alarm %s", getattr(event, "code", "?"))
            self._send_machine(force=True)
        elif kind == "connected":
            log.info("board connected: %s", getattr(self.link.status, "firmware", "?"))
            self._send_machine(force=True)
            self._maybe_auto_start()
        elif kind == "disconnected":
            log.warning("board disconnected")
            self._send_machine(force=True)

    def _on_status(self) -> None:
        status = self.link.status
        free = getattr(status, "planner_free", None)
        if isinstance(free, int) and free > self._planner_blocks:
            self._planner_blocks = free
        job = self.jobs.get(self.active) if self.active else None
        if job is not None and isinstance(free, int):
            queued = self._planner_blocks - free + SEGMENT_BLOCKS
            job["safe_line"] = first_unexecuted_line(
                self._motion, job["lines_done"], queued, self._run_floor
            )
        if job is not None:
            self._follow_buttons(job, getattr(status, "state", None))
        self._send_machine()
        if getattr(status, "state", None) == "Idle":
            self._maybe_auto_start()

    def _follow_buttons(self, job: dict[str, Any], state: str | None) -> None:
        """The board's pause and resume buttons change the job state too."""
        settled = time.monotonic() - self._control_at > 0.5  # our own ! or ~ is not yet reported
        if job["state"] == "running" and state == "Hold" and settled:
            job["state"] = "paused"
            self._changed(job)
            log.info("job %s paused at the machine", job["id"])
        elif job["state"] == "paused" and state == "Run" and settled:
            job["state"] = "running"
            self._changed(job)
            log.info("job %s resumed at the machine", job["id"])

    def _send_machine(self, force: bool = False) -> None:
        machine = self.machine()
        now = time.monotonic()
        moving = machine["state"] in MOVING
        due = moving and now - self._last_machine_sent > 0.1
        if force or due or machine != self._last_machine:
            self._last_machine = machine
            self._last_machine_sent = now
            self.hub.broadcast({"type": "machine", "machine": machine})

    def _on_log(self, direction: str, line: str) -> None:
        if not line or line.startswith("<") or line == "?":
            return
        if self.active is not None and (direction == "tx" or line == "ok"):
            return  # a streaming job would flood the consoles; errors and messages still go
        self.hub.broadcast({"type": "log", "direction": direction, "line": line})

    # ---- imports ------------------------------------------------------------

    async def create(
        self,
        *,
        kind: str,
        source: Path | str,
        filename: str,
        name: str,
        options: dict[str, Any],
        placement: dict[str, Any],
    ) -> dict[str, Any]:
        """Import an upload (a file already on disk) or a pattern into a new queued job."""
        job_id = uuid.uuid4().hex[:12]
        jobs_dir = self.config.jobs_dir
        partial = jobs_dir / f".{job_id}.partial"
        final = jobs_dir / job_id
        partial.mkdir(parents=True)
        try:
            source_arg = str(source)
            if kind == "file":
                original = partial / ("original" + _safe_suffix(filename))
                await asyncio.to_thread(shutil.move, str(source), original)
                source_arg = str(original)
            outcome = await self._import(kind, source_arg, filename, partial, options)
            if outcome[0] != "ok":
                raise JobError(outcome[1], {"errors": outcome[2]})
            fields = outcome[1]
            await asyncio.to_thread(partial.rename, final)
        except BaseException:
            await asyncio.to_thread(shutil.rmtree, partial, True)
            raise
        job = {
            "id": job_id,
            "name": name,
            "state": "queued",
            "created_at": time.time(),
            "lines_done": 0,
            "progress": 0.0,
            "error": None,
            "placement": placement,
            "resume_line": None,
            "started_at": None,
            "finished_at": None,
            # not public:
            "kind": kind,
            "source": Path(source_arg).name if kind == "file" else source_arg,
            "filename": filename,
            "options": options,
            **fields,
        }
        self.jobs[job_id] = job
        await asyncio.wrap_future(self._save(job))
        self._publish(job)
        log.info("job %s (%s) queued: %d lines", job_id, name, job["lines_total"])
        self._maybe_auto_start()
        return job

    async def _worker(self, function: Callable[..., Any], *args: Any) -> Any:
        """Run `function` in an import worker (importing/workers.py: supervised, limited;
        keeps the importer's heavy modules out of the server process)."""
        try:
            return await self.imports.call(function, *args)
        except ImportLimit as exc:
            raise _failed(exc.status, str(exc)) from exc

    async def _import(
        self, kind: str, source: str, filename: str, dest: Path, options: dict[str, Any]
    ) -> tuple:
        settings = dict(getattr(self.link, "settings", {}) or {})
        size = await asyncio.to_thread(os.path.getsize, source) if kind == "file" else 0
        try:
            await self.imports.check_room(self.config.jobs_dir, size)
            outcome = await self.imports.call(
                run_import, kind, source, filename, str(dest), options, settings, size=size
            )
            if outcome[0] == "ok":
                await self.imports.check_job(dest)
        except ImportLimit as exc:
            return ("failed", exc.status, [{"line": None, "message": str(exc)}])
        return outcome

    async def _preamble(self, program: Path, line: int) -> list[str]:
        return await self._worker(resume_preamble, str(program), line)

    async def patterns(self) -> dict[str, str]:
        if self._patterns is None:
            self._patterns = await self._worker(patterns)
        return self._patterns

    async def reimport(
        self, job_id: str, name: str | None, placement: dict[str, Any] | None
    ) -> dict[str, Any]:
        job = self.get(job_id)
        if job["state"] != "queued":
            raise JobError(409, f"job {job_id} is {job['state']}; only a queued job can be changed")
        if placement is not None:
            options = {**job["options"], **placement}
            folder = self.config.jobs_dir / job_id
            partial = self.config.jobs_dir / f".{job_id}.reimport"
            partial.mkdir(parents=True)
            try:
                source = job["source"]
                if job["kind"] == "file":
                    await asyncio.to_thread(shutil.copy2, folder / source, partial / source)
                    source = str(partial / source)
                outcome = await self._import(job["kind"], source, job["filename"], partial, options)
                if outcome[0] != "ok":
                    raise JobError(outcome[1], {"errors": outcome[2]})
            except BaseException:
                await asyncio.to_thread(shutil.rmtree, partial, True)
                raise
            if job["state"] != "queued":  # started meanwhile: keep what runs
                await asyncio.to_thread(shutil.rmtree, partial, True)
                raise JobError(409, f"job {job_id} started while it was being re-imported")
            await asyncio.to_thread(_swap_dirs, partial, folder)
            job.update(outcome[1], options=options, placement={**job["placement"], **placement})
        if name is not None:
            job["name"] = name
        self._changed(job)
        return job

    # ---- queue --------------------------------------------------------------

    def move(self, job_id: str, position: int) -> list[dict[str, Any]]:
        job = self.get(job_id)
        if job["state"] != "queued":
            raise JobError(409, f"job {job_id} is {job['state']}; only waiting jobs can be moved")
        ids = list(self.jobs)
        waiting = [i for i in ids if self.jobs[i]["state"] == "queued" and i != job_id]
        position = min(position, len(waiting))
        waiting.insert(position, job_id)
        slots = iter(waiting)
        order = [next(slots) if self.jobs[i]["state"] == "queued" else i for i in ids]
        self.jobs = {i: self.jobs[i] for i in order}
        self._db.submit(self.store.set_order, order)
        self.hub.broadcast({"type": "queue", "order": order})
        log.info("job %s moved to waiting position %d", job_id, position)
        return self.list()

    async def delete(self, job_id: str) -> None:
        job = self.get(job_id)
        if job["state"] in ACTIVE:
            raise JobError(409, f"job {job_id} is {job['state']}; cancel it before deleting it")
        del self.jobs[job_id]
        await asyncio.wrap_future(self._db.submit(self.store.delete, job_id))
        await asyncio.to_thread(shutil.rmtree, self.config.jobs_dir / job_id, True)
        self.hub.broadcast({"type": "job_deleted", "id": job_id})
        log.info("job %s deleted", job_id)

    def preview_path(self, job_id: str) -> Path:
        self.get(job_id)
        return self.config.jobs_dir / job_id / "preview.json"

    def _maybe_auto_start(self) -> None:
        if not self.config.auto_start or self.active is not None:
            return
        if self.machine()["state"] != "Idle":
            return
        for job in self.jobs.values():
            if job["state"] == "queued":
                self._begin(job, 1)
                return

    # ---- control --------------------------------------------------------------

    def _check_machine_ready(self) -> None:
        if self.active is not None:
            other = self.jobs[self.active]
            raise JobError(
                409, f"job {other['id']} ({other['name']}) is {other['state']}; "
                "wait for it to finish or cancel it first"
            )
        state = self.machine()["state"]
        if state == "Disconnected":
            raise JobError(409, "the plotter is not connected; check the cable or power")
        if state == "Alarm":
            raise JobError(409, "the machine is in Alarm: home it ($H) or unlock it ($X) first")
        if state != "Idle":
            raise JobError(409, f"the machine is {state}; wait until it is Idle")

    def start_job(self, job_id: str) -> dict[str, Any]:
        job = self.get(job_id)
        if job["state"] in ACTIVE:
            raise JobError(409, f"job {job_id} is already {job['state']}")
        self._check_machine_ready()
        line = (job["resume_line"] or 1) if job["state"] in RESUMABLE else 1
        self._begin(job, line)
        return job

    def pause(self, job_id: str | None = None) -> dict[str, Any]:
        return self._hold_or_go(job_id, b"!", "running", "paused")

    def resume(self, job_id: str | None = None) -> dict[str, Any]:
        if job_id is not None and self.get(job_id)["state"] in RESUMABLE:
            return self.start_job(job_id)
        return self._hold_or_go(job_id, b"~", "paused", "running")

    def _hold_or_go(
        self, job_id: str | None, byte: bytes, before: str, after: str
    ) -> dict[str, Any]:
        """Feed hold (`!`) or cycle start (`~`) for the active job in state `before`."""
        job = self._active_job(job_id)
        if job["state"] != before:
            raise JobError(409, f"job {job['id']} is {job['state']}, not {before}")
        self._realtime(byte)
        job["state"] = after
        self._changed(job)
        log.info("job %s %s", job["id"], "paused" if after == "paused" else "resumed")
        return job

    def _realtime(self, byte: bytes) -> None:
        from plotbridge.link import LinkDown

        self._control_at = time.monotonic()
        try:
            self.link.realtime(byte)
        except LinkDown as exc:
            raise JobError(409, "the plotter is not connected") from exc

    def _active_job(self, job_id: str | None) -> dict[str, Any]:
        if job_id is not None:
            job = self.get(job_id)
            if job["state"] not in ACTIVE:
                raise JobError(409, f"job {job_id} is {job['state']}, not running or paused")
            return job
        if self.active is None:
            raise JobError(409, "no job is running")
        return self.jobs[self.active]

    async def cancel(self, job_id: str) -> dict[str, Any]:
        job = self.get(job_id)
        if job["state"] in FINISHED:
            raise JobError(409, f"job {job_id} is already {job['state']}")
        if job["state"] not in ACTIVE:
            self._finish(job, "cancelled", None)
            return job
        self._control_at = time.monotonic()
        self._finish(job, "cancelled", None)
        await self._halt()
        return job

    async def _halt(self) -> None:
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

    async def _quiet_command(self, line: str) -> None:
        try:
            await self.link.command(line)
        except Exception as exc:
            log.warning("%s after stopping a job failed: %s", line, exc)

    async def _wait_state(self, predicate: Callable[[str], bool], limit: float) -> str:
        """Wait (at most `limit` s) for the machine state to satisfy `predicate`."""
        deadline = time.monotonic() + limit
        while True:
            state = self.machine()["state"]
            if predicate(state) or time.monotonic() > deadline:
                return state
            await asyncio.sleep(0.02)

    def estop(self, source: str) -> None:
        """Emergency stop: the reset byte goes out first, before any other work."""
        self.link.estop()
        log.warning("EMERGENCY STOP (%s)", source)
        if self.active is not None:
            job = self.jobs[self.active]
            job["resume_line"] = self._resume_line(job)
            self._finish(job, "stopped", "emergency stop")
        self._send_machine(force=True)

    # ---- running a job ---------------------------------------------------------

    def _begin(self, job: dict[str, Any], line: int) -> None:
        resumed = line > 1
        self.active = job["id"]
        job.update(
            state="running", error=None, started_at=time.time(), finished_at=None, safe_line=line
        )
        if not resumed:
            job.update(lines_done=0, progress=0.0, resume_line=None)
        self._run_floor = line
        self._changed(job)
        log.info("job %s (%s) %s at line %d", job["id"], job["name"],
                 "resumed" if resumed else "started", line)  # fmt: skip
        self._task = asyncio.create_task(self._run(job, line))

    async def _run(self, job: dict[str, Any], line: int) -> None:
        from plotbridge.link import LinkDown, StreamAborted

        program = self.config.jobs_dir / job["id"] / "program.gcode"
        try:
            preamble = await self._preamble(program, line) if line > 1 else []
            reader = ProgramReader(program, line, preamble)
            self._motion = reader.motion  # filled as the reader goes
            start_time = time.time()
            async with contextlib.aclosing(reader.lines()) as lines:
                await self.link.stream(lines, self._on_ack)
            state = await self._wait_done(start_time)
            if job["state"] not in ACTIVE:
                return  # settled meanwhile (estop, cancel)
            if state == "Idle":
                job["lines_done"] = job["lines_total"]
                self._finish(job, "done", None)
            elif state == "Alarm":
                self._finish(job, "failed", f"the board raised an alarm: {self._alarm_text()}")
            else:
                self._interrupt(job)
        except StreamAborted as exc:
            settled = job["state"] not in ACTIVE
            self._aborted(job, exc)
            if exc.reason == "error" and not settled:
                await self._halt()  # the board would go on with the lines it holds
        except LinkDown:
            self._interrupt(job)
        except asyncio.CancelledError:
            raise
        except Exception as exc:  # keep the queue consistent whatever went wrong
            log.exception("job %s crashed", job["id"])
            settled = job["state"] not in ACTIVE
            self._finish(job, "failed", f"server error while streaming: {exc}")
            if not settled:  # e.g. the program could not be read on: stop what was sent
                with contextlib.suppress(Exception):
                    await self._halt()
        finally:
            if self.active == job["id"]:
                self.active = None
            self._maybe_auto_start()

    async def _wait_done(self, since: float) -> str:
        """After the last ok: wait until the board is Idle (or fails)."""
        while True:
            status = self.link.status
            state = self.machine()["state"]
            if state in ("Alarm", "Disconnected"):
                return state
            if state == "Idle" and getattr(status, "updated_at", 0) > since:
                return state
            await asyncio.sleep(0.05)

    def _alarm_text(self) -> str:
        code = getattr(self.link.status, "alarm", None)
        return f"ALARM:{code}" if code is not None else "alarm"

    def _on_ack(self, line: int) -> None:
        if line <= 0 or self.active is None:
            return
        job = self.jobs[self.active]
        job["lines_done"] = line
        now = time.monotonic()
        if now - self._last_progress.get(job["id"], 0.0) >= PROGRESS_INTERVAL:
            self._progress(job)
            self._publish(job)
        if now - self._last_save >= SAVE_INTERVAL:
            self._last_save = now
            self._save(job)

    def _progress(self, job: dict[str, Any]) -> None:
        total = max(job["lines_total"], 1)
        job["progress"] = round(min(job["lines_done"] / total, 1.0), 4)
        try:
            left = eta(job["timeline"], job["estimate_s"], job["lines_done"])
            job["eta_s"] = round(float(left), 1)
        except Exception:
            job["eta_s"] = round(job["estimate_s"] * (1 - job["progress"]), 1)

    def _aborted(self, job: dict[str, Any], exc: Any) -> None:
        if job["state"] not in ACTIVE:
            return  # already settled (estop, cancel)
        reason = getattr(exc, "reason", "error")
        last = getattr(exc, "last_acked", None)
        if isinstance(last, int) and last > 0:
            job["lines_done"] = max(job["lines_done"], last)
        if reason == "disconnected":
            self._interrupt(job)
        elif reason == "estop":
            job["resume_line"] = self._resume_line(job)
            self._finish(job, "stopped", "emergency stop")
        elif reason == "cancelled":
            self._finish(job, "cancelled", None)
        else:  # error or alarm from the board
            line = getattr(exc, "error_line", None) or job["lines_done"] + 1
            message = getattr(exc, "message", None) or str(exc)
            self._finish(job, "failed", f"line {line}: {message}")

    def _interrupt(self, job: dict[str, Any]) -> None:
        if job["state"] not in ACTIVE:
            return
        job["resume_line"] = self._resume_line(job)
        self._finish(job, "interrupted", "the link to the plotter was lost")

    def _resume_line(self, job: dict[str, Any]) -> int:
        """Two safe bounds, the later wins: the last status report's (acked minus the
        blocks it still had queued) and now's (acked minus full planner and segment
        buffers: a line is acknowledged only once it is in the planner)."""
        full = first_unexecuted_line(
            self._motion, job["lines_done"], self._planner_blocks + SEGMENT_BLOCKS, self._run_floor
        )
        return max(job.get("safe_line") or self._run_floor, full)

    def _finish(self, job: dict[str, Any], state: str, error: str | None) -> None:
        job["state"] = state
        job["error"] = error
        job["finished_at"] = time.time()
        self._progress(job)
        if state == "done":
            job["eta_s"] = 0.0
        if self.active == job["id"]:
            self.active = None
        self._changed(job)
        at = f" at line {job['lines_done']}" if state != "done" else ""
        log.info("job %s %s%s%s", job["id"], state, at, f": {error}" if error else "")


def _safe_suffix(filename: str) -> str:
    suffix = Path(filename).suffix.lower()
    return suffix if 1 < len(suffix) <= 9 and suffix[1:].isalnum() else ""


def _swap_dirs(new: Path, old: Path) -> None:
    trash = old.with_name(f".{old.name}.old")
    old.rename(trash)
    new.rename(old)
    shutil.rmtree(trash, ignore_errors=True)
