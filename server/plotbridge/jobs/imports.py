"""Imports: an upload (or a built-in pattern) to a job's folder with its normalized program.

The importer runs in a worker process, which keeps its heavy modules (numpy,
svgelements) out of the server. A job's folder appears whole or not at all:
the import writes into a hidden `.ID.partial` folder renamed at the end.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import shutil
import uuid
from collections.abc import AsyncIterator, Callable
from pathlib import Path
from typing import Any

from plotbridge.errors import Refused
from plotbridge.importing.workers import ImportLimit, ImportService, Limits
from plotbridge.jobs.model import Imported


def run_import(kind: str, source: str, filename: str, dest: str, options: dict, board: dict):
    """Worker-process entry: import one upload or pattern; never raises. It plans for
    `board` (Plotter.import_model: the work area, and the estimate's motion model).

    Returns ("ok", Imported fields) or ("failed", status, errors), in plain Python
    types: unpickling the importer's own classes would load its modules into the server.
    """
    from plotbridge import importing

    try:
        profile = importing.MachineProfile.for_board(**board)
        opts = importing.ImportOptions(**options)
        if kind == "pattern":
            result = importing.import_pattern(source, Path(dest), opts, profile)
        else:
            result = importing.import_file(Path(source), filename, Path(dest), opts, profile)
        return ("ok", Imported.of(result).model_dump())
    except importing.ImportFailed as exc:
        return ("failed", exc.status, list(exc.errors)[:100])
    except MemoryError:
        raise  # the worker answers it naming the memory limit (importing/workers.py)
    except Exception as exc:  # an importer bug must still answer as a refused upload
        return ("failed", 422, [{"line": None, "message": f"import failed: {exc}"}])


def patterns() -> dict[str, str]:
    """Worker-process entry: the importer's pattern names and descriptions."""
    from plotbridge.importing import PATTERNS

    return dict(PATTERNS)


class Importer:
    def __init__(self, jobs_dir: Path, limits: Limits | None = None) -> None:
        self.jobs_dir = jobs_dir
        self.workers = ImportService(limits)  # supervised, limited (importing/workers.py)
        self._patterns: dict[str, str] | None = None

    @contextlib.asynccontextmanager
    async def reserve(self, size: int) -> AsyncIterator[None]:
        """Room for an upload of `size` bytes (the jobs' quota), from before it is
        written until its job is in place; 507 when there is none."""
        try:
            async with self.workers.reservation(self.jobs_dir, size):
                yield
        except ImportLimit as exc:
            raise Refused(exc.status, {"errors": [{"line": None, "message": str(exc)}]}) from exc

    def clean(self) -> None:
        """Remove what a crash left half-done (blocking; at start-up)."""
        for leftover in self.jobs_dir.glob(".*"):
            shutil.rmtree(leftover, ignore_errors=True)

    def close(self) -> None:
        self.workers.close()

    async def create(self, kind: str, source: Path | str, filename: str, options: dict[str, Any],
                     board: dict[str, Any]) -> tuple[str, str, Imported]:  # fmt: skip
        """Import into a new job folder, planned for `board` (Plotter.import_model):
        (job id, the source as the job keeps it, result)."""
        job_id = uuid.uuid4().hex[:12]
        partial = self.jobs_dir / f".{job_id}.partial"
        size = await asyncio.to_thread(os.path.getsize, source) if kind == "file" else 0
        async with self.reserve(size):
            partial.mkdir(parents=True)
            try:
                source_arg = str(source)
                if kind == "file":
                    original = partial / ("original" + _safe_suffix(filename))
                    await asyncio.to_thread(shutil.move, str(source), original)
                    source_arg = str(original)
                result = await self._import(kind, source_arg, filename, partial, options, board)
                await asyncio.to_thread(_publish, partial, self.jobs_dir / job_id)
            except BaseException:
                await asyncio.to_thread(shutil.rmtree, partial, True)
                raise
        return job_id, Path(source_arg).name if kind == "file" else source_arg, result

    async def reimport(self, job_id: str, kind: str, source: str, filename: str,
                       options: dict[str, Any], board: dict[str, Any],
                       still_wanted: Callable[[], bool]) -> Imported:  # fmt: skip
        """Import a job again from its original; its folder is swapped only if still wanted."""
        folder = self.jobs_dir / job_id
        partial = self.jobs_dir / f".{job_id}.reimport"
        async with self.reserve(0):
            partial.mkdir(parents=True)
            try:
                if kind == "file":
                    await asyncio.to_thread(shutil.copy2, folder / source, partial / source)
                    source = str(partial / source)
                result = await self._import(kind, source, filename, partial, options, board)
                if not still_wanted():
                    raise Refused(409, f"job {job_id} started while it was being re-imported")
            except BaseException:
                await asyncio.to_thread(shutil.rmtree, partial, True)
                raise
            await asyncio.to_thread(_swap_dirs, partial, folder)
        return result

    async def delete(self, job_id: str) -> None:
        await asyncio.to_thread(shutil.rmtree, self.jobs_dir / job_id, True)

    def preview_path(self, job_id: str) -> Path:
        return self.jobs_dir / job_id / "preview.json"

    def program_path(self, job_id: str) -> Path:
        return self.jobs_dir / job_id / "program.gcode"

    async def patterns(self) -> dict[str, str]:
        if self._patterns is None:
            self._patterns = await self._worker(patterns)
        return self._patterns

    async def _import(self, kind: str, source: str, filename: str, dest: Path,
                      options: dict[str, Any], board: dict[str, Any]) -> Imported:  # fmt: skip
        size = await asyncio.to_thread(os.path.getsize, source) if kind == "file" else 0
        try:
            outcome = await self.workers.call(run_import, kind, source, filename, str(dest),
                                              options, board, size=size)  # fmt: skip
            if outcome[0] == "ok":
                await self.workers.settle(self.jobs_dir, dest)
        except ImportLimit as exc:
            raise Refused(exc.status, {"errors": [{"line": None, "message": str(exc)}]}) from exc
        if outcome[0] != "ok":
            raise Refused(outcome[1], {"errors": outcome[2]})
        return Imported.model_validate(outcome[1])

    async def _worker(self, function: Callable[..., Any], *args: Any) -> Any:
        """Run `function` in an import worker; a limit answers as a refusal."""
        try:
            return await self.workers.call(function, *args)
        except ImportLimit as exc:
            raise Refused(exc.status, {"errors": [{"line": None, "message": str(exc)}]}) from exc


def _safe_suffix(filename: str) -> str:
    suffix = Path(filename).suffix.lower()
    return suffix if 1 < len(suffix) <= 9 and suffix[1:].isalnum() else ""


def _swap_dirs(new: Path, old: Path) -> None:
    trash = old.with_name(f".{old.name}.old")
    old.rename(trash)
    new.rename(old)
    shutil.rmtree(trash, ignore_errors=True)


def _fsync(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _publish(partial: Path, folder: Path) -> None:
    """Rename a finished import's folder into place, its files on the disk first and the
    rename after (blocking): an acknowledged job keeps its files through a power cut."""
    for path in partial.rglob("*"):  # files, and the folders that list them
        _fsync(path)
    _fsync(partial)
    partial.rename(folder)
    _fsync(folder.parent)
