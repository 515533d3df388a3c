"""The supervised import service (importing/workers.py) with real worker processes."""

from __future__ import annotations

import asyncio
import ctypes
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time

import pytest
from plotbridge.importing.workers import ImportLimit, ImportService, Limits, jobs_size

from tests.fixtures.waits import settle


def echo(value: int) -> int:
    return value


def pid() -> int:
    return os.getpid()


def sleep_then(seconds: float, value: str) -> str:
    time.sleep(seconds)
    return value


def wait_for_file(path: str, value: str) -> str:
    """Runs until `path` exists (the test's release), at most a minute."""
    deadline = time.monotonic() + 60
    while not os.path.exists(path) and time.monotonic() < deadline:
        time.sleep(0.01)
    return value


def hog(megabytes: int) -> int:
    return len(bytearray(megabytes * 1024 * 1024))


def kill_self() -> None:
    os.kill(os.getpid(), signal.SIGKILL)


def alive(process_id: int) -> bool:
    try:
        os.kill(process_id, 0)
    except ProcessLookupError:
        return False
    with open(f"/proc/{process_id}/stat") as stat:  # a zombie is dead too
        return stat.read().split(") ")[1][0] != "Z"


def thread_address_space() -> int:
    """KB of address space a thread that calls malloc adds while it lives."""
    def size() -> int:
        with open("/proc/self/status") as status:
            return next(int(line.split()[1]) for line in status if line.startswith("VmSize"))
    libc = ctypes.CDLL(None)
    libc.malloc.restype = ctypes.c_void_p
    started, done = threading.Event(), threading.Event()

    def work() -> None:
        block = libc.malloc(64)
        started.set()
        done.wait(30)
        libc.free(ctypes.c_void_p(block))
    before = size()
    thread = threading.Thread(target=work)
    thread.start()
    started.wait(30)
    grown = size() - before
    done.set()
    thread.join()
    return grown


@pytest.fixture
async def service():
    imports = ImportService(Limits(workers=2, time_limit=20, memory_mb=400, small_bytes=1000))
    yield imports
    pids = [w.process.pid for w in imports.workers]
    imports.close()
    assert not any(alive(p) for p in pids)


async def test_a_killed_worker_is_replaced_and_its_upload_told(service):
    with pytest.raises(ImportLimit, match=r"died .*signal 9"):
        await service.call(kill_self)
    assert await service.call(echo, 7) == 7


async def test_an_idle_worker_killed_is_replaced_before_the_next_call(service):
    """Killed while it waited (as the OOM killer may pick it): the next call gets a
    fresh worker, not the news of the death."""
    first = await service.call(pid)
    os.kill(first, signal.SIGKILL)
    await settle(lambda: not alive(first), 10)
    assert await service.call(echo, 5) == 5
    assert first not in [w.process.pid for w in service.workers]


async def test_time_and_memory_limits_answer_what_was_too_big(service):
    service.limits.time_limit = 1.0
    with pytest.raises(ImportLimit, match="longer than the 1 s limit") as slow:
        await service.call(sleep_then, 30, "late")
    assert slow.value.status == 413
    service.limits.time_limit = 60.0  # a loaded machine must not turn the next into a timeout
    with pytest.raises(ImportLimit, match="more than the 400 MB memory limit"):
        await service.call(hog, 600)
    assert await service.call(hog, 10) == 10 * 1024 * 1024


async def test_an_imports_threads_share_one_malloc_arena(service):
    # (the estimate and the G-code scan run on threads of their own; an arena of a
    # thread's own would reserve 64 MB of the worker's limited address space)
    assert await service.call(thread_address_space) < 32 * 1024


async def test_small_uploads_do_not_wait_behind_a_large_one(service, tmp_path):
    release = tmp_path / "release"
    large = [asyncio.create_task(service.call(wait_for_file, str(release), "large",
                                              size=10**6))
             for _ in range(2)]  # fmt: skip
    # one large import runs; the other waits, as it may not take the last free worker
    await settle(lambda: len(service.waiting) == 1
                 and sum(w.busy for w in service.workers) == 1, what="the large ones in")
    try:  # the second large one waits, not this
        small = await asyncio.wait_for(service.call(echo, 1, size=10), 30)
        assert small == 1 and not any(task.done() for task in large)
    finally:
        release.touch()
    assert await asyncio.gather(*large) == ["large", "large"]


def test_workers_die_with_the_server(tmp_path):
    """SIGKILL of the server process: the kernel kills its workers (PR_SET_PDEATHSIG)."""
    script = textwrap.dedent("""
        import asyncio, sys
        from tests.unit.test_import_workers import pid
        from plotbridge.importing.workers import ImportService

        async def main():
            service = ImportService()
            print(await service.call(pid), flush=True)
            await asyncio.sleep(60)

        asyncio.run(main())
    """)
    server = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True,
                              cwd=os.getcwd())  # fmt: skip
    try:
        worker = int(server.stdout.readline())
        assert alive(worker)
        server.kill()
        server.wait(10)
        deadline = time.monotonic() + 10
        while alive(worker) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not alive(worker)
    finally:
        server.kill()
        server.wait()


def test_an_import_out_of_memory_reaches_the_worker_to_name_the_limit(monkeypatch, tmp_path):
    """run_import turns an importer's failures into answers, but not a MemoryError: the
    worker answers that one with the memory limit it hit (not "import failed:")."""
    from plotbridge import importing
    from plotbridge.jobs.imports import run_import

    def out_of_memory(*args, **kwargs):
        raise MemoryError

    monkeypatch.setattr(importing.MachineProfile, "for_board", out_of_memory)
    with pytest.raises(MemoryError):
        run_import("file", str(tmp_path / "a.gcode"), "a.gcode", str(tmp_path / "job"), {}, {})


async def test_quota_room_is_reserved_before_writing_and_settled_atomically(tmp_path):
    """Two uploads that each fit alone but not together: the second is refused before a
    byte of it is written, and an import that outgrows its reservation is refused when
    settled, so the jobs never take more than the quota."""
    service = ImportService(Limits(workers=1, total_quota_mb=1.0, job_quota_mb=1.0))
    jobs = tmp_path / "jobs"
    (jobs / "old").mkdir(parents=True)
    (jobs / "old" / "program.gcode").write_bytes(b"x" * 400_000)
    entered = asyncio.Event()

    async def upload(name: str, size: int, written: int) -> str:
        try:
            async with service.reservation(jobs, size):
                entered.set()
                await asyncio.sleep(0.2)  # the upload streams in meanwhile
                folder = jobs / f".{name}.partial"
                folder.mkdir()
                (folder / "program.gcode").write_bytes(b"x" * written)
                await service.settle(jobs, folder)
                folder.rename(jobs / name)
        except ImportLimit as exc:
            assert exc.status == 507 and "1 MB quota" in str(exc), exc
            return "refused"
        return "stored"

    first = asyncio.create_task(upload("a", 400_000, 400_000))
    await entered.wait()
    assert await upload("b", 400_000, 400_000) == "refused"  # reserved room is taken
    assert await first == "stored"
    assert service.reserved == {}
    # a small declared upload whose import grows past the room left, beside another
    results = await asyncio.gather(upload("c", 10_000, 150_000), upload("d", 10_000, 150_000))
    assert sorted(results) == ["refused", "stored"]
    assert jobs_size(jobs) <= 1024 * 1024
    service.close()
