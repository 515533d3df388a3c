"""The upload's import fields (form fields or query parameters) as ImportOptions keys.

Numpy-free: the server process reads them before handing the upload to a worker.
"""

from __future__ import annotations

import math
from typing import Any

PEN_DIALECTS = ("auto", "m3", "z", "m300", "m280", "laser", "none")
FILLS = ("none", "outline", "hatch")
FONTS = ("futural", "futuram", "scripts", "timesr", "gothiceng")   # Hershey-Fonts names
_TRUE = ("1", "true", "yes", "on")
_FALSE = ("0", "false", "no", "off", "")
# field: (kind, choices or bounds, description) -- also the OpenAPI description
FIELDS: dict[str, tuple[str, Any, str]] = {
    "pen_dialect": ("choice", PEN_DIALECTS, "G-code pen convention (auto detects it)"),
    "fill": ("choice", FILLS, "SVG fills: none, outline filled-only shapes, or hatch"),
    "hatch_spacing": ("number", (0.05, 100.0), "mm between hatch lines"),
    "hatch_angle": ("number", (-360.0, 360.0), "degrees of the hatch lines"),
    "hatch_cross": ("flag", None, "cross-hatch"),
    "font": ("choice", FONTS, "single-stroke font for SVG text"),
    "clip_to_page": ("flag", None, "SVG: leave out what lies outside the page"),
}


def import_fields(params: dict[str, str]) -> dict[str, Any]:
    """The import fields present in `params`, checked; ValueError says which is wrong."""
    out: dict[str, Any] = {}
    for key, (kind, spec, _) in FIELDS.items():
        if key not in params:
            continue
        raw = params[key].strip()
        if kind == "choice":
            if raw.lower() not in spec:
                raise ValueError(f"{key}: expected one of {', '.join(spec)}, got {raw!r}")
            out[key] = raw.lower()
        elif kind == "flag":
            if raw.lower() not in _TRUE + _FALSE:
                raise ValueError(f"{key}: expected true or false, got {raw!r}")
            out[key] = raw.lower() in _TRUE
        else:
            try:
                value = float(raw)
            except ValueError:
                raise ValueError(f"{key}: expected a number, got {raw!r}") from None
            lo, hi = spec
            if not (math.isfinite(value) and lo <= value <= hi):
                raise ValueError(f"{key}: must be between {lo:g} and {hi:g}")
            out[key] = value
    return out


def openapi_fields() -> dict[str, dict]:
    """The fields' OpenAPI schemas."""
    types = {"choice": "string", "flag": "boolean", "number": "number"}
    out = {}
    for key, (kind, spec, text) in FIELDS.items():
        schema: dict[str, Any] = {"type": types[kind], "description": text}
        if kind == "choice":
            schema["enum"] = list(spec)
        out[key] = schema
    return out
