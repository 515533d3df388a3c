"""A progress bar on stderr for a job being followed (`submit --wait`, the vpype command)."""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from typing import Any

from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn


@contextlib.contextmanager
def job_progress(name: str, quiet: bool = False) -> Iterator[Callable[[dict[str, Any]], None]]:
    """Yields `update(job)`, to be called with the job as it is polled: the bar shows
    the job's own `progress` (its plan's time done) and `eta_s`."""
    columns = (
        TextColumn("{task.description}"), BarColumn(),
        TextColumn("{task.percentage:>3.0f}%"), TextColumn("{task.fields[left]}"),
    )  # fmt: skip
    with Progress(*columns, console=Console(stderr=True), disable=quiet) as progress:
        bar = progress.add_task(name, total=1.0, left="")
        shown: list[str | None] = [None]

        def update(job: dict[str, Any]) -> None:
            prompt = (job.get("pen_change") or {}).get("message")
            if prompt and prompt != shown[0]:  # a pen change or re-ink: kept above the bar
                progress.console.print(f"{name}: {prompt} (plotbridge resume, or the UI)")
            shown[0] = prompt
            eta = job.get("eta_s")
            progress.update(bar, completed=job.get("progress") or 0,
                            description=describe(name, job),
                            left=f"{eta:.0f} s left" if eta else "")  # fmt: skip

        yield update


def describe(name: str, job: dict[str, Any]) -> str:
    """The bar's label: the job's state, and what it waits for (a pen change, the machine)
    or, once it stopped, the server's summary of where."""
    why = (job.get("pen_change") or {}).get("message") or job.get("waiting")
    if not why and job.get("summary") and "stop" not in job.get("actions", ()):
        why = job["summary"]
    return f"{name} [{job['state']}]" + (f": {why}" if why else "")
