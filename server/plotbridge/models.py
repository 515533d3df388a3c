"""Pydantic models at the API edge (request bodies and answers)."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import (
    AfterValidator,
    BaseModel,
    ConfigDict,
    Field,
    StringConstraints,
    model_validator,
)

from plotbridge.importing.fields import openapi_fields
from plotbridge.notify import check_urls
from plotbridge.papers import PAPER_PATTERN


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


LayerRef = Annotated[str, StringConstraints(strip_whitespace=True, min_length=1, max_length=200)]
PenRef = Annotated[str | int | None, Field(description="a pen's id or name; null: none")]
LayerPens = dict[LayerRef, PenRef]
"""Which pen draws which layer: the layer by 1-based number or name, the pen by id or name."""


class LoginBody(Strict):
    """The token, or the code of a one-time login link (`plotbridge users add`)."""

    token: str | None = Field(None, max_length=256)
    link: str | None = Field(None, max_length=256)


class DeclineBody(Strict):
    """Why an upload is declined: its sender sees it."""

    reason: str = Field(min_length=1, max_length=500)


class PenBody(Strict):
    down: bool


class JogBody(Strict):
    dx: float = Field(0.0, ge=-10000, le=10000)
    dy: float = Field(0.0, ge=-10000, le=10000)
    feed: float = Field(3000.0, gt=0, le=100000)


class MotorsBody(Strict):
    enabled: bool


class MoveBody(Strict):
    position: int = Field(ge=0)


class CommandBody(Strict):
    line: str = Field(min_length=1, max_length=120)
    confirm: bool = Field(False, description="send a line that wedges or wipes the board "
                          "($SLP, $RST=...): without it such a line is refused with 428")


class SettingsBody(Strict):
    settings: dict[Annotated[int, Field(ge=0, le=255)], Annotated[float, Field(ge=-1e6, le=1e6)]]


def _quarter_turn(value: int) -> int:
    if value not in (0, 90, 180, 270):
        raise ValueError("must be 0, 90, 180 or 270")
    return value


class Placement(Strict):
    paper: str | None = Field(None, pattern="(?i)" + PAPER_PATTERN)
    margin: float = Field(10.0, ge=0, le=200)
    fit: bool = False
    rotate: Annotated[int, AfterValidator(_quarter_turn)] = 0
    scale: float = Field(1.0, gt=0, le=100)
    dx: float = Field(0.0, ge=-10000, le=10000)
    dy: float = Field(0.0, ge=-10000, le=10000)


class ResumeFrom(Strict):
    """A point of the program: a stroke vertex nearest to x, y (mm), a line, or a layer."""

    x: float | None = Field(None, ge=-1e5, le=1e5)
    y: float | None = Field(None, ge=-1e5, le=1e5)
    line: int | None = Field(None, ge=1)
    layer: int | None = Field(None, ge=1)

    @model_validator(mode="after")
    def one_kind(self) -> ResumeFrom:
        kinds = [name for name, given in (("x/y", self.x is not None or self.y is not None),
                                          ("line", self.line is not None),
                                          ("layer", self.layer is not None)) if given]  # fmt: skip
        if len(kinds) != 1:
            raise ValueError("give exactly one of {x, y}, {line} or {layer}"
                             + (f", not {' and '.join(kinds)}" if kinds else ""))  # fmt: skip
        if kinds == ["x/y"] and (self.x is None or self.y is None):
            raise ValueError("x and y go together")
        return self


class ResumeBody(Strict):
    """Resume options: where from (default: where the job stopped), how far back along
    the stroke to start (mm), whether to home ($H) first, and the layers to plot after
    the one it resumes in (1-based; as a start's `layers`; default: those chosen before)."""

    from_: ResumeFrom | None = Field(None, alias="from")
    overlap: float = Field(0.0, ge=0, le=1000)
    home: bool = False
    layers: list[Annotated[int, Field(ge=1)]] | None = Field(None, min_length=1, max_length=1000)

    @property
    def special(self) -> bool:
        """From a point or after homing (else: a plain continue or resume)."""
        return self.from_ is not None or self.home

    def where(self) -> dict[str, Any] | None:
        return self.from_.model_dump(exclude_none=True) if self.from_ is not None else None

    @model_validator(mode="after")
    def overlap_needs_a_point(self) -> ResumeBody:
        if self.overlap and self.from_ is None:
            raise ValueError("overlap goes with from (a point to go back from)")
        return self


class PatchJobBody(Strict):
    name: str | None = Field(None, min_length=1, max_length=200)
    placement: Placement | None = None
    pens: LayerPens | None = None
    """Which pen draws which layer (docs/INTERNALS.md, "Pen library")."""


class StartBody(Strict):
    """Options of a start (all optional; the body itself may be left out): the layers to
    plot (1-based, the others skipped; kept for resumes) and each layer's pen."""

    layers: list[Annotated[int, Field(ge=1)]] | None = Field(None, min_length=1, max_length=1000)
    start_layer: int | None = Field(None, ge=1, description="plot from this layer on")
    pens: LayerPens | None = None


class WebhooksBody(Strict):
    urls: Annotated[list[Annotated[str, Field(max_length=2048)]], Field(max_length=16),
                    AfterValidator(check_urls)]  # fmt: skip


class Webhook(BaseModel):
    url: str
    source: Literal["option", "settings"]
    queued: int
    delivered: int
    retries: int
    dropped: int
    refused: int
    last_error: str | None


class Webhooks(BaseModel):
    urls: list[str]
    """The URLs kept in the settings (PUT replaces them)."""
    fixed: list[str]
    """The URLs given with `plotbridge serve --webhook` (not editable here)."""
    webhooks: list[Webhook]


class Position(BaseModel):
    x: float
    y: float


class Machine(BaseModel):
    connected: bool
    state: str
    position: Position
    pen: Literal["up", "down"]
    firmware: str | None
    alarm: int | None = None
    feed: float | None = None
    pins: str | None = None
    planner_free: int | None = None
    line: int | None = None  # the executing program line (Ln:), boards that number lines


class ErrorBody(BaseModel):
    """Every error answer: `detail` is a message, or `{"errors": [{"line", "message"}]}`."""

    detail: Any


ERROR_RESPONSES: dict[int | str, dict[str, Any]] = {
    status: {"model": ErrorBody, "description": text}
    for status, text in {
        401: "missing or wrong token",
        404: "no such job, or not available in this mode",
        409: "not allowed in the current machine or job state",
        400: "Host header not one of this server's names",
        403: "cross-site request (no matching Origin or X-Plotbridge header)",
        408: "request body arrived too slowly",
        413: "request body or upload too large, or an import limit reached",
        415: "file format not accepted",
        422: "invalid request or invalid drawing (errors with line numbers)",
        428: "a console line that wedges or wipes the board needs confirm: true",
        429: "too many failed logins from this client; try again later",
        503: "too many open connections (only an emergency stop gets through)",
        507: "disk quota for jobs reached",
    }.items()
}


def upload_openapi() -> dict[str, Any]:
    """The upload's request body for the OpenAPI schema (the route reads the raw request)."""
    fields: dict[str, Any] = {
        "file": {"type": "string", "format": "binary", "description": "the drawing"},
        "name": {"type": "string", "maxLength": 200},
        "pattern": {"type": "string", "description": "a built-in test pattern instead of a file"},
        "start": {"type": "boolean", "description": "start the job at once"},
        "optimize": {"type": "boolean", "description": "merge and reorder strokes"},
        "layers": {"type": "string", "description": "SVG group ids, labels or stroke colours"},
        "pens": {"type": "string", "description": "which pen draws which layer: "
                 "LAYER=PEN,... or a JSON object (layer by number or name, pen by id or name)"},
        **Placement.model_json_schema()["properties"],
        **openapi_fields(),
    }
    query = ("name", "pattern", "start", "optimize", "paper", "fit", "scale", "rotate")
    return {
        "parameters": [
            {"name": key, "in": "query", "required": False, "schema": fields[key]}
            for key in query
        ],
        "requestBody": {
            "content": {
                "multipart/form-data": {"schema": {"type": "object", "properties": fields}},
                "application/octet-stream": {"schema": {"type": "string", "format": "binary"}},
                "text/plain": {"schema": {"type": "string"}},
            }
        },
    }
