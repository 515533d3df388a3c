"""The job: one typed shape from the store to the API.

Fields marked `exclude=True` are the server's own (where the job came from, how
to resume it): the store keeps them, the API never shows them.
"""

from __future__ import annotations

import time
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, computed_field, model_validator
from pydantic_core import to_jsonable_python

from plotbridge.colours import label as colour_label
from plotbridge.jobs.lifecycle import ACTIVE, RESUMABLE, allowed

__all__ = ["ACTIVE", "AFTER_JOB", "RESUMABLE", "Bounds", "Imported", "Job", "JobState", "Layer"]

JobState = Literal[
    "queued", "waiting", "running", "paused", "pen_change", "done", "failed", "cancelled",
    "stopped", "interrupted", "awaiting_approval",
]  # fmt: skip (jobs/lifecycle.py's State)

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
    """Its lines the pen has finished, 0..lines_total."""
    progress: float = 0.0
    """The share of its planned time the pen has done, 0..1."""
    drawn_mm: float = 0.0
    """Its pen-down length drawn."""
    eta_s: float | None = None
    """Its planned time still to come."""
    pen: int | None = None
    """The pen library's id of the pen that draws it ("Pen library"), or None."""
    label: str = ""
    """Its name as texts for people show it: a name that is a colour code becomes the
    colour's word (`colours.label`: "#d40000" is "red")."""

    @model_validator(mode="after")
    def _label(self) -> Layer:
        self.label = colour_label(self.name, self.colour)
        return self

    @property
    def lines_total(self) -> int:
        return self.last_line - self.first_line + 1


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
    """Lines the pen has finished (from the line the board executes, not the acks)."""
    progress: float = 0.0
    """The share of the plan's time the pen has done, 0..1."""
    drawn_mm: float = 0.0
    """Pen-down length drawn."""
    done_point: dict[str, Any] | None = None
    """Where the pen is (or stopped): {"line", "x", "y", "layer", "layer_name"}."""
    summary: str = ""
    """One sentence on where the job is, naming its layer and position."""
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
    approval: dict[str, Any] | None = None
    """An upload that needs approval: {"start": started once approved, "decision": None,
    "approved" or "declined", "by", "reason" (a decline's, shown to the sender), "at"}."""
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
    lines_acked: int = Field(0, exclude=True)
    """Lines the board acknowledged (a planner's depth ahead of the pen)."""
    claim: str | None = Field(None, exclude=True)
    """The action under way that holds the job (jobs/lifecycle.py, `claim`)."""

    @computed_field  # type: ignore[prop-decorator]
    @property
    def actions(self) -> list[str]:
        """What may be asked of the job now (jobs/lifecycle.py)."""
        return allowed(self.state, self.claim is not None)

    def public(self) -> dict[str, Any]:
        """The API's job object."""
        return self.model_dump(mode="json")

    def record(self) -> dict[str, Any]:
        """Everything, for the store (not `actions`: it follows from the state)."""
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

    @property
    def active(self) -> bool:
        return self.state in ACTIVE
