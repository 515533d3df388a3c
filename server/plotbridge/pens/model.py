"""The pen library's typed shapes: a pen as stored and shown, and the API's bodies."""

from __future__ import annotations

import json
from typing import Annotated

from pydantic import ConfigDict, Field, StringConstraints, ValidationError

from plotbridge.models import LayerPens, Strict

SERVO_US = (500, 2500)  # the firmware's accepted range for $60/$61 (firmware/src/settings.c)

PenName = Annotated[str, StringConstraints(strip_whitespace=True, min_length=1, max_length=64)]
Colour = Annotated[str, StringConstraints(strip_whitespace=True, to_lower=True,
                                          pattern=r"^(#[0-9a-fA-F]{6})?$")]  # fmt: skip
ServoUs = Annotated[int, Field(ge=SERVO_US[0], le=SERVO_US[1])]
Speed = Annotated[float, Field(gt=0, le=100_000, description="draw feed, mm/min")]
Accel = Annotated[float, Field(gt=0, le=100_000, description="acceleration limit, mm/s²")]
Interval = Annotated[float, Field(gt=0, le=1_000_000, description="re-ink interval, m")]


class PenSpec(Strict):
    """What the user sets about a pen (the create body)."""

    name: PenName
    colour: Colour = ""
    up_us: ServoUs = 1000
    """Pen-up servo pulse (the firmware's $60)."""
    down_us: ServoUs = 2000
    """Pen-down servo pulse (the firmware's $61)."""
    speed: Speed | None = None
    """Draw speed: the layer's draw feeds are capped to it; None: the program's."""
    accel: Accel | None = None
    """Acceleration limit (kept for the user; the firmware's $120/$121 stay as set)."""
    reink_m: Interval | None = None
    """Pause to re-ink (or replace) the pen every this many metres drawn; None: never."""


class PenPatch(Strict):
    """A change to some of a pen's settings (the PATCH body); null clears an optional one."""

    name: PenName | None = None
    colour: Colour | None = None
    up_us: ServoUs | None = None
    down_us: ServoUs | None = None
    speed: Speed | None = None
    accel: Accel | None = None
    reink_m: Interval | None = None


class Pen(PenSpec):
    """A pen of the library, as the API shows it."""

    model_config = ConfigDict(extra="ignore")

    id: int
    odometer_m: float = 0.0
    """Pen-down metres drawn with it, across jobs and restarts (since the last reset)."""


class TryBody(Strict):
    down: bool = Field(description="lower (true) or lift (false) the pen")


class LayerPensBody(Strict):
    """Which pen draws which layer (the upload field's shape, checked)."""

    pens: LayerPens


def parse_layer_pens(text: str) -> dict[str, str | int | None]:
    """An upload's `pens` field: a JSON object {"LAYER": PEN}, or `LAYER=PEN,LAYER=PEN`
    (an empty PEN: none). ValueError says what is wrong."""
    text = text.strip()
    if text.startswith("{"):
        try:
            raw = json.loads(text)
        except ValueError as exc:
            raise ValueError(f"pens: not a JSON object: {exc}") from exc
    else:
        raw = {}
        for part in filter(None, (p.strip() for p in text.split(","))):
            layer, sep, pen = part.partition("=")
            if not sep or not layer.strip():
                raise ValueError(f"pens: expected LAYER=PEN, got {part!r}")
            raw[layer.strip()] = pen.strip() or None
    try:
        return LayerPensBody(pens=raw).pens
    except ValidationError as exc:
        first = exc.errors(include_url=False)[0]
        where = ".".join(str(p) for p in first.get("loc", ()))
        raise ValueError(f"{where}: {first.get('msg')}") from exc
