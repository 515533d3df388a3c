"""previewjson.c: the preview's strokes as the JSON text json.dumps writes for them."""

from __future__ import annotations

import ctypes

import numpy as np

from . import function


def _fn():
    p = ctypes.c_void_p
    return function("previewjson", "strokes_json", [ctypes.c_long, p, p, p], ctypes.c_long)


def strokes_json(strokes: list[np.ndarray]) -> str | None:
    """json.dumps([np.round(s, 3).tolist() for s in strokes], separators=(",", ":")) for
    n x 2 float arrays; None when a value is too large to write here."""
    sizes = np.array([len(s) for s in strokes], np.int64)
    xy = np.ascontiguousarray(np.concatenate(strokes) if strokes else np.empty((0, 2)),
                              np.float64)
    out = np.empty(2 + 3 * len(strokes) + 44 * len(xy), np.uint8)
    n = _fn()(len(strokes), sizes.ctypes.data, xy.ctypes.data, out.ctypes.data)
    return None if n < 0 else out[:n].tobytes().decode("ascii")
