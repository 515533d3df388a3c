"""The job: one typed shape from the store to the API.

Fields marked `exclude=True` are the server's own (where the job came from, how
to resume it): the store keeps them, the API never shows them.
"""

from __future__ import annotations

import time
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field
from pydantic_core import to_jsonable_python

from plotbridge.motion.eta import Timeline, share_done

JobState = Literal[
    "queued", "waiting", "running", "paused", "pen_change", "done", "failed", "cancelled",
    "stopped", "interrupted",
]  # fmt: skip

ACTIVE: frozenset[str] = frozenset({"running", "paused", "pen_change"})
FINISHED: frozenset[str] = frozenset({"done", "failed", "cancelled", "stopped"})
RESUMABLE: frozenset[str] = frozenset({"interrupted", "stopped"})

AfterJob = Literal["park", "home", "none"]
"""What a plotter does once a job is done: pen up and park, home, or nothing."""
AFTER_JOB: tuple[str, ...] = ("park", "home", "none")


class Bounds(BaseModel):
    min_x: float
    min_y: float
    max_x: float
    max_y: float

    def fits(self, width: float, height: float) -> bool:
        """Inside a work area of `width` x `height` mm from the origin."""
        eps = 1e-6
        return (self.min_x >= -eps and self.min_y >= -eps
                and self.max_x <= width + eps and self.max_y <= height + eps)


class Layer(BaseModel):
    """One layer of a job (docs/INTERNALS.md, "Layers"): what the import measured, and
    how far the job's streaming has drawn it."""

    model_config = ConfigDict(extra="allow")  # more about a layer may come with the import

    name: str
    colour: str = ""
    first_line: int
    """Its first program line (1-based); the line before is its `M0` (not the first layer)."""
    last_line: int
    strokes: int = 0
    pen_down_mm: float = 0.0
    estimate_s: float = 0.0
    lines_done: int = 0
    """Its lines acknowledged by the board, 0..lines_total."""
    progress: float = 0.0
    """The share of its estimated time drawn, 0..1."""
    pen: int | None = None
    """The pen library's id of the pen that draws it ("Pen library"), or None."""

    @property
    def lines_total(self) -> int:
        return self.last_line - self.first_line + 1

    def follow(self, lines_done: int, timeline: Timeline) -> None:
        """Its progress when the job has `lines_done` lines acknowledged."""
        self.lines_done = min(max(lines_done - self.first_line + 1, 0), self.lines_total)
        self.progress = round(share_done(timeline, self.first_line, self.last_line,
                                         lines_done), 4)  # fmt: skip


class Imported(BaseModel):
    """What the importer tells about a program (worker process to server, plain types)."""

    format: str
    lines_total: int
    estimate_s: float
    bounds: Bounds
    stats: dict[str, float] = {}
    timeline: list[tuple[int, float]] = []
    layers: list[Layer] = []                   # docs/INTERNALS.md, "Layers"
    warnings: list[dict[str, Any]] = []        # what the importer dropped or changed
    substitutions: list[dict[str, Any]] = []   # SVG text set in a substitute font

    @classmethod
    def of(cls, result: Any) -> Imported:
        """From an `importing.ImportResult` (in the worker process)."""
        return cls(
            format=str(result.format),
            lines_total=int(result.lines_total),
            estimate_s=round(float(result.estimate_s), 1),
            bounds={key: float(value) for key, value in result.bounds.items()},
            stats={key: float(value) for key, value in result.stats.items()},
            timeline=[(int(line), float(seconds)) for line, seconds in result.timeline],
            layers=list(getattr(result, "layers", [])),
            warnings=list(getattr(result, "warnings", [])),
            substitutions=list(getattr(result, "substitutions", [])),
        )


class Job(BaseModel):
    model_config = ConfigDict(validate_assignment=False)

    id: str
    name: str
    state: JobState = "queued"
    format: str
    created_at: float = Field(default_factory=time.time)
    lines_total: int
    lines_done: int = 0
    progress: float = 0.0
    estimate_s: float
    eta_s: float | None = None
    bounds: Bounds | None = None
    error: str | None = None
    stats: dict[str, float] = {}
    placement: dict[str, Any] = {}
    resume_line: int | None = None
    started_at: float | None = None
    finished_at: float | None = None
    layers: list[Layer] = []
    warnings: list[dict[str, Any]] = []
    substitutions: list[dict[str, Any]] = []
    plotter: str | None = None
    """The plotter that runs (or ran) the job, or will run it once it waits for it."""
    target: str | None = None
    """The plotter asked for on upload or start; None: the first free one it fits."""
    waiting: str | None = None
    """Why a `waiting` job does not run yet."""
    after: AfterJob | None = None
    """What the plotter does once this job is done; None: the server's default."""
    plot_layers: list[int] | None = None
    """The 1-based numbers of the layers a start plots (the start's `layers`); None: all."""
    owner: str | None = None
    """Who uploaded it, as the audit log names them ("ann", "key ci", "token (first admin)")."""
    pen_change: dict[str, Any] | None = None
    """In `pen_change`: {"reason" ("layer" or "reink"), "layer" (1-based), "layers", "name",
    "colour", "pen" (its name or None), "message"}."""
    # the server's own:
    kind: Literal["file", "pattern"] = Field("file", exclude=True)
    source: str = Field("", exclude=True)
    filename: str = Field("", exclude=True)
    options: dict[str, Any] = Field(default_factory=dict, exclude=True)
    timeline: list[tuple[int, float]] = Field(default_factory=list, exclude=True)
    safe_line: int | None = Field(None, exclude=True)

    def public(self) -> dict[str, Any]:
        """The API's job object."""
        return self.model_dump(mode="json")

    def record(self) -> dict[str, Any]:
        """Everything, for the store."""
        return {name: to_jsonable_python(getattr(self, name)) for name in type(self).model_fields}

    def imported(self, result: Imported) -> None:
        self.format = result.format
        self.lines_total = result.lines_total
        self.estimate_s = self.eta_s = result.estimate_s
        self.bounds = result.bounds
        self.stats = result.stats
        self.timeline = result.timeline
        self.layers = [layer.model_copy() for layer in result.layers]
        self.warnings = result.warnings
        self.substitutions = result.substitutions

    def follow_layers(self) -> None:
        """Each layer's progress from the job's acknowledged lines."""
        for layer in self.layers:
            layer.follow(self.lines_done, self.timeline)

    @property
    def active(self) -> bool:
        return self.state in ACTIVE
