"""Imports as a supervised service: worker processes with limits, fair queueing.

Each worker is a spawned process (never a fork of the threaded server) that runs
one call at a time and is bound to the server three ways: PR_SET_PDEATHSIG kills
it when the server dies (even by SIGKILL); a worker waiting for work exits at
EOF on its pipe; `close()` kills it at shutdown. No multiprocessing queues, so no
resource-tracker process is left behind either.

Limits, answered with what was too big:
- memory: RLIMIT_AS in the worker; a MemoryError is answered, and a worker the
  kernel kills (OOM) is replaced and the upload that killed it told so;
- time: a call past `time_limit` has its worker killed and replaced;
- disk: room reserved before an upload is written (`reservation`), the files'
  true size settled against both quotas under one lock after the import (`settle`).

Fairness: calls wait in order of size class (small first), then arrival, and a
large call never takes the last free worker, so small uploads never queue
behind a huge one.
"""

from __future__ import annotations

import asyncio
import contextlib
import ctypes
import itertools
import logging
import multiprocessing
import os
import resource
import signal
import time
from collections.abc import AsyncIterator, Callable
from contextvars import ContextVar
from dataclasses import dataclass, field
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any

log = logging.getLogger("plotbridge.importing.workers")

PR_SET_PDEATHSIG = 1  # linux/prctl.h
STARTUP_LIMIT = 60.0  # s for a new worker's interpreter to start (slow on a busy Pi)
_HELD: ContextVar[int | None] = ContextVar("quota_reservation", default=None)  # this request's


@dataclass
class Limits:
    workers: int = 2  # one always free for small uploads
    time_limit: float = 120.0  # s per import
    memory_mb: int = 512  # address space per worker (a Pi 4 with 2 GB keeps room)
    small_bytes: int = 1024 * 1024  # uploads up to this size are "small"
    job_quota_mb: float = 200.0  # one job's files (original, program, preview)
    total_quota_mb: float = 2048.0  # every job's files together


class ImportLimit(Exception):
    """An import refused for a limit; `status` is the HTTP status to answer with."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status


# ---- the worker process ------------------------------------------------------------


def _bind_to_parent() -> None:
    """Die with the server: the kernel sends SIGKILL when the parent exits."""
    with contextlib.suppress(OSError, AttributeError):
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    if os.getppid() == 1:  # the server died before the line above ran
        os._exit(1)


def _serve(conn: Connection, memory_bytes: int) -> None:
    _bind_to_parent()
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the server's to handle
    resource.setrlimit(resource.RLIMIT_AS, (memory_bytes, memory_bytes))
    # the time limit counts from here, not from a slow start; CLOCK_MONOTONIC is the
    # machine's, so the server can tell how long the start took
    conn.send(("ready", time.monotonic()))
    while True:
        try:
            function, args = conn.recv()
        except (EOFError, OSError):
            return  # the server closed the pipe: shut down
        try:
            answer: tuple = ("ok", function(*args))
        except MemoryError:
            answer = ("memory",)
        except Exception as exc:
            answer = ("error", f"{type(exc).__name__}: {exc}")
        try:
            conn.send(answer)
        except MemoryError:
            conn.send(("memory",))


# ---- the server side ----------------------------------------------------------------


class Worker:
    def __init__(self, memory_bytes: int) -> None:
        context = multiprocessing.get_context("spawn")
        self.conn, child = context.Pipe()
        # Inherited by the spawned interpreter: one BLAS thread, and one malloc arena (an
        # import's own threads, the estimate's and the G-code scan's, would each reserve
        # 64 MB of the address space the worker is limited to for an arena of their own).
        env = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
               "MALLOC_ARENA_MAX": "1"}
        saved = {key: os.environ.get(key) for key in env}
        os.environ.update(env)
        try:
            self.process = context.Process(
                target=_serve, args=(child, memory_bytes), name="plotbridge-import", daemon=True
            )
            self.process.start()
        finally:
            for key, value in saved.items():
                if value is None:
                    os.environ.pop(key, None)
                else:
                    os.environ[key] = value
        child.close()
        self.spawned = time.monotonic()
        self.busy = False
        self.started = False

    def alive(self) -> bool:
        """False once the process has exited (killed while idle, say); never blocks."""
        return self.process.exitcode is None

    def kill(self) -> None:
        with contextlib.suppress(Exception):
            self.process.kill()
        with contextlib.suppress(Exception):
            self.process.join(1)
        with contextlib.suppress(Exception):
            self.conn.close()
        with contextlib.suppress(Exception):
            self.process.close()

    async def call(self, function: Callable[..., Any], args: tuple, limit: float) -> tuple:
        """("ok", value) / ("memory",) / ("error", text) / ("died", exitcode) / ("timeout",)."""
        if not self.started:
            answer = await self._answer(STARTUP_LIMIT)
            if answer[0] != "ready":
                return answer
            self.started = True
            # (its first job may come long after: the start's own time, not the wait)
            log.info("import worker %d started in %.1f s", self.process.pid,
                     answer[1] - self.spawned)
        try:
            self.conn.send((function, args))
        except OSError:
            return await self._answer(1.0)
        return await self._answer(limit)

    async def _answer(self, limit: float) -> tuple:
        """The worker's next message, or how it failed to send one within `limit` s."""
        loop = asyncio.get_running_loop()
        done: asyncio.Future[str] = loop.create_future()
        fds = (self.conn.fileno(), self.process.sentinel)
        for fd, what in zip(fds, ("answer", "died"), strict=True):
            loop.add_reader(fd, lambda what=what: done.done() or done.set_result(what))
        try:
            what = await asyncio.wait_for(done, limit)
        except TimeoutError:
            return ("timeout",)
        finally:
            for fd in fds:
                loop.remove_reader(fd)
        if what == "answer":
            with contextlib.suppress(EOFError, OSError):
                return self.conn.recv()
        self.process.join(1)
        return ("died", self.process.exitcode)


@dataclass(order=True)
class _Waiting:
    large: bool
    seq: int
    ready: asyncio.Future[Worker] = field(compare=False)


class ImportService:
    def __init__(self, limits: Limits | None = None) -> None:
        self.limits = limits or Limits()
        self.workers: list[Worker] = []
        self.waiting: list[_Waiting] = []
        self._seq = itertools.count()
        self._closed = False
        self.reserved: dict[int, int] = {}  # quota reservations' bytes, by key
        self._quota_lock = asyncio.Lock()

    # ---- scheduling ------------------------------------------------------------

    def _large_running(self) -> int:
        return sum(1 for w in self.workers if w.busy and getattr(w, "large", False))

    def _dispatch(self) -> None:
        self.waiting.sort()
        for entry in list(self.waiting):
            if entry.ready.done():
                self.waiting.remove(entry)
                continue
            if entry.large and self._large_running() >= max(1, self.limits.workers - 1):
                continue  # keep a worker for small uploads
            worker = self._free_worker()
            if worker is None:
                return
            worker.busy = True
            worker.large = entry.large  # type: ignore[attr-defined]
            self.waiting.remove(entry)
            entry.ready.set_result(worker)

    def _free_worker(self) -> Worker | None:
        for worker in [w for w in self.workers if not w.busy and not w.alive()]:
            log.warning("idle import worker %d died (exit %s); replaced before its next import",
                        worker.process.pid, worker.process.exitcode)  # fmt: skip
            worker.kill()
            self.workers.remove(worker)
        for worker in self.workers:
            if not worker.busy:
                return worker
        if len(self.workers) < self.limits.workers:
            worker = Worker(self.limits.memory_mb * 1024 * 1024)
            self.workers.append(worker)
            return worker
        return None

    def _release(self, worker: Worker, broken: bool) -> None:
        worker.busy = False
        if broken:
            worker.kill()
            self.workers.remove(worker)  # a fresh one is spawned when next needed
        if not self._closed:
            self._dispatch()

    # ---- calls -------------------------------------------------------------------

    async def call(self, function: Callable[..., Any], *args: Any, size: int = 0) -> Any:
        """`function(*args)` in a worker; ImportLimit when a limit stopped it."""
        if self._closed:
            raise ImportLimit(503, "the server is shutting down")
        entry = _Waiting(size > self.limits.small_bytes, next(self._seq),
                         asyncio.get_running_loop().create_future())  # fmt: skip
        self.waiting.append(entry)
        self._dispatch()
        try:
            worker = await entry.ready
        except asyncio.CancelledError:
            if entry.ready.done() and not entry.ready.cancelled():
                self._release(entry.ready.result(), broken=False)
            raise
        answer: tuple = ("timeout",)
        try:
            answer = await worker.call(function, args, self.limits.time_limit)
        finally:
            self._release(worker, broken=answer[0] in ("timeout", "died"))
        return self._unpack(answer)

    def _unpack(self, answer: tuple) -> Any:
        kind = answer[0]
        if kind == "ok":
            return answer[1]
        if kind == "memory":
            raise ImportLimit(413, f"the import needed more than the {self.limits.memory_mb} MB "
                              "memory limit (--import-memory-mb); simplify or split the drawing")
        if kind == "timeout":
            log.warning("import stopped after %g s; worker replaced", self.limits.time_limit)
            raise ImportLimit(413, f"the import took longer than the {self.limits.time_limit:g} s "
                              "limit (--import-time-limit); simplify or split the drawing")
        if kind == "died":
            code = answer[1]
            killed = isinstance(code, int) and code < 0
            how = f"killed by signal {-code}" if killed else f"exit {code}"
            log.warning("import worker died (%s); replaced", how)
            raise ImportLimit(
                413, f"the import worker died ({how}) while importing this upload, as the "
                "kernel does when memory runs out; simplify or split the drawing",
            )  # fmt: skip
        raise ImportLimit(422, f"import failed: {answer[1]}")

    # ---- disk quotas --------------------------------------------------------------

    @contextlib.asynccontextmanager
    async def reservation(self, jobs_dir: Path, size: int) -> AsyncIterator[None]:
        """Room for `size` bytes in the jobs' quota, reserved before an upload is
        written and held until its job is in place; nested, the outer one holds."""
        if _HELD.get() is not None:
            yield
            return
        async with self._quota_lock:
            used = await asyncio.to_thread(jobs_size, jobs_dir)
            self._check_total(used, size, None)
            key = next(self._seq)
            self.reserved[key] = size
        held = _HELD.set(key)
        try:
            yield
        finally:
            _HELD.reset(held)
            del self.reserved[key]

    async def settle(self, jobs_dir: Path, folder: Path) -> None:
        """After an import into `folder` (hidden: not yet a job): its files against the
        per-job quota, and with the jobs and the other reservations against the total.
        Under the lock, so two imports never both take the last room; the reservation
        then holds the files' true size until the folder is renamed into a job."""
        async with self._quota_lock:
            mine = await asyncio.to_thread(tree_size, folder)
            if mine > self.limits.job_quota_mb * 1024 * 1024:
                raise ImportLimit(507, f"this job's files would take {mine / 2**20:.0f} MB, more "
                                  f"than the {self.limits.job_quota_mb:g} MB per-job quota")
            used = await asyncio.to_thread(jobs_size, jobs_dir)
            key = _HELD.get()
            self._check_total(used, mine, key)
            if key is not None:
                self.reserved[key] = mine

    def _check_total(self, used: int, size: int, own: int | None) -> None:
        others = sum(held for key, held in self.reserved.items() if key != own)
        total = self.limits.total_quota_mb * 1024 * 1024
        if used + others + size > total:
            pending = f" ({others / 2**20:.0f} MB more on the way)" if others else ""
            raise ImportLimit(507, f"the jobs take {used / 2**20:.0f} MB of the "
                              f"{self.limits.total_quota_mb:g} MB quota{pending}, too little "
                              f"room for {size / 2**20:.1f} MB more; delete finished jobs")

    def close(self) -> None:
        self._closed = True
        for entry in self.waiting:
            if not entry.ready.done():
                entry.ready.cancel()
        for worker in self.workers:
            worker.kill()
        self.workers.clear()


def jobs_size(jobs_dir: Path) -> int:
    """The jobs' files: every folder but the hidden ones imports are writing (their
    room is reserved)."""
    return sum(tree_size(entry) for entry in jobs_dir.iterdir()
               if entry.is_dir() and not entry.name.startswith("."))  # fmt: skip


def tree_size(path: Path) -> int:
    total = 0
    for root, _, files in os.walk(path):
        for name in files:
            with contextlib.suppress(OSError):
                total += os.lstat(os.path.join(root, name)).st_size
    return total


