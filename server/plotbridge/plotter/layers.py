"""A job's layers, one after the other: each streamed with its pen (`LayerStream`), the
pen change before the next (`PenChanges`), and inside a layer the stops to re-ink where
drawing follows; the pen's point told to `StopPoint` at each boundary."""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from pathlib import Path

from plotbridge.jobs.model import Job
from plotbridge.pens import Pen, PenFeed
from plotbridge.plotter.layerstream import LayerStream
from plotbridge.plotter.penchange import PenChanges
from plotbridge.plotter.stoppoint import StopPoint
from plotbridge.resume import ResumePoint, layer_runs, resume_preamble


class LayerRuns:
    def __init__(self, point: StopPoint, changes: PenChanges, stream: LayerStream,
                 on_ack: Callable[[int], None]) -> None:  # fmt: skip
        self.point = point
        self.on_ack = on_ack  # the runner's: each acknowledged line
        self.changes = changes
        self.stream = stream
        self._feed: PenFeed | None = None

    def acked(self, line: int) -> None:
        """The board acknowledged `line`: its pen-down length goes to the pen's odometer."""
        if self._feed is not None:
            self._feed.acked(line)

    async def plot(self, job: Job, program: Path, line: int, preamble: list[str],
                   floor: int) -> str:  # fmt: skip
        """Plot from `line` (after `preamble`; `floor`: the earliest line a resume may need)
        to the end of the job's plotted layers. The board's state once it stands (Idle:
        all done), or "Ended" when the job ended meanwhile (stop, cancel, link lost)."""
        state, reink = "Idle", None
        try:
            for number, (start, stop, layer) in enumerate(layer_runs(job.layers,
                                                                     job.plot_layers, line)):
                if number:  # after a layer: the M0s (not sent) and skipped layers are done
                    self.point.parked(job, start)
                    prompt = self.changes.layer_prompt(job, layer, reink)
                    if not await self.changes.wait(job, prompt):
                        return "Ended"
                    floor = start
                    preamble = (await asyncio.to_thread(resume_preamble, program,
                                                        ResumePoint(start)))[1]  # fmt: skip
                state, reink = await self._layer(job, program, layer, start, stop, preamble,
                                                 floor)  # fmt: skip
                if state != "Idle":
                    break
        finally:
            self._feed = None
        return state

    async def _layer(self, job: Job, program: Path, index: int, line: int, stop: int | None,
                     preamble: list[str], floor: int) -> tuple[str, Pen | None]:  # fmt: skip
        """Stream lines `line`..`stop` with the pen of layer `index` (0-based), stopping to
        re-ink where due and drawing follows. The board's state once it stands ("Ended":
        the job ended meanwhile) and the pen still due for re-inking at the layer's end."""
        end = (stop - 1) if stop is not None else job.lines_total
        due: Pen | None = None
        while True:
            feed = self._feed = await self.changes.load(job, index)
            self.point.floor = floor
            try:
                state = await self.stream.run(program, line, stop, preamble, feed,
                                              self.on_ack, self.point.streaming)  # fmt: skip
            finally:
                self.point.live = False
            if not job.active:
                return "Ended", None
            if state != "Idle" or feed.stopped_at is None or feed.pen is None:
                return state, due
            line, floor = feed.stopped_at + 1, feed.stopped_at + 1
            if not self.point.draws_between(job, feed.stopped_at, end):
                due, preamble = feed.pen, []  # the last stroke: told at the boundary, if any
                if line > end:
                    return state, due
                continue  # the rest of the layer (travel) as it is
            self.point.parked(job, line)
            if not await self.changes.wait(job, self.changes.reink_prompt(job, feed.pen,
                                                                          index)):
                return "Ended", None
            x, y = feed.position  # back where the pen went up, then on
            preamble = [f"G0 X{x:.3f} Y{y:.3f}"]

