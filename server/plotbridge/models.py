"""Pydantic models at the API edge (request bodies and answers)."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import AfterValidator, BaseModel, ConfigDict, Field

from plotbridge.importing.fields import openapi_fields
from plotbridge.notify import check_urls
from plotbridge.papers import PAPER_PATTERN


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class LoginBody(Strict):
    token: str


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


class PatchJobBody(Strict):
    name: str | None = Field(None, min_length=1, max_length=200)
    placement: Placement | None = None


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
        429: "too many failed logins from this client; try again later",
        503: "too many connections from this client",
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
