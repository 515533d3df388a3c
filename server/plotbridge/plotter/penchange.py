"""Pens during a run: each layer's pen loaded on the board, and the stops to change the pen
between layers or to re-ink it (the job `pen_change` with a prompt until it continues).

Re-ink prompts come only where drawing follows in the layer: one due at a layer's last
stroke joins that boundary's pen change (one prompt), one due at the job's last stroke is
not made at all. The metres they name are the pen's odometer's.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable

from plotbridge.colours import is_code
from plotbridge.jobs.lifecycle import Lifecycle
from plotbridge.jobs.model import Job, Layer
from plotbridge.pens import Pen, PenFeed, PenLibrary, servo_lines
from plotbridge.plotter.link import Link

log = logging.getLogger("plotbridge.runner")

PARK_S = 120.0  # s the park move may take

Prompt = dict[str, object]


def pen_to_load(layer: Layer, pen: Pen | None) -> str:
    """What a pen-change prompt asks to load, after the layer's number: the pen by its
    name, else the pen of the layer by the layer's name, else by the colour's word; never
    a colour code (a layer split by colour is named by its code)."""
    if layer.name and not is_code(layer.name):
        named = f", '{layer.name}'"
        return f"{named}: load pen '{pen.name}'" if pen is not None else f"{named}: load its pen"
    colour = layer.label
    if pen is not None:
        return f" ({colour}): load pen '{pen.name}'" if colour else f": load pen '{pen.name}'"
    return f": load the {colour} pen" if colour else ": load its pen"


class PenChanges:
    def __init__(self, link: Link, lifecycle: Lifecycle, pens: PenLibrary | None,
                 park_lines: Callable[[], list[str]]) -> None:  # fmt: skip
        self.link = link
        self.lifecycle = lifecycle
        self.pens = pens
        self.park_lines = park_lines
        self._done = asyncio.Event()

    async def load(self, job: Job, index: int) -> PenFeed:
        """The pen of layer `index` (0-based): its servo positions written to the board
        ($60/$61, only those that differ), and its feed for the stream."""
        pen = self.pen_of(job, index)
        if pen is not None:
            for setting in servo_lines(pen, self.link.settings):
                await self.link.command(setting)
                log.info("job %s: pen %r: %s", job.id, pen.name, setting)
        odometer = self.pens.odometer_mm(pen.id) if self.pens and pen else 0.0
        return PenFeed(pen, odometer, self.pens.drawn if self.pens else lambda _p, _mm: None)

    def pen_of(self, job: Job, index: int) -> Pen | None:
        if self.pens is None or not job.layers:
            return None
        return self.pens.layer_pen(job.layers[index])

    def metres(self, pen: Pen) -> str:
        """The pen's odometer, as the pen library shows it."""
        if self.pens is None:
            return "0.000 m"
        self.pens.flush()
        return f"{self.pens.odometer_mm(pen.id) / 1000:.3f} m"

    def layer_prompt(self, job: Job, index: int, reink: Pen | None = None) -> Prompt:
        """What to load before layer `index` (0-based); `reink`: the pen just used is due
        for re-inking too (said in the same prompt)."""
        layer = job.layers[index]
        pen = self.pen_of(job, index)
        message = f"Layer {index + 1} of {len(job.layers)}{pen_to_load(layer, pen)}, then continue"
        if reink is not None:
            message += f" (pen '{reink.name}' is due for re-inking: {self.metres(reink)} drawn)"
        return {"reason": "layer", "layer": index + 1, "layers": len(job.layers),
                "name": layer.label or f"layer {index + 1}", "colour": layer.colour,
                "pen": pen.name if pen else None, "message": message,
                "reink": reink.name if reink is not None else None}  # fmt: skip

    def reink_prompt(self, job: Job, pen: Pen, index: int) -> Prompt:
        """The pen of layer `index` went past a multiple of its re-ink interval."""
        prompt = self.layer_prompt(job, index) if job.layers else {
            "layer": 1, "layers": 1, "name": job.name, "colour": "", "pen": pen.name}
        prompt.update(reason="reink", reink=pen.name,
                      message=f"Re-ink pen '{pen.name}': {self.metres(pen)} drawn; continue "
                              "when it is ready")  # fmt: skip
        return prompt

    async def wait(self, job: Job, prompt: Prompt) -> bool:
        """Pen up, carriage parked, the job `pen_change` with `prompt` until it continues
        (UI, REST, WebSocket, or the board's resume button). False when the job ended
        meanwhile (emergency stop, cancel, link lost)."""
        for line in self.park_lines():
            await self.link.command(line, timeout=PARK_S)
        self._done.clear()
        self.lifecycle.move(job, "pen_change", pen_change=prompt)
        log.info("job %s: %s", job.id, prompt["message"])
        await self._done.wait()  # continued, or the job ended (ended())
        job.pen_change = None
        return job.state == "running"

    def loaded(self, job: Job, cause: str) -> Job:
        """The pen is in: `continue` (asked) or `released` (the board's resume button)."""
        self.lifecycle.move(job, cause)
        self._done.set()
        log.info("job %s: pen change done (%s)", job.id, cause)
        return job

    def ended(self) -> None:
        """The job ended: a wait for a pen gives up."""
        self._done.set()
