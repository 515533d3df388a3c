"""The upload's import fields (form fields or query parameters) as ImportOptions keys.

Numpy-free: the server process reads them before handing the upload to a worker.
"""

from __future__ import annotations

import json
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
    "fill": ("choice", FILLS, "SVG fills: outline filled-only shapes (the default), none, "
                              "or hatch"),
    "hatch_spacing": ("number", (0.05, 100.0), "mm between hatch lines"),
    "hatch_angle": ("number", (-360.0, 360.0), "degrees of the hatch lines"),
    "hatch_cross": ("flag", None, "cross-hatch"),
    "layer_fill": ("layers", None, "SVG: fill per layer, group or fill colour, a JSON object "
                   '{"name or #rrggbb": {"fill", "hatch_spacing", "hatch_angle", '
                   '"hatch_cross"}}; an entry without fill hatches'),
    "font": ("choice", FONTS, "single-stroke font for SVG text"),
    "clip_to_page": ("flag", None, "SVG: leave out what lies outside the page"),
}


# per layer or per colour (the `layer_fill` field): these keys, checked as above
LAYER_FILL_KEYS = ("fill", "hatch_spacing", "hatch_angle", "hatch_cross")
MAX_LAYER_FILLS = 256
MAX_LAYER_FILL_CHARS = 64 * 1024


def _value(key: str, raw: Any) -> Any:
    """One field's value (text, or a JSON scalar inside `layer_fill`), checked."""
    kind, spec, _ = FIELDS[key]
    if isinstance(raw, bool) and kind != "flag":
        raise ValueError(f"{key}: expected a {'number' if kind == 'number' else 'word'}, "
                         f"got {str(raw).lower()}")
    text = str(raw).strip() if not isinstance(raw, bool) else ("true" if raw else "false")
    if kind == "choice":
        if text.lower() not in spec:
            raise ValueError(f"{key}: expected one of {', '.join(spec)}, got {text!r}")
        return text.lower()
    if kind == "flag":
        if text.lower() not in _TRUE + _FALSE:
            raise ValueError(f"{key}: expected true or false, got {text!r}")
        return text.lower() in _TRUE
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"{key}: expected a number, got {text!r}") from None
    lo, hi = spec
    if not (math.isfinite(value) and lo <= value <= hi):
        raise ValueError(f"{key}: must be between {lo:g} and {hi:g}")
    return value


def layer_fills(raw: str) -> dict[str, dict[str, Any]]:
    """The `layer_fill` field: a JSON object from layer, group or fill colour to its own
    fill settings; ValueError names the entry and the setting that is wrong."""
    if len(raw) > MAX_LAYER_FILL_CHARS:
        raise ValueError(f"layer_fill: longer than {MAX_LAYER_FILL_CHARS} characters")
    try:
        table = json.loads(raw) if raw.strip() else {}
    except RecursionError:
        raise ValueError("layer_fill: nested too deeply") from None
    except ValueError as e:
        raise ValueError(f"layer_fill: not JSON ({e})") from None
    if not isinstance(table, dict):
        raise ValueError("layer_fill: expected a JSON object of layer or colour: settings")
    if len(table) > MAX_LAYER_FILLS:
        raise ValueError(f"layer_fill: at most {MAX_LAYER_FILLS} layers or colours")
    out: dict[str, dict[str, Any]] = {}
    for name, settings in table.items():
        where = f"layer_fill: {name!r}"
        if not name.strip():
            raise ValueError("layer_fill: a layer or colour name is empty")
        if not isinstance(settings, dict):
            raise ValueError(f"{where}: expected an object such as "
                             '{"hatch_spacing": 1, "hatch_angle": 0}')
        unknown = [k for k in settings if k not in LAYER_FILL_KEYS]
        if unknown:
            raise ValueError(f"{where}: unknown setting {unknown[0]!r} (known: "
                             f"{', '.join(LAYER_FILL_KEYS)})")
        try:
            out[name.strip()] = {k: _value(k, v) for k, v in settings.items()}
        except ValueError as e:
            raise ValueError(f"{where}: {e}") from None
    return out


def import_fields(params: dict[str, str]) -> dict[str, Any]:
    """The import fields present in `params`, checked; ValueError says which is wrong."""
    out: dict[str, Any] = {}
    for key, (kind, _, _) in FIELDS.items():
        if key in params:
            out[key] = layer_fills(params[key]) if kind == "layers" else _value(key, params[key])
    return out


def openapi_fields() -> dict[str, dict]:
    """The fields' OpenAPI schemas."""
    types = {"choice": "string", "flag": "boolean", "number": "number", "layers": "string"}
    out = {}
    for key, (kind, spec, text) in FIELDS.items():
        schema: dict[str, Any] = {"type": types[kind], "description": text}
        if kind == "choice":
            schema["enum"] = list(spec)
        out[key] = schema
    return out
